//! The client's optional cache on disk: the pages of one version of one remote file,
//! kept at their own offsets in a sparse file, so that a second visit reads them there
//! instead of asking the server.
//!
//! The file is named by the URL and the version the server gave (its ETag, else its
//! Last-Modified, and its length): a new build of the file on the server has another
//! name, so pages of two versions never meet. A page is trusted only when it is intact
//! (written, its checksum right); anything else, a hole included, is fetched again. A
//! server that gives neither an ETag nor a Last-Modified gets no disk cache, since a
//! change could not be told.

use std::fs::{File, OpenOptions};
use std::io;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use crate::store::page;

pub(crate) struct DiskCache {
    file: File,
    page_size: usize,
}

impl DiskCache {
    /// The cache of `url` at `version` (of `len` bytes) in `dir`, made if missing.
    pub(crate) fn open(
        dir: &Path,
        url: &str,
        version: &str,
        len: u64,
        page_size: usize,
    ) -> io::Result<DiskCache> {
        std::fs::create_dir_all(dir)?;
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(cache_path(dir, url, version, len))?;
        if file.metadata()?.len() != len {
            file.set_len(len)?;
        }
        Ok(DiskCache { file, page_size })
    }

    /// Page `page` into `buf` if the cache holds it intact.
    pub(crate) fn get(&self, page: u64, buf: &mut [u8]) -> bool {
        self.file
            .read_exact_at(buf, page * self.page_size as u64)
            .is_ok()
            && page::intact(buf)
    }

    /// Keeps page `page`. A failed write only loses the saving, never a read.
    pub(crate) fn put(&self, page: u64, bytes: &[u8]) {
        let _ = self.file.write_all_at(bytes, page * self.page_size as u64);
    }
}

/// The cache file's name: a hash of the URL and the version, readable enough to tell
/// the file's own name apart.
fn cache_path(dir: &Path, url: &str, version: &str, len: u64) -> PathBuf {
    // FNV-1a: stable across runs and builds, which std's hasher is not.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in url
        .bytes()
        .chain([0])
        .chain(version.bytes())
        .chain(len.to_le_bytes())
    {
        h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
    }
    let name: String = url
        .rsplit('/')
        .next()
        .unwrap_or("")
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '.' || *c == '-' || *c == '_')
        .take(40)
        .collect();
    dir.join(format!("{name}.{h:016x}.pages"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::page::encode_into;
    use crate::store::PageKind;

    #[test]
    fn keeps_intact_pages_and_refuses_holes_and_damage() {
        let dir = tempfile::tempdir().unwrap();
        let cache =
            DiskCache::open(dir.path(), "http://h/c.flaneur", "\"v1\"", 4096 * 4, 1024).unwrap();
        let mut page = Vec::new();
        encode_into(PageKind::Mesh, b"a mesh", 1024, &mut page);
        cache.put(2, &page);
        let mut buf = vec![0u8; 1024];
        assert!(cache.get(2, &mut buf) && buf == page);
        assert!(!cache.get(1, &mut buf), "a hole is not a page");
        page[crate::store::page::PAYLOAD_OFFSET + 1] ^= 1;
        cache.put(3, &page);
        assert!(!cache.get(3, &mut buf), "a damaged page is not trusted");
        // Another version of the same URL is another file.
        let other =
            DiskCache::open(dir.path(), "http://h/c.flaneur", "\"v2\"", 4096 * 4, 1024).unwrap();
        assert!(!other.get(2, &mut buf));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
