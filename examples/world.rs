//! A streamed world: a camera flies over a procedural landscape at 10 m/s,
//! blasting a crater every few metres; terrain chunks stream in ahead of
//! it (built on the async compute pool, nearest first) and out behind it,
//! and the chunks it carved are kept and come back exactly as left.
//! Beyond the full-detail chunks, coarse chunks reach to the horizon, each
//! at the coarsest level whose error stays under 2 pixels.
//!
//! The landscape is integer value noise on a 1 cm grid (exact and the
//! same on every machine); the chunks are 20.48 m cubes, each an ordinary
//! destructible terrain. The HUD shows the chunk counts and build times.
//!
//! `U` takes the last crater back, in every chunk it reached, and `R` puts
//! it back again. `F5` saves the world's edited chunks in the background
//! (`SaveWorld`: only the chunks changed since the last save are written,
//! off the main thread),
//! a window autosaves every 30 s, and `F9` loads the last save (the world
//! entity is spawned again and its chunks stream in from the files).
//!
//! Runs in a window when a display exists; otherwise renders headless,
//! streams within smaller radii, flies a fixed 12 m path and writes PNG
//! screenshots to `screenshots/` (about 30 s on two cores); on the way it
//! saves the world to a temporary folder and reads the save back, and
//! fails unless every chunk edited at the save is in it. Headless with
//! `-- --horizon`, it keeps the window's radii (coarse chunks to 320 m)
//! and its camera draws only a few frames: three once the world first
//! settles (so that every pipeline is ready) and the one it captures, so
//! that a software renderer can take the picture of the README
//! (`screenshots/world-0012.png`; a few minutes on two cores).
//!
//! `cargo run --release --all-features --example world`

use std::path::PathBuf;
use std::time::Duration;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::terrain::{
    LodSettings, NoiseOctave, SaveWorld, StreamSettings, Terrain, TerrainError, TerrainFocus,
    TerrainMaterials, TerrainPlugin, TerrainSurface, TerrainSystems, TerrainWorld,
    TriplanarMaterial, TriplanarMaterialPlugin, ValueNoise, WorldCarve, WorldChunk, WorldLayout,
    WorldLod, WorldRedo, WorldRedoRejected, WorldRedone, WorldSaveFailed, WorldSaved, WorldSource,
    WorldUndo, WorldUndoRejected, WorldUndone, surface_table,
};
use bevy_chisel::viewer::{Overlay, blast, overlay_text};

const ROCK: u8 = 1;
const DIRT: u8 = 2;
const GRASS: u8 = 3;

/// Grid unit (m).
const UNIT: f64 = 0.01;
/// Chunk edge 2^11 cm = 20.48 m; samples 2^7 cm = 1.28 m apart.
const CHUNK_LOG2: u8 = 11;
const SPACING_LOG2: u8 = 7;
/// Flying speed (m/s) and height above the ground (m).
const SPEED: f32 = 10.0;
const ALTITUDE: f32 = 14.0;
/// A crater every this many metres flown.
const CRATER_EVERY: f32 = 6.0;
const CRATER_RADIUS: f32 = 1.6;
/// Craters are blasted this far ahead of the camera (m), in its view: at
/// 14 m up, looking 40 m ahead with a 45° field of view, the ground shows
/// from about 16 m ahead on, so a crater stays in view for 12 m of flight.
const CRATER_AHEAD: f32 = 28.0;
/// Headless: the camera moves this far per counted frame.
const HEADLESS_STEP: f32 = 1.0;
/// Headless: the counted frames captured (the HUD's figures are logged
/// at the last), and the streaming radii (m), smaller than in a window so
/// that a run builds about a dozen chunks instead of thirty.
const HEADLESS_CAPTURES: [u32; 2] = [2, 12];
const HEADLESS_RADII: (f32, f32) = (16.0, 24.0);
/// How far coarse chunks reach (m), in a window and headless (a ring of
/// them past the full-detail chunks: on a software renderer each frame
/// with coarse terrain to the horizon takes seconds).
const FAR_RADIUS: f32 = 320.0;
const HEADLESS_FAR_RADIUS: f32 = 30.0;
/// Window radii (m): full-detail chunks stream in within the first and
/// out beyond the second.
const WINDOW_RADII: (f32, f32) = (30.0, 45.0);
/// Headless `--horizon`: frames the camera draws once the world first
/// settles, before any is counted, so that every pipeline is ready for
/// the capture.
const HORIZON_WARM_UP_FRAMES: u32 = 3;
/// A window autosaves this often.
const AUTOSAVE_EVERY: Duration = Duration::from_secs(30);
/// Headless: the counted frame that saves the world (between the two
/// captures, after a few craters); counting waits until it is written.
const HEADLESS_SAVE_FRAME: u32 = 8;

