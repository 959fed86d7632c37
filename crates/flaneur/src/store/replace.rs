//! How a new file replaces an old one: written to a temporary of its own beside it
//! (`.<name>.<random>.tmp`), synced, then renamed into place durably, so that a writer
//! killed midway leaves the old file or none, never a part of the new one. A database
//! build and a visibility shard are both written so.

use std::fs::File;
use std::io;
use std::path::Path;

use crate::error::{Error, Result};

/// Renames the finished temporary `temp` to `path` and makes the rename durable (best
/// effort: not every platform can fsync a folder). On failure the temporary is dropped,
/// which removes it.
pub(super) fn persist(temp: tempfile::TempPath, path: &Path) -> Result<()> {
    temp.persist(path).map_err(|e| Error::io(path, e.error))?;
    if let Ok(d) = File::open(folder_of(path)) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Writes `bytes` to `path` as a build writes a database: into a temporary beside it,
/// synced, then renamed into place, so that a writer killed midway leaves the old file
/// or none, never a part of the new one.
pub(crate) fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut temp = temp_file(path).map_err(|e| Error::io(path, e))?;
    io::Write::write_all(&mut temp, bytes).map_err(|e| Error::io(path, e))?;
    temp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    persist(temp.into_temp_path(), path)
}

/// A new, uniquely named temporary file in `path`'s folder, where the database that
/// will be `path` is built: `.<name>.<random>.tmp`, created with mode 0666 less the
/// umask, as `File::create` would, whatever a stale temporary's mode.
pub(super) fn temp_file(path: &Path) -> io::Result<tempfile::NamedTempFile> {
    use std::os::unix::fs::PermissionsExt;
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .permissions(std::fs::Permissions::from_mode(0o666))
        .tempfile_in(folder_of(path))
}

/// The folder `path` is in: its parent, or the current folder for a bare name.
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}
