//! `chisel boolean A B --op union|intersection|difference -o OUT`: the
//! exact Boolean of two solids, each a closed mesh (OBJ, PLY or GLB,
//! millimetres) or an exact octree file (`.chisel`); the result is written
//! as a mesh or, for an `OUT` ending in `.chisel`, as an exact octree.
//!
//! Both operands go into octrees over one cube: meshes are imported
//! (§3.9); an octree file is used as stored when its cube holds both
//! solids, else moved into the common cube exactly. `B` is then applied to
//! `A` one leaf cell at a time: the convex cells of the leaf's BSP inside
//! the leaf's box are exact convex polyhedra, so their union is a [`Tool`]
//! holding exactly `B` within that box. Union adds those tools (each of
//! `B`'s materials as itself), difference subtracts them, and intersection
//! subtracts the tools made of `B`'s *empty* cells (`A ∩ B = A − (cube −
//! B)`). Every step is exact, so with octree files `A ∩ A` is `A` and
//! `A − A` is empty.

use std::path::{Path, PathBuf};
use std::time::Instant;

use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
use chisel_bsp::tree::EMPTY;
use serde_json::json;

use crate::failure::Failure;
use crate::meshfile;
use crate::octree_file::{self, leaf_tool};
use crate::scenario::extract;
use crate::scenario::sequence::root_cube;

/// The Boolean operations on two solids.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BooleanKind {
    /// Material of A or B.
    Union,
    /// Material of both A and B.
    Intersection,
    /// Material of A that is not in B.
    Difference,
}

/// What `chisel boolean` was asked to do: its command-line arguments.
#[derive(clap::Args)]
pub struct BooleanArgs {
    /// First operand (.obj, .ply, .glb or .chisel).
    pub a: PathBuf,
    /// Second operand (.obj, .ply, .glb or .chisel).
    pub b: PathBuf,
    /// The operation.
    #[arg(long, value_enum)]
    pub op: BooleanKind,
    /// Output: a mesh (.obj, .ply or .glb) or the exact octree
    /// (.chisel).
    #[arg(short, long)]
    pub output: PathBuf,
    /// One line of JSON instead of a report.
    #[arg(long)]
    pub json: bool,
}

/// One operand as read: a mesh to import, or an exact octree file.
enum Operand {
    Mesh(meshfile::GridMesh),
    Octree(Octree),
}

impl Operand {
    fn read(path: &Path) -> Result<Operand, String> {
        if octree_file::is_octree_file(path) {
            octree_file::read(path).map(Operand::Octree)
        } else {
            meshfile::read_grid(path).map(Operand::Mesh)
        }
    }

    /// A box around the operand's material (`None` for an empty octree).
    fn bounds(&self) -> Option<CellBox> {
        match self {
            Operand::Mesh(mesh) => Some(mesh.bounds),
            Operand::Octree(octree) => octree_file::solid_bounds(octree),
        }
    }

    /// The octree's cube, when it holds `bounds`.
    fn cube_holding(&self, bounds: &CellBox) -> Option<([i64; 3], u8)> {
        match self {
            Operand::Octree(o) if octree_file::holds(&o.root_box(), bounds) => {
                Some((o.origin(), o.size_log2()))
            }
            _ => None,
        }
    }

    fn triangles(&self) -> Option<usize> {
        match self {
            Operand::Mesh(mesh) => Some(mesh.triangles.len()),
            Operand::Octree(_) => None,
        }
    }

    /// The operand as an octree over the cube `(origin, size_log2)`:
    /// imported (a mesh), as stored (an octree over that cube) or moved
    /// there exactly.
    fn into_octree(
        self,
        origin: [i64; 3],
        size_log2: u8,
        config: OctreeConfig,
        path: &Path,
    ) -> Result<Octree, String> {
        match self {
            Operand::Mesh(mesh) => {
                Octree::from_triangles(origin, size_log2, &mesh.triangles, 1, config)
                    .map_err(|e| format!("{}: {e}", path.display()))
            }
            Operand::Octree(octree) => octree_file::embed(octree, origin, size_log2)
                .map_err(|e| format!("{}: {e}", path.display())),
        }
    }
}

