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
    /// A convex tool from more distinct points than
    /// [`crate::tools::MAX_HULL_POINTS`]: the hull and the edit would take
    /// time growing with the square of the points.
    TooManyHullPoints {
        /// Distinct points given.
        points: usize,
        /// The limit.
        limit: usize,
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
    /// A closed mesh that is inside out: its triangles face inwards
    /// (clockwise seen from outside), as a whole or in a shell that is not
    /// a cavity of another.
    InsideOut {
        /// The signed volume enclosed, cubic grid units (negative).
        volume: f64,
        /// Which part: the whole mesh or one shell, with its box.
        shell: String,
    },
    /// A closed mesh whose shells do not nest as the boundary of a solid
    /// must: an outward shell inside another outward shell, or a cavity
    /// that is not directly inside an outward shell. Where shells of the
    /// same orientation nest, the even-odd and the nonzero reading of the
    /// mesh give different solids, so it has no one meaning.
    MisnestedShell {
        /// The shell's signed volume, cubic grid units (positive: outward).
        volume: f64,
        /// The winding number of the other shells around it (an outward
        /// shell needs 0, a cavity 1).
        winding: i64,
        /// Which shell, with its box.
        shell: String,
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
    /// Bytes that do not start with the octree file magic
    /// ([`crate::octree::store::MAGIC`]): not an octree file.
    NotAnOctreeFile,
    /// An octree file of a format version this build cannot read.
    UnsupportedFormatVersion {
        /// Version found in the file.
        found: u32,
        /// The version this build reads and writes.
        supported: u32,
    },
    /// An octree file that ends in the middle of a record.
    TruncatedFile {
        /// Byte offset where more data was expected.
        at: usize,
    },
    /// An octree file whose checksum does not match its content: the bytes
    /// were damaged after writing.
    ChecksumMismatch {
        /// The checksum stored in the file.
        stored: u64,
        /// The checksum of the bytes read.
        computed: u64,
    },
    /// An octree file with a malformed record (unknown tag, impossible
    /// count, dangling index, bytes after the end).
    CorruptFile {
        /// Byte offset of the record.
        at: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A plane in an octree file outside the exact bit budget (or with a
    /// zero normal); `cause` is the error [`crate::exact::Plane::new`] gives.
    StoredPlaneOutOfBudget {
        /// Byte offset of the plane.
        at: usize,
        /// Why the plane was refused.
        cause: Box<Error>,
    },
    /// A BSP in an octree file whose nodes do not form one tree over its
    /// planes.
    InvalidStoredBsp {
        /// Index of the BSP's leaf in the file's node table.
        index: usize,
        /// The defect found.
        reason: String,
    },
    /// An edit would cut loose more debris than
    /// [`crate::octree::DebrisConfig`] allows; nothing was changed.
    TooMuchDebris {
        /// Convex cells of debris found when the limit was passed.
        cells: usize,
        /// Their volume in cubic grid units (at least; the search stops
        /// at the limit).
        volume: f64,
        /// The cell limit.
        max_cells: Option<usize>,
        /// The volume limit, in cubic grid units.
        max_volume: Option<u128>,
    },
    /// Reading or writing an octree file failed.
    Io {
        /// The operating system's message.
        message: String,
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
            Error::InsideOut { volume, shell } => write!(
                f,
                "the mesh is inside out: {shell} encloses a negative volume ({volume} cubic \
                 grid units); give every triangle counter-clockwise seen from outside \
                 (cavities clockwise), or reverse the faces"
            ),
            Error::MisnestedShell {
                volume,
                winding,
                shell,
            } => write!(
                f,
                "the mesh's shells do not nest as a solid's boundary: {shell} (volume {volume} \
                 cubic grid units, {}) lies inside other shells with winding number \
                 {winding}; an outward shell must lie inside no outward shell, and a cavity \
                 (faces clockwise seen from outside) directly inside one. Reverse the faces \
                 of a shell nested in another with the same orientation to make it a cavity, \
                 or remove it",
                if *volume > 0.0 { "outward" } else { "a cavity" }
            ),
            Error::TooManyHullPoints { points, limit } => write!(
                f,
                "a convex tool of {points} distinct points is over the limit of {limit}; \
                 give fewer points (a hull's faces follow from its outermost points), or split \
                 the tool into several convex tools"
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
            Error::NotAnOctreeFile => write!(
                f,
                "not a chisel octree file (the magic bytes are missing); give a file written \
                 by `Octree::to_bytes` or `chisel --export FILE.chisel`"
            ),
            Error::UnsupportedFormatVersion { found, supported } => write!(
                f,
                "octree file format version {found} is not supported (this build reads version \
                 {supported}); write the file again with a matching build"
            ),
            Error::TruncatedFile { at } => write!(
                f,
                "octree file is truncated: data missing at byte {at}; the file was cut short \
                 while writing or copying"
            ),
            Error::ChecksumMismatch { stored, computed } => write!(
                f,
                "octree file is damaged: checksum {computed:016x} of its content differs from \
                 the stored {stored:016x}"
            ),
            Error::CorruptFile { at, reason } => {
                write!(f, "octree file is corrupt at byte {at}: {reason}")
            }
            Error::StoredPlaneOutOfBudget { at, cause } => {
                write!(
                    f,
                    "octree file holds an invalid plane at byte {at}: {cause}"
                )
            }
            Error::InvalidStoredBsp { index, reason } => {
                write!(
                    f,
                    "octree file holds an invalid BSP (number {index}): {reason}"
                )
            }
            Error::TooMuchDebris {
                cells,
                volume,
                max_cells,
                max_volume,
            } => {
                let limit = |l: Option<String>| l.unwrap_or_else(|| "none".into());
                write!(
                    f,
                    "the edit would cut loose at least {cells} cells ({volume:.6e} cubic grid \
                     units) of unanchored debris, over the limits (cells: {}, volume: {}); carve \
                     less at once, mark anchor boxes under the piece, or raise the limits of the \
                     debris config",
                    limit(max_cells.map(|m| m.to_string())),
                    limit(max_volume.map(|m| m.to_string())),
                )
            }
            Error::Io { message } => write!(f, "octree file: {message}"),
            Error::CollinearPoints => write!(
                f,
                "the three points are collinear or coincide, so they define no plane"
            ),
        }
    }
}

impl std::error::Error for Error {}