fn main() -> AppExit {
    let horizon = std::env::args().any(|a| a == "--horizon");
    let presentation = match Presentation::detect("world") {
        Presentation::Headless(config) => Presentation::Headless(HeadlessConfig {
            // The horizon's frames are slow on a software renderer: only
            // the last is captured.
            capture_frames: if horizon {
                vec![HEADLESS_CAPTURES[1]]
            } else {
                HEADLESS_CAPTURES.to_vec()
            },
            max_frames: 3000,
            // The terrain fills most of the view; sky alone fails.
            min_foreground: 0.3,
            ..config
        }),
        window => window,
    };
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — world");
    app.add_plugins((TerrainPlugin, TriplanarMaterialPlugin))
        .insert_resource(ClearColor(Color::srgb(0.53, 0.68, 0.84)))
        .insert_resource(Flight {
            headless,
            horizon: headless && horizon,
            ..default()
        })
        .insert_resource(Saves::new(headless))
        .add_systems(Startup, spawn_scene)
        .add_systems(
            Update,
            (
                (fly, undo_crater, save_and_load.after(fly)).before(TerrainSystems::Carve),
                update_hud.after(TerrainSystems::Mesh),
            ),
        )
        .add_observer(give_chunks_materials);
    if headless {
        app.insert_resource(HoldCaptures(true));
    }
    app.run()
}

/// The landscape: integer value noise, 1 m to about 9.2 m high, hills
/// about 30 m across with bumps of 8 m.
fn landscape() -> ValueNoise {
    ValueNoise {
        base: 100,
        octaves: vec![
            NoiseOctave {
                cell: 24,
                amplitude: 650,
                seed: 1,
            },
            NoiseOctave {
                cell: 6,
                amplitude: 180,
                seed: 2,
            },
        ],
    }
}

/// The ground's height (m) at the sample nearest `(x, z)`.
fn ground(x: f32, z: f32) -> f32 {
    let spacing = (1i64 << SPACING_LOG2) as f32 * UNIT as f32;
    let (i, j) = ((x / spacing).round() as i64, (z / spacing).round() as i64);
    landscape().height(i, j) as f32 * UNIT as f32
}

fn spawn_scene(
    mut commands: Commands,
    mut materials: ResMut<Assets<TriplanarMaterial>>,
    flight: Res<Flight>,
) -> Result {
    let table = surface_table(
        &mut materials,
        [
            (ROCK, TerrainSurface::Rock),
            (DIRT, TerrainSurface::Dirt),
            (GRASS, TerrainSurface::Grass),
        ],
        TerrainSurface::Rock,
    );
    commands.spawn(world_bundle(&flight, &table, None)?);
    commands.insert_resource(Palette(table));
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
    commands.spawn((
        Camera3d::default(),
        TerrainFocus,
        camera_at(0.0),
        Name::new("flying camera"),
    ));
    commands.spawn(overlay_text());
    Ok(())
}

/// The world's grid, chunks and layers.
fn layout() -> Result<WorldLayout, TerrainError> {
    Ok(WorldLayout {
        quantization: Quantization::new(UNIT, [0.0; 3])?,
        chunk_log2: CHUNK_LOG2,
        spacing_log2: SPACING_LOG2,
        floor: 0,
        label: ROCK,
        // Grass 25 cm deep over 1.2 m of dirt, in grid units.
        layers: vec![(120, DIRT), (25, GRASS)],
    })
}

/// The world with its coarse chunks, its edited chunks read from the save
/// in `edits` when given; the coarse chunks take the world entity's
/// material table.
fn world_bundle(
    flight: &Flight,
    table: &TerrainMaterials<TriplanarMaterial>,
    edits: Option<&PathBuf>,
) -> Result<impl Bundle> {
    let (load_radius, unload_radius) = if flight.headless && !flight.horizon {
        HEADLESS_RADII
    } else {
        WINDOW_RADII
    };
    let mut world = TerrainWorld::new(layout()?, landscape())?.with_streaming(StreamSettings {
        load_radius,
        unload_radius,
        max_building: 4,
    })?;
    if let Some(folder) = edits {
        world = world.load_edits(folder)?;
    }
    let lod = WorldLod::new(LodSettings {
        far_radius: if flight.headless && !flight.horizon {
            HEADLESS_FAR_RADIUS
        } else {
            FAR_RADIUS
        },
        ..default()
    })?;
    Ok((world, lod, table.clone(), Name::new("world")))
}

