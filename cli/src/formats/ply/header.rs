//! The PLY header: format line, elements, and their scalar and list
//! properties.

use std::path::Path;

use crate::formats::{FormatError, Location, Problem};

/// A scalar type of the PLY header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
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

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(super) fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) properties: Vec<(String, Kind)>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    BinaryLittleEndian,
}

/// The parsed header and where the body starts.
pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) elements: Vec<Element>,
    pub(super) body_offset: usize,
    pub(super) body_line: usize,
}

pub(super) fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, FormatError> {
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
