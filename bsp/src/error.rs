//! The one error type of `chisel_bsp`.

use crate::exact::budget::{MAX_COORD, MAX_NORMAL, MAX_OFFSET};

/// Everything that can go wrong when values enter the exact kernel.
///
/// Each variant says what was wrong with the input and how to fix it. None of
/// them signals an internal bug: the kernel's own arithmetic cannot fail once
/// its inputs are inside the bit budget.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Error {
    /// An input coordinate is outside `±2^26` (`MAX_COORD`).
    #[error(
        "coordinate {}={value} is outside the exact range ±{MAX_COORD} (2^26); \
         scale the input down or use a coarser quantization unit",
        axis_name(*.axis)
    )]
    CoordinateOutOfRange {
        /// Which coordinate: 0 = x, 1 = y, 2 = z.
        axis: usize,
        /// The offending value.
        value: i64,
    },
    /// A plane normal component is outside `±2^55` (`MAX_NORMAL`).
    #[error(
        "plane normal component {}={value} is outside ±{MAX_NORMAL} (2^55); \
         divide the plane by the gcd of its coefficients or build it from in-range points",
        coefficient_name(*.component)
    )]
    NormalOutOfRange {
        /// Which component: 0 = a, 1 = b, 2 = c.
        component: usize,
        /// The offending value.
        value: i64,
    },
    /// A plane offset `d` is outside `±2^83` (`MAX_OFFSET`).
    #[error(
        "plane offset d={value} is outside ±{MAX_OFFSET} (2^83); \
         the plane lies too far from the origin for the exact range"
    )]
    OffsetOutOfRange {
        /// The offending value.
        value: i128,
    },
    /// A floating-point input (a coordinate, scale or rotation entry) is
    /// NaN or infinite.
    #[error("{what} is not a finite number (NaN or infinite)")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A plane has the zero normal `(0, 0, 0)`, which defines no plane.
    #[error("a plane needs a non-zero normal (a, b, c)")]
    ZeroNormal,
    /// Three points meant to define a plane are collinear (or coincide).
    #[error("the three points are collinear or coincide, so they define no plane")]
    CollinearPoints,
    /// The points of a convex tool span no volume: fewer than four distinct
    /// points, or all on one line or one plane.
    #[error(
        "the tool's points are {reason}, so their convex hull has no volume; \
         give at least four points that do not all lie in one plane"
    )]
    DegenerateHull {
        /// What kind of degeneracy: `"fewer than four distinct points"`,
        /// `"collinear"` or `"coplanar"`.
        reason: &'static str,
    },
    /// A convex tool from more distinct points than
    /// [`crate::tools::MAX_HULL_POINTS`]: the hull and the edit would take
    /// time growing with the square of the points.
    #[error(
        "a convex tool of {points} distinct points is over the limit of {limit}; \
         give fewer points (a hull's faces follow from its outermost points), or split \
         the tool into several convex tools"
    )]
    TooManyHullPoints {
        /// Distinct points given.
        points: usize,
        /// The limit.
        limit: usize,
    },
    /// A round tool (sphere, cylinder, capsule) with a size, tolerance or
    /// rounding allowance that means nothing.
    #[error("invalid round tool: {reason}")]
    InvalidRoundTool {
        /// Which number is wrong, and how.
        reason: &'static str,
    },
    /// No polyhedron of at most `max_points` corners brings a round tool
    /// within the tolerance asked for.
    #[error(
        "a round tool within {tolerance} of its surface needs more than {max_points} corners \
         (the closest fit allowed is {best}); ask for a larger tolerance (more than twice \
         the grid rounding, √3 grid steps) or allow more corners"
    )]
    ToleranceUnreachable {
        /// The tolerance asked for.
        tolerance: f64,
        /// The deviation of the finest polyhedron within the limit
        /// (infinite when not even the coarsest one fits).
        best: f64,
        /// The most corners allowed.
        max_points: usize,
    },
    /// A box needs `min < max` on every axis.
    #[error(
        "box from {min:?} to {max:?} has no volume; every coordinate of min must be \
         below the same coordinate of max"
    )]
    DegenerateBox {
        /// The requested minimum corner.
        min: [i64; 3],
        /// The requested maximum corner.
        max: [i64; 3],
    },
    /// An octree root cube that is too small, too large or out of range.
    #[error(
        "octree cube at {origin:?} with edge 2^{size_log2} is invalid: the edge must be \
         2^1 to 2^27 and the cube must lie within ±{MAX_COORD} (2^26)"
    )]
    OctreeSize {
        /// Requested lower corner.
        origin: [i64; 3],
        /// Requested edge exponent.
        size_log2: u8,
    },
    /// Stored octree leaves that do not tile the cube.
    #[error("invalid octree: {reason}")]
    InvalidOctree {
        /// What is wrong with them.
        reason: &'static str,
    },
    /// A union of no tools.
    #[error("a union of tools needs at least one tool")]
    NoTools,
    /// A quantization unit that is not a positive finite length.
    #[error("quantization unit {unit} is not a positive finite length")]
    InvalidUnit {
        /// The unit given.
        unit: f64,
    },
    /// A mesh that is not closed: some directed edges are used more or
    /// less often than their opposite.
    #[error(
        "the mesh is not watertight: {open_edges} directed edges are not matched by an \
         opposite edge (e.g. {:?} -> {:?} in grid units); close the holes and make \
         the triangles consistently oriented",
        .example[0], .example[1]
    )]
    NotWatertight {
        /// How many directed edges are unmatched.
        open_edges: usize,
        /// One such edge, in grid coordinates.
        example: [[i64; 3]; 2],
    },
    /// A closed mesh that is inside out: its triangles face inwards
    /// (clockwise seen from outside), as a whole or in a shell that is not
    /// a cavity of another.
    #[error(
        "the mesh is inside out: {shell} encloses a negative volume ({volume} cubic \
         grid units); give every triangle counter-clockwise seen from outside \
         (cavities clockwise), or reverse the faces"
    )]
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
    #[error(
        "the mesh's shells do not nest as a solid's boundary: {shell} (volume {volume} \
         cubic grid units, {}) lies inside other shells with winding number \
         {winding}; an outward shell must lie inside no outward shell, and a cavity \
         (faces clockwise seen from outside) directly inside one. Reverse the faces \
         of a shell nested in another with the same orientation to make it a cavity, \
         or remove it",
        if *.volume > 0.0 { "outward" } else { "a cavity" }
    )]
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
    #[error(
        "the mesh intersects itself: triangles {} {:?} and {} {:?} (grid units) meet \
         outside their shared corners and edges; repair the mesh before importing it",
        .triangles[0], .corners[0], .triangles[1], .corners[1]
    )]
    SelfIntersecting {
        /// Indices of two triangles that meet improperly.
        triangles: [usize; 2],
        /// Their corners, in grid units.
        corners: Box<[[[i64; 3]; 3]; 2]>,
    },
    /// Input reaching outside the octree's cube.
    #[error(
        "grid point {point:?} lies outside the octree's cube; enlarge the cube or \
         move the input"
    )]
    OutsideOctree {
        /// A grid point outside it.
        point: [i64; 3],
    },
    /// A heightfield that describes no solid
    /// ([`crate::octree::import_layers::LayeredHeightfield`]).
    #[error("invalid heightfield: {reason}")]
    InvalidHeightfield {
        /// What is wrong with it.
        reason: String,
    },
    /// An edit that cannot mean anything.
    #[error("invalid edit: {reason}")]
    InvalidEdit {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// Bytes that do not start with the octree file magic
    /// ([`crate::octree::store::MAGIC`]): not an octree file.
    #[error(
        "not a chisel octree file (the magic bytes are missing); give a file written \
         by `Octree::to_bytes` or `chisel --export FILE.chisel`"
    )]
    NotAnOctreeFile,
    /// An octree file of a format version this build cannot read.
    #[error(
        "octree file format version {found} is not supported (this build reads version \
         {supported}); write the file again with a matching build"
    )]
    UnsupportedFormatVersion {
        /// Version found in the file.
        found: u32,
        /// The version this build reads and writes.
        supported: u32,
    },
    /// An octree file that ends in the middle of a record.
    #[error(
        "octree file is truncated: data missing at byte {at}; the file was cut short \
         while writing or copying"
    )]
    TruncatedFile {
        /// Byte offset where more data was expected.
        at: usize,
    },
    /// An octree file whose checksum does not match its content: the bytes
    /// were damaged after writing.
    #[error(
        "octree file is damaged: checksum {computed:016x} of its content differs from \
         the stored {stored:016x}"
    )]
    ChecksumMismatch {
        /// The checksum stored in the file.
        stored: u64,
        /// The checksum of the bytes read.
        computed: u64,
    },
    /// An octree file with a malformed record (unknown tag, impossible
    /// count, dangling index, bytes after the end).
    #[error("octree file is corrupt at byte {at}: {reason}")]
    CorruptFile {
        /// Byte offset of the record.
        at: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A plane in an octree file outside the exact bit budget (or with a
    /// zero normal); `cause` is the error [`crate::exact::Plane::new`] gives.
    #[error("octree file holds an invalid plane at byte {at}: {cause}")]
    StoredPlaneOutOfBudget {
        /// Byte offset of the plane.
        at: usize,
        /// Why the plane was refused.
        cause: Box<Error>,
    },
    /// A BSP in an octree file whose nodes do not form one tree over its
    /// planes.
    #[error("octree file holds an invalid BSP (number {index}): {reason}")]
    InvalidStoredBsp {
        /// Index of the BSP's leaf in the file's node table.
        index: usize,
        /// The defect found.
        reason: String,
    },
    /// An edit would cut loose more debris than
    /// [`crate::octree::DebrisConfig`] allows; nothing was changed.
    #[error(
        "the edit would cut loose at least {cells} cells ({volume:.6e} cubic grid \
         units) of unanchored debris, over the limits (cells: {}, volume: {}); carve \
         less at once, mark anchor boxes under the piece, or raise the limits of the \
         debris config",
        limit_text(*.max_cells),
        limit_text(*.max_volume)
    )]
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
    /// Chunks for a detach across chunks that do not form a grid of
    /// cubes side by side (two cubes overlap), or a seed naming no chunk
    /// ([`crate::octree::detach_across_chunks`]).
    #[error("invalid chunks: {reason}")]
    InvalidChunks {
        /// What is wrong with them.
        reason: String,
    },
    /// Reading or writing an octree file failed.
    #[error("octree file: {message}")]
    Io {
        /// The operating system's message.
        message: String,
    },
}

/// The letter of axis `axis` (0 = x, 1 = y, 2 = z; larger as z).
fn axis_name(axis: usize) -> char {
    ['x', 'y', 'z'][axis.min(2)]
}

/// The letter of normal component `component` (0 = a, 1 = b, 2 = c; larger
/// as c).
fn coefficient_name(component: usize) -> char {
    ['a', 'b', 'c'][component.min(2)]
}

/// A debris limit as text: the number, or `none`.
fn limit_text<T: ToString>(limit: Option<T>) -> String {
    limit.map_or_else(|| "none".into(), |l| l.to_string())
}
