//! Debris across chunk borders falls promptly while the rest of the world
//! is busy (`MinimalPlugins`): a slab over the border x = 32 on a pillar
//! that a carve cuts through falls as one [`TerrainDebris`], with its
//! exact volume, within a bounded number of frames while a chunk far away
//! is carved every frame next to its border (its own seeds wait for its
//! carves; they do not hold the slab's search back), and while a second
//! focus keeps moving so that chunks keep building.

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::terrain::{CarveTool, TerrainFocus, WorldCarve};

use super::terrain_world::{app_with, settle, the_world, world};
use super::terrain_world_debris::{CUT, build_slab, cuboid, debris, falling};

/// Most frames (1 ms apart) from the cut to the debris. Measured on one
/// async compute thread: 4 in an idle world, 7 with a far chunk carved
/// every frame, 11 to 12 while chunks keep building; up to 23 with the
/// whole suite running beside it. The margin is for slower machines.
const MOST_FRAMES: u64 = 100;

/// The same with a far chunk carved every frame, whose carve jobs share
/// the loaded machine's cores with the search: over 100 once with the
/// whole suite and a build beside it. The rule this test guards against
/// (any chunk's busy neighbour held back every search) never let the
/// slab fall while the carves went on, so a wider margin still tells.
const MOST_FRAMES_CARVING: u64 = 400;

fn carve(app: &mut App, world: Entity, tool: CarveTool, edit: Edit) {
    app.world_mut()
        .write_message(WorldCarve { world, tool, edit });
}

/// The slab of 12×4×4 from x = 26 to 38 over the border x = 32 on a
/// pillar in chunk (0, 0), with a second focus at x = `far_x` whose
/// chunks are built too: the app, the world and the second focus.
fn slab_and_far_focus(far_x: f32) -> (App, Entity, Entity) {
    let (mut app, world, _) = app_with(world(), Vec3::new(32.0, 30.0, 16.0));
    build_slab(&mut app, world, false);
    let far = app
        .world_mut()
        .spawn((
            TerrainFocus,
            Transform::from_translation(Vec3::new(far_x, 30.0, 16.0)),
        ))
        .id();
    settle(&mut app, world);
    // A second slab over the border x = 288, on a pillar in chunk (9, 0).
    carve(
        &mut app,
        world,
        cuboid([290, 4, 10], [293, 25, 13]),
        Edit::Add(1),
    );
    settle(&mut app, world);
    carve(
        &mut app,
        world,
        cuboid([282, 24, 10], [294, 28, 14]),
        Edit::Add(1),
    );
    settle(&mut app, world);
    assert!(
        debris(&mut app).is_empty(),
        "the slabs rest on their pillars"
    );
    (app, world, far)
}

/// Cuts the pillar, then runs frames (1 ms apart), calling `busy` before
/// each, until the slab's debris is spawned: the frames it took. Then
/// stops the business, settles and checks that exactly the slab fell.
fn cut_to_debris(
    app: &mut App,
    world: Entity,
    most_frames: u64,
    mut busy: impl FnMut(&mut App, u64),
) -> u64 {
    carve(app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    let mut frames = 0;
    while debris(app).is_empty() {
        frames += 1;
        assert!(
            frames <= most_frames,
            "no debris {most_frames} frames after the cut"
        );
        busy(app, frames);
        app.update();
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    settle(app, world);
    let pieces = debris(app);
    assert_eq!(pieces.len(), 1, "one body for both parts");
    assert_eq!(pieces[0].exact_volume, falling());
    assert_eq!(the_world(app, world).stats().detached_across, 1);
    frames
}

#[test]
fn the_slab_falls_promptly_in_an_idle_world() {
    let (mut app, world, _) = slab_and_far_focus(272.0);
    cut_to_debris(&mut app, world, MOST_FRAMES, |_, _| {});
}

/// The second slab's part in chunk (8, 0), far from the first slab, is
/// carved every frame (a notch taken out of its top and put back in
/// turn): each carve leaves seeds there (the part rests on chunk (9, 0)
/// only) and the chunk is never idle, yet the first slab's search does
/// not wait for it.
#[test]
fn carves_beside_a_far_border_every_frame_do_not_hold_the_slab() {
    let (mut app, world, _) = slab_and_far_focus(272.0);
    let spot = cuboid([283, 26, 9], [285, 29, 15]);
    cut_to_debris(&mut app, world, MOST_FRAMES_CARVING, |app, frame| {
        let edit = if frame % 2 == 1 {
            Edit::Subtract
        } else {
            Edit::Add(1)
        };
        carve(app, world, spot.clone(), edit);
    });
}

/// A second focus moves one chunk every other frame: chunks keep
/// building (and leaving) while the slab falls.
#[test]
fn the_slab_falls_promptly_while_chunks_keep_building() {
    let (mut app, world, far) = slab_and_far_focus(272.0);
    let built = the_world(&app, world).stats().generated;
    cut_to_debris(&mut app, world, MOST_FRAMES, |app, frame| {
        let x = 272.0 + 32.0 * frame.div_ceil(2) as f32;
        app.world_mut()
            .get_mut::<Transform>(far)
            .expect("focus")
            .translation
            .x = x;
    });
    assert!(
        the_world(&app, world).stats().generated > built,
        "chunks were built meanwhile"
    );
}
