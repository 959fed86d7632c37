//! The visibility table: its head (grid, settings, directory of cells) and each cell's
//! record (the PVS with its DoVs).

use crate::store::framing::reseal;
use crate::visibility::table::{cell_count, decode_head, decode_record, TableHead};

/// A whole visibility table, as it is and with its checksums rewritten (the head's,
/// then each record's the head places): the head, then every record it names.
pub fn visibility_table(data: &[u8]) {
    let mut sealed = data.to_vec();
    if let Some(head) = head_of(&mut sealed, true) {
        for c in &head.cells {
            let (start, len) = (c.offset as usize, c.len as usize);
            reseal(&mut sealed[start..start + len]);
        }
    }
    for mut b in [data.to_vec(), sealed] {
        let Some(head) = head_of(&mut b, false) else {
            continue;
        };
        for c in head.cells.iter().take(super::MAX_ITEMS) {
            let record = &b[c.offset as usize..][..c.len as usize];
            let _ = decode_record(record, c.count);
            let _ = head.cell(c.id);
        }
        let _ = head.cell(u32::MAX);
    }
}

/// The head of the table `b`, its checksum rewritten first when `sealing`.
fn head_of(b: &mut [u8], sealing: bool) -> Option<TableHead> {
    let n = cell_count(b).ok()?;
    let (len, total) = (TableHead::len_for(n), b.len() as u64);
    let head = b.get_mut(..len)?;
    if sealing {
        reseal(head);
    }
    decode_head(head, total).ok()
}
