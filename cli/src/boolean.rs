//! `chisel boolean A B --op union|intersection|difference -o OUT`: the
//! exact Boolean of two closed meshes (OBJ, PLY or GLB, millimetres).
//!
//! Both meshes are imported into octrees over one cube (§3.9). `B` is then
//! applied to `A` one leaf cell at a time: the convex cells of the leaf's
//! BSP inside the leaf's box are exact convex polyhedra, so their union is
//! a [`Tool`] holding exactly `B` within that box. Union adds those tools,
//! difference subtracts them, and intersection subtracts the tools made of
//! `B`'s *empty* cells (`A ∩ B = A − (cube − B)`). Every step is exact.

use std::path::PathBuf;
use std::time::Instant;

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::octree::{CellBox, Edit, Leaf, Octree, OctreeConfig, Tool};
use chisel_bsp::tree::EMPTY;
use serde_json::json;

use crate::meshfile;
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

/// What `chisel boolean` was asked to do.
pub struct BooleanArgs {
    /// First operand.
    pub a: PathBuf,
    /// Second operand.
    pub b: PathBuf,
    /// The operation.
    pub op: BooleanKind,
    /// Output mesh file.
    pub output: PathBuf,
    /// One JSON line instead of a report.
    pub json: bool,
}

/// The tool holding `B`'s cells of label `solid` (material, or empty when
/// `solid` is false) inside one leaf, or `None` when there are none.
fn leaf_tool(leaf: &Leaf, cell: CellBox, solid: bool) -> Result<Option<Tool>, String> {
    let wanted = |label| (label != EMPTY) == solid;
    match leaf {
        Leaf::Uniform(label) if wanted(*label) => {
            Tool::cuboid(cell).map(Some).map_err(|e| e.to_string())
        }
        Leaf::Uniform(_) => Ok(None),
        Leaf::Bsp(bsp) => {
            let mut arena = ConvexArena::new();
            let bounds = cell.add_to(&mut arena).map_err(|e| e.to_string())?;
            let pieces: Vec<Tool> = bsp
                .cells(&mut arena, bounds)
                .into_iter()
                .filter(|c| wanted(c.label))
                .map(|c| Tool::from_polyhedron(&arena, c.poly))
                .collect();
            if pieces.is_empty() {
                return Ok(None);
            }
            Tool::union(&pieces).map(Some).map_err(|e| e.to_string())
        }
    }
}

/// Runs the command; errors are messages for the user.
pub fn run(args: &BooleanArgs) -> Result<(), String> {
    let start = Instant::now();
    let a = meshfile::read_grid(&args.a)?;
    let b = meshfile::read_grid(&args.b)?;
    let bounds = CellBox {
        min: [0, 1, 2].map(|i| a.bounds.min[i].min(b.bounds.min[i])),
        max: [0, 1, 2].map(|i| a.bounds.max[i].max(b.bounds.max[i])),
    };
    let (origin, size_log2) = root_cube(bounds)?;
    let config = OctreeConfig::default();
    let import = |mesh: &meshfile::GridMesh, path: &PathBuf| {
        Octree::from_triangles(origin, size_log2, &mesh.triangles, 1, config)
            .map_err(|e| format!("{}: {e}", path.display()))
    };
    let mut result = import(&a, &args.a)?;
    let other = import(&b, &args.b)?;
    let imported = start.elapsed().as_secs_f64();
    let (volume_a, volume_b) = (result.solid_volume(), other.solid_volume());
    let (edit, solid) = match args.op {
        BooleanKind::Union => (Edit::Add(1), true),
        BooleanKind::Difference => (Edit::Subtract, true),
        BooleanKind::Intersection => (Edit::Subtract, false),
    };
    let mut tools = 0;
    for (key, leaf) in other.leaves() {
        if let Some(tool) = leaf_tool(leaf, other.cell_box(key), solid)? {
            result.apply(&tool, edit).map_err(|e| e.to_string())?;
            tools += 1;
        }
    }
    let (mesh, closure) = extract::whole(&result);
    let seconds = start.elapsed().as_secs_f64();
    meshfile::write(&args.output, &mesh)?;
    let mm3 = |v: f64| v / 1e9;
    let figures = json!({
        "op": format!("{:?}", args.op).to_lowercase(),
        "a_triangles": a.triangles.len(),
        "b_triangles": b.triangles.len(),
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
        println!(
            "{:?} of {} ({} triangles, {:.6} mm³) and {} ({} triangles, {:.6} mm³)",
            args.op,
            args.a.display(),
            a.triangles.len(),
            mm3(volume_a),
            args.b.display(),
            b.triangles.len(),
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
