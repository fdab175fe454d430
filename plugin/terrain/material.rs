//! Materials of terrain cells: a table from labels to materials of any
//! Bevy [`Material`] type on the terrain entity ([`TerrainMaterials`]),
//! and the plugin that gives each cell entity the material of its label
//! ([`TerrainMaterialPlugin`]).
//!
//! Cell entities are spawned without a material; in the same frame,
//! [`TerrainSystems::Material`] gives each
//! new [`TerrainCell`] the `MeshMaterial3d<M>` of its label from its
//! terrain's `TerrainMaterials<M>`, for every `M` with a
//! `TerrainMaterialPlugin<M>`. Changing a table re-assigns the materials of
//! all that terrain's cells. A terrain without any table shows Bevy's
//! default `StandardMaterial`.
//!
//! [`triplanar`] is a textured PBR material for terrain that needs no UVs:
//! [`triplanar::TriplanarMaterial`].
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy::render::render_resource::AsBindGroup;
//! use bevy_chisel::terrain::{Terrain, TerrainMaterialPlugin, TerrainMaterials, TerrainPlugin};
//!
//! // A game's own material type, with its own shader.
//! #[derive(Asset, TypePath, AsBindGroup, Clone)]
//! struct Toon {
//!     #[uniform(0)]
//!     color: LinearRgba,
//! }
//! impl Material for Toon {}
//!
//! fn setup(mut commands: Commands, mut toons: ResMut<Assets<Toon>>, terrain: Single<Entity, With<Terrain>>) {
//!     let rock = toons.add(Toon { color: LinearRgba::gray(0.5) });
//!     let ore = toons.add(Toon { color: LinearRgba::rgb(0.9, 0.7, 0.2) });
//!     // Label 1 is rock, label 4 ore. Carves that add or paint any other
//!     // label are refused; other labels the terrain was built with are
//!     // drawn as rock.
//!     commands.entity(*terrain).insert(TerrainMaterials::new([(1, rock.clone()), (4, ore)], rock));
//! }
//!
//! App::new().add_plugins((
//!     DefaultPlugins,
//!     TerrainPlugin,
//!     MaterialPlugin::<Toon>::default(),
//!     TerrainMaterialPlugin::<Toon>::default(),
//! ));
//! ```

pub mod triplanar;

use std::collections::{BTreeSet, HashMap};
use std::marker::PhantomData;

use bevy::prelude::*;
use chisel_bsp::tree::Label;

use super::TerrainSystems;
use super::component::{Terrain, TerrainCell};
use super::debris::DebrisPart;
use super::world::LodMesh;

/// Materials of a terrain's labels: put it on the terrain entity. Carves
/// that add or paint a label without an entry are refused
/// ([`TerrainError::NoMaterial`](super::TerrainError::NoMaterial)), so the
/// table decides which materials a game can carve in; labels the terrain
/// was built with and the table lacks are drawn with `fallback`, with a
/// warning when the table is inserted or changed. `M` is any Bevy [`Material`] (with a
/// [`TerrainMaterialPlugin<M>`] in the app; `TerrainPlugin` adds the one
/// for [`StandardMaterial`]).
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(Component)]
#[require(HasTerrainMaterials)]
pub struct TerrainMaterials<M: Material = StandardMaterial> {
    /// Material per label.
    pub by_label: HashMap<Label, Handle<M>>,
    /// Material of labels not in the table.
    pub fallback: Handle<M>,
}

impl<M: Material> Default for TerrainMaterials<M> {
    fn default() -> Self {
        Self {
            by_label: HashMap::new(),
            fallback: Handle::default(),
        }
    }
}

impl<M: Material> TerrainMaterials<M> {
    /// A table from `(label, material)` pairs.
    #[must_use]
    pub fn new(entries: impl IntoIterator<Item = (Label, Handle<M>)>, fallback: Handle<M>) -> Self {
        Self {
            by_label: entries.into_iter().collect(),
            fallback,
        }
    }

    /// The material of `label`.
    #[must_use]
    pub fn get(&self, label: Label) -> Handle<M> {
        self.by_label
            .get(&label)
            .cloned()
            .unwrap_or_else(|| self.fallback.clone())
    }
}

/// Marks a terrain entity that has a [`TerrainMaterials`] table of some
/// material type (inserted with it): the cells of a terrain without one
/// get Bevy's default [`StandardMaterial`].
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Default)]
pub struct HasTerrainMaterials;

/// Gives every [`TerrainCell`] the `MeshMaterial3d<M>` of its label from
/// its terrain's [`TerrainMaterials<M>`], in the frame the cell is spawned
/// and again whenever the table changes. Runs in
/// [`TerrainSystems::Material`]; add one per material type that terrains
/// use (rendering that type also needs Bevy's `MaterialPlugin<M>`).
pub struct TerrainMaterialPlugin<M: Material>(PhantomData<M>);

impl<M: Material> Default for TerrainMaterialPlugin<M> {
    fn default() -> Self {
        Self(PhantomData)
    }
}

/// Present once [`TerrainMaterialPlugin<M>`] has added its system.
#[derive(Resource)]
struct MaterialSystemAdded<M>(PhantomData<M>);