/// The camera `distance` metres along its path (+x), looking ahead and
/// down, the horizon in view.
fn camera_at(distance: f32) -> Transform {
    let (x, z) = (distance, 10.0);
    let eye = Vec3::new(x, ground(x, z) + ALTITUDE, z);
    Transform::from_translation(eye).looking_at(Vec3::new(x + 40.0, ground(x, z), z + 4.0), Vec3::Y)
}

/// The chunks' look: the world's material table on every chunk.
#[derive(Resource)]
struct Palette(TerrainMaterials<TriplanarMaterial>);

fn give_chunks_materials(add: On<Add, WorldChunk>, palette: Res<Palette>, mut commands: Commands) {
    commands.entity(add.entity).insert(palette.0.clone());
}

#[derive(Resource, Default)]
struct Flight {
    headless: bool,
    /// Headless with the window's radii, drawing only the warm-up frames
    /// and the captured one.
    horizon: bool,
    /// Headless `--horizon`: warm-up frames drawn so far.
    drawn: u32,
    distance: f32,
    next_crater: f32,
    craters: usize,
    /// Craters taken back with `U`.
    undone: usize,
    /// Craters put back with `R`.
    redone: usize,
    /// Headless: frames counted towards the captures.
    counted: u32,
}

/// Flies the camera and blasts a crater ahead of it every few metres. In
/// a headless run the camera moves a fixed step per frame, and only once
/// every chunk in reach is built and meshed (the captures wait as well);
/// with `--horizon` the camera draws only its warm-up frames and the
/// captured one.
fn fly(
    time: Res<Time>,
    mut flight: ResMut<Flight>,
    mut hold: Option<ResMut<HoldCaptures>>,
    worlds: Query<(Entity, &TerrainWorld, &WorldLod)>,
    terrains: Query<&Terrain>,
    mut camera: Query<(&mut Transform, &mut Camera), With<TerrainFocus>>,
    mut carves: MessageWriter<WorldCarve>,
    saves: Res<Saves>,
) -> Result {
    let Ok((world_entity, world, lod)) = worlds.single() else {
        return Ok(());
    };
    let step = if flight.headless {
        let settled = world.is_settled()
            && lod.is_settled()
            && world.live_chunks().count() > 0
            && world
                .live_chunks()
                .all(|(_, e)| terrains.get(e).is_ok_and(Terrain::is_idle))
            && !saves.pending;
        let warming_up = flight.horizon && flight.drawn < HORIZON_WARM_UP_FRAMES;
        if flight.horizon
            && let Ok((_, mut camera)) = camera.single_mut()
        {
            // Drawn: the warm-up frames, then only the captured one.
            let capture = flight.counted + 1 == HEADLESS_CAPTURES[1];
            camera.is_active = settled && (warming_up || capture);
            flight.drawn += u32::from(settled && warming_up);
        }
        if let Some(hold) = hold.as_mut() {
            hold.0 = !settled || warming_up;
        }
        if !settled || warming_up {
            debug!(
                "waiting: world settled {}, coarse {:?}, {} live",
                world.is_settled(),
                lod.stats(),
                world.live_chunks().count()
            );
            return Ok(());
        }
        flight.counted += 1;
        if flight.counted == HEADLESS_CAPTURES[1] {
            report(world, lod);
            saves.read_back()?;
        }
        HEADLESS_STEP
    } else {
        SPEED * time.delta_secs()
    };
    flight.distance += step;
    if let Ok((mut transform, _)) = camera.single_mut() {
        *transform = camera_at(flight.distance);
    }
    if flight.distance >= flight.next_crater {
        flight.next_crater = flight.distance + CRATER_EVERY;
        let (x, z) = (
            flight.distance + CRATER_AHEAD,
            10.0 + 3.0 * (flight.craters % 3) as f32 - 3.0,
        );
        carves.write(WorldCarve {
            world: world_entity,
            tool: blast(Vec3::new(x, ground(x, z), z), CRATER_RADIUS, flight.craters),
            edit: Edit::Subtract,
        });
        flight.craters += 1;
    }
    Ok(())
}

