//! The scratch space of the cutting operations, and the records it holds.
//!
//! One [`Scratch`] lives in each arena: the per-cut maps over vertex and
//! face indices ([`StampMap`]), the march's queues, what the split needs
//! to know about each face ([`FaceInfo`], [`RingFace`]) and, kept from
//! one cut to the next, where the next cut may start (`starts`).

use super::stamp_map::StampMap;
use super::starts::{Extremes, Landmarks};
use crate::exact::Sign;

/// What the split needs to know about one face that meets the section,
/// found in a single walk around it before anything changes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum FaceInfo {
    /// The face has `+` and `−` vertices: it will be split in two.
    Straddling {
        /// The half-edges of the face that will enter its two `0`
        /// vertices once its crossing edges are split, in loop order.
        enter: [u32; 2],
        /// The side of the vertices between the first and the second.
        first_chain: Sign,
        /// Its half-edge from a `+` to a `−` vertex (a convex face has at
        /// most one), or `u32::MAX`.
        crossing: u32,
    },
    /// The face lies on one side and has an edge in the cutting plane.
    Touching {
        /// The side of its vertices off the plane.
        side: Sign,
        /// Its half-edge lying in the plane.
        edge: u32,
    },
}

/// One face of a generic section's ring (notation of `ring`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct RingFace {
    /// The face `f_i`.
    pub(super) face: u32,
    /// `x_i`: its half-edge the section enters it across.
    pub(super) entry: u32,
    /// `y_i`: its half-edge the section leaves it across.
    pub(super) exit: u32,
    /// Its rank (see the docs of `ring`).
    pub(super) rank: u32,
    /// Whether the face's stored half-edge is one of those the walk took,
    /// from the one after `x_i` to `y_i` (what decides which of the two
    /// comes first in loop order, for the two-sided split).
    pub(super) stored_walked: bool,
}

/// The scratch space of the cutting operations, kept in the arena so that
/// cuts allocate nothing once it has grown to the arena's size.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    /// Side of each classified vertex.
    pub(crate) sides: StampMap<Sign>,
    /// Faces already queued by the march.
    pub(crate) faces: StampMap<bool>,
    /// Vertices already rotated around by the march.
    pub(crate) vertices: StampMap<bool>,
    /// Cap half-edge starting at each section vertex.
    pub(crate) cap_starts: StampMap<u32>,
    /// The march's queue of faces to visit, each with the crossing
    /// half-edge it is entered by (or `u32::MAX`).
    pub(crate) queue: Vec<(u32, u32)>,
    /// The faces that meet the section, with what the split needs to know
    /// about each.
    pub(crate) relevant: Vec<(u32, FaceInfo)>,
    /// The vertices on the cutting plane of the face the march visits.
    pub(crate) on_plane: Vec<u32>,
    /// The half-edges lying in the cutting plane, on faces of the lower
    /// and of the upper part.
    pub(crate) section: [Vec<u32>; 2],
    /// The faces of a generic section in the order the section crosses
    /// them (`ring`).
    pub(crate) ring: Vec<RingFace>,
    /// Ring positions in the order of their faces, then the cap half-edge
    /// leaving each new vertex (`ring_both`).
    pub(crate) order: Vec<u32>,
    /// Where the next cut of a part of the last cut starts (kept from one
    /// operation to the next, unlike the rest).
    pub(crate) landmarks: Landmarks,
    /// The extreme vertices of the parts of the last cut in fixed
    /// directions (kept from one operation to the next, like `landmarks`).
    pub(crate) extremes: Extremes,
    /// The side whose chain the march should walk on the face it starts
    /// from, when the start vertex tells (an extreme vertex lies near the
    /// small part).
    pub(crate) chain: Option<Sign>,
    /// The steps the edge descents of the operation took.
    pub(crate) descent_steps: u32,
}

impl Scratch {
    /// Makes room for `vertices` vertex and `faces` face indices.
    pub(crate) fn reserve(&mut self, vertices: usize, faces: usize) {
        self.sides.reserve(vertices);
        self.vertices.reserve(vertices);
        self.cap_starts.reserve(vertices);
        self.faces.reserve(faces);
    }

    /// Starts a new operation.
    pub(crate) fn clear(&mut self) {
        self.sides.clear();
        self.faces.clear();
        self.vertices.clear();
        self.cap_starts.clear();
        self.descent_steps = 0;
        self.chain = None;
    }
}
