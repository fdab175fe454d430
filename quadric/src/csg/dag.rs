//! The CSG DAG: primitives and Boolean / transform nodes (paper 2, §5).
//!
//! Nodes live in an arena and refer to children by [`NodeId`]. A node's
//! children always have smaller ids than the node itself, so the graph is
//! acyclic by construction; a child may be shared by several parents (a DAG,
//! not only a tree). Builders check their operands, so every node in a
//! `CsgDag` is valid.
//!
//! Point membership uses open sets: a primitive contains `x` iff `Q(x) < 0`;
//! complement is logical negation.

use glam::{DMat4, DVec3};

use crate::error::{Error, Result};
use crate::quadric::{Quadric, affine_inverse, snap_affine};

/// Linear RGB colour of a primitive, each channel in `[0, 1]`.
pub type Color = [f32; 3];

/// The id of a node in one [`CsgDag`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(usize);

impl NodeId {
    /// The node's position in [`CsgDag::nodes`].
    #[must_use]
    pub fn index(self) -> usize {
        self.0
    }
}

/// The physically based surface parameters a primitive may set for its
/// part of the surface; a field left `None` takes the value of the whole
/// prop's material (in the plugin, its `PropMaterial`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceMaterial {
    /// Metallic, 0 (dielectric) to 1 (metal).
    pub metallic: Option<f32>,
    /// Perceptual roughness, 0 (mirror) to 1 (fully rough), as Bevy's
    /// `StandardMaterial::perceptual_roughness`.
    pub perceptual_roughness: Option<f32>,
}

impl SurfaceMaterial {
    /// The fields by name, as a scene file writes them.
    #[must_use]
    pub fn fields(&self) -> [(&'static str, Option<f32>); 2] {
        [
            ("metallic", self.metallic),
            ("roughness", self.perceptual_roughness),
        ]
    }

    /// The first field that is given but not a finite number in `[0, 1]`,
    /// with its value.
    #[must_use]
    pub fn out_of_range(&self) -> Option<(&'static str, f32)> {
        self.fields().into_iter().find_map(|(field, value)| {
            value
                .filter(|v| !(v.is_finite() && (0.0..=1.0).contains(v)))
                .map(|v| (field, v))
        })
    }
}

/// A leaf of the DAG: a quadric, its display colour and its surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Primitive {
    /// The quadric, inside where `Q < 0`.
    pub quadric: Quadric,
    /// Its colour.
    pub color: Color,
    /// Its metallic and roughness, where it sets them.
    pub material: SurfaceMaterial,
}

/// One node of a [`CsgDag`].
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// A leaf: index into [`CsgDag::primitives`].
    Primitive(usize),
    /// The union of at least one child.
    Union(Vec<NodeId>),
    /// The intersection of at least one child.
    Intersection(Vec<NodeId>),
    /// The first child minus all the others: `base − s₁ − s₂ − …`.
    Difference {
        /// What is cut from.
        base: NodeId,
        /// What is cut away (at least one).
        subtracted: Vec<NodeId>,
    },
    /// Everything not in the child.
    Complement(NodeId),
    /// The child moved by an affine matrix.
    Transform {
        /// The matrix and its inverse.
        transform: Box<Affine>,
        /// The transformed node.
        child: NodeId,
    },
}

/// An affine matrix with its inverse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// The affine matrix applied to a child's geometry (last row `0 0 0 1`).
    pub matrix: DMat4,
    /// Its inverse (maps world points into the child's frame).
    pub inverse: DMat4,
}

/// A CSG directed acyclic graph over quadric primitives.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CsgDag {
    primitives: Vec<Primitive>,
    nodes: Vec<Node>,
}

impl CsgDag {
    /// An empty DAG.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The primitives, indexed by [`Node::Primitive`].
    #[must_use]
    pub fn primitives(&self) -> &[Primitive] {
        &self.primitives
    }

    /// All nodes; children precede parents.
    #[must_use]
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The node with id `id`, or [`Error::UnknownNode`].
    pub fn node(&self, id: NodeId) -> Result<&Node> {
        self.nodes.get(id.0).ok_or(Error::UnknownNode { id: id.0 })
    }

    /// The most recently added node, a natural root; [`Error::EmptyTree`]
    /// for an empty DAG.
    pub fn last(&self) -> Result<NodeId> {
        self.nodes
            .len()
            .checked_sub(1)
            .map(NodeId)
            .ok_or(Error::EmptyTree)
    }

    fn check(&self, id: NodeId) -> Result<NodeId> {
        self.node(id).map(|_| id)
    }

    fn push(&mut self, node: Node) -> NodeId {
        self.nodes.push(node);
        NodeId(self.nodes.len() - 1)
    }

    fn operands(&self, ids: &[NodeId], op: &'static str) -> Result<Vec<NodeId>> {
        if ids.is_empty() {
            return Err(Error::EmptyOperation { op });
        }
        ids.iter().map(|&id| self.check(id)).collect()
    }

    /// Adds a primitive leaf with the prop's material.
    pub fn primitive(&mut self, quadric: Quadric, color: Color) -> NodeId {
        self.primitive_with_material(quadric, color, SurfaceMaterial::default())
    }

