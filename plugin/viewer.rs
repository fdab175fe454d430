//! Viewer conveniences shared by the examples: an orbit camera, a text
//! overlay, the terrain under the mouse cursor and click-to-carve.
//!
//! [`ViewerPlugin`] drives every [`OrbitCamera`] (arrow keys and a drag of
//! its [`OrbitCamera::drag_buttons`] orbit, the wheel zooms, WASD/QE move
//! the focus unless [`OrbitCamera::move_keys`] is off) and, when a
//! [`ClickCarving`] resource exists, carves the terrain under the cursor:
//! left click blasts a crater, right click heaps up material, and
//! [`ClickCarving::undo_key`] (Z in the examples) undoes the last carve,
//! [`ClickCarving::redo_key`] (Y) redoes it.

use bevy::ecs::system::SystemParam;
use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll};
use bevy::prelude::*;
use chisel_bsp::octree::Edit;
use chisel_bsp::tree::Label;

use crate::terrain::{
    Carve, CarveShape, CarveTool, RedoCarve, Terrain, TerrainHit, TerrainSystems, UndoCarve,
};

/// Orbit cameras, text overlays and (with [`ClickCarving`]) mouse carving.
/// Carving needs [`crate::terrain::TerrainPlugin`].
pub struct ViewerPlugin;

impl Plugin for ViewerPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<OrbitCamera>()
            .register_type::<Overlay>()
            .register_type::<ClickCarving>()
            .add_systems(
                Update,
                (
                    orbit_cameras,
                    click_carving
                        .run_if(resource_exists::<ClickCarving>)
                        .before(TerrainSystems::Carve),
                ),
            );
    }
}

/// A camera orbiting `focus` at `distance`, `yaw` about the vertical
/// (`+y`) and `pitch` above the horizon, both in radians. Its `Transform`
/// is set from these every frame.
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(Component)]
#[require(Camera3d)]
pub struct OrbitCamera {
    /// The point looked at.
    pub focus: Vec3,
    /// Angle about `+y`.
    pub yaw: f32,
    /// Angle above the horizontal plane, kept in `[0.05, 1.5]`.
    pub pitch: f32,
    /// Distance from the focus.
    pub distance: f32,
    /// Nearest zoom.
    pub min_distance: f32,
    /// Farthest zoom.
    pub max_distance: f32,
    /// Whether WASD (along the ground) and Q/E (down, up) move the focus.
    pub move_keys: bool,
    /// Mouse buttons whose drag orbits.
    pub drag_buttons: Vec<MouseButton>,
}

impl OrbitCamera {
    /// Looking at `focus` from `distance` away, from the south-east and a
    /// little above; zoom between a tenth and five times the distance;
    /// WASD/QE move; a middle-button drag orbits.
    #[must_use]
    pub fn new(focus: Vec3, distance: f32) -> Self {
        Self {
            focus,
            yaw: 0.9,
            pitch: 0.55,
            distance,
            min_distance: 0.1 * distance,
            max_distance: 5.0 * distance,
            move_keys: true,
            drag_buttons: vec![MouseButton::Middle],
        }
    }

    /// The same camera seen from `yaw` and `pitch`.
    #[must_use]
    pub fn with_angles(mut self, yaw: f32, pitch: f32) -> Self {
        self.yaw = yaw;
        self.pitch = pitch;
        self
    }

    /// The same camera orbiting on a drag of any of `buttons`.
    #[must_use]
    pub fn with_drag(mut self, buttons: impl IntoIterator<Item = MouseButton>) -> Self {
        self.drag_buttons = buttons.into_iter().collect();
        self
    }

    /// The camera's transform now.
    #[must_use]
    pub fn transform(&self) -> Transform {
        let offset = Vec3::new(
            self.yaw.cos() * self.pitch.cos(),
            self.pitch.sin(),
            self.yaw.sin() * self.pitch.cos(),
        ) * self.distance;
        Transform::from_translation(self.focus + offset).looking_at(self.focus, Vec3::Y)
    }
}

/// The controls of the orbit cameras, for the help overlays.
pub const ORBIT_HELP: &str = "arrows or drag orbit | wheel zoom";

fn orbit_cameras(
    time: Res<Time>,
    keys: Res<ButtonInput<KeyCode>>,
    buttons: Res<ButtonInput<MouseButton>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    mut cameras: Query<(&mut OrbitCamera, &mut Transform)>,
) {
    let dt = time.delta_secs();
    let key = |k: KeyCode| if keys.pressed(k) { 1.0 } else { 0.0 };
    for (mut orbit, mut transform) in &mut cameras {
        orbit.yaw += (key(KeyCode::ArrowLeft) - key(KeyCode::ArrowRight)) * 1.5 * dt;
        orbit.pitch += (key(KeyCode::ArrowUp) - key(KeyCode::ArrowDown)) * dt;
        if orbit.drag_buttons.iter().any(|&b| buttons.pressed(b)) {
            orbit.yaw -= motion.delta.x * 0.005;
            orbit.pitch += motion.delta.y * 0.005;
        }
        orbit.pitch = orbit.pitch.clamp(0.05, 1.5);
        orbit.distance = (orbit.distance * (1.0 - 0.1 * scroll.delta.y)).clamp(
            orbit.min_distance,
            orbit.max_distance.max(orbit.min_distance),
        );
        if orbit.move_keys {
            let forward = Vec3::new(-orbit.yaw.cos(), 0.0, -orbit.yaw.sin());
            let right = Vec3::new(-forward.z, 0.0, forward.x);
            let step = forward * (key(KeyCode::KeyW) - key(KeyCode::KeyS))
                + right * (key(KeyCode::KeyD) - key(KeyCode::KeyA))
                + Vec3::Y * (key(KeyCode::KeyE) - key(KeyCode::KeyQ));
            let speed = 0.5 * orbit.distance * dt;
            orbit.focus += step * speed;
        }
        *transform = orbit.transform();
    }
}

