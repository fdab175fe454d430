//! Shared by the terrain tests: running an app until a terrain is idle.

use std::time::Duration;

use bevy::prelude::*;
use bevy_chisel::terrain::Terrain;

/// Runs frames until the terrain `entity` has applied every carve and
/// shown every mesh, then one more so that systems after the terrain's see
/// the last messages. Panics after 20,000 frames.
pub fn settle(app: &mut App, entity: Entity) {
    for _ in 0..20_000 {
        app.update();
        let idle = (app.world().get::<Terrain>(entity)).is_some_and(Terrain::is_idle);
        if idle {
            app.update();
            return;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("terrain did not settle");
}
