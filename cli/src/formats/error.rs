//! The one error type of mesh file reading and writing: which file, where
//! in it, and what is wrong.

use core::fmt;
use std::path::{Path, PathBuf};

/// Where in a file a problem was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (opening it, its extension, its overall shape).
    File,
    /// A line of a text file (OBJ, ASCII PLY), counting from 1.
    Line(usize),
    /// A byte offset into a binary file (binary PLY, GLB).
    Offset(u64),
    /// A face, counting from 0 in the order of the file.
    Face(usize),
    /// A primitive of a glTF mesh.
    Primitive {
        /// The mesh index.
        mesh: usize,
        /// The primitive index within the mesh.
        primitive: usize,
    },
}

/// What is wrong.
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    /// The file could not be read or written (missing, unreadable, disk
    /// full).
    #[error("{0}")]
    Io(std::io::Error),
    /// The extension names no supported format; use `.obj`, `.ply` or
    /// `.glb`.
    #[error("{}", unknown_format(.extension.as_deref()))]
    UnknownFormat {
        /// The extension found, if any.
        extension: Option<String>,
    },
    /// A number could not be parsed.
    #[error("malformed number '{text}'")]
    MalformedNumber {
        /// The offending text.
        text: String,
    },
    /// A statement or record lacks a value.
    #[error("missing {what}")]
    Missing {
        /// What is missing, e.g. "z coordinate".
        what: &'static str,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {} has a NaN or infinite coordinate", .vertex + 1)]
    NonFinite {
        /// The vertex index, from 0 (shown from 1, as every vertex number
        /// in messages is).
        vertex: usize,
    },
    /// A face names a vertex that does not exist.
    #[error("vertex index {index} out of range (the file has {count} vertices)")]
    IndexOutOfRange {
        /// The index as written in the file.
        index: i64,
        /// How many vertices there are.
        count: usize,
    },
    /// A face has fewer than three corners.
    #[error("face with {corners} corner(s); at least 3 are needed")]
    FaceTooSmall {
        /// Its number of corners.
        corners: usize,
    },
    /// The file ends in the middle of the data.
    #[error("unexpected end of file")]
    UnexpectedEnd,
    /// The header (PLY) or container (GLB) is malformed.
    #[error("malformed file: {reason}")]
    Malformed {
        /// What was expected or found.
        reason: String,
    },
    /// Valid, but a feature this reader does not support.
    #[error("unsupported: {what}")]
    Unsupported {
        /// Which feature, and how to avoid it.
        what: String,
    },
    /// The glTF parser rejected the file.
    #[error("invalid glTF: {reason}")]
    Gltf {
        /// The parser's message.
        reason: String,
    },
    /// The file holds no triangles at all.
    #[error("no triangles in the file")]
    NoTriangles,
    /// A mesh to write is inconsistent (an index beyond the positions, a
    /// per-triangle list of the wrong length, a non-finite value).
    #[error("invalid mesh: {reason}")]
    InvalidMesh {
        /// What is inconsistent.
        reason: String,
    },
}

/// A mesh file could not be read or written.
#[derive(Debug)]
pub struct FormatError {
    /// The file.
    pub path: PathBuf,
    /// Where in it.
    pub location: Location,
    /// What is wrong.
    pub problem: Problem,
}

impl FormatError {
    /// An error in `path` at `location`.
    pub fn new(path: &Path, location: Location, problem: Problem) -> Self {
        Self {
            path: path.to_path_buf(),
            location,
            problem,
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(line) => write!(f, "line {line}: "),
            Location::Offset(offset) => write!(f, "byte offset {offset}: "),
            Location::Face(face) => write!(f, "face {face}: "),
            Location::Primitive { mesh, primitive } => {
                write!(f, "mesh {mesh}, primitive {primitive}: ")
            }
        }
    }
}

/// The text of [`Problem::UnknownFormat`].
fn unknown_format(extension: Option<&str>) -> String {
    match extension {
        Some(ext) => format!("unknown mesh format '.{ext}' (use .obj, .ply or .glb)"),
        None => "no file extension (use .obj, .ply or .glb)".into(),
    }
}

// Written out rather than derived: the source is the I/O error only when
// the problem is one, which thiserror's `#[source]` cannot say.
impl fmt::Display for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {}{}",
            self.path.display(),
            self.location,
            self.problem
        )
    }
}

impl std::error::Error for FormatError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.problem {
            Problem::Io(e) => Some(e),
            _ => None,
        }
    }
}
