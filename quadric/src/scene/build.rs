//! Turns a parsed scene into a [`CsgDag`], resolving names.

use std::collections::HashMap;

use crate::csg::{Color, CsgDag, NodeId, SurfaceMaterial};
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::scene::spec::{NodeSpec, PrimitiveSpec, RawNode, SceneSpec};

/// The colour of a primitive that names none.
pub const DEFAULT_COLOR: Color = [0.8, 0.8, 0.8];

/// Deepest nesting of CSG expressions, against runaway recursion.
const MAX_DEPTH: usize = 256;

/// Where `"name"` is first mentioned in the source (1-based), or `(0, 0)`.
fn locate(source: &str, name: &str) -> (usize, usize) {
    let needle = format!("\"{name}\"");
    source
        .lines()
        .enumerate()
        .find_map(|(i, line)| line.find(&needle).map(|c| (i + 1, c + 1)))
        .unwrap_or((0, 0))
}

pub(crate) fn build(source: &str, spec: &SceneSpec) -> Result<Scene> {
    let mut b = Builder {
        source,
        dag: CsgDag::new(),
        names: Vec::new(),
        defined: HashMap::new(),
        nodes: HashMap::new(),
        visiting: Vec::new(),
    };
    for p in &spec.primitives {
        b.add_primitive(p)?;
    }
    for n in &spec.nodes {
        if b.defined.contains_key(&n.name) || b.nodes.contains_key(&n.name) {
            return Err(b.duplicate(&n.name));
        }
        b.nodes.insert(n.name.clone(), &n.node);
    }
    let root = b.node(&spec.root, 0)?;
    Ok(Scene {
        dag: b.dag,
        root,
        names: b.names,
        bounds: spec.bounds.map(|b| b.0),
    })
}

struct Builder<'a> {
    source: &'a str,
    dag: CsgDag,
    names: Vec<String>,
    /// Primitives and already built named nodes.
    defined: HashMap<String, NodeId>,
    nodes: HashMap<String, &'a NodeSpec>,
    visiting: Vec<String>,
}

impl<'a> Builder<'a> {
    fn err(&self, name: &str, message: String) -> Error {
        let (line, column) = locate(self.source, name);
        Error::Scene {
            line,
            column,
            message,
        }
    }

    fn duplicate(&self, name: &str) -> Error {
        self.err(
            name,
            format!("the name \"{name}\" is defined twice; names must be unique"),
        )
    }

    fn add_primitive(&mut self, p: &PrimitiveSpec) -> Result<()> {
        if self.defined.contains_key(&p.name) {
            return Err(self.duplicate(&p.name));
        }
        let color = p.color.map_or(DEFAULT_COLOR, |c| c.0);
        let material = SurfaceMaterial {
            metallic: p.metallic,
            perceptual_roughness: p.roughness,
        };
        if let Some((field, value)) = material.out_of_range() {
            let (line, column) = locate(self.source, &p.name);
            return Err(Error::MaterialOutOfRange {
                primitive: p.name.clone(),
                field,
                value,
                line,
                column,
            });
        }
        let mut ids = Vec::with_capacity(p.shape.0.len());
        for (k, q) in p.shape.0.iter().enumerate() {
            let q = match &p.transform {
                Some(t) => q
                    .transformed(&t.0)
                    .map_err(|e| self.err(&p.name, format!("primitive \"{}\": {e}", p.name)))?,
                None => *q,
            };
            ids.push(self.dag.try_primitive_with_material(q, color, material)?);
            self.names.push(if p.shape.0.len() == 1 {
                p.name.clone()
            } else {
                format!("{}[{k}]", p.name)
            });
        }
        let id = if ids.len() == 1 {
            ids[0]
        } else {
            self.dag.intersection(&ids)?
        };
        self.defined.insert(p.name.clone(), id);
        Ok(())
    }

    fn reference(&mut self, name: &str, depth: usize) -> Result<NodeId> {
        if let Some(&id) = self.defined.get(name) {
            return Ok(id);
        }
        let Some(&spec) = self.nodes.get(name) else {
            return Err(self.err(
                name,
                format!(
                    "Ref(\"{name}\") names no primitive or node; \
                     define it under `primitives` or `nodes`"
                ),
            ));
        };
        if self.visiting.iter().any(|v| v == name) {
            return Err(self.err(
                name,
                format!("node \"{name}\" refers to itself; a scene must be acyclic"),
            ));
        }
        self.visiting.push(name.to_owned());
        let id = self.node(spec, depth + 1)?;
        self.visiting.pop();
        self.defined.insert(name.to_owned(), id);
        Ok(id)
    }

    fn list(&mut self, items: &[NodeSpec], depth: usize) -> Result<Vec<NodeId>> {
        items.iter().map(|n| self.node(n, depth + 1)).collect()
    }

    fn node(&mut self, spec: &NodeSpec, depth: usize) -> Result<NodeId> {
        if depth > MAX_DEPTH {
            return Err(Error::Scene {
                line: 0,
                column: 0,
                message: format!("the CSG expression nests deeper than {MAX_DEPTH} levels"),
            });
        }
        match &spec.0 {
            RawNode::Ref(name) => self.reference(name, depth),
            RawNode::Union(items) => {
                let ids = self.list(items, depth)?;
                self.dag.union(&ids)
            }
            RawNode::Intersection(items) => {
                let ids = self.list(items, depth)?;
                self.dag.intersection(&ids)
            }
            RawNode::Difference(items) => {
                let ids = self.list(items, depth)?;
                match ids.split_first() {
                    Some((&base, rest)) => self.dag.difference(base, rest),
                    None => Err(Error::EmptyOperation { op: "difference" }),
                }
            }
            RawNode::Complement(child) => {
                let id = self.node(child, depth + 1)?;
                self.dag.complement(id)
            }
            RawNode::Transform(t, child) => {
                let id = self.node(child, depth + 1)?;
                self.dag.transform(t.0, id)
            }
        }
    }
}
