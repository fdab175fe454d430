//! How a failed command ends: a message on standard error and an exit
//! code saying what kind of failure it was (README, "Exit codes").

/// The exit code of a failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// 2: the command line is wrong (an unknown option, a value out of its
    /// range, an output name with an unknown extension); nothing was read.
    Usage = 2,
    /// 3: an input is unreadable, malformed or outside what the kernels
    /// accept (an open or inside-out mesh, out-of-range coordinates, a
    /// damaged `.chisel` file, a limit passed).
    Data = 3,
    /// 4: `--check` found a step breaking an invariant.
    Check = 4,
    /// 5: an output could not be written (any existing file is kept).
    Write = 5,
}

/// A failed command: what to print and how to exit.
#[derive(Clone, Debug)]
pub struct Failure {
    /// The kind, and so the exit code.
    pub exit: Exit,
    /// The message for the user.
    pub message: String,
}

impl Failure {
    /// A usage failure.
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            exit: Exit::Usage,
            message: message.into(),
        }
    }

    /// A failed `--check`.
    pub fn check(message: impl Into<String>) -> Self {
        Self {
            exit: Exit::Check,
            message: message.into(),
        }
    }

    /// A failed write.
    pub fn write(message: impl Into<String>) -> Self {
        Self {
            exit: Exit::Write,
            message: message.into(),
        }
    }
}

/// Messages from reading and computing are data failures.
impl From<String> for Failure {
    fn from(message: String) -> Self {
        Self {
            exit: Exit::Data,
            message,
        }
    }
}

/// Fails with [`Exit::Usage`] unless the folder that would hold `path`
/// exists, and, for `mesh_or_octree`, unless its extension names a format
/// the commands write (`.obj`, `.ply`, `.glb` or `.chisel`): checked
/// before any work starts.
pub fn check_output(path: &std::path::Path, mesh_or_octree: bool) -> Result<(), Failure> {
    if mesh_or_octree
        && !crate::octree_file::is_octree_file(path)
        && crate::formats::MeshFormat::from_path(path).is_err()
    {
        let what = path.extension().map_or_else(
            || "no file extension".to_owned(),
            |ext| format!("unknown output format '.{}'", ext.to_string_lossy()),
        );
        return Err(Failure::usage(format!(
            "{}: {what} (use .obj, .ply, .glb or .chisel)",
            path.display()
        )));
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if !folder.is_dir() {
        return Err(Failure::usage(format!(
            "{}: the folder {} does not exist",
            path.display(),
            folder.display()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{Exit, Failure};

    /// The codes of the README's exit-code table, one per kind of failure
    /// (a failed `--check` cannot be provoked from outside: the invariants
    /// hold on every input the commands accept).
    #[test]
    fn each_kind_of_failure_has_its_documented_code() {
        let kinds = [
            (Failure::usage("u"), Exit::Usage, 2),
            (Failure::from("d".to_string()), Exit::Data, 3),
            (Failure::check("c"), Exit::Check, 4),
            (Failure::write("w"), Exit::Write, 5),
        ];
        for (failure, exit, code) in kinds {
            assert_eq!(failure.exit, exit, "{}", failure.message);
            assert_eq!(exit as u8, code, "{}", failure.message);
        }
    }
}
