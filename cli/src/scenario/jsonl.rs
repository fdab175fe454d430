//! The replay format: one JSON object per line, coordinates in millimetres.
//!
//! ```text
//! {"base": {"box": [[x0, y0, z0], [x1, y1, z1]]}}     first line: the base solid,
//! {"base": {"mesh": "part.glb"}}                      or a closed mesh (OBJ/PLY/GLB)
//! {"base": {"mesh": "part.chisel"}}                   or an exact octree file,
//! {"base": "empty"}                                   or nothing (unions build it)
//! {"op": "subtract", "hull": [[x, y, z], ...]}        then one line per step:
//! {"op": "union", "hull": [[x, y, z], ...]}           the tool is the convex hull
//! {"op": "intersect", "hull": [[x, y, z], ...]}       of the points
//! ```
//!
//! An exact octree file (`.chisel`, written by `--export FILE.chisel`) is
//! used as stored, with no re-import. Points are quantized to the 1 µm grid
//! on reading. A recorded file holds
//! the grid points exactly (their shortest decimals in millimetres), so a
//! replay, or a peer given the same file, applies exactly the same tools.
//! Blank lines are ignored; anything else malformed is an error naming its
//! line.

use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use chisel_bsp::octree::CellBox;
use serde::Deserialize;
use serde_json::json;

use super::sequence::{Base, Op, Sequence, Step, quantize_mm, spans_volume, to_mm};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BaseLine {
    base: BaseSpec,
}

