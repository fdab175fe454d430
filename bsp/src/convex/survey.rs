//! What one walk around a face tells the split (paper 1 §3.3, Fig. 4).
//!
//! Notation: a face's loop runs from its stored half-edge; each half-edge
//! `h` goes from a vertex on side `here` to one on side `there` of the
//! cutting plane `s` (`+`, `0` or `−`). A face *meets the section* when it
//! has `+` and `−` vertices (it *straddles* `s` and will be split) or an
//! edge lying in `s` (it *touches* `s`).
//!
//! The march walks every face it visits once, classifying its vertices;
//! [`FaceSurvey`] gathers in that same walk everything the split needs, so
//! no face is walked twice. A face the march enters through a crossing
//! edge is walked only along the chain of vertices after it, up to the
//! section's other end (`ConvexArena::survey_from_crossing`), which tells
//! the same.

use super::mesh::ConvexArena;
use super::scratch::FaceInfo;
use super::stamp_map::StampMap;
use crate::exact::{Plane, Sign};

/// The state of one walk around a face: feed in loop order every half-edge
/// that does not run along one side of the plane (`here ≠ there`, or
/// `here = 0`) to [`FaceSurvey::step`], then call [`FaceSurvey::finish`].
/// A half-edge from `+` to `+` or `−` to `−` tells nothing: every run of
/// one side ends in a half-edge that leaves it, which records the side.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FaceSurvey {
    plus: bool,
    minus: bool,
    /// The half-edge lying in `s`, or `u32::MAX`.
    in_plane: u32,
    /// The half-edge from `+` to `−`, or `u32::MAX`.
    crossing: u32,
    /// Where the section meets the face boundary, in loop order: at a `0`
    /// vertex (entered by the previous half-edge, `u32::MAX` while unknown)
    /// or inside a crossing edge (entered by that half-edge once it is
    /// split).
    enter: [u32; 2],
    events: u32,
    first_chain: Sign,
}

impl FaceSurvey {
    /// A walk about to start.
    #[inline]
    pub(crate) fn new() -> Self {
        Self {
            plus: false,
            minus: false,
            in_plane: u32::MAX,
            crossing: u32::MAX,
            enter: [u32::MAX; 2],
            events: 0,
            first_chain: Sign::Zero,
        }
    }

    /// Records half-edge `h`, from a vertex on side `here` to one on side
    /// `there` (not both `+` nor both `−`); `before` is the half-edge of
    /// the loop just before `h`, or `u32::MAX` when `h` is the first.
    #[inline]
    pub(crate) fn step(&mut self, h: u32, before: u32, here: Sign, there: Sign) {
        debug_assert!(here != there || here == Sign::Zero);
        self.plus |= here == Sign::Positive;
        self.minus |= here == Sign::Negative;
        if here == Sign::Positive && there == Sign::Negative {
            self.crossing = h;
        } else if here == Sign::Zero && there == Sign::Zero {
            debug_assert_eq!(self.in_plane, u32::MAX, "a face has one edge in the plane");
            self.in_plane = h;
        }
        let entered = if here == Sign::Zero {
            Some(before)
        } else if here.as_i32() * there.as_i32() < 0 {
            Some(h)
        } else {
            None
        };
        if let Some(e) = entered {
            if self.events < 2 {
                self.enter[self.events as usize] = e;
            }
            if self.events == 0 {
                self.first_chain = there;
            }
            self.events += 1;
        }
    }

    /// What the split needs to know about the face, once the walk has
    /// ended at half-edge `last`; `None` when it does not meet the section.
    #[inline]
    pub(crate) fn finish(self, last: u32) -> Option<FaceInfo> {
        if self.plus && self.minus {
            debug_assert_eq!(self.events, 2, "a convex face meets a plane twice");
            let mut enter = self.enter;
            if enter[0] == u32::MAX {
                // The walk started at a `0` vertex: it is entered last.
                enter[0] = last;
            }
            Some(FaceInfo::Straddling {
                enter,
                first_chain: self.first_chain,
                crossing: self.crossing,
            })
        } else if self.in_plane != u32::MAX {
            Some(FaceInfo::Touching {
                side: if self.plus {
                    Sign::Positive
                } else {
                    Sign::Negative
                },
                edge: self.in_plane,
            })
        } else {
            None
        }
    }
}

/// Where the section leaves a straddling face, the walk having entered it
/// through a crossing edge.
#[derive(Clone, Copy, Debug)]
pub(crate) enum SectionExit {
    /// Across this crossing half-edge of the face.
    Crossing(u32),
    /// At this vertex on the cutting plane.
    Vertex(u32),
}

impl ConvexArena {
    /// What a whole walk around face `f` from its stored half-edge tells
    /// ([`FaceSurvey`]), from a walk along part of it only, given its
    /// half-edge `x` whose ends lie on opposite sides of `s`; and where the
    /// section leaves `f`.
    ///
    /// By convexity the section meets the boundary of `f` exactly twice:
    /// inside `x`, and at the first vertex after `x` that is off the side
    /// `A` of `x`'s destination — on `s` (a `0` vertex), or else on the
    /// other side (the half-edge entering it crosses `s`). So the walk
    /// classifies only the chain on side `A`, and every vertex beyond lies
    /// on the other side. The stored half-edge's place decides which of
    /// the two comes first in loop order.
    pub(super) fn survey_from_crossing(
        &self,
        f: u32,
        x: u32,
        s: &Plane,
        sides: &mut StampMap<Sign>,
    ) -> (FaceInfo, SectionExit) {
        let first = self.faces[f as usize].half_edge;
        let mut h = self.half_edges[x as usize].next;
        let mut e = self.half_edges[h as usize];
        let side_a = self.side_in(e.origin, s, sides);
        debug_assert_ne!(side_a, Sign::Zero, "x crosses s");
        // Whether `first` lies after x, up to where the walk finds the
        // second place the section meets the boundary.
        let mut passed_first = false;
        let exit = loop {
            passed_first |= h == first;
            let next = self.half_edges[e.next as usize];
            let there = self.side_in(next.origin, s, sides);
            if there == Sign::Zero {
                // Found when the half-edge leaving that vertex is walked.
                passed_first |= e.next == first;
                break SectionExit::Vertex(next.origin);
            }
            if there != side_a {
                break SectionExit::Crossing(h);
            }
            (h, e) = (e.next, next);
        };
        // h enters the second place: as the entering half-edge of a `0`
        // vertex, or as the crossing half-edge.
        let (enter, first_chain) = if passed_first {
            ([h, x], -side_a)
        } else {
            ([x, h], side_a)
        };
        let crossing = match (side_a, exit) {
            (Sign::Negative, _) => x,
            (_, SectionExit::Crossing(y)) => y,
            (_, SectionExit::Vertex(_)) => u32::MAX,
        };
        let info = FaceInfo::Straddling {
            enter,
            first_chain,
            crossing,
        };
        (info, exit)
    }
}