impl<M: Material> Plugin for TerrainMaterialPlugin<M> {
    fn build(&self, app: &mut App) {
        // Added by several plugins (say `TerrainPlugin` and a game), it
        // still assigns once per frame.
        if app.world().contains_resource::<MaterialSystemAdded<M>>() {
            return;
        }
        app.insert_resource(MaterialSystemAdded::<M>(PhantomData))
            .register_type::<TerrainMaterials<M>>()
            .register_type::<HasTerrainMaterials>()
            .add_systems(PreUpdate, sync_material_labels::<M>)
            .add_systems(
                Update,
                assign_materials::<M>.in_set(TerrainSystems::Material),
            );
    }

    fn is_unique(&self) -> bool {
        false
    }
}

/// Keeps [`Terrain::material_labels`] of every terrain with a
/// `TerrainMaterials<M>` equal to the labels of its table, so that carves
/// that would add or paint a label without a material are refused
/// ([`TerrainError::NoMaterial`](super::TerrainError::NoMaterial)), and
/// warns when a new or changed table has no material for a label the
/// terrain already has (those are drawn with the fallback). Runs in
/// `PreUpdate`, before the carves of the frame are read. A terrain is
/// marked changed only when its material labels change.
pub fn sync_material_labels<M: Material>(
    mut tables: Query<
        (Entity, &mut Terrain, Ref<TerrainMaterials<M>>),
        Or<(Changed<TerrainMaterials<M>>, Added<Terrain>)>,
    >,
    mut removed: RemovedComponents<TerrainMaterials<M>>,
    mut bare: Query<&mut Terrain, Without<TerrainMaterials<M>>>,
) {
    for (entity, mut terrain, table) in &mut tables {
        let drawn: BTreeSet<Label> = table.by_label.keys().copied().collect();
        if table.is_changed() {
            let missing: Vec<Label> = terrain.labels().difference(&drawn).copied().collect();
            if !missing.is_empty() {
                warn!(
                    "terrain {entity}: its material table has no material for labels \
                     {missing:?}; they are drawn with the fallback, and carves that add \
                     or paint them are refused"
                );
            }
        }
        // What carves may add or paint changes only with the table's labels.
        if terrain.material_labels() != Some(&drawn) {
            terrain.runtime.material_labels = Some(drawn);
        }
    }
    for entity in removed.read() {
        if let Ok(mut terrain) = bare.get_mut(entity)
            && terrain.material_labels().is_some()
        {
            terrain.runtime.material_labels = None;
        }
    }
}

/// Gives new cells (and every cell of a terrain whose table changed) the
/// material of its label.
pub fn assign_materials<M: Material>(
    tables: Query<Ref<TerrainMaterials<M>>>,
    new_cells: Query<(Entity, &TerrainCell), Added<TerrainCell>>,
    all_cells: Query<(Entity, &TerrainCell)>,
    new_debris: Query<(Entity, &DebrisPart), Added<DebrisPart>>,
    new_coarse: Query<(Entity, &LodMesh), Added<LodMesh>>,
    mut commands: Commands,
) {
    for (entity, part) in &new_debris {
        if let Ok(table) = tables.get(part.terrain) {
            commands
                .entity(entity)
                .try_insert(MeshMaterial3d(table.get(part.label)));
        }
    }
    // Coarse chunks take the world entity's table.
    for (entity, coarse) in &new_coarse {
        if let Ok(table) = tables.get(coarse.world) {
            commands
                .entity(entity)
                .try_insert(MeshMaterial3d(table.get(coarse.label)));
        }
    }
    let mut give = |entity: Entity, cell: &TerrainCell, table: &TerrainMaterials<M>| {
        commands
            .entity(entity)
            .try_insert(MeshMaterial3d(table.get(cell.label)));
    };
    if tables.iter().any(|t| t.is_changed()) {
        for (entity, cell) in &all_cells {
            match tables.get(cell.terrain) {
                Ok(table) if table.is_changed() => give(entity, cell, &table),
                _ => {}
            }
        }
    }
    for (entity, cell) in &new_cells {
        if let Ok(table) = tables.get(cell.terrain)
            && !table.is_changed()
        {
            give(entity, cell, &table);
        }
    }
}

/// Gives new cells of terrains without any material table Bevy's default
/// [`StandardMaterial`].
pub(crate) fn default_materials(
    new_cells: Query<(Entity, &TerrainCell), Added<TerrainCell>>,
    new_debris: Query<(Entity, &DebrisPart), Added<DebrisPart>>,
    new_coarse: Query<(Entity, &LodMesh), Added<LodMesh>>,
    tables: Query<(), With<HasTerrainMaterials>>,
    mut commands: Commands,
) {
    for (entity, coarse) in &new_coarse {
        if !tables.contains(coarse.world) {
            commands
                .entity(entity)
                .try_insert(MeshMaterial3d::<StandardMaterial>::default());
        }
    }
    for (entity, part) in &new_debris {
        if !tables.contains(part.terrain) {
            commands
                .entity(entity)
                .try_insert(MeshMaterial3d::<StandardMaterial>::default());
        }
    }
    for (entity, cell) in &new_cells {
        if !tables.contains(cell.terrain) {
            commands
                .entity(entity)
                .try_insert(MeshMaterial3d::<StandardMaterial>::default());
        }
    }
}
