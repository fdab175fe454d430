//! A player's app: the world streamed around its camera, physics for what
//! falls, mouse and keyboard or a script, and the HUD.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use avian3d::prelude::PhysicsPlugins;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::net::{
    NetClientPlugin, NetClientStats, NetServerPlugin, NetServerStats, NetWorld,
    NetWorldCarveRequest, WireTool,
};
use bevy_chisel::presentation::{HoldCaptures, Presentation};
use bevy_chisel::terrain::avian::TerrainAvianPlugin;
use bevy_chisel::terrain::{
    CarveTool, DebrisDetached, Terrain, TerrainFocus, TerrainMaterials, TerrainPlugin,
    TerrainSurface, TerrainSystems, TerrainWorld, TriplanarMaterial, TriplanarMaterialPlugin,
    WorldChunk, surface_table,
};
use bevy_chisel::viewer::{
    CursorPick, ORBIT_HELP, OrbitCamera, Overlay, ViewerPlugin, blast, overlay_text,
};

use super::headless::{ServerState, connect_when_drawn, release_captures, stop_when_disconnected};
use super::{
    BLAST_RADIUS, CAMERA_DISTANCE, CAMERA_PITCH, CRATERS, DIRT, GRASS, HEAP_RADIUS, ROCK, SITE,
    bridge, new_world, on_ground, settled,
};

/// What a player does, sees and waits for.
#[derive(Resource)]
pub struct Player {
    /// What a scripted player sends; `None` for a mouse player.
    pub script: Option<Script>,
    /// Requests sent.
    pub sent: u64,
    /// Pieces seen cut loose, and the first one's height when it was.
    pub fallen: usize,
    pub deck: Option<(Entity, f32)>,
    /// The headless run's checking player: the server's state.
    pub check: Option<Arc<Mutex<Option<ServerState>>>>,
    /// Frames since the check passed.
    pub checked: Option<u32>,
    /// Headless: set by the watching player once it joined the world, and
    /// waited for by the scripted ones, so that it sees the carves happen
    /// rather than receiving them in its snapshot.
    pub watching: Option<Arc<AtomicBool>>,
}

#[derive(Clone, Copy)]
pub enum Script {
    /// Blasts [`CRATERS`] craters across the border along z = 4 m.
    Craters,
    /// Builds and cuts the bridge at [`SITE`].
    Bridge,
}

impl Player {
    pub fn new(script: Option<Script>, check: Option<Arc<Mutex<Option<ServerState>>>>) -> Self {
        Self {
            watching: None,
            script,
            sent: 0,
            fallen: 0,
            deck: None,
            check,
            checked: None,
        }
    }
}

/// The networked world of a player's app, streamed `load_radius` around
/// its focus, with the materials for its chunks.
pub fn spawn_world(app: &mut App, load_radius: f32) -> Result<(), BevyError> {
    let world = new_world(load_radius)?;
    let mut materials = app.world_mut().resource_mut::<Assets<TriplanarMaterial>>();
    let table = surface_table(
        &mut materials,
        [
            (ROCK, TerrainSurface::Rock),
            (DIRT, TerrainSurface::Dirt),
            (GRASS, TerrainSurface::Grass),
        ],
        TerrainSurface::Rock,
    );
    app.insert_resource(Palette(table.clone()));
    app.world_mut()
        .spawn((world, NetWorld(1), table, Name::new("world")));
    Ok(())
}

/// The world's material table, for every chunk.
#[derive(Resource)]
pub struct Palette(TerrainMaterials<TriplanarMaterial>);

pub fn give_chunks_materials(
    add: On<Add, WorldChunk>,
    palette: Res<Palette>,
    mut commands: Commands,
) {
    commands.entity(add.entity).insert(palette.0.clone());
}

