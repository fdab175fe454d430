//! The label of a BSP just beside a point (symbolic perturbation).
//!
//! Notation: `p` — a point given doubled, `2p` on the integer grid (a
//! cell's centre may be a half-integer); `u` — a push direction, `o` — an
//! order of the axes; `q = p + ε·u_{o0}·x̂_{o0} + ε²·u_{o1}·x̂_{o1} +
//! ε³·u_{o2}·x̂_{o2}` for an infinitesimal `ε > 0`; `n·x + d` — a node's
//! plane.
//!
//! `q` lies on no plane when every axis is pushed (`u` has no zero):
//! `n·q + d` has the sign of `n·p + d` when that is not zero, and else
//! the sign of the first non-zero `n_a·u_a` in the order `o`, which
//! exists because `n ≠ 0`. So the descent follows one side at every node
//! and reaches the region holding `q` — a region that meets every
//! neighbourhood of `p` on the pushed side.
//!
//! Bit budget: `|n_a| ≤ 2^55`, `|2p_a| ≤ 2^28` and `|d| ≤ 2^83` for points
//! within the coordinate budget, so `n·2p + 2d` is exact in `i128`.

use super::bsp::{Bsp, Label, Node};

impl Bsp {
    /// The label of the region holding `twice / 2` pushed infinitesimally
    /// by `push` along the axes in `order` (see the module notes); `push`
    /// must have no zero component.
    pub(crate) fn label_near(&self, twice: [i128; 3], push: [i64; 3], order: [usize; 3]) -> Label {
        debug_assert!(push.iter().all(|&u| u != 0), "every axis is pushed");
        let mut n = 0;
        loop {
            match self.nodes()[n as usize] {
                Node::Leaf(label) => return label,
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let s = &self.planes()[plane as usize];
                    let normal = s.normal();
                    let value = (0..3)
                        .map(|a| i128::from(normal[a]) * twice[a])
                        .sum::<i128>()
                        + 2 * s.offset();
                    let side = match value.signum() {
                        0 => order
                            .iter()
                            .map(|&a| normal[a].signum() * push[a].signum())
                            .find(|&x| x != 0)
                            .unwrap_or(1),
                        sign => sign as i64,
                    };
                    n = if side < 0 { below } else { above };
                }
            }
        }
    }
}
