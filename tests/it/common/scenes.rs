//! The four benchmark scenes (`assets/scenes/`) and the camera of their comparison views: shared
//! by the headless splat tests (through [`super`]) and the splat bench
//! (`benches/splat.rs` includes this file by path), so it names nothing of
//! the test binary.

use bevy::math::DVec3;
use bevy_chisel::quadric::Scene;

/// Vertical field of view of every comparison camera.
pub const FOV_DEGREES: f64 = 30.0;
/// World units per scene unit (millimetres to decimetres): exercises the
/// prop's `Transform`.
pub const SCALE: f32 = 0.01;

/// `(scene, bounding centre, bounding radius)` as in the sampling benchmark.
pub const SCENES: [(&str, [f64; 3], f64); 4] = [
    ("three_spheres", [0.0, 0.0, 10.0], 75.0),
    ("classic", [0.0, 0.0, 0.0], 90.0),
    ("sharp8", [0.0, 0.0, 0.0], 60.0),
    ("machine80", [0.0, 0.0, 35.0], 100.0),
];

/// A shipped scene file.
pub fn load_scene(name: &str) -> Scene {
    let path = format!(
        "{}/assets/scenes/{name}.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    Scene::load(&path).expect("shipped scene")
}

/// The eye of the comparison views, in scene units.
pub fn eye(centre: DVec3, radius: f64) -> DVec3 {
    centre + DVec3::new(1.8, -2.4, 1.5) * radius * 0.85
}
