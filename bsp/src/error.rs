//! The one error type of `chisel_bsp`.

use core::fmt;

use crate::exact::budget::{MAX_COORD, MAX_NORMAL, MAX_OFFSET};

/// Everything that can go wrong when values enter the exact kernel.
///
/// Each variant says what was wrong with the input and how to fix it. None of
/// them signals an internal bug: the kernel's own arithmetic cannot fail once
/// its inputs are inside the bit budget.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    /// An input coordinate is outside `±2^26` (`MAX_COORD`).
    CoordinateOutOfRange {
        /// Which coordinate: 0 = x, 1 = y, 2 = z.
        axis: usize,
        /// The offending value.
        value: i64,
    },
    /// A plane normal component is outside `±2^55` (`MAX_NORMAL`).
    NormalOutOfRange {
        /// Which component: 0 = a, 1 = b, 2 = c.
        component: usize,
        /// The offending value.
        value: i64,
    },
    /// A plane offset `d` is outside `±2^83` (`MAX_OFFSET`).
    OffsetOutOfRange {
        /// The offending value.
        value: i128,
    },
    /// A floating-point input (a coordinate, scale or rotation entry) is
    /// NaN or infinite.
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A plane has the zero normal `(0, 0, 0)`, which defines no plane.
    ZeroNormal,
    /// Three points meant to define a plane are collinear (or coincide).
    CollinearPoints,
    /// The points of a convex tool span no volume: fewer than four distinct
    /// points, or all on one line or one plane.
    DegenerateHull {
        /// What kind of degeneracy: `"fewer than four distinct points"`,
        /// `"collinear"` or `"coplanar"`.
        reason: &'static str,
    },
    /// A box needs `min < max` on every axis.
    DegenerateBox {
        /// The requested minimum corner.
        min: [i64; 3],
        /// The requested maximum corner.
        max: [i64; 3],
    },
    /// An octree root cube that is too small, too large or out of range.
    OctreeSize {
        /// Requested lower corner.
        origin: [i64; 3],
        /// Requested edge exponent.
        size_log2: u8,
    },
    /// Stored octree leaves that do not tile the cube.
    InvalidOctree {
        /// What is wrong with them.
        reason: &'static str,
    },
    /// A union of no tools.
    NoTools,
    /// A quantization unit that is not a positive finite length.
    InvalidUnit {
        /// The unit given.
        unit: f64,
    },
    /// A mesh that is not closed: some directed edges are used more or
    /// less often than their opposite.
    NotWatertight {
        /// How many directed edges are unmatched.
        open_edges: usize,
        /// One such edge, in grid coordinates.
        example: [[i64; 3]; 2],
    },
    /// A mesh whose triangles cross each other.
    SelfIntersecting {
        /// Indices of two triangles that meet improperly.
        triangles: [usize; 2],
        /// Their corners, in grid units.
        corners: Box<[[[i64; 3]; 3]; 2]>,
    },
    /// Input reaching outside the octree's cube.
    OutsideOctree {
        /// A grid point outside it.
        point: [i64; 3],
    },
    /// An edit that cannot mean anything.
    InvalidEdit {
        /// What is wrong with it.
        reason: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const AXES: [char; 3] = ['x', 'y', 'z'];
        const COEFFS: [char; 3] = ['a', 'b', 'c'];
        match self {
            Error::CoordinateOutOfRange { axis, value } => write!(
                f,
                "coordinate {}={value} is outside the exact range ±{MAX_COORD} (2^26); \
                 scale the input down or use a coarser quantization unit",
                AXES[(*axis).min(2)]
            ),
            Error::NormalOutOfRange { component, value } => write!(
                f,
                "plane normal component {}={value} is outside ±{MAX_NORMAL} (2^55); \
                 divide the plane by the gcd of its coefficients or build it from in-range points",
                COEFFS[(*component).min(2)]
            ),
            Error::OffsetOutOfRange { value } => write!(
                f,
                "plane offset d={value} is outside ±{MAX_OFFSET} (2^83); \
                 the plane lies too far from the origin for the exact range"
            ),
            Error::NonFinite { what } => {
                write!(f, "{what} is not a finite number (NaN or infinite)")
            }
            Error::ZeroNormal => write!(f, "a plane needs a non-zero normal (a, b, c)"),
            Error::DegenerateHull { reason } => write!(
                f,
                "the tool's points are {reason}, so their convex hull has no volume; \
                 give at least four points that do not all lie in one plane"
            ),
            Error::DegenerateBox { min, max } => write!(
                f,
                "box from {min:?} to {max:?} has no volume; every coordinate of min must be \
                 below the same coordinate of max"
            ),
            Error::OctreeSize { origin, size_log2 } => write!(
                f,
                "octree cube at {origin:?} with edge 2^{size_log2} is invalid: the edge must be \
                 2^1 to 2^27 and the cube must lie within ±{MAX_COORD} (2^26)"
            ),
            Error::InvalidOctree { reason } => write!(f, "invalid octree: {reason}"),
            Error::NoTools => write!(f, "a union of tools needs at least one tool"),
            Error::InvalidUnit { unit } => write!(
                f,
                "quantization unit {unit} is not a positive finite length"
            ),
            Error::NotWatertight {
                open_edges,
                example,
            } => write!(
                f,
                "the mesh is not watertight: {open_edges} directed edges are not matched by an \
                 opposite edge (e.g. {:?} -> {:?} in grid units); close the holes and make \
                 the triangles consistently oriented",
                example[0], example[1]
            ),
            Error::SelfIntersecting { triangles, corners } => write!(
                f,
                "the mesh intersects itself: triangles {} {:?} and {} {:?} (grid units) meet \
                 outside their shared corners and edges; repair the mesh before importing it",
                triangles[0], corners[0], triangles[1], corners[1]
            ),
            Error::OutsideOctree { point } => write!(
                f,
                "grid point {point:?} lies outside the octree's cube; enlarge the cube or \
                 move the input"
            ),
            Error::InvalidEdit { reason } => write!(f, "invalid edit: {reason}"),
            Error::CollinearPoints => write!(
                f,
                "the three points are collinear or coincide, so they define no plane"
            ),
        }
    }
}

impl std::error::Error for Error {}
