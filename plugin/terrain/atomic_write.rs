//! Files written whole or not at all: a new file is filled beside its
//! path, synced and renamed over it, so a crash or a full disk never
//! leaves a file half-written ([`super::file`], the world's chunk files).

use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

/// Writes `path` atomically with what `fill` writes into a new temporary
/// file beside it: `fill`, then a sync, then a rename over `path`, then a
/// sync of the folder (so the rename itself survives a crash). On any
/// error before the rename the temporary file is removed and `path` is
/// untouched.
pub(crate) fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut File) -> io::Result<()>,
) -> io::Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?
        .to_string_lossy()
        .into_owned();
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let (temp, mut file) = create_temp(&folder, &name)?;
    let written = fill(&mut file)
        .and_then(|()| file.sync_all())
        .and_then(|()| {
            drop(file);
            fs::rename(&temp, path)
        });
    if let Err(e) = written {
        // The error that matters is the write's; a temporary file that
        // cannot be removed either is left for the user to see.
        let _ = fs::remove_file(&temp);
        return Err(e);
    }
    // The new file is in place; syncing the folder makes the rename
    // durable. Folders cannot be opened for syncing everywhere (Windows),
    // and the data itself is already synced, so a failure here is not an
    // error of the save.
    if let Ok(dir) = File::open(&folder) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// A new temporary file `.NAME.PID.N.tmp` in `folder`, created only where
/// no such file exists.
fn create_temp(folder: &Path, name: &str) -> io::Result<(PathBuf, File)> {
    let mut n = 0u32;
    loop {
        let temp = folder.join(format!(".{name}.{}.{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(file) => return Ok((temp, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && n < 1000 => n += 1,
            Err(e) => return Err(e),
        }
    }
}
