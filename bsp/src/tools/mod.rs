//! Convex tools: exact convex hulls of integer points, and the shapes built
//! from them (prisms, dodecahedra, swept volumes).

pub mod hull;
pub mod quantize;
pub mod shapes;

pub use hull::convex_hull;
pub use quantize::Quantization;
pub use shapes::{Pose, dodecahedron_corners, placed_tool, prism_corners, swept_tool};
