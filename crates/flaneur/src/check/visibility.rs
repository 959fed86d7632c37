//! The visibility table: its directory against its records, and each record's objects.

use super::claims::Claims;
use super::objects::Objects;
use crate::store::{PageKind, Store};
use crate::visibility::VisibilityTable;

pub(super) fn check(store: &Store, table: &VisibilityTable, objects: &Objects, c: &mut Claims) {
    let part = "the visibility table";
    let extent = table.extent();
    c.claim_extent(&extent, PageKind::Visibility, part);
    c.count_kind(PageKind::Visibility, table.pages());
    let head = match table.head(store) {
        Ok(h) => h.clone(),
        Err(e) => return c.problem(&e, part),
    };
    let mut end_of_last = 0u64;
    let mut by_offset: Vec<_> = head.cells.iter().collect();
    by_offset.sort_by_key(|cell| cell.offset);
    for cell in by_offset {
        let end = cell.offset + cell.len as u64;
        // The page the record starts on, for the report.
        let page = extent.page_of(cell.offset, store.payload_size());
        let record = format!("the PVS record of cell {}", cell.id);
        if end > extent.byte_len as u64 || cell.offset < end_of_last {
            c.found(
                Some(page),
                &record,
                format!(
                    "the directory puts it at bytes {}..{end} of a table of {} bytes, \
                     over the record before it or past the end",
                    cell.offset, extent.byte_len
                ),
            );
            continue;
        }
        end_of_last = end;
        match table.pvs(store, cell.id) {
            Ok(Some(pvs)) => {
                if let Some(id) = pvs.ids.iter().find(|id| !objects.contains_key(id)) {
                    c.found(
                        Some(page),
                        &record,
                        format!("it names object {id}, which the database does not hold"),
                    );
                }
            }
            Ok(None) => {}
            Err(e) => c.problem(&e, &record),
        }
    }
}
