//! Convex tools: exact convex hulls of integer points, and the shapes built
//! from them (prisms, dodecahedra, swept volumes; spheres, cylinders and
//! capsules within a tolerance, [`round`]); swept volumes of
//! non-convex solids as unions of convex pieces ([`sweep`]).

pub mod hull;
pub mod quantize;
pub mod round;
pub mod shapes;
pub mod sweep;

pub use hull::{MAX_HULL_POINTS, convex_hull};
pub use quantize::Quantization;
pub use round::{
    GRID_ROUNDING, GeodesicSphere, RoundCorners, capsule_corners, cylinder_corners,
    geodesic_point_count, geodesic_sphere, sphere_corners,
};
pub use shapes::{Pose, dodecahedron_corners, placed_tool, prism_corners, swept_tool};
pub use sweep::{CubicBezier, Gear, GearSweep, WedgeMesh, spans_volume};
