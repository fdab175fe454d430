//! Carving: a scene's solid minus tool solids (destructible props).
//!
//! Notation: `S` the scene's solid, `T₁ … T_k` the tools (any quadric
//! solids, `T < 0` inside: a sphere, or the ellipsoid a sphere becomes
//! under a prop's affine transform). The carved solid is
//! `S − T₁ − … − T_k`, the scene's root under one `Difference` node whose
//! subtracted children are the tools, each a new DAG primitive whose
//! colour is that of the faces it cuts.
//!
//! In normal form ([`Dnf`](crate::Dnf)) a carve adds the literal
//! "outside `Tᵢ`" to every product, and nothing else: the base is
//! normalized first, so the scene's quadrics keep their indices and the
//! tools' come after them, and appending the same last literal to every
//! product keeps the products' order and absorption. That is the edit
//! [`RegionSamples::resample`](crate::sampling::partial::RegionSamples::resample)
//! recognizes: it re-samples only the regions near the tool and the
//! tool's own surface.
//!
//! Growth: every carve adds a literal to every product, so a solid of `p`
//! products sampled after `k` carves has `k·p` more literal instances to
//! sample, and every distance query of the sampler and the renderer looks
//! at them. [`Scene::carved`] refuses more than [`MAX_CARVES`] tools with
//! [`Error::TooManyCarves`]; [`Scene::carved_with_limit`] takes another
//! limit.
//!
//! ```
//! use chisel_quadric::scene::carve::Carve;
//! use chisel_quadric::{Quadric, Scene};
//! use glam::DVec3;
//!
//! let scene = Scene::from_ron(
//!     r#"Scene(primitives: [(name: "a", shape: Sphere(center: (0, 0, 0), radius: 10))],
//!        root: Ref("a"))"#,
//! )?;
//! let bite = Carve::new(Quadric::sphere(DVec3::new(10.0, 0.0, 0.0), 3.0)?, [0.2; 3]);
//! let carved = scene.carved(&[bite])?;
//! let dnf = carved.dnf()?;
//! assert!(dnf.contains(DVec3::new(-9.0, 0.0, 0.0)));
//! assert!(!dnf.contains(DVec3::new(9.0, 0.0, 0.0)));
//! # Ok::<(), chisel_quadric::Error>(())
//! ```

use crate::csg::{Color, NodeId};
use crate::error::{Error, Result};
use crate::quadric::Quadric;
use crate::scene::Scene;

/// The most tools [`Scene::carved`] cuts from one scene.
pub const MAX_CARVES: usize = 16;

/// One tool cut from a scene's solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Carve {
    /// The tool's solid (`Q < 0` inside), in the scene's frame.
    pub tool: Quadric,
    /// The colour of the faces the tool cuts (linear RGB).
    pub color: Color,
}

impl Carve {
    /// A carve of `tool` whose cut faces have colour `color`.
    #[must_use]
    pub fn new(tool: Quadric, color: Color) -> Self {
        Self { tool, color }
    }
}

impl Scene {
    /// The scene with `carves` cut from its solid, in order (see the module
    /// notes); no carve gives the scene itself.
    ///
    /// Errors: [`Error::TooManyCarves`] beyond [`MAX_CARVES`] tools.
    pub fn carved(&self, carves: &[Carve]) -> Result<Self> {
        self.carved_with_limit(carves, MAX_CARVES)
    }

    /// As [`carved`](Self::carved), with at most `limit` tools.
    ///
    /// Errors: [`Error::TooManyCarves`] beyond `limit` tools.
    pub fn carved_with_limit(&self, carves: &[Carve], limit: usize) -> Result<Self> {
        if carves.len() > limit {
            return Err(Error::TooManyCarves {
                limit,
                given: carves.len(),
            });
        }
        if carves.is_empty() {
            return Ok(self.clone());
        }
        let mut scene = self.clone();
        let tools: Vec<NodeId> = carves
            .iter()
            .enumerate()
            .map(|(i, carve)| {
                scene.names.push(format!("#carve{i}"));
                scene.dag.primitive(carve.tool, carve.color)
            })
            .collect();
        scene.root = scene.dag.difference(self.root, &tools)?;
        Ok(scene)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csg::{Literal, Side};
    use glam::DVec3;

    fn machine() -> Scene {
        Scene::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../assets/scenes/machine80.quadric.ron"
        ))
        .unwrap()
    }

    /// A carve is the literal "outside the tool" appended to every
    /// product, the scene's quadrics unchanged before the tool's.
    #[test]
    fn a_carve_appends_one_literal_to_every_product() {
        let scene = machine();
        let before = scene.dnf().unwrap();
        let tools = [
            Carve::new(
                Quadric::sphere(DVec3::new(10.0, 5.0, 3.0), 4.0).unwrap(),
                [0.1; 3],
            ),
            Carve::new(
                Quadric::ellipsoid(DVec3::new(-20.0, 0.0, 8.0), DVec3::new(3.0, 5.0, 2.0)).unwrap(),
                [0.2; 3],
            ),
        ];
        let after = scene.carved(&tools).unwrap().dnf().unwrap();
        let n = before.quadrics().len();
        assert_eq!(after.quadrics().len(), n + 2);
        assert_eq!(&after.quadrics()[..n], before.quadrics());
        assert_eq!(after.quadrics()[n].quadric, tools[0].tool);
        assert_eq!(after.quadrics()[n + 1].quadric, tools[1].tool);
        assert_eq!(after.products().len(), before.products().len());
        for (old, new) in before.products().iter().zip(after.products()) {
            let mut expected = old.clone();
            for q in [n, n + 1] {
                expected.push(Literal {
                    quadric: q,
                    side: Side::Outside,
                });
            }
            assert_eq!(new, &expected);
        }
    }

    #[test]
    fn the_carved_solid_is_the_solid_minus_the_tools() {
        let scene = machine();
        let tool = Quadric::sphere(DVec3::new(0.0, 0.0, 10.0), 12.0).unwrap();
        let before = scene.dnf().unwrap();
        let after = scene
            .carved(&[Carve::new(tool, [0.1; 3])])
            .unwrap()
            .dnf()
            .unwrap();
        let mut state = 7_u64;
        let (mut removed, mut kept) = (0, 0);
        for _ in 0..20_000 {
            let mut next = || {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1);
                (state >> 11) as f64 / (1u64 << 53) as f64 * 120.0 - 60.0
            };
            let p = DVec3::new(next(), next(), next());
            let expected = before.contains(p) && tool.value(p) >= 0.0;
            assert_eq!(after.contains(p), expected, "{p}");
            if before.contains(p) {
                if expected {
                    kept += 1;
                } else {
                    removed += 1;
                }
            }
        }
        assert!(removed > 10 && kept > 10, "{removed} {kept}");
    }

    #[test]
    fn too_many_carves_are_refused() {
        let scene = machine();
        let tool = Carve::new(Quadric::sphere(DVec3::ZERO, 1.0).unwrap(), [0.1; 3]);
        assert_eq!(scene.carved(&[]).unwrap(), scene);
        assert!(scene.carved(&[tool; MAX_CARVES]).is_ok());
        assert_eq!(
            scene.carved(&[tool; MAX_CARVES + 1]),
            Err(Error::TooManyCarves {
                limit: MAX_CARVES,
                given: MAX_CARVES + 1
            })
        );
        assert_eq!(
            scene.carved_with_limit(&[tool; 3], 2),
            Err(Error::TooManyCarves { limit: 2, given: 3 })
        );
    }
}
