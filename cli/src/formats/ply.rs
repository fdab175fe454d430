//! Stanford PLY: a text header declaring elements and their properties,
//! then an ASCII or binary little-endian body. The `vertex` element gives
//! `x, y, z`; the `face` element's list property `vertex_indices` (or
//! `vertex_index`) gives polygons, fan-triangulated. Other elements and
//! properties are read past and ignored. Written as binary little-endian
//! with a normal and a material label per face.

use std::fmt::Write as _;
use std::path::Path;

use chisel_bsp::mesh::TriangleMesh;

use super::{FormatError, Location, Problem, TriangleSoup, push_fan};

/// A scalar type of the PLY header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<(String, Kind)>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLittleEndian,
}

/// A value read from the body.
#[derive(Clone, Copy, Debug)]
enum Value {
    Int(i64),
    Float(f64),
}

impl Value {
    fn as_f64(self) -> f64 {
        match self {
            Value::Int(i) => i as f64,
            Value::Float(f) => f,
        }
    }
}

/// Where a value was read (for errors).
#[derive(Clone, Copy)]
enum At {
    Line(usize),
    Offset(usize),
}

impl From<At> for Location {
    fn from(at: At) -> Location {
        match at {
            At::Line(line) => Location::Line(line),
            At::Offset(offset) => Location::Offset(offset as u64),
        }
    }
}

/// The body reader: tokens of one line per item (ASCII) or bytes (binary).
trait Body {
    fn begin_item(&mut self) -> Result<(), (At, Problem)>;
    fn read(&mut self, scalar: Scalar) -> Result<Value, (At, Problem)>;
    fn at(&self) -> At;
}

/// The lines of an ASCII body, numbered from 0.
type Lines<'a> = std::iter::Enumerate<std::slice::Split<'a, u8, fn(&u8) -> bool>>;

struct AsciiBody<'a> {
    lines: Lines<'a>,
    first_line: usize,
    line: usize,
    tokens: Vec<String>,
    next: usize,
}

impl Body for AsciiBody<'_> {
    fn begin_item(&mut self) -> Result<(), (At, Problem)> {
        loop {
            let Some((i, raw)) = self.lines.next() else {
                return Err((At::Line(self.line + 1), Problem::UnexpectedEnd));
            };
            self.line = self.first_line + i;
            let text = String::from_utf8_lossy(raw);
            self.tokens = text.split_whitespace().map(str::to_string).collect();
            self.next = 0;
            if !self.tokens.is_empty() {
                return Ok(());
            }
        }
    }

    fn read(&mut self, scalar: Scalar) -> Result<Value, (At, Problem)> {
        let at = At::Line(self.line);
        let token = self.tokens.get(self.next).ok_or((
            at,
            Problem::Missing {
                what: "property value",
            },
        ))?;
        self.next += 1;
        let malformed = || {
            (
                at,
                Problem::MalformedNumber {
                    text: token.clone(),
                },
            )
        };
        if scalar.is_integer() {
            token
                .parse::<i64>()
                .map(Value::Int)
                .map_err(|_| malformed())
        } else {
            token
                .parse::<f64>()
                .map(Value::Float)
                .map_err(|_| malformed())
        }
    }

    fn at(&self) -> At {
        At::Line(self.line)
    }
}

struct BinaryBody<'a> {
    data: &'a [u8],
    pos: usize,
    /// Offset of `data[0]` in the file.
    base: usize,
}

impl Body for BinaryBody<'_> {
    fn begin_item(&mut self) -> Result<(), (At, Problem)> {
        Ok(())
    }

    fn read(&mut self, scalar: Scalar) -> Result<Value, (At, Problem)> {
        let n = scalar.size();
        let bytes = self
            .data
            .get(self.pos..self.pos + n)
            .ok_or((At::Offset(self.base + self.pos), Problem::UnexpectedEnd))?;
        self.pos += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(bytes);
        Ok(match scalar {
            Scalar::I8 => Value::Int(b[0] as i8 as i64),
            Scalar::U8 => Value::Int(b[0] as i64),
            Scalar::I16 => Value::Int(i16::from_le_bytes([b[0], b[1]]) as i64),
            Scalar::U16 => Value::Int(u16::from_le_bytes([b[0], b[1]]) as i64),
            Scalar::I32 => Value::Int(i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64),
            Scalar::U32 => Value::Int(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64),
            Scalar::F32 => Value::Float(f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64),
            Scalar::F64 => Value::Float(f64::from_le_bytes(b)),
        })
    }

    fn at(&self) -> At {
        At::Offset(self.base + self.pos)
    }
}

