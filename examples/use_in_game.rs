//! bevy_chisel in a game: a terrain, a crater on every left click, a log
//! of the cells that changed, and a quadric CSG prop standing on it.
use bevy::prelude::*;
use bevy_chisel::prelude::*;

fn main() {
    App::new()
        .add_plugins((DefaultPlugins, ChiselPlugins, game))
        .run();
}

/// The game's systems, as a plugin function.
pub fn game(app: &mut App) {
    app.add_systems(Startup, setup).add_systems(
        Update,
        (
            blast_on_click.before(TerrainSystems::Carve),
            log_changed_cells.after(TerrainSystems::Mesh),
        ),
    );
}

fn setup(mut commands: Commands, assets: Res<AssetServer>) -> Result {
    // 40 m × 8 m × 40 m of rock (label 1) on a 1 mm grid, its top at y = 0.
    let grid = Quantization::new(0.001, [0.0; 3])?;
    let min = Vec3::new(-20.0, -8.0, -20.0);
    let terrain = commands
        .spawn(Terrain::from_box(grid, min, Vec3::new(20.0, 0.0, 20.0), 1)?)
        .id();
    // A first crater; carves run on the async compute pool.
    commands.write_message(Carve {
        terrain,
        tool: CarveTool::dodecahedron(3.0, Vec3::ZERO),
        edit: Edit::Subtract,
    });
    // A prop: the scene is a 100-unit cube cut by a sphere and three
    // bores; scaled to 1 m, it stands on the ground at x = 8 m.
    commands.spawn((
        QuadricProp {
            scene: assets.load("scenes/classic.quadric.ron"),
            bounds: Some(PropBounds {
                centre: Vec3::ZERO,
                radius: 90.0,
            }),
            radius: SplatRadius::default(),
        },
        Transform::from_xyz(8.0, 0.5, 0.0).with_scale(Vec3::splat(0.01)),
    ));
    commands.spawn((
        Camera3d::default(),
        Transform::from_xyz(0.0, 18.0, 30.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.spawn((
        DirectionalLight::default(),
        Transform::from_xyz(4.0, 10.0, 6.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    Ok(())
}

/// A crater where the cursor ray meets the terrain.
fn blast_on_click(
    buttons: Res<ButtonInput<MouseButton>>,
    windows: Query<&Window>,
    cameras: Query<(&Camera, &GlobalTransform)>,
    terrains: Query<(Entity, &Terrain, &GlobalTransform)>,
    mut carves: MessageWriter<Carve>,
) {
    if !buttons.just_pressed(MouseButton::Left) {
        return;
    }
    let Some(cursor) = windows.iter().find_map(Window::cursor_position) else {
        return;
    };
    let Some(ray) = cameras
        .iter()
        .find_map(|(camera, eye)| camera.viewport_to_world(eye, cursor).ok())
    else {
        return;
    };
    for (entity, terrain, place) in &terrains {
        // Rays and tools are in the terrain's local frame.
        let to_local = place.affine().inverse();
        let Ok(direction) = Dir3::new(to_local.transform_vector3(*ray.direction)) else {
            continue;
        };
        let local = Ray3d::new(to_local.transform_point3(ray.origin), direction);
        if let Some(hit) = terrain.ray_cast(local, 200.0) {
            carves.write(Carve {
                terrain: entity,
                tool: CarveTool::dodecahedron(2.0, hit.point),
                edit: Edit::Subtract,
            });
        }
    }
}

/// Only the cells a carve reached are re-meshed; each one is reported.
fn log_changed_cells(mut changed: MessageReader<TerrainCellChanged>) {
    for cell in changed.read() {
        debug!("cell {:?}: {} meshes", cell.key, cell.entities.len());
    }
}