/// The world's saves: where, what was asked and answered.
#[derive(Resource)]
struct Saves {
    folder: PathBuf,
    /// Removed once read back (a headless run's temporary folder).
    temporary: bool,
    /// A save was asked for and is not answered yet.
    pending: bool,
    next_autosave: Duration,
    /// The answer to the last save that was written.
    last: Option<WorldSaved>,
    /// The last answer or load, for the HUD.
    message: String,
}

impl Saves {
    fn new(headless: bool) -> Self {
        let folder = if headless {
            std::env::temp_dir().join(format!("bevy_chisel-world-{}", std::process::id()))
        } else {
            std::env::temp_dir().join("bevy_chisel-world")
        };
        Self {
            folder,
            temporary: headless,
            pending: false,
            next_autosave: AUTOSAVE_EVERY,
            last: None,
            message: "nothing saved yet".to_owned(),
        }
    }

    /// Headless: reads the scripted save back into a fresh world, which
    /// must hold every chunk that was edited when the save was asked for.
    fn read_back(&self) -> Result {
        let saved = (self.last.as_ref()).ok_or("the scripted save was never written")?;
        let edited = saved.written.len() + saved.unchanged;
        let loaded = TerrainWorld::new(layout()?, landscape())?.load_edits(&self.folder)?;
        let read = loaded.stored_chunks().count();
        if saved.written.is_empty() || read != edited {
            return Err(format!(
                "save round trip: {} chunks written, {edited} edited, {read} read back",
                saved.written.len()
            )
            .into());
        }
        info!(
            "save round trip: {read} edited chunks, {} kB, read back from {}",
            saved.bytes / 1024,
            self.folder.display()
        );
        if self.temporary {
            std::fs::remove_dir_all(&self.folder)?;
        }
        Ok(())
    }
}

/// `F5` saves the world's edited chunks in the background and a window
/// autosaves every [`AUTOSAVE_EVERY`]; a headless run saves once, at
/// [`HEADLESS_SAVE_FRAME`]. `F9` spawns the world again from the last
/// save. Answers go to the HUD and the log.
fn save_and_load(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    time: Res<Time>,
    flight: Res<Flight>,
    palette: Res<Palette>,
    worlds: Query<Entity, With<TerrainWorld>>,
    mut saves: ResMut<Saves>,
    mut requests: MessageWriter<SaveWorld>,
    mut saved: MessageReader<WorldSaved>,
    mut failed: MessageReader<WorldSaveFailed>,
    mut commands: Commands,
) {
    for answer in saved.read() {
        saves.pending = false;
        saves.message = format!(
            "save: {} chunks written ({} kB), {} unchanged, {} carves in flight left out",
            answer.written.len(),
            answer.bytes / 1024,
            answer.unchanged,
            answer.left_out
        );
        info!("{} to {}", saves.message, answer.folder.display());
        saves.last = Some(answer.clone());
    }
    for failure in failed.read() {
        saves.pending = false;
        // A world with a world undo waiting for `max_save_wait` frames
        // (300 by default) is not saved: the next autosave tries again.
        // One carved in every frame saves the carves that landed.
        saves.message = format!("save failed: {}", failure.error);
        warn!("{}", saves.message);
    }
    let Ok(world) = worlds.single() else {
        return;
    };
    let pressed = |key| keys.as_ref().is_some_and(|k| k.just_pressed(key));
    let due = if flight.headless {
        flight.counted == HEADLESS_SAVE_FRAME && saves.last.is_none()
    } else {
        pressed(KeyCode::F5) || time.elapsed() >= saves.next_autosave
    };
    if due && !saves.pending {
        requests.write(SaveWorld {
            world,
            folder: saves.folder.clone(),
        });
        saves.pending = true;
        saves.next_autosave = time.elapsed() + AUTOSAVE_EVERY;
    }
    if pressed(KeyCode::F9) {
        match world_bundle(&flight, &palette.0, Some(&saves.folder)) {
            Ok(bundle) => {
                // The chunks are the world's children: they go with it.
                commands.entity(world).despawn();
                commands.spawn(bundle);
                saves.pending = false;
                saves.message = format!("loaded {}", saves.folder.display());
            }
            Err(error) => saves.message = format!("load failed: {error}"),
        }
        info!("{}", saves.message);
    }
}