#[derive(Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
enum BaseSpec {
    Box([[f64; 3]; 2]),
    Mesh(PathBuf),
    Empty,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StepLine {
    op: OpName,
    hull: Vec<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(rename_all = "lowercase")]
enum OpName {
    Subtract,
    Union,
    Intersect,
}

fn quantize_point(p: [f64; 3]) -> Result<[i64; 3], String> {
    Ok([quantize_mm(p[0])?, quantize_mm(p[1])?, quantize_mm(p[2])?])
}

fn parse_base(text: &str, dir: &Path) -> Result<Base, String> {
    let line: BaseLine = serde_json::from_str(text).map_err(|e| {
        format!("{e}; the first line must be {{\"base\": {{\"box\": [[x0,y0,z0],[x1,y1,z1]]}}}}, {{\"base\": {{\"mesh\": \"FILE\"}}}} or {{\"base\": \"empty\"}}")
    })?;
    Ok(match line.base {
        BaseSpec::Empty => Base::Empty,
        BaseSpec::Mesh(path) => Base::Mesh(dir.join(path)),
        BaseSpec::Box([min, max]) => {
            let b = CellBox {
                min: quantize_point(min)?,
                max: quantize_point(max)?,
            };
            if (0..3).any(|a| b.min[a] >= b.max[a]) {
                return Err("the base box must have min < max on every axis (at 1 µm)".into());
            }
            Base::Box(b)
        }
    })
}

fn parse_step(text: &str) -> Result<Step, String> {
    let line: StepLine = serde_json::from_str(text).map_err(|e| {
        format!("{e}; a step is {{\"op\": \"subtract\"|\"union\"|\"intersect\", \"hull\": [[x,y,z], ...]}}")
    })?;
    if line.hull.len() < 4 {
        return Err(format!(
            "a hull needs at least 4 points, got {}",
            line.hull.len()
        ));
    }
    let hull: Vec<[i64; 3]> = line
        .hull
        .into_iter()
        .map(quantize_point)
        .collect::<Result<_, _>>()?;
    if !spans_volume(&hull) {
        return Err("the hull points are coplanar (at 1 µm): the tool has no volume".into());
    }
    Ok(Step {
        op: match line.op {
            OpName::Subtract => Op::Subtract,
            OpName::Union => Op::Union,
            OpName::Intersect => Op::Intersect,
        },
        hull,
    })
}

/// Reads a replay file; a relative mesh path is taken from the file's
/// folder.
///
/// # Errors
/// A message naming the file and line of the first malformed line.
pub fn read(path: &Path) -> Result<Sequence, String> {
    let file = File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse(BufReader::new(file), dir).map_err(|e| format!("{}:{e}", path.display()))
}

/// Parses a replay sequence; errors start with the line number.
///
/// # Errors
/// `"LINE: what is wrong"` for the first malformed line, or a missing base.
pub fn parse(reader: impl BufRead, dir: &Path) -> Result<Sequence, String> {
    let mut base = None;
    let mut steps = Vec::new();
    for (i, line) in reader.lines().enumerate() {
        let number = i + 1;
        let line = line.map_err(|e| format!("{number}: {e}"))?;
        let text = line.trim();
        if text.is_empty() {
            continue;
        }
        if base.is_none() {
            base = Some(parse_base(text, dir).map_err(|e| format!("{number}: {e}"))?);
        } else {
            steps.push(parse_step(text).map_err(|e| format!("{number}: {e}"))?);
        }
    }
    let base = base.ok_or("1: the file is empty; the first line must give the base")?;
    Ok(Sequence { base, steps })
}

/// Writes `sequence` in the replay format.
///
/// # Errors
/// A message naming the file when it cannot be written.
pub fn write(path: &Path, sequence: &Sequence) -> Result<(), String> {
    let fail = |e: std::io::Error| format!("{}: {e}", path.display());
    crate::atomic::write_with(path, |out| write_to(out, sequence)).map_err(fail)
}

fn write_to(out: &mut impl Write, sequence: &Sequence) -> std::io::Result<()> {
    let base = match &sequence.base {
        Base::Empty => json!({ "base": "empty" }),
        // Absolute, so that the file can be replayed from any folder.
        Base::Mesh(mesh) => {
            let mesh = std::fs::canonicalize(mesh).unwrap_or_else(|_| mesh.clone());
            json!({ "base": { "mesh": mesh } })
        }
        Base::Box(b) => json!({ "base": { "box": [point_mm(b.min), point_mm(b.max)] } }),
    };
    writeln!(out, "{base}")?;
    for step in &sequence.steps {
        let hull: Vec<[f64; 3]> = step.hull.iter().map(|&p| point_mm(p)).collect();
        writeln!(out, "{}", json!({ "op": step.op.name(), "hull": hull }))?;
    }
    Ok(())
}

fn point_mm(p: [i64; 3]) -> [f64; 3] {
    p.map(to_mm)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_text(text: &str) -> Result<Sequence, String> {
        parse(text.as_bytes(), Path::new("/data"))
    }

    #[test]
    fn parses_bases_and_steps_in_millimetres() {
        let seq = parse_text(
            "{\"base\": {\"box\": [[0,0,0],[100,100,40.5]]}}\n\n\
             {\"op\": \"subtract\", \"hull\": [[0,0,0],[1,0,0],[0,1,0],[0,0,0.0015]]}\n",
        )
        .unwrap();
        assert_eq!(
            seq.base,
            Base::Box(CellBox {
                min: [0; 3],
                max: [100_000, 100_000, 40_500]
            })
        );
        assert_eq!(seq.steps.len(), 1);
        assert_eq!(seq.steps[0].op, Op::Subtract);
        assert_eq!(seq.steps[0].hull[3], [0, 0, 2]);
        let seq = parse_text("{\"base\": {\"mesh\": \"a.obj\"}}").unwrap();
        assert_eq!(seq.base, Base::Mesh(PathBuf::from("/data/a.obj")));
        assert_eq!(
            parse_text("{\"base\": \"empty\"}").unwrap().base,
            Base::Empty
        );
    }

    #[test]
    fn written_sequences_read_back_identically() {
        let seq = Sequence {
            base: Base::Box(CellBox {
                min: [-1, 0, 3],
                max: [100_000, 100_001, 40_000],
            }),
            steps: vec![Step {
                op: Op::Intersect,
                hull: vec![[0, 0, 0], [1, 0, 0], [0, 12_345, 0], [0, 0, -7_777_777]],
            }],
        };
        let path = std::env::temp_dir().join(format!("chisel-jsonl-{}.jsonl", std::process::id()));
        write(&path, &seq).unwrap();
        let back = read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(back, seq);
    }

    #[test]
    fn malformed_lines_are_named() {
        let base = "{\"base\": {\"box\": [[0,0,0],[1,1,1]]}}\n";
        for (text, line) in [
            ("", "1:"),
            ("{\"op\": \"subtract\", \"hull\": []}", "1:"),
            ("{\"base\": {\"box\": [[0,0,0],[0,1,1]]}}", "1:"),
            (&format!("{base}{{\"op\": \"cut\", \"hull\": []}}"), "2:"),
            (
                &format!("{base}\n{{\"op\": \"union\", \"hull\": [[0,0,0]]}}"),
                "3:",
            ),
            (
                &format!(
                    "{base}{{\"op\": \"union\", \"hull\": [[0,0,1e9],[0,0,0],[1,0,0],[0,1,0]]}}"
                ),
                "2:",
            ),
            (&format!("{base}not json"), "2:"),
            (
                &format!(
                    "{base}{{\"op\": \"union\", \"hull\": [[0,0,0],[1,0,0],[0,1,0],[1,1,0]]}}"
                ),
                "2:",
            ),
        ] {
            let err = parse_text(text).unwrap_err();
            assert!(err.starts_with(line), "{text:?}: {err}");
        }
    }
}
