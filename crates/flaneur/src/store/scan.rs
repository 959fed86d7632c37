//! Reading a page without knowing its kind: what an integrity check does as it reads
//! every page of a file in turn.

use super::page::{self, PageKind};
use super::Store;
use crate::error::Result;

impl Store {
    /// Reads data page `page` whatever its kind, verifies it (framing and checksum) and
    /// returns its kind and payload; counted under its kind. Errors as
    /// [`Store::read_page`], and a `CorruptPage` for a kind byte no page has.
    pub fn read_any_page(&self, page: u64) -> Result<(PageKind, Vec<u8>)> {
        self.check_range(page)?;
        let mut buf = vec![0u8; self.page_size];
        match self.in_memory(page) {
            Some(bytes) => buf.copy_from_slice(bytes),
            None => self
                .source
                .read(page, &mut buf)
                .map_err(|e| self.read_error(page, e))?,
        }
        let kind = match PageKind::from_u8(buf[0]) {
            Some(PageKind::Header) => {
                return Err(self.corrupt(page, "a data page marked as the file header".into()))
            }
            Some(kind) => kind,
            // A blank page: the framing's own message says so.
            None if buf[0] == 0 => {
                let what = page::decode(&buf, PageKind::Meta)
                    .err()
                    .unwrap_or_else(|| "blank page".into());
                return Err(self.corrupt(page, what));
            }
            None => {
                return Err(self.corrupt(page, format!("unknown kind byte {:#04x}", buf[0])));
            }
        };
        self.counters.record(kind);
        let payload = self.verify(page, &buf, kind)?;
        Ok((kind, payload.to_vec()))
    }
}