/// The parsed header and where the body starts.
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    body_offset: usize,
    body_line: usize,
}

fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, FormatError> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut offset = 0;
    let mut line = 0;
    loop {
        line += 1;
        let malformed = |reason: String| {
            FormatError::new(path, Location::Line(line), Problem::Malformed { reason })
        };
        let Some(end) = bytes[offset..].iter().position(|&b| b == b'\n') else {
            return Err(FormatError::new(
                path,
                Location::Line(line),
                if line == 1 {
                    Problem::Malformed {
                        reason: "not a PLY file (no 'ply' line)".into(),
                    }
                } else {
                    Problem::UnexpectedEnd
                },
            ));
        };
        let text = String::from_utf8_lossy(&bytes[offset..offset + end]).into_owned();
        offset += end + 1;
        let words: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if words != ["ply"] {
                return Err(malformed("not a PLY file (no 'ply' line)".into()));
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", kind, version] => {
                if *version != "1.0" {
                    return Err(malformed(format!("format version {version}, not 1.0")));
                }
                encoding = Some(match *kind {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => {
                        return Err(FormatError::new(
                            path,
                            Location::Line(line),
                            Problem::Unsupported {
                                what: "binary big-endian PLY (convert to little-endian or ASCII)"
                                    .into(),
                            },
                        ));
                    }
                    other => return Err(malformed(format!("unknown PLY format '{other}'"))),
                });
            }
            ["element", name, count] => {
                let count = count.parse::<usize>().map_err(|_| {
                    FormatError::new(
                        path,
                        Location::Line(line),
                        Problem::MalformedNumber {
                            text: count.to_string(),
                        },
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count, item, name] => {
                let (Some(count), Some(item)) = (Scalar::parse(count), Scalar::parse(item)) else {
                    return Err(malformed(format!("unknown type in '{text}'")));
                };
                if !count.is_integer() {
                    return Err(malformed(format!(
                        "list count type must be an integer in '{text}'"
                    )));
                }
                let element = elements
                    .last_mut()
                    .ok_or_else(|| malformed("property before any element".into()))?;
                element
                    .properties
                    .push((name.to_string(), Kind::List { count, item }));
            }
            ["property", kind, name] => {
                let scalar = Scalar::parse(kind)
                    .ok_or_else(|| malformed(format!("unknown type '{kind}'")))?;
                let element = elements
                    .last_mut()
                    .ok_or_else(|| malformed("property before any element".into()))?;
                element
                    .properties
                    .push((name.to_string(), Kind::Scalar(scalar)));
            }
            ["end_header"] => {
                let encoding = encoding
                    .ok_or_else(|| malformed("end of header before a format line".into()))?;
                return Ok(Header {
                    encoding,
                    elements,
                    body_offset: offset,
                    body_line: line + 1,
                });
            }
            _ => return Err(malformed(format!("unexpected header line '{text}'"))),
        }
    }
}

/// Parses PLY content.
pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<TriangleSoup, FormatError> {
    let header = parse_header(bytes, path)?;
    let body = &bytes[header.body_offset..];
    let result = match header.encoding {
        Encoding::Ascii => {
            let split: fn(&u8) -> bool = |&b| b == b'\n';
            let mut reader = AsciiBody {
                lines: body.split(split).enumerate(),
                first_line: header.body_line,
                line: header.body_line,
                tokens: Vec::new(),
                next: 0,
            };
            read_body(&header.elements, &mut reader, body.len())
        }
        Encoding::BinaryLittleEndian => {
            let mut reader = BinaryBody {
                data: body,
                pos: 0,
                base: header.body_offset,
            };
            read_body(&header.elements, &mut reader, body.len())
        }
    };
    let (positions, faces) =
        result.map_err(|(at, problem)| FormatError::new(path, at.into(), problem))?;
    let count = positions.len();
    let mut soup = TriangleSoup {
        positions,
        triangles: Vec::new(),
    };
    for (f, corners) in faces.iter().enumerate() {
        let err = |problem| FormatError::new(path, Location::Face(f), problem);
        if corners.len() < 3 {
            return Err(err(Problem::FaceTooSmall {
                corners: corners.len(),
            }));
        }
        if let Some(&index) = corners.iter().find(|&&i| i < 0 || i >= count as i64) {
            return Err(err(Problem::IndexOutOfRange { index, count }));
        }
        let corners: Vec<u32> = corners.iter().map(|&i| i as u32).collect();
        push_fan(&mut soup.triangles, &corners);
    }
    Ok(soup)
}

type Parsed = (Vec<[f64; 3]>, Vec<Vec<i64>>);

/// Reads every element; keeps vertex positions and face corner lists.
/// `available` bounds the counts (each item takes at least a byte), so a
/// corrupt count cannot make it allocate without limit.
fn read_body(
    elements: &[Element],
    body: &mut impl Body,
    available: usize,
) -> Result<Parsed, (At, Problem)> {
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for element in elements {
        let find = |name: &str| element.properties.iter().position(|(n, _)| n == name);
        let start = body.at();
        let malformed = |reason: String| (start, Problem::Malformed { reason });
        let xyz = if element.name == "vertex" {
            let mut xyz = [0; 3];
            for (slot, name) in xyz.iter_mut().zip(["x", "y", "z"]) {
                let i = find(name)
                    .ok_or_else(|| malformed(format!("vertex element has no property '{name}'")))?;
                if matches!(element.properties[i].1, Kind::List { .. }) {
                    return Err(malformed(format!("vertex property '{name}' is a list")));
                }
                *slot = i;
            }
            Some(xyz)
        } else {
            None
        };
        let corners = if element.name == "face" {
            let i = find("vertex_indices")
                .or_else(|| find("vertex_index"))
                .ok_or_else(|| malformed("face element has no list 'vertex_indices'".into()))?;
            match element.properties[i].1 {
                Kind::List { item, .. } if item.is_integer() => Some(i),
                _ => {
                    return Err(malformed(
                        "face property 'vertex_indices' is not a list of integers".into(),
                    ));
                }
            }
        } else {
            None
        };
        if element.count > available {
            return Err((body.at(), Problem::UnexpectedEnd));
        }
        for _ in 0..element.count {
            body.begin_item()?;
            let mut p = [0.0; 3];
            let mut list = Vec::new();
            let item_at = body.at();
            for (i, (_, kind)) in element.properties.iter().enumerate() {
                match *kind {
                    Kind::Scalar(scalar) => {
                        let value = body.read(scalar)?;
                        if let Some(axis) = xyz.and_then(|xyz| xyz.iter().position(|&j| j == i)) {
                            p[axis] = value.as_f64();
                        }
                    }
                    Kind::List { count, item } => {
                        let at = body.at();
                        let n = match body.read(count)? {
                            Value::Int(n) if n >= 0 && (n as usize) <= available => n as usize,
                            other => {
                                return Err((
                                    at,
                                    Problem::Malformed {
                                        reason: format!("list length {}", other.as_f64()),
                                    },
                                ));
                            }
                        };
                        let keep = corners == Some(i);
                        for _ in 0..n {
                            let value = body.read(item)?;
                            if keep && let Value::Int(v) = value {
                                list.push(v);
                            }
                        }
                    }
                }
            }
            if xyz.is_some() {
                if p.iter().any(|c| !c.is_finite()) {
                    return Err((
                        item_at,
                        Problem::NonFinite {
                            vertex: positions.len(),
                        },
                    ));
                }
                positions.push(p);
            }
            if corners.is_some() {
                faces.push(list);
            }
        }
    }
    if u32::try_from(positions.len()).is_err() {
        return Err((
            body.at(),
            Problem::Unsupported {
                what: "more than 2^32 − 1 vertices".into(),
            },
        ));
    }
    Ok((positions, faces))
}

/// Encodes a (checked) mesh as binary little-endian PLY with `x, y, z`
/// vertices and faces carrying `vertex_indices`, a normal and a material
/// label.
pub(super) fn encode(mesh: &TriangleMesh) -> Vec<u8> {
    let mut header = String::new();
    let _ = write!(
        header,
        "ply\nformat binary_little_endian 1.0\ncomment chisel surface mesh\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar uint vertex_indices\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty uchar material\n\
         end_header\n",
        mesh.positions.len(),
        mesh.indices.len()
    );
    let mut out = header.into_bytes();
    out.reserve(12 * mesh.positions.len() + 26 * mesh.indices.len());
    for p in &mesh.positions {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for ((triangle, normal), label) in mesh.indices.iter().zip(&mesh.normals).zip(&mesh.labels) {
        out.push(3);
        for v in triangle {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for c in normal {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out.push(*label);
    }
    out
}
