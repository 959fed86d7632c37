//! The mmap backend: the whole file mapped read-only, pages copied out of the map.

use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;

use memmap2::Mmap;

use super::RawPageSource;

/// Reads pages out of a read-only shared mapping of the file. Pages beyond the
/// mapping (a writable store whose file grew since it was mapped) are read with
/// `pread` until `refresh` maps the file again; on Linux a shared mapping sees data
/// written through the file, so a writable store reads its own writes.
pub(crate) struct MmapSource {
    file: File,
    map: Mmap,
    page_size: usize,
    map_pages: u64,
}

impl MmapSource {
    pub(crate) fn new(file: File, page_size: usize) -> io::Result<MmapSource> {
        let map = map(&file)?;
        let map_pages = map.len() as u64 / page_size as u64;
        Ok(MmapSource {
            file,
            map,
            page_size,
            map_pages,
        })
    }
}

fn map(file: &File) -> io::Result<Mmap> {
    // SAFETY: the mapping is read-only and private to this source. The store never
    // shrinks a database file while it is open (writes only overwrite pages in place
    // or extend the file), and a built database is never modified in place by the
    // engine. Another process truncating the file under us would make reads fault;
    // that is the documented contract of every mmap reader.
    unsafe { Mmap::map(file) }
}

impl RawPageSource for MmapSource {
    fn read(&self, page: u64, buf: &mut [u8]) -> io::Result<()> {
        match self.page_bytes(page) {
            Some(b) if b.len() == buf.len() => {
                buf.copy_from_slice(b);
                Ok(())
            }
            _ => self.file.read_exact_at(buf, page * self.page_size as u64),
        }
    }

    #[inline]
    fn page_bytes(&self, page: u64) -> Option<&[u8]> {
        if page >= self.map_pages {
            return None;
        }
        let start = usize::try_from(page).ok()?.checked_mul(self.page_size)?;
        self.map.get(start..start.checked_add(self.page_size)?)
    }

    fn refresh(&mut self) -> io::Result<()> {
        let len = self.file.metadata()?.len();
        if len > self.map.len() as u64 {
            self.map = map(&self.file)?;
            self.map_pages = self.map.len() as u64 / self.page_size as u64;
        }
        Ok(())
    }
}
