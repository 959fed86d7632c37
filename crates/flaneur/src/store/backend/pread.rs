//! The pread backend: one positioned read per page, optionally with O_DIRECT so
//! that every read goes to the device (cold-cache experiments).

use std::fs::{File, OpenOptions};
use std::io;
use std::os::unix::fs::{FileExt, OpenOptionsExt};
use std::path::Path;

use super::RawPageSource;

/// Buffer alignment for O_DIRECT reads (the usual logical block size bound).
const DIRECT_ALIGN: usize = 4096;

/// Reads pages with `read_exact_at`.
pub(crate) struct PreadSource {
    file: File,
    page_size: usize,
    direct: bool,
}

/// The error for a filesystem that refuses O_DIRECT.
fn direct_refused(what: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "the filesystem refused O_DIRECT ({what}: EINVAL); \
             use the `pread` or `mmap` backend on this filesystem"
        ),
    )
}

impl PreadSource {
    /// Reads through `file` (buffered).
    pub(crate) fn buffered(file: File, page_size: usize) -> PreadSource {
        PreadSource {
            file,
            page_size,
            direct: false,
        }
    }

    /// Opens `path` read-only with O_DIRECT.
    pub(crate) fn direct(path: &Path, page_size: usize) -> io::Result<PreadSource> {
        let file = OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_DIRECT)
            .open(path)
            .map_err(|e| {
                if e.raw_os_error() == Some(libc::EINVAL) {
                    direct_refused("open")
                } else {
                    e
                }
            })?;
        Ok(PreadSource {
            file,
            page_size,
            direct: true,
        })
    }
}

impl RawPageSource for PreadSource {
    fn read(&self, page: u64, buf: &mut [u8]) -> io::Result<()> {
        let offset = page * self.page_size as u64;
        if !self.direct {
            return self.file.read_exact_at(buf, offset);
        }
        // O_DIRECT needs an aligned buffer: over-allocate and read into the aligned
        // window (calloc'd, so the unused slack costs nothing).
        let mut raw = vec![0u8; buf.len() + DIRECT_ALIGN];
        let skip = raw.as_ptr().align_offset(DIRECT_ALIGN);
        let window = raw
            .get_mut(skip..skip + buf.len())
            .ok_or_else(|| io::Error::other("cannot align an O_DIRECT buffer"))?;
        self.file.read_exact_at(window, offset).map_err(|e| {
            if e.raw_os_error() == Some(libc::EINVAL) {
                direct_refused("read")
            } else {
                e
            }
        })?;
        buf.copy_from_slice(window);
        Ok(())
    }
}
