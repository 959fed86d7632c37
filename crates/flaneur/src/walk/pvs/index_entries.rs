//! Every object's index entry by id, read once: what a PVS walk reads the meshes of
//! the objects a row names through.

use crate::database::Database;
use crate::error::{Error, Result};
use crate::rtree::ObjectEntry;
use std::collections::HashMap;

/// Every object's index entry by id: what a PVS walk reads the meshes of the objects a
/// row names through.
#[derive(Debug, Default)]
pub(super) struct IndexEntries(HashMap<u64, ObjectEntry>);

impl IndexEntries {
    /// The whole index of `db`, read once.
    pub(super) fn read(db: &Database) -> Result<IndexEntries> {
        let all = db.range(&db.bounds())?.objects;
        Ok(IndexEntries(all.into_iter().map(|o| (o.id, o)).collect()))
    }

    /// Object `id`'s entry; an error for an id a PVS names and the index does not hold.
    pub(super) fn get(&self, id: u64) -> Result<&ObjectEntry> {
        self.0.get(&id).ok_or_else(|| {
            Error::Invalid(format!(
                "object {id} of a PVS is not in the database's index"
            ))
        })
    }
}
