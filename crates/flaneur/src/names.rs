//! The object names table: what each object was called in the file it was imported from
//! (an OpenStreetMap element such as `way/123`, a glTF node's name, an OBJ object's), so
//! that a query or the window can say which building it is. One extent of `meta` pages
//! that the header's `names` segment names (a = first page, b = byte length, c = the
//! names it holds); a database built from a scene file has none.
//!
//! ```text
//! offset      width     field
//! ----------  --------  --------------------------------------------------------------
//!          0         4  magic     b"FLNM"
//!          4         4  version   u32, NAMES_VERSION
//!          8         8  names     u64, n: objects 0..n have a name (maybe empty)
//!         16  8(n + 1)  offsets   u64 each, into the text: name i is bytes
//!                                 offsets[i]..offsets[i + 1], ascending, the first 0
//! 24 + 8n           …   text      the names, UTF-8, one after the other
//! ```
//!
//! A lookup reads 16 bytes of offsets and the name's own bytes, the pages that hold
//! them and no others (the store checks each page's checksum); the table checks what a
//! page cannot: the head, the offsets' order and bounds, and the text's UTF-8.

use crate::error::{Error, Result};
use crate::store::framing::{u32_at, u64_at};
use crate::store::Extent;
use crate::store::{PageKind, Segment, Store};

/// The header segment naming the table.
pub const NAMES_SEGMENT: &str = "names";
const MAGIC: [u8; 4] = *b"FLNM";
const NAMES_VERSION: u32 = 1;
const HEAD_LEN: usize = 16;

/// The table's bytes for `names`, object `i`'s at index `i`.
pub(crate) fn encode_names<S: AsRef<str>>(names: &[S]) -> Vec<u8> {
    let text: usize = names.iter().map(|s| s.as_ref().len()).sum();
    let mut b = Vec::with_capacity(HEAD_LEN + 8 * (names.len() + 1) + text);
    b.extend(MAGIC);
    b.extend(NAMES_VERSION.to_le_bytes());
    b.extend((names.len() as u64).to_le_bytes());
    let mut at = 0u64;
    b.extend(at.to_le_bytes());
    for s in names {
        at += s.as_ref().len() as u64;
        b.extend(at.to_le_bytes());
    }
    for s in names {
        b.extend(s.as_ref().as_bytes());
    }
    b
}

/// Appends the table for `names` and names it in the header; the pages written.
pub(crate) fn store_names<S: AsRef<str>>(store: &mut Store, names: &[S]) -> Result<u64> {
    let extent = store.append_extent(PageKind::Meta, &encode_names(names))?;
    store.set_segment(Segment::new(
        NAMES_SEGMENT,
        extent.first_page,
        extent.byte_len as u64,
        names.len() as u64,
    ))?;
    Ok(extent.page_count as u64)
}

/// An open names table: where it lies and how many names it holds.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NameTable {
    extent: Extent,
    names: u64,
}

impl NameTable {
    /// The table the header names, its head checked; `None` without one.
    pub(crate) fn open(store: &Store) -> Result<Option<NameTable>> {
        let Some((extent, names)) = store.segment_extent(NAMES_SEGMENT, |e, n| {
            let need = (HEAD_LEN as u64).saturating_add(n.saturating_add(1).saturating_mul(8));
            if need > e.byte_len as u64 {
                return Err(format!(
                    "{n} names need {need} bytes, the table has {}",
                    e.byte_len
                ));
            }
            Ok(())
        })?
        else {
            return Ok(None);
        };
        let table = NameTable { extent, names };
        let head = store.read_extent_range(&extent, PageKind::Meta, 0, HEAD_LEN)?;
        if head[..4] != MAGIC || u32_at(&head, 4) != NAMES_VERSION || u64_at(&head, 8) != names {
            return Err(table.corrupt(
                store,
                format!(
                    "head {:?} is not a version {NAMES_VERSION} table of {names} names",
                    &head[..]
                ),
            ));
        }
        Ok(Some(table))
    }

    /// Names held (objects `0..names`).
    pub(crate) fn len(&self) -> u64 {
        self.names
    }

    /// The table's extent.
    pub(crate) fn extent(&self) -> Extent {
        self.extent
    }

    /// Object `id`'s name; `None` past the table or for an empty name.
    pub(crate) fn name(&self, store: &Store, id: u64) -> Result<Option<String>> {
        if id >= self.names {
            return Ok(None);
        }
        let at = HEAD_LEN + 8 * id as usize;
        let offsets = store.read_extent_range(&self.extent, PageKind::Meta, at, 16)?;
        let (start, end) = (u64_at(&offsets, 0), u64_at(&offsets, 8));
        let text_at = HEAD_LEN as u64 + 8 * (self.names + 1);
        let room = self.extent.byte_len as u64 - text_at;
        if start > end || end > room {
            return Err(self.corrupt(
                store,
                format!("name {id} at bytes {start}..{end} of a text of {room}"),
            ));
        }
        if start == end {
            return Ok(None);
        }
        let bytes = store.read_extent_range(
            &self.extent,
            PageKind::Meta,
            (text_at + start) as usize,
            (end - start) as usize,
        )?;
        String::from_utf8(bytes)
            .map(Some)
            .map_err(|e| self.corrupt(store, format!("name {id} is not UTF-8: {e}")))
    }

    fn corrupt(&self, store: &Store, what: String) -> Error {
        Error::CorruptPage {
            path: store.path().to_path_buf(),
            page: self.extent.first_page,
            what: format!("object names: {what}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_found_by_id_reading_only_their_pages() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("n.db");
        let names: Vec<String> = (0..2000)
            .map(|i| {
                if i % 7 == 0 {
                    String::new()
                } else {
                    format!("way/{}", 1_000_000 + i)
                }
            })
            .collect();
        let mut store = Store::create(&path, 1024).unwrap();
        let pages = store_names(&mut store, &names).unwrap();
        assert!(pages > 10, "{pages}");
        store.finish().unwrap();
        let store = Store::open(&path, crate::Backend::default()).unwrap();
        let table = NameTable::open(&store).unwrap().unwrap();
        assert_eq!(table.len(), 2000);
        store.reset_stats();
        assert_eq!(
            table.name(&store, 1234).unwrap().as_deref(),
            Some("way/1001234")
        );
        assert!(store.stats().page_reads <= 3, "{:?}", store.stats());
        assert_eq!(
            table.name(&store, 7).unwrap(),
            None,
            "an empty name is none"
        );
        assert_eq!(table.name(&store, 2000).unwrap(), None, "past the table");
        for i in [1, 1999] {
            assert_eq!(table.name(&store, i).unwrap().unwrap(), names[i as usize]);
        }
    }

    #[test]
    fn a_database_without_names_has_no_table() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("n.db");
        Store::create(&path, 1024).unwrap().finish().unwrap();
        let store = Store::open(&path, crate::Backend::default()).unwrap();
        assert!(NameTable::open(&store).unwrap().is_none());
    }
}
