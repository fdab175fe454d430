//! The one error type of `chisel_quadric`.

/// Everything that can go wrong when values enter `chisel_quadric`.
///
/// Each variant says what was wrong with the input and how to fix it. None of
/// them signals an internal bug.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Error {
    /// A number given to a constructor or transform is NaN or infinite.
    #[error("{what} is NaN or infinite; give a finite number")]
    NonFinite {
        /// Which input held the value (e.g. `"sphere radius"`).
        what: &'static str,
    },
    /// A size that must be strictly positive (radius, semi-axis, angle) is not.
    #[error("{what} is {value}; it must be strictly positive")]
    NonPositive {
        /// Which input held the value.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A direction vector (axis, plane normal, ray direction) is zero.
    #[error("{what} is the zero vector; give a non-zero direction")]
    ZeroDirection {
        /// Which input held the vector.
        what: &'static str,
    },
    /// A raw matrix given as a quadric is not symmetric.
    #[error(
        "quadric matrix entry ({row}, {col}) differs from ({col}, {row}); \
         a quadric matrix must be symmetric"
    )]
    NotSymmetric {
        /// Row of the first mismatching entry.
        row: usize,
        /// Column of the first mismatching entry.
        col: usize,
    },
    /// The quadratic and linear coefficients are all zero: the quadric is a
    /// constant and has no surface.
    #[error(
        "the quadratic and linear quadric coefficients are all zero, so it is a \
         constant with no surface"
    )]
    ZeroQuadric,
    /// A transform matrix cannot be inverted (it flattens space).
    #[error("the transform is singular (it flattens space); use a non-zero scale")]
    SingularTransform,
    /// A transform matrix is projective; only affine matrices (last row
    /// `0 0 0 1`) keep the inside/outside sign of a quadric.
    #[error("the transform is projective; its last row must be (0, 0, 0, 1)")]
    NotAffine,
    /// A half-open angle is outside `(0°, 90°)`.
    #[error("the cone half-angle {degrees}° is outside (0°, 90°)")]
    AngleOutOfRange {
        /// The offending angle in degrees.
        degrees: f64,
    },
    /// A CSG operation was given no operands.
    #[error("a {op} needs at least one operand")]
    EmptyOperation {
        /// The operation (`"union"`, `"intersection"`, `"difference"`).
        op: &'static str,
    },
    /// A CSG node id does not belong to the DAG it was used with.
    #[error("node id {id} does not belong to this CSG DAG; use ids it returned")]
    UnknownNode {
        /// The offending id.
        id: usize,
    },
    /// The DAG has no node to use as the root.
    #[error("the CSG tree is empty: add a primitive first")]
    EmptyTree,
    /// Normalizing to disjunctive normal form would exceed the product budget.
    #[error(
        "the disjunctive normal form would have more than {limit} products; \
         simplify the tree (fewer unions below intersections or differences)"
    )]
    DnfTooLarge {
        /// The product limit that was hit.
        limit: usize,
    },
    /// A scene was given more carve tools than its limit
    /// ([`MAX_CARVES`](crate::scene::carve::MAX_CARVES) by default): every
    /// carve adds a literal to every product of the normal form.
    #[error(
        "{given} carves asked for, more than the limit of {limit}; every carve adds a \
         literal to every product of the normal form, so sampling and drawing grow with them"
    )]
    TooManyCarves {
        /// The limit.
        limit: usize,
        /// Tools given.
        given: usize,
    },
    /// Sampling would emit more samples than
    /// [`SampleOptions::max_samples`](crate::SampleOptions::max_samples);
    /// nothing is returned.
    #[error(
        "sampling needs more than {limit} samples ({reached} counted when it stopped); \
         use a larger splat radius or smaller bounds, or raise the limit \
         (`--max-samples` on the command line, `SampleOptions::max_samples`)"
    )]
    TooManySamples {
        /// The limit.
        limit: u64,
        /// Samples counted (or reserved for a grid) when it was passed.
        reached: u64,
    },
    /// Sampling would need more memory for its tables than
    /// [`SampleOptions::max_memory`](crate::SampleOptions::max_memory)
    /// ([`sampling_cost`](crate::sampling_cost)); nothing was allocated.
    #[error(
        "sampling this scene needs about {} MiB for its tables ({products} products with \
         {literals} literals in normal form, {regions} basic regions), more than the \
         limit of {} MiB; simplify the scene (fewer unions inside intersections or \
         differences), or raise the limit (`--max-memory-mb` on the command line, \
         `SampleOptions::max_memory`)",
        .needed.div_ceil(1 << 20),
        .limit / (1 << 20)
    )]
    SamplingTooLarge {
        /// Products of the normal form.
        products: u64,
        /// Literal instances: the literals of all products together.
        literals: u64,
        /// Basic regions to subdivide, one job each.
        regions: u64,
        /// Estimated bytes.
        needed: u64,
        /// The limit in bytes.
        limit: u64,
    },
    /// Sampling cannot keep the coverage guarantee: the bounding sphere is
    /// too large for the splat radius, or regions stayed unclassified at
    /// the subdivision limit.
    #[error("sampling cannot keep its coverage guarantee: {reason}")]
    CoverageNotReached {
        /// Why, and what to change.
        reason: String,
    },
    /// A primitive's metallic or roughness is not a finite number in
    /// `[0, 1]`.
    #[error(
        "{}",
        scene_message(
            *.line,
            *.column,
            &format!(
                "primitive \"{primitive}\": {field} {value} is out of range; give a finite \
                 number from 0 to 1 (or leave it out to take the prop's)"
            )
        )
    )]
    MaterialOutOfRange {
        /// The primitive's name in the scene file (`#n`, its index, for a
        /// primitive added in code).
        primitive: String,
        /// `"metallic"` or `"roughness"`.
        field: &'static str,
        /// The value given.
        value: f32,
        /// 1-based line of the primitive's name in the scene file (0 when
        /// unknown).
        line: usize,
        /// 1-based column of the primitive's name (0 when unknown).
        column: usize,
    },
    /// A scene file could not be read, parsed or understood.
    #[error("{}", scene_message(*.line, *.column, .message))]
    Scene {
        /// 1-based line of the problem (0 when unknown).
        line: usize,
        /// 1-based column of the problem (0 when unknown).
        column: usize,
        /// What is wrong and how to fix it.
        message: String,
    },
}

/// The text of [`Error::Scene`]: the message, after its line and column
/// when they are known.
fn scene_message(line: usize, column: usize, message: &str) -> String {
    if line == 0 {
        format!("scene: {message}")
    } else {
        format!("scene line {line}, column {column}: {message}")
    }
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = core::result::Result<T, E>;

/// Returns `Ok(x)` if `x` is finite, otherwise [`Error::NonFinite`].
pub(crate) fn finite(x: f64, what: &'static str) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::NonFinite { what })
    }
}

/// Returns `Ok(x)` if `x` is finite and strictly positive.
pub(crate) fn positive(x: f64, what: &'static str) -> Result<f64> {
    finite(x, what)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(Error::NonPositive { what, value: x })
    }
}

/// Returns the unit vector along `v`, or an error if it is zero or not finite.
pub(crate) fn direction(v: glam::DVec3, what: &'static str) -> Result<glam::DVec3> {
    if !v.is_finite() {
        return Err(Error::NonFinite { what });
    }
    v.try_normalize().ok_or(Error::ZeroDirection { what })
}