/// Marks the text of an overlay.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Default)]
pub struct Overlay;

/// A block of text in the top-left corner, marked [`Overlay`]: spawn it and
/// write its `Text` each frame.
#[must_use]
pub fn overlay_text() -> impl Bundle {
    (
        Text::new(""),
        TextFont {
            font_size: FontSize::Px(15.0),
            ..default()
        },
        Node {
            position_type: PositionType::Absolute,
            top: px(10),
            left: px(12),
            ..default()
        },
        Overlay,
    )
}

/// The terrain under the mouse cursor, seen through the first
/// [`OrbitCamera`].
#[derive(SystemParam)]
pub struct CursorPick<'w, 's> {
    windows: Query<'w, 's, &'static Window>,
    cameras: Query<'w, 's, (&'static Camera, &'static GlobalTransform), With<OrbitCamera>>,
    terrains: Query<'w, 's, (Entity, &'static Terrain, &'static GlobalTransform)>,
}

impl CursorPick<'_, '_> {
    /// The ray under the cursor, in world space.
    #[must_use]
    pub fn ray(&self) -> Option<Ray3d> {
        let cursor = self.windows.iter().find_map(Window::cursor_position)?;
        let (camera, transform) = self.cameras.iter().next()?;
        camera.viewport_to_world(transform, cursor).ok()
    }

    /// The nearest terrain hit under the cursor within `max_distance`: the
    /// terrain entity and the hit in its local frame.
    #[must_use]
    pub fn terrain_hit(&self, max_distance: f32) -> Option<(Entity, TerrainHit)> {
        let ray = self.ray()?;
        self.terrains
            .iter()
            .filter_map(|(entity, terrain, transform)| {
                let to_local = transform.affine().inverse();
                let origin = to_local.transform_point3(ray.origin);
                let direction = Dir3::new(to_local.transform_vector3(*ray.direction)).ok()?;
                let hit = terrain.ray_cast(Ray3d::new(origin, direction), max_distance)?;
                Some((hit.distance, entity, hit))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, entity, hit)| (entity, hit))
    }
}

/// A crater: a dodecahedron of circumradius `radius` at `centre`, turned
/// differently for each `count` so that neighbouring craters differ.
#[must_use]
pub fn blast(centre: Vec3, radius: f32, count: usize) -> CarveTool {
    let turn = Quat::from_euler(EulerRot::YXZ, 0.9 * count as f32, 0.4, 0.3 * count as f32);
    CarveTool::new(
        CarveShape::Dodecahedron { radius },
        Transform::from_translation(centre).with_rotation(turn),
    )
}

/// Mouse carving: with this resource present, [`ViewerPlugin`] blasts a
/// crater ([`blast`]) where a left click hits a terrain, heaps up material
/// where a right click hits, undoes the last carve on `undo_key` and redoes
/// the last undone one on `redo_key`.
#[derive(Resource, Reflect, Clone, Debug)]
#[reflect(Resource)]
pub struct ClickCarving {
    /// Circumradius of a crater.
    pub blast_radius: f32,
    /// Radius of a heap (a sphere, `CarveTool::sphere`, sunk a little into
    /// the surface).
    pub heap_radius: f32,
    /// The material of heaps.
    pub heap_label: Label,
    /// Farthest hit.
    pub reach: f32,
    /// The undo key, if any.
    pub undo_key: Option<KeyCode>,
    /// The redo key, if any ([`RedoCarve`]).
    pub redo_key: Option<KeyCode>,
}

/// The controls of [`ClickCarving`], for the help overlays.
pub const CARVING_HELP: &str = "LMB blast crater | RMB heap material | Z undo | Y redo";

fn click_carving(
    settings: Res<ClickCarving>,
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    pick: CursorPick,
    terrains: Query<(Entity, &Terrain)>,
    mut carves: MessageWriter<Carve>,
    mut undo: MessageWriter<UndoCarve>,
    mut redo: MessageWriter<RedoCarve>,
) {
    if settings.undo_key.is_some_and(|k| keys.just_pressed(k)) {
        for (terrain, _) in &terrains {
            undo.write(UndoCarve { terrain });
        }
    }
    if settings.redo_key.is_some_and(|k| keys.just_pressed(k)) {
        for (terrain, _) in &terrains {
            redo.write(RedoCarve { terrain });
        }
    }
    let left = buttons.just_pressed(MouseButton::Left);
    let right = buttons.just_pressed(MouseButton::Right);
    if !(left || right) {
        return;
    }
    let Some((entity, hit)) = pick.terrain_hit(settings.reach) else {
        return;
    };
    let Ok((_, terrain)) = terrains.get(entity) else {
        return;
    };
    let (tool, edit) = if left {
        (
            blast(hit.point, settings.blast_radius, terrain.journal().len()),
            Edit::Subtract,
        )
    } else {
        let centre = hit.point + hit.normal * (0.6 * settings.heap_radius);
        (
            CarveTool::sphere(settings.heap_radius, centre),
            Edit::Add(settings.heap_label),
        )
    };
    carves.write(Carve {
        terrain: entity,
        tool,
        edit,
    });
}