/// A player's app with a window or offscreen target: the world, physics
/// for what falls, both networking plugins (the role is picked by what is
/// started: a server or a connection) and an orbit camera over `look_at`
/// that streams the chunks around it.
pub fn player_app(
    presentation: Presentation,
    player: Player,
    look_at: Vec3,
) -> Result<App, BevyError> {
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — multiplayer world");
    app.add_plugins((
        TerrainPlugin,
        TriplanarMaterialPlugin,
        PhysicsPlugins::default(),
        TerrainAvianPlugin::default(),
        ViewerPlugin,
        NetServerPlugin,
        NetClientPlugin,
    ))
    .insert_resource(ClearColor(Color::srgb(0.53, 0.68, 0.84)))
    .insert_resource(player)
    .add_observer(give_chunks_materials)
    .add_systems(
        Update,
        (
            (click, scripted).before(TerrainSystems::Carve),
            (watch_debris, hud).after(TerrainSystems::Mesh),
        ),
    );
    spawn_world(&mut app, if headless { 16.0 } else { 45.0 })?;
    // In Startup: a headless run points cameras at its offscreen image,
    // made in PreStartup.
    app.add_systems(Startup, move |commands: Commands| {
        spawn_view(commands, look_at)
    });
    if headless {
        app.insert_resource(HoldCaptures(true)).add_systems(
            Update,
            (
                release_captures.after(TerrainSystems::Mesh),
                connect_when_drawn.after(TerrainSystems::Mesh),
                stop_when_disconnected,
            ),
        );
    }
    app.add_systems(PostUpdate, follow_orbit);
    Ok(app)
}

