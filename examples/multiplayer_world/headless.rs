//! The one-process headless run: a dedicated server and two scripted
//! players in threads, and a third player rendering offscreen who checks
//! the outcome against the server's state.

use std::collections::BTreeMap;
use std::net::{Ipv4Addr, SocketAddr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::Duration;

use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy_chisel::net::{
    NetClientPlugin, NetServerStats, NetWorld, WorldSynced, start_client, start_server,
    world_state_hash,
};
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::terrain::{
    CellOutput, ChunkCoord, Terrain, TerrainDebris, TerrainFocus, TerrainPlugin, TerrainSettings,
    TerrainSystems, TerrainWorld,
};
use bevy_replicon_renet::RenetClient;

use super::player::{Player, Script, player_app, scripted};
use super::{
    CARVES, FALL_FRAMES, FAR, SITE, edited_chunks, fail, new_world, on_ground, server_app, settled,
};

/// The server's world once settled, as the headless run's checking
/// player sees it.
pub struct ServerState {
    accepted: u64,
    /// Pieces the server's debris pass cut loose across chunk borders.
    detached: u64,
    chunks: BTreeMap<ChunkCoord, (Vec<u8>, u64)>,
}

/// The server's state, published after each settled frame that changed.
pub fn publish(app: &mut App, out: &Mutex<Option<ServerState>>) {
    let world = app.world_mut();
    let accepted = world.resource::<NetServerStats>().accepted;
    let mut worlds = world.query::<&TerrainWorld>();
    let Ok(terrain_world) = worlds.single(world) else {
        return;
    };
    let idle = |e: Entity| world.get::<Terrain>(e).is_some_and(Terrain::is_idle);
    if !settled(terrain_world, idle) {
        return;
    }
    let detached = terrain_world.stats().detached_across;
    let Ok(mut state) = out.lock() else {
        return;
    };
    if state
        .as_ref()
        .is_some_and(|s| s.accepted == accepted && s.detached == detached)
    {
        return;
    }
    let chunks = edited_chunks(terrain_world, |e| world.get::<Terrain>(e));
    *state = Some(ServerState {
        accepted,
        detached,
        chunks,
    });
}

/// Headless: once the server is settled after every carve, checks that
/// this player holds every edited chunk as the server does, then waits
/// for the deck to land before the captures.
pub fn release_captures(
    mut player: ResMut<Player>,
    mut hold: ResMut<HoldCaptures>,
    worlds: Query<&TerrainWorld, With<NetWorld>>,
    terrains: Query<&Terrain>,
    debris: Query<&GlobalTransform, With<TerrainDebris>>,
    mut exit: MessageWriter<AppExit>,
    mut synced: MessageReader<WorldSynced>,
) {
    if synced.read().count() > 0
        && let Some(watching) = &player.watching
    {
        watching.store(true, Ordering::Relaxed);
    }
    if !hold.0 {
        return;
    }
    if player.checked.is_none() {
        let Ok(world) = worlds.single() else {
            return;
        };
        let idle = |e: Entity| terrains.get(e).is_ok_and(Terrain::is_idle);
        if !settled(world, idle) {
            return;
        }
        let Some(check) = &player.check else {
            return;
        };
        let Ok(server) = check.lock() else {
            return;
        };
        let Some(state) = server.as_ref() else {
            return;
        };
        if state.accepted < CARVES || state.detached == 0 {
            return;
        }
        let mine = edited_chunks(world, |e| terrains.get(e).ok());
        if mine != state.chunks {
            return;
        }
        let hash = world_state_hash(mine.iter().map(|(c, (_, h))| (*c, *h)));
        println!(
            "all {CARVES} carves and {} detach across a chunk border applied; {} edited chunks \
             identical to the server's (world hash {hash:016x})",
            state.detached,
            mine.len()
        );
        drop(server);
        player.checked = Some(0);
    }
    // The deck fell: its centre is a metre below where it hung.
    let waited = player.checked.map_or(0, |frames| frames + 1);
    player.checked = Some(waited);
    let Some((deck, hung_at)) = player.deck else {
        return;
    };
    if waited > FALL_FRAMES {
        eprintln!("multiplayer_world: the deck did not fall within {FALL_FRAMES} frames");
        exit.write(AppExit::error());
        return;
    }
    if let Ok(transform) = debris.get(deck)
        && transform.translation().y < hung_at - 1.0
    {
        println!(
            "the deck fell {:.1} m across the chunk border",
            hung_at - transform.translation().y
        );
        hold.0 = false;
    }
}

/// Headless: where the watching player connects once its world is drawn.
#[derive(Resource)]
pub struct ConnectWhenDrawn {
    addr: SocketAddr,
    id: u64,
    /// Frames drawn with the world streamed in.
    drawn: u32,
}

/// Connects once the world around the camera has streamed in and a few
/// frames are drawn: the first frames of a software renderer (its
/// pipelines compiled) can take longer than the connection's 15 s
/// timeout.
pub fn connect_when_drawn(world: &mut World) {
    let streamed = {
        let mut worlds = world.query_filtered::<&TerrainWorld, With<NetWorld>>();
        worlds.single(world).is_ok_and(|w| {
            w.live_chunks().count() > 0
                && settled(w, |e| world.get::<Terrain>(e).is_some_and(Terrain::is_idle))
        })
    };
    let Some(mut connect) = world.get_resource_mut::<ConnectWhenDrawn>() else {
        return;
    };
    if streamed {
        connect.drawn += 1;
    }
    if connect.drawn < 5 {
        return;
    }
    let (addr, id) = (connect.addr, connect.id);
    world.remove_resource::<ConnectWhenDrawn>();
    if let Err(e) = start_client(world, addr, id) {
        eprintln!("multiplayer_world: cannot connect: {e}");
        world.write_message(AppExit::error());
    }
}

/// A headless player that lost its connection fails the run at once.
pub fn stop_when_disconnected(client: Option<Res<RenetClient>>, mut exit: MessageWriter<AppExit>) {
    if client.is_some_and(|c| c.is_disconnected()) {
        eprintln!("multiplayer_world: the watching player lost its connection");
        exit.write(AppExit::error());
    }
}

/// A scripted player without a renderer, in a thread, until `stop`.
pub fn scripted_player(
    addr: SocketAddr,
    id: u64,
    (script, camera): (Script, Vec2),
    watching: Arc<AtomicBool>,
    stop: &AtomicBool,
) {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin::default(),
        TransformPlugin,
        TerrainPlugin,
        NetClientPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    .insert_resource(TerrainSettings {
        output: CellOutput::Nothing,
        ..TerrainSettings::default()
    })
    .insert_resource(Player {
        watching: Some(watching),
        ..Player::new(Some(script), None)
    })
    .add_systems(Update, scripted.before(TerrainSystems::Carve));
    let Ok(world) = new_world(24.0) else {
        return;
    };
    app.world_mut().spawn((world, NetWorld(1)));
    app.world_mut().spawn((
        TerrainFocus,
        Transform::from_translation(on_ground(camera, 10.0)),
    ));
    app.finish();
    app.cleanup();
    if start_client(app.world_mut(), addr, id).is_ok() {
        while !stop.load(Ordering::Relaxed) {
            app.update();
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

/// One process: a dedicated server and two scripted players in threads,
/// and the checking player rendering offscreen in the main thread.
pub fn run_headless(config: HeadlessConfig) -> AppExit {
    let stop = Arc::new(AtomicBool::new(false));
    let watching = Arc::new(AtomicBool::new(false));
    let server_state: Arc<Mutex<Option<ServerState>>> = Arc::default();
    let (tx, rx) = mpsc::channel();
    let mut threads = Vec::new();
    {
        let (stop, state) = (stop.clone(), server_state.clone());
        threads.push(std::thread::spawn(move || {
            let mut app = match server_app(None) {
                Ok(app) => app,
                Err(e) => {
                    let _ = tx.send(Err(e.to_string()));
                    return;
                }
            };
            let bound = start_server(app.world_mut(), (Ipv4Addr::LOCALHOST, 0).into(), 8);
            let _ = tx.send(bound.map_err(|e| e.to_string()));
            while !stop.load(Ordering::Relaxed) {
                app.update();
                publish(&mut app, &state);
                std::thread::sleep(Duration::from_millis(2));
            }
        }));
    }
    let addr = match rx.recv() {
        Ok(Ok(addr)) => addr,
        Ok(Err(e)) => return fail(&format!("server: {e}")),
        Err(e) => return fail(&format!("server thread: {e}")),
    };
    for (id, script, camera) in [(100, Script::Craters, SITE), (101, Script::Bridge, FAR)] {
        let (stop, watching) = (stop.clone(), watching.clone());
        threads.push(std::thread::spawn(move || {
            scripted_player(addr, id, (script, camera), watching, &stop);
        }));
    }
    let presentation = Presentation::Headless(HeadlessConfig {
        capture_frames: vec![4],
        max_frames: 4000,
        min_foreground: 0.3,
        ..config
    });
    let exit = match player_app(
        presentation,
        Player {
            watching: Some(watching),
            ..Player::new(None, Some(server_state))
        },
        on_ground(SITE + Vec2::new(2.0, -2.0), 0.0),
    ) {
        Ok(mut app) => {
            app.insert_resource(ConnectWhenDrawn {
                addr,
                id: 102,
                drawn: 0,
            });
            app.run()
        }
        Err(e) => fail(&format!("world: {e}")),
    };
    stop.store(true, Ordering::Relaxed);
    for thread in threads {
        let _ = thread.join();
    }
    exit
}
