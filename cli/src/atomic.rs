//! Output files are replaced whole or not at all: each is written to a
//! temporary file in the same folder, synced to disk, then renamed over
//! the target. A failed write (a full disk, a file size limit) removes the
//! temporary file and leaves any existing file, an input among them,
//! exactly as it was.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically.
///
/// # Errors
/// The first failed step's error; `path` is then unchanged.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_with(path, |out| out.write_all(bytes))
}

/// Writes to `path` atomically what `fill` writes to the buffered writer
/// it is given.
///
/// # Errors
/// The first failed step's error (from `fill`, the flush, the sync or the
/// rename); `path` is then unchanged.
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let (temp, file) = create_temp(path)?;
    let result = (|| {
        let mut out = BufWriter::new(file);
        fill(&mut out)?;
        let file = out.into_inner().map_err(io::IntoInnerError::into_error)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&temp, path)
    })();
    if result.is_err() {
        // Nothing else to do if the temporary file cannot be removed.
        let _ = fs::remove_file(&temp);
    }
    result
}

/// A new temporary file beside `path`: `.NAME.PID.N.tmp`, created only if
/// it does not exist.
fn create_temp(path: &Path) -> io::Result<(PathBuf, File)> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "no file name"))?
        .to_string_lossy()
        .into_owned();
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut n = 0u32;
    loop {
        let temp = folder.join(format!(".{name}.{}.{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(file) => return Ok((temp, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && n < 100 => n += 1,
            Err(e) => return Err(e),
        }
    }
}
