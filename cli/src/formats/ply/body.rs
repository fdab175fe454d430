//! The PLY body: one line of tokens per item (ASCII) or packed
//! little-endian values (binary), read element by element.

use super::header::{Element, Kind, Scalar};
use crate::formats::{Location, Problem};

/// A value read from the body.
#[derive(Clone, Copy, Debug)]
pub(super) enum Value {
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
pub(super) enum At {
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
pub(super) trait Body {
    fn begin_item(&mut self) -> Result<(), (At, Problem)>;
    fn read(&mut self, scalar: Scalar) -> Result<Value, (At, Problem)>;
    fn at(&self) -> At;
}

/// The lines of an ASCII body, numbered from 0.
pub(super) type Lines<'a> = std::iter::Enumerate<std::slice::Split<'a, u8, fn(&u8) -> bool>>;

pub(super) struct AsciiBody<'a> {
    pub(super) lines: Lines<'a>,
    pub(super) first_line: usize,
    pub(super) line: usize,
    pub(super) tokens: Vec<String>,
    pub(super) next: usize,
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

pub(super) struct BinaryBody<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    /// Offset of `data[0]` in the file.
    pub(super) base: usize,
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

pub(super) type Parsed = (Vec<[f64; 3]>, Vec<Vec<i64>>);

/// Reads every element; keeps vertex positions and face corner lists.
/// `available` bounds the counts (each item takes at least a byte), so a
/// corrupt count cannot make it allocate without limit.
pub(super) fn read_body(
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