/// The cube both operands go into: an operand octree's own cube when it
/// holds both solids (first `A`'s, then `B`'s; no copy needed), else the
/// smallest cube around both.
fn common_cube(a: &Operand, b: &Operand) -> Result<([i64; 3], u8), String> {
    let bounds = [a.bounds(), b.bounds()]
        .into_iter()
        .flatten()
        .reduce(|x, y| CellBox {
            min: [0, 1, 2].map(|i| x.min[i].min(y.min[i])),
            max: [0, 1, 2].map(|i| x.max[i].max(y.max[i])),
        });
    let Some(bounds) = bounds else {
        // Both empty: any cube of an operand will do.
        return match (a, b) {
            (Operand::Octree(o), _) | (_, Operand::Octree(o)) => Ok((o.origin(), o.size_log2())),
            _ => root_cube(CellBox {
                min: [0; 3],
                max: [2; 3],
            }),
        };
    };
    match a.cube_holding(&bounds).or_else(|| b.cube_holding(&bounds)) {
        Some(cube) => Ok(cube),
        None => root_cube(bounds),
    }
}

/// Runs the command; errors are messages for the user.
pub fn run(args: &BooleanArgs) -> Result<(), Failure> {
    crate::failure::check_output(&args.output, true)?;
    let start = Instant::now();
    let a = Operand::read(&args.a)?;
    let b = Operand::read(&args.b)?;
    let (a_triangles, b_triangles) = (a.triangles(), b.triangles());
    let (origin, size_log2) = common_cube(&a, &b)?;
    let config = match &a {
        Operand::Octree(octree) => *octree.config(),
        Operand::Mesh(_) => OctreeConfig::default(),
    };
    let mut result = a.into_octree(origin, size_log2, config, &args.a)?;
    let other = b.into_octree(origin, size_log2, config, &args.b)?;
    let imported = start.elapsed().as_secs_f64();
    let (volume_a, volume_b) = (result.solid_volume(), other.solid_volume());
    let mut tools = 0;
    for (key, leaf) in other.leaves() {
        let cell = other.cell_box(key);
        // Union adds each of B's materials as itself; difference removes
        // all of them; intersection removes B's empty space.
        let steps: Vec<(Edit, Option<Tool>)> = match args.op {
            BooleanKind::Union => octree_file::leaf_labels(leaf)
                .into_iter()
                .filter(|&l| l != EMPTY)
                .map(|label| Ok((Edit::Add(label), leaf_tool(leaf, cell, |l| l == label)?)))
                .collect::<Result<_, String>>()?,
            BooleanKind::Difference => {
                vec![(Edit::Subtract, leaf_tool(leaf, cell, |l| l != EMPTY)?)]
            }
            BooleanKind::Intersection => {
                vec![(Edit::Subtract, leaf_tool(leaf, cell, |l| l == EMPTY)?)]
            }
        };
        for (edit, tool) in steps {
            if let Some(tool) = tool {
                result.apply(&tool, edit).map_err(|e| e.to_string())?;
                tools += 1;
            }
        }
    }
    let (mesh, closure) = extract::whole(&result);
    let seconds = start.elapsed().as_secs_f64();
    if octree_file::is_octree_file(&args.output) {
        octree_file::write(&args.output, &result).map_err(Failure::write)?;
    } else {
        meshfile::write(&args.output, &mesh).map_err(Failure::write)?;
    }
    // `+ 0.0` reports an empty result as 0, not −0.
    let mm3 = |v: f64| v / 1e9 + 0.0;
    let figures = json!({
        "op": format!("{:?}", args.op).to_lowercase(),
        "a_triangles": a_triangles,
        "b_triangles": b_triangles,
        "a_volume_mm3": mm3(volume_a),
        "b_volume_mm3": mm3(volume_b),
        "volume_mm3": mm3(result.solid_volume()),
        "triangles": mesh.len(),
        "closed": closure.closed,
        "watertight": closure.manifold,
        "tools": tools,
        "import_seconds": imported,
        "seconds": seconds,
        "output": args.output,
    });
    if args.json {
        println!("{figures}");
    } else {
        let size = |triangles: Option<usize>| {
            triangles.map_or_else(|| "exact octree".to_string(), |t| format!("{t} triangles"))
        };
        println!(
            "{:?} of {} ({}, {:.6} mm³) and {} ({}, {:.6} mm³)",
            args.op,
            args.a.display(),
            size(a_triangles),
            mm3(volume_a),
            args.b.display(),
            size(b_triangles),
            mm3(volume_b)
        );
        println!(
            "result: {} triangles ({}), volume {:.6} mm³, in {seconds:.3} s ({imported:.3} s import)",
            mesh.len(),
            match (closure.closed, closure.manifold) {
                (true, true) => "watertight",
                (true, false) => "closed, touching itself along edges",
                _ => "NOT closed",
            },
            mm3(result.solid_volume())
        );
        println!("wrote {}", args.output.display());
    }
    Ok(())
}
