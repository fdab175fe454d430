//! The app both latency benches of a busy world run in
//! (`carve_latency_while_streaming`, `debris_latency_across_borders`): the
//! `world` example's layout (1 cm grid, 20.48 m chunks) with the four
//! chunks around the corner x = z = 20.48 m live, a second focus 100 m
//! away, and frames at 60 a second (each padded to 16.7 ms), in which one
//! kind of other activity goes on.

use super::world_debris::corner_world_app;
use super::*;
use bevy::ecs::message::MessageCursor;
use bevy_chisel::terrain::{ChunkCoord, TerrainFocus, TerrainWorld, WorldCarve};

/// One frame at 60 frames per second.
const FRAME: Duration = Duration::from_micros(16_667);
/// Where the second focus stands (metres, z), out of reach of the corner.
const FAR_Z: f32 = 112.64;
/// Frames between the streaming focus's steps of one chunk.
const STEP_FRAMES: u64 = 4;
/// Chunk edge (metres).
pub(super) const EDGE: f32 = 20.48;
/// The most frames a bench waits for anything before it gives up.
pub(super) const MOST_FRAMES: u64 = 3_000;

/// What else happens in the world while a bench measures.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Activity {
    /// Nothing.
    Idle,
    /// The second focus moves one chunk every four frames, so that chunks
    /// keep building.
    Streaming,
    /// The second focus stands still and a radius-1 m crater is carved in
    /// its chunks every frame.
    Carving,
}

impl Activity {
    pub(super) fn name(self) -> &'static str {
        match self {
            Activity::Idle => "idle",
            Activity::Streaming => "streaming",
            Activity::Carving => "carving",
        }
    }
}

/// The headless app, the second focus, the frame count and a cursor over
/// [`CarveApplied`].
pub(super) struct CornerApp {
    pub app: App,
    pub world: Entity,
    far_focus: Entity,
    activity: Activity,
    frame: u64,
    next: Box<dyn FnMut() -> f64>,
    applied: MessageCursor<CarveApplied>,
}

impl CornerApp {
    /// The app with everything around both foci built.
    pub(super) fn new(activity: Activity) -> Self {
        let (mut app, world) = corner_world_app();
        let far_focus = (app.world_mut())
            .spawn((
                TerrainFocus,
                Transform::from_translation(Vec3::new(10.24, 10.0, FAR_Z)),
            ))
            .id();
        let applied = (app.world().resource::<Messages<CarveApplied>>()).get_cursor_current();
        let mut corner = Self {
            app,
            world,
            far_focus,
            activity,
            frame: 0,
            next: Box::new(uniform(0x5eed_cafe)),
            applied,
        };
        // Everything built, before the activity starts.
        for _ in 0..100_000 {
            corner.app.update();
            let w = corner.the_world();
            if w.is_settled()
                && w.live_chunks().count() > 4
                && w.live_chunks().all(|(_, e)| corner.chunk_idle(e))
            {
                return corner;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        panic!("the world did not settle");
    }

    pub(super) fn the_world(&self) -> &TerrainWorld {
        (self.app.world().get::<TerrainWorld>(self.world)).expect("world")
    }

    fn chunk_idle(&self, entity: Entity) -> bool {
        (self.app.world().get::<Terrain>(entity)).is_some_and(Terrain::is_idle)
    }

    /// Whether the four chunks around the corner are live and idle and no
    /// search for debris runs.
    fn corner_quiet(&self) -> bool {
        let w = self.the_world();
        !w.debris_searching()
            && (0..4).all(|k| {
                let coord = ChunkCoord { x: k % 2, z: k / 2 };
                w.chunk_entity(coord).is_some_and(|e| self.chunk_idle(e))
            })
    }

    /// One frame: the activity's step, the app's update, the padding to
    /// 16.7 ms. Returns how many carves of the corner (with an edit) were
    /// applied in it.
    pub(super) fn frame(&mut self) -> usize {
        let start = Instant::now();
        match self.activity {
            Activity::Idle => {}
            Activity::Streaming => {
                let x = 10.24 + EDGE * (self.frame / STEP_FRAMES) as f32;
                let mut transform = (self.app.world_mut())
                    .get_mut::<Transform>(self.far_focus)
                    .expect("focus");
                transform.translation.x = x;
            }
            Activity::Carving => {
                let next = &mut self.next;
                let (x, z) = (40.96 * next() as f32, 81.92 + 40.96 * next() as f32);
                let centre = Vec3::new(x, 2.0 + 6.0 * next() as f32, z);
                self.cut(CarveTool::new(
                    CarveShape::Dodecahedron { radius: 1.0 },
                    Transform::from_translation(centre),
                ));
            }
        }
        self.app.update();
        self.frame += 1;
        let corner: Vec<Entity> = (0..4)
            .filter_map(|k| (self.the_world()).chunk_entity(ChunkCoord { x: k % 2, z: k / 2 }))
            .collect();
        let messages = self.app.world().resource::<Messages<CarveApplied>>();
        let applied = (self.applied.read(messages))
            .filter(|a| a.edit.is_some() && corner.contains(&a.terrain))
            .count();
        if let Some(rest) = FRAME.checked_sub(start.elapsed()) {
            std::thread::sleep(rest);
        }
        applied
    }

    /// Carves `tool` out of the world.
    pub(super) fn cut(&mut self, tool: CarveTool) {
        let world = self.world;
        self.app.world_mut().write_message(WorldCarve {
            world,
            tool,
            edit: Edit::Subtract,
        });
    }

    /// Runs frames until the corner is quiet for three.
    pub(super) fn wait_quiet(&mut self) {
        let mut quiet = 0;
        for _ in 0..MOST_FRAMES {
            self.frame();
            quiet = if self.corner_quiet() { quiet + 1 } else { 0 };
            if quiet == 3 {
                return;
            }
        }
        panic!("the corner did not settle");
    }
}

/// The median of `v` (the upper one of an even count).
pub(super) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// The largest of `v` (0 when empty).
pub(super) fn most(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}
