//! Where a traversal reads its nodes: the store itself, or an index cache over it
//! (`cache::BufferPool`). The hints tell a cache what a page is, so its replacement
//! policy can weigh level and distance (Shou 2002 §4.2.4) without global state.
//!
//! It lives with the store rather than with the R-tree because both the tree and the
//! cache read pages through it, and the cache sits below the tree.

use std::path::Path;

use super::{PageKind, Store};
use crate::error::Result;
use crate::geom::Aabb;

/// What a node page is, as the traversal knows it when it asks for the page.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeHint {
    /// Level of the node: 0 for a leaf, `height - 1` for the root.
    pub level: u16,
    /// Levels of the tree: the root is at `height - 1`.
    pub height: u32,
    /// The node's MBR from its parent's entry; `Aabb::EMPTY` for the root.
    pub mbr: Aabb,
}

/// A source of R-tree node pages.
pub trait PageSource {
    /// Reads node `page` into `buf` (its payload), verified.
    fn read_node(&self, page: u64, hint: &NodeHint, buf: &mut Vec<u8>) -> Result<()>;

    /// The database file, for error messages.
    fn path(&self) -> &Path;

    /// Node pages the traversal will read next: a source whose reads cost a round trip
    /// fetches them together now. A hint only: nothing is counted, and a failure shows
    /// when the page is read.
    fn will_read(&self, _pages: &[u64]) {}

    /// Node `page`'s payload into `buf` if it is held without a round trip, uncounted: a
    /// traversal looks ahead through what is held to fetch the next level together.
    fn peek_node(&self, _page: u64, _buf: &mut Vec<u8>) -> bool {
        false
    }

    /// A search of `query` starts (a cache measures distances against it).
    fn begin_search(&self, _query: &Aabb) {}

    /// The search is over (a cache ages its entries).
    fn end_search(&self) {}
}

impl PageSource for Store {
    fn read_node(&self, page: u64, _hint: &NodeHint, buf: &mut Vec<u8>) -> Result<()> {
        self.read_page_into(page, PageKind::RtreeNode, buf)
    }

    fn path(&self) -> &Path {
        Store::path(self)
    }

    fn will_read(&self, pages: &[u64]) {
        self.announce(pages);
    }

    fn peek_node(&self, page: u64, buf: &mut Vec<u8>) -> bool {
        self.peek_page_into(page, PageKind::RtreeNode, buf)
    }
}
