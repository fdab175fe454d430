//! Regions of a sampling plane (paper 2, §4.1–4.2, Fig. 8): the basic
//! regions and the pieces their subdivision makes.
//!
//! Notation: `(x, y)` plane coordinates of a [`Heightfield`]. A region is
//! either a convex [`Polygon`] (a triangle or an axis-aligned rectangle,
//! straight sides) or a [`CurvedTriangle`] (sides on conics centred at the
//! origin, see [`curved`](crate::sampling::curved)). Both answer what the
//! subdivision of §4.2 asks: corners, a bounding box, a cover radius (every
//! point within that path length of a corner), the reach from each corner,
//! a distortion bound and a split into two children that cover it.
//! Paths inside a polygon are straight; inside a curved triangle they are
//! arcs, and its radii are path lengths.
//!
//! The two region types live in [`polygon`](crate::sampling::polygon) and
//! [`curved`](crate::sampling::curved), below this module: neither imports
//! it.
//!
//! [`Heightfield`]: crate::sampling::heightfield::Heightfield

use glam::DVec2;

use crate::sampling::curved::CurvedTriangle;
use crate::sampling::heightfield::Heightfield;
use crate::sampling::polygon::Polygon;
use crate::sampling::warp::ArcKind;

/// What a basic region is (Fig. 8a).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RegionKind {
    /// A triangle with straight sides.
    Triangle,
    /// An axis-aligned rectangle.
    Rectangle,
    /// A curved triangle with a side on an ellipse centred at the origin.
    EllipticTriangle,
    /// A curved triangle with a side on a hyperbola centred at the origin.
    HyperbolicTriangle,
    /// A curved triangle with a side on a parabola (a paraboloid seen from
    /// the side: one axis of the plane is linear).
    ParabolicTriangle,
}

impl RegionKind {
    /// The number of kinds.
    pub const COUNT: usize = 5;

    /// The index of the kind in [`SamplingStats`](crate::sampling::SamplingStats) arrays.
    #[must_use]
    pub fn index(self) -> usize {
        match self {
            Self::Triangle => 0,
            Self::Rectangle => 1,
            Self::EllipticTriangle => 2,
            Self::HyperbolicTriangle => 3,
            Self::ParabolicTriangle => 4,
        }
    }

    /// The curved-triangle kind of an arc (a straight one gives
    /// [`Triangle`](Self::Triangle)).
    #[must_use]
    pub fn of_arc(arc: ArcKind) -> Self {
        match arc {
            ArcKind::Straight => Self::Triangle,
            ArcKind::Elliptic => Self::EllipticTriangle,
            ArcKind::Hyperbolic => Self::HyperbolicTriangle,
            ArcKind::Parabolic => Self::ParabolicTriangle,
        }
    }

    /// The kind of a curved triangle: that of its first curved side, or
    /// [`Triangle`](Self::Triangle) when all its sides are straight.
    #[must_use]
    pub fn of_curved(triangle: &CurvedTriangle) -> Self {
        (0..3)
            .map(|i| triangle.side_kind(i))
            .find(|k| *k != ArcKind::Straight)
            .map_or(Self::Triangle, Self::of_arc)
    }
}

/// A region of a sampling plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Region {
    /// A triangle or an axis-aligned rectangle.
    Polygon(Polygon),
    /// A triangle of the warped plane (curved sides).
    Curved(CurvedTriangle),
}

impl Region {
    /// A straight triangle.
    #[must_use]
    pub fn triangle(a: DVec2, b: DVec2, c: DVec2) -> Self {
        Self::Polygon(Polygon::triangle(a, b, c))
    }

    /// The axis-aligned rectangle `[lo, hi]`.
    #[must_use]
    pub fn rectangle(lo: DVec2, hi: DVec2) -> Self {
        Self::Polygon(Polygon::rectangle(lo, hi))
    }

    /// The corners, where the subdivision evaluates distances.
    #[must_use]
    pub fn vertices(&self) -> &[DVec2] {
        match self {
            Self::Polygon(p) => p.vertices(),
            Self::Curved(c) => c.vertices(),
        }
    }

    /// The bounding box `(lo, hi)`.
    #[must_use]
    pub fn bounds(&self) -> (DVec2, DVec2) {
        match self {
            Self::Polygon(p) => p.bounds(),
            Self::Curved(c) => c.bounds(),
        }
    }

    /// The longest path inside the region from corner `i` to any of its points.
    #[must_use]
    pub fn reach(&self, i: usize) -> f64 {
        match self {
            Self::Polygon(p) => p.reach(i),
            Self::Curved(c) => c.reach(i),
        }
    }

    /// An upper bound of the diameter.
    #[must_use]
    pub fn diameter(&self) -> f64 {
        match self {
            Self::Polygon(p) => p.diameter(),
            Self::Curved(c) => c.diameter(),
        }
    }

    /// A path length `ρ` within which every point of the region has a corner.
    #[must_use]
    pub fn cover_radius(&self) -> f64 {
        match self {
            Self::Polygon(p) => p.cover_radius(),
            Self::Curved(c) => c.cover_radius(),
        }
    }

    /// Bounds `(min, max)` of the distortion of `hf` over the region (§3.4):
    /// at the corners of the bounding box for a polygon, at the vertices
    /// for a curved triangle.
    #[must_use]
    pub fn distortion_bounds(&self, hf: &Heightfield) -> (f64, f64) {
        match self {
            Self::Polygon(p) => {
                let (lo, hi) = p.bounds();
                hf.distortion_bounds(lo, hi)
            }
            Self::Curved(c) => c.distortion_bounds(hf),
        }
    }

    /// A point of the region and a path length within which all of the
    /// region lies around it (for culling far products).
    #[must_use]
    pub fn anchor(&self) -> (DVec2, f64) {
        match self {
            Self::Polygon(p) => {
                let v = p.vertices();
                #[allow(clippy::cast_precision_loss)]
                let centroid = v.iter().copied().sum::<DVec2>() / v.len() as f64;
                let reach = v
                    .iter()
                    .map(|w| w.distance_squared(centroid))
                    .fold(0.0, f64::max)
                    .sqrt();
                (centroid, reach)
            }
            Self::Curved(c) => (c.vertices()[0], c.reach(0)),
        }
    }

    /// Two children that together cover the region (Fig. 8c).
    #[must_use]
    pub fn split(&self) -> [Self; 2] {
        match self {
            Self::Polygon(p) => p.split().map(Self::Polygon),
            Self::Curved(c) => c.split().map(Self::Curved),
        }
    }
}