/// `U` takes the last crater back in every chunk it reached
/// ([`WorldUndo`]), `R` puts the last one taken back there again
/// ([`WorldRedo`]); the answers are logged.
fn undo_crater(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    worlds: Query<Entity, With<TerrainWorld>>,
    mut flight: ResMut<Flight>,
    mut requests: (MessageWriter<WorldUndo>, MessageWriter<WorldRedo>),
    mut undone: (MessageReader<WorldUndone>, MessageReader<WorldRedone>),
    mut refused: (
        MessageReader<WorldUndoRejected>,
        MessageReader<WorldRedoRejected>,
    ),
) {
    if let (Some(keys), Ok(world)) = (keys, worlds.single()) {
        if keys.just_pressed(KeyCode::KeyU) {
            requests.0.write(WorldUndo { world });
        }
        if keys.just_pressed(KeyCode::KeyR) {
            requests.1.write(WorldRedo { world });
        }
    }
    for done in undone.0.read() {
        flight.undone += 1;
        info!("crater undone in chunks {:?}", done.chunks);
    }
    for done in undone.1.read() {
        flight.redone += 1;
        info!("crater redone in chunks {:?}", done.chunks);
    }
    for refusal in refused.0.read() {
        warn!("undo refused: {}", refusal.reason);
    }
    for refusal in refused.1.read() {
        warn!("redo refused: {}", refusal.reason);
    }
}

fn report(world: &TerrainWorld, lod: &WorldLod) {
    let l = lod.stats();
    info!(
        "coarse chunks: {} drawn (per level {:?}), {} triangles, {} kB of mesh data; {} built \
         ({} edited), {:.2} ms each on the pool",
        l.drawn_per_level.iter().sum::<usize>(),
        l.drawn_per_level,
        l.triangles,
        l.mesh_bytes / 1024,
        l.built_from_source + l.built_edited,
        l.built_edited,
        l.build_time.as_secs_f64() * 1e3 / (l.built_from_source + l.built_edited).max(1) as f64,
    );
    let s = world.stats();
    let built = s.generated + s.restored;
    info!(
        "world: {} chunks built ({} generated, {} restored), {:.1} ms each on the pool; \
         {} live, {} released, {} edited chunks stored in {} bytes",
        built,
        s.generated,
        s.restored,
        s.build_time.as_secs_f64() * 1e3 / built.max(1) as f64,
        s.live,
        s.released,
        s.stored,
        s.stored_bytes,
    );
}

fn update_hud(
    flight: Res<Flight>,
    saves: Res<Saves>,
    worlds: Query<(&TerrainWorld, &WorldLod)>,
    terrains: Query<&Terrain>,
    mut hud: Query<&mut Text, With<Overlay>>,
) {
    let Ok((world, lod)) = worlds.single() else {
        return;
    };
    let l = lod.stats();
    let s = world.stats();
    let built = (s.generated + s.restored).max(1);
    let triangles: usize = world
        .live_chunks()
        .filter_map(|(_, e)| terrains.get(e).ok())
        .map(Terrain::triangle_count)
        .sum();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let lines = [
        "bevy_chisel world: streamed exact terrain chunks".to_owned(),
        format!(
            "flown {:.0} m | craters {} ({} undone, {} redone; U undo, R redo) | triangles \
             {triangles}",
            flight.distance, flight.craters, flight.undone, flight.redone
        ),
        format!(
            "{}{} | F5 save, F9 load, autosave every {} s",
            saves.message,
            if saves.pending { " | saving..." } else { "" },
            AUTOSAVE_EVERY.as_secs()
        ),
        format!(
            "chunks: {} live, {} building, {} edited stored ({} kB) | built {} ({} restored), {:.1} ms each",
            s.live,
            s.building,
            s.stored,
            s.stored_bytes / 1024,
            s.generated + s.restored,
            s.restored,
            ms(s.build_time) / built as f64
        ),
        format!(
            "coarse: {} chunks drawn, per level {:?} | {} triangles",
            l.drawn_per_level.iter().sum::<usize>(),
            l.drawn_per_level,
            l.triangles
        ),
    ];
    for mut text in &mut hud {
        text.0 = lines.join("\n");
    }
}