    /// Adds a primitive leaf with its own surface parameters.
    ///
    /// Errors: [`Error::MaterialOutOfRange`] (naming primitive number
    /// `primitives().len()`) when a field is not a finite number in `[0, 1]`.
    pub fn try_primitive_with_material(
        &mut self,
        quadric: Quadric,
        color: Color,
        material: SurfaceMaterial,
    ) -> Result<NodeId> {
        if let Some((field, value)) = material.out_of_range() {
            return Err(Error::MaterialOutOfRange {
                primitive: format!("#{}", self.primitives.len()),
                field,
                value,
                line: 0,
                column: 0,
            });
        }
        Ok(self.primitive_with_material(quadric, color, material))
    }

    fn primitive_with_material(
        &mut self,
        quadric: Quadric,
        color: Color,
        material: SurfaceMaterial,
    ) -> NodeId {
        self.primitives.push(Primitive {
            quadric,
            color,
            material,
        });
        self.push(Node::Primitive(self.primitives.len() - 1))
    }

    /// Adds the union of `children` (at least one).
    pub fn union(&mut self, children: &[NodeId]) -> Result<NodeId> {
        let c = self.operands(children, "union")?;
        Ok(self.push(Node::Union(c)))
    }

    /// Adds the intersection of `children` (at least one).
    pub fn intersection(&mut self, children: &[NodeId]) -> Result<NodeId> {
        let c = self.operands(children, "intersection")?;
        Ok(self.push(Node::Intersection(c)))
    }

    /// Adds `base − subtracted[0] − subtracted[1] − …` (at least one subtracted).
    pub fn difference(&mut self, base: NodeId, subtracted: &[NodeId]) -> Result<NodeId> {
        let base = self.check(base)?;
        let subtracted = self.operands(subtracted, "difference")?;
        Ok(self.push(Node::Difference { base, subtracted }))
    }

    /// Adds the complement of `child`.
    pub fn complement(&mut self, child: NodeId) -> Result<NodeId> {
        let child = self.check(child)?;
        Ok(self.push(Node::Complement(child)))
    }

    /// Adds `child` moved by the affine `matrix`.
    ///
    /// Errors: [`Error::NonFinite`], [`Error::NotAffine`],
    /// [`Error::SingularTransform`], [`Error::UnknownNode`].
    pub fn transform(&mut self, matrix: DMat4, child: NodeId) -> Result<NodeId> {
        let child = self.check(child)?;
        let matrix = snap_affine(&matrix)?;
        let inverse = affine_inverse(&matrix)?;
        Ok(self.push(Node::Transform {
            transform: Box::new(Affine { matrix, inverse }),
            child,
        }))
    }

    /// Adds the box `[min, max]` as the intersection of six half-spaces, all
    /// with colour `color`.
    pub fn cuboid(&mut self, min: DVec3, max: DVec3, color: Color) -> Result<NodeId> {
        let planes = Quadric::box_planes(min, max)?;
        let ids = planes.map(|q| self.primitive(q, color));
        self.intersection(&ids)
    }

    /// Whether `point` is inside the solid of node `root`.
    ///
    /// Errors: [`Error::UnknownNode`] if `root` is not in this DAG.
    pub fn contains(&self, root: NodeId, point: DVec3) -> Result<bool> {
        self.check(root)?;
        Ok(self.contains_unchecked(root, point))
    }

    fn contains_unchecked(&self, id: NodeId, p: DVec3) -> bool {
        match &self.nodes[id.0] {
            Node::Primitive(i) => self.primitives[*i].quadric.value(p) < 0.0,
            Node::Union(c) => c.iter().any(|&k| self.contains_unchecked(k, p)),
            Node::Intersection(c) => c.iter().all(|&k| self.contains_unchecked(k, p)),
            Node::Difference { base, subtracted } => {
                self.contains_unchecked(*base, p)
                    && !subtracted.iter().any(|&k| self.contains_unchecked(k, p))
            }
            Node::Complement(c) => !self.contains_unchecked(*c, p),
            Node::Transform { transform, child } => {
                self.contains_unchecked(*child, transform.inverse.transform_point3(p))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builders_check_operands() {
        let mut dag = CsgDag::new();
        assert_eq!(dag.last(), Err(Error::EmptyTree));
        assert_eq!(dag.union(&[]), Err(Error::EmptyOperation { op: "union" }));
        assert_eq!(dag.complement(NodeId(3)), Err(Error::UnknownNode { id: 3 }));
        let s = dag.primitive(Quadric::sphere(DVec3::ZERO, 1.0).unwrap(), [1.0; 3]);
        assert_eq!(dag.transform(DMat4::ZERO, s), Err(Error::NotAffine));
        assert!(dag.difference(s, &[]).is_err());
    }

    #[test]
    fn classify_simple_tree() {
        let mut dag = CsgDag::new();
        let cube = dag
            .cuboid(DVec3::splat(-1.0), DVec3::splat(1.0), [0.5; 3])
            .unwrap();
        let ball = dag.primitive(Quadric::sphere(DVec3::ZERO, 0.5).unwrap(), [1.0; 3]);
        let moved = dag
            .transform(DMat4::from_translation(DVec3::X * 10.0), ball)
            .unwrap();
        let hollow = dag.difference(cube, &[ball]).unwrap();
        let root = dag.union(&[hollow, moved]).unwrap();
        let inside = |p: DVec3| dag.contains(root, p).unwrap();
        assert!(inside(DVec3::new(0.8, 0.8, 0.8)));
        assert!(!inside(DVec3::ZERO));
        assert!(inside(DVec3::new(10.2, 0.0, 0.0)));
        assert!(!inside(DVec3::new(5.0, 0.0, 0.0)));
        let outside = dag.complement(root).unwrap();
        assert!(dag.contains(outside, DVec3::ZERO).unwrap());
    }
}
