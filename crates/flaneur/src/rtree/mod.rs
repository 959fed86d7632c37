//! The paged R-tree: one node per page of the store, the objects' boxes in its leaves.
//!
//! Shou 2002 §4.1–4.2.2. BOX (`range`) and CSearch (`complement`) are two selection
//! functions over one traversal (`search`); the tree is bulk-loaded at build (STR,
//! `bulk`) and can grow by one-by-one insertion with the Ang–Tan linear split
//! (`insert`, `split`), as the thesis built its trees.

mod box_index;
mod bulk;
mod complement;
mod history;
mod insert;
pub(crate) mod node;
mod range;
mod search;
mod split;
mod stats;

pub(crate) use box_index::BoxIndex;
pub(crate) use bulk::tile as str_tile;
pub use bulk::DEFAULT_FILL;
use complement::Complement;
pub use complement::Coverlap;
pub use history::{History, DEFAULT_HISTORY_LEN};
pub(crate) use node::Node;
pub use node::{Fanout, ObjectEntry};
use range::Range;
pub use search::QueryResult;
pub use stats::TreeStats;

use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::store::{PageSource, Segment, Store};

/// The name of the store segment that records the tree: a = root page, b = height,
/// c = number of objects.
pub(crate) const SEGMENT: &str = "rtree";

/// A handle on the tree in a store: where its root is and how tall it is. Reads go
/// through the `Store` passed to each call, so they are all counted there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RTree {
    /// The root's page.
    pub root: u64,
    /// Levels including the leaves: 1 when the root is a leaf.
    pub height: u32,
    /// Objects in the tree.
    pub objects: u64,
    /// Entries per node for the store's page size.
    pub fanout: Fanout,
}

impl RTree {
    /// Reads the tree's segment from an open store.
    pub fn load(store: &Store) -> Result<RTree> {
        let seg = store
            .header()
            .segment(SEGMENT)
            .ok_or_else(|| Error::NotADatabase {
                path: store.path().to_path_buf(),
                what: "it has no R-tree segment".into(),
            })?;
        if seg.a == 0 || seg.a >= store.page_count() || seg.b == 0 || seg.b > 64 {
            return Err(Error::CorruptPage {
                path: store.path().to_path_buf(),
                page: 0,
                what: format!(
                    "R-tree segment names root page {} and height {}",
                    seg.a, seg.b
                ),
            });
        }
        Ok(RTree {
            root: seg.a,
            height: seg.b as u32,
            objects: seg.c,
            fanout: Fanout::for_payload(store.payload_size()),
        })
    }

    /// Records the tree in the store's header (persisted at the store's flush/finish).
    pub fn save(&self, store: &mut Store) -> Result<()> {
        store.set_segment(Segment {
            name: SEGMENT.into(),
            a: self.root,
            b: self.height as u64,
            c: self.objects,
        })
    }

    /// The plain range query BOX: every object whose box overlaps `query`.
    pub fn range<P: PageSource + ?Sized>(&self, pages: &P, query: &Aabb) -> Result<QueryResult> {
        query.validate()?;
        search::search(self, pages, &Range { query: *query }, query)
    }

    /// CSearch (Shou 2002, Fig. 4.5): the objects whose boxes overlap `cell` and none
    /// of the `history` cells — exactly `range(cell) − ∪ range(hᵢ)`.
    pub fn csearch<P: PageSource + ?Sized>(
        &self,
        pages: &P,
        cell: &Aabb,
        history: &[Aabb],
    ) -> Result<QueryResult> {
        self.csearch_with(pages, cell, history, Coverlap::default())
    }

    /// CSearch with an explicit descent rule (see [`Coverlap`]); the result is the
    /// same under both, the pages read are not.
    pub fn csearch_with<P: PageSource + ?Sized>(
        &self,
        pages: &P,
        cell: &Aabb,
        history: &[Aabb],
        rule: Coverlap,
    ) -> Result<QueryResult> {
        cell.validate()?;
        for h in history {
            h.validate()?;
        }
        search::search(
            self,
            pages,
            &Complement {
                cell: *cell,
                history,
                rule,
            },
            cell,
        )
    }

    /// One step of a walk: filters `history` against `cell`, runs CSearch, and records
    /// `cell` with what it retrieved.
    pub fn csearch_step<P: PageSource + ?Sized>(
        &self,
        pages: &P,
        history: &mut History,
        cell: &Aabb,
        rule: Coverlap,
    ) -> Result<QueryResult> {
        cell.validate()?;
        history.filter(cell);
        let result = search::search(
            self,
            pages,
            &Complement {
                cell: *cell,
                history: &history.cells(),
                rule,
            },
            cell,
        )?;
        history.record(*cell, &result.objects);
        Ok(result)
    }

    /// Adds one object to the tree, writing changed and new nodes through the store.
    pub fn insert(&mut self, store: &mut Store, entry: ObjectEntry) -> Result<()> {
        entry.bounds.validate()?;
        insert::insert(self, store, entry)
    }

    /// Builds a tree over `entries` by Sort-Tile-Recursive packing, nodes filled to
    /// `fill` of their fan-out.
    pub fn bulk_load(store: &mut Store, entries: Vec<ObjectEntry>, fill: f32) -> Result<RTree> {
        bulk::bulk_load(store, entries, fill)
    }

    /// Walks every node: nodes and entries per level, fill.
    pub fn stats(&self, store: &Store) -> Result<TreeStats> {
        stats::collect(self, store)
    }
}

pub(crate) fn corrupt(path: &std::path::Path, page: u64, what: impl Into<String>) -> Error {
    Error::CorruptPage {
        path: path.to_path_buf(),
        page,
        what: what.into(),
    }
}