/// The light, the orbit camera over `look_at`, the streaming focus and the
/// HUD.
pub fn spawn_view(mut commands: Commands, look_at: Vec3) {
    commands.spawn((
        DirectionalLight {
            illuminance: 11_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(12.0, 25.0, 8.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.insert_resource(GlobalAmbientLight {
        brightness: 400.0,
        ..default()
    });
    commands.spawn(OrbitCamera {
        min_distance: 4.0,
        max_distance: 120.0,
        ..OrbitCamera::new(look_at, CAMERA_DISTANCE).with_angles(1.35, CAMERA_PITCH)
    });
    commands.spawn((Focus, Transform::from_translation(look_at)));
    commands.spawn(overlay_text());
}

/// The point the chunks stream around: the point the orbit camera looks
/// at (WASD moves it).
#[derive(Component)]
#[require(TerrainFocus)]
pub struct Focus;

pub fn follow_orbit(
    cameras: Query<&OrbitCamera>,
    mut focus: Query<&mut Transform, (With<Focus>, Without<OrbitCamera>)>,
) {
    if let (Ok(orbit), Ok(mut transform)) = (cameras.single(), focus.single_mut()) {
        transform.translation = orbit.focus;
    }
}

/// The world entity of a player's app.
pub fn world_entity(worlds: &Query<Entity, With<NetWorld>>) -> Option<Entity> {
    worlds.single().ok()
}

pub fn request(
    requests: &mut MessageWriter<NetWorldCarveRequest>,
    player: &mut Player,
    world: Entity,
    tool: &CarveTool,
    edit: Edit,
) {
    player.sent += 1;
    requests.write(NetWorldCarveRequest {
        request: player.sent,
        world,
        tool: WireTool::from(tool),
        edit,
    });
}

/// Left click: a crater; right click: a heap of dirt; `B`: a bridge at
/// the cursor, knocked down. All are requests to the server, which sends
/// them back to everyone in its order.
pub fn click(
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    pick: CursorPick,
    worlds: Query<Entity, With<NetWorld>>,
    mut player: ResMut<Player>,
    mut requests: MessageWriter<NetWorldCarveRequest>,
) {
    let left = buttons.just_pressed(MouseButton::Left);
    let right = buttons.just_pressed(MouseButton::Right);
    let build = keys.just_pressed(KeyCode::KeyB);
    if !(left || right || build) || player.script.is_some() {
        return;
    }
    let (Some(world), Some(ray), Some((_, hit))) =
        (world_entity(&worlds), pick.ray(), pick.terrain_hit(300.0))
    else {
        return;
    };
    // The world sits at the origin, unscaled: world space is its frame.
    let point = ray.get_point(hit.distance);
    let normal = hit.normal;
    if build {
        for (tool, edit) in bridge(point.x, point.z) {
            request(&mut requests, &mut player, world, &tool, edit);
        }
    } else if left {
        let tool = blast(point, BLAST_RADIUS, player.sent as usize);
        request(&mut requests, &mut player, world, &tool, Edit::Subtract);
    } else {
        let tool = CarveTool::dodecahedron(HEAP_RADIUS, point + normal * (0.6 * HEAP_RADIUS));
        request(&mut requests, &mut player, world, &tool, Edit::Add(DIRT));
    }
}

/// A scripted player sends its carves once its world has streamed in.
pub fn scripted(
    worlds: Query<(Entity, &TerrainWorld), With<NetWorld>>,
    terrains: Query<&Terrain>,
    mut player: ResMut<Player>,
    mut requests: MessageWriter<NetWorldCarveRequest>,
) {
    let Some(script) = player.script else {
        return;
    };
    let Ok((entity, world)) = worlds.single() else {
        return;
    };
    let idle = |e: Entity| terrains.get(e).is_ok_and(Terrain::is_idle);
    let watched = (player.watching.as_ref()).is_none_or(|w| w.load(Ordering::Relaxed));
    if player.sent > 0 || !watched || world.live_chunks().count() == 0 || !settled(world, idle) {
        return;
    }
    match script {
        Script::Craters => {
            for k in 0..CRATERS {
                let at = on_ground(Vec2::new(12.5 + 3.0 * k as f32, 4.0), 0.3);
                request(
                    &mut requests,
                    &mut player,
                    entity,
                    &blast(at, BLAST_RADIUS, k),
                    Edit::Subtract,
                );
            }
        }
        Script::Bridge => {
            for (tool, edit) in bridge(SITE.x, SITE.y) {
                request(&mut requests, &mut player, entity, &tool, edit);
            }
        }
    }
}

/// Counts the pieces cut loose, and notes where the first one was.
pub fn watch_debris(
    mut detached: MessageReader<DebrisDetached>,
    chunks: Query<&GlobalTransform, With<Terrain>>,
    mut player: ResMut<Player>,
) {
    for piece in detached.read() {
        player.fallen += 1;
        if player.deck.is_none()
            && let Ok(chunk) = chunks.get(piece.terrain)
        {
            player.deck = Some((piece.entity, chunk.transform_point(piece.centre).y));
        }
    }
}

pub fn hud(
    player: Res<Player>,
    client: Res<NetClientStats>,
    served: Res<NetServerStats>,
    worlds: Query<&TerrainWorld, With<NetWorld>>,
    terrains: Query<&Terrain>,
    mut text: Query<&mut Text, With<Overlay>>,
) {
    let (Ok(world), Ok(mut text)) = (worlds.single(), text.single_mut()) else {
        return;
    };
    // Counted, not hashed: a world hash would decode every stored chunk
    // each frame (the hash checks compare it with the server's).
    let live_edited = (world.live_chunks())
        .filter(|(coord, e)| {
            terrains
                .get(*e)
                .is_ok_and(|t| world.chunk_edited(*coord, t))
        })
        .count();
    let stats = world.stats();
    let role = if served.accepted > 0 {
        format!(
            "hosting: {} carves ordered, {} refused",
            served.accepted, served.rejected
        )
    } else {
        format!(
            "hash checks passed: {}, resyncs: {}",
            client.checks_passed, client.desyncs
        )
    };
    text.0 = format!(
        "multiplayer world | edited chunks: {live_edited} live, {} stored | {} live, {} building\n\
         {role} | pieces cut loose: {}\n\
         LMB blast | RMB heap dirt | B bridge, knocked down | {ORBIT_HELP}",
        stats.stored, stats.live, stats.building, player.fallen,
    );
}
