//! The one traversal every query kind shares. A query is a `Selection`: which
//! subtrees to enter and which leaf entries to return. Nodes are read straight from
//! their pages through `NodeView`, without decoding them whole.

use super::node::{NodeView, ObjectEntry};
use super::{corrupt, RTree};
use crate::error::Result;
use crate::geom::Aabb;
use crate::store::{PageKind, Store};

/// What a query selects. `descend` is asked of internal entries (subtree MBRs),
/// `select` of leaf entries (object boxes).
pub trait Selection {
    fn descend(&self, mbr: &Aabb) -> bool;
    fn select(&self, bounds: &Aabb) -> bool;
}

/// The objects a query returned and the pages it read, in the order it read them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QueryResult {
    pub objects: Vec<ObjectEntry>,
    pub pages: Vec<u64>,
}

impl QueryResult {
    /// The ids of the objects, sorted.
    pub fn ids(&self) -> Vec<u64> {
        let mut ids: Vec<u64> = self.objects.iter().map(|o| o.id).collect();
        ids.sort_unstable();
        ids
    }
}

pub(crate) fn search<S: Selection>(tree: &RTree, store: &Store, sel: &S) -> Result<QueryResult> {
    let mut result = QueryResult::default();
    let mut buf = Vec::with_capacity(store.page_size());
    // Levels must fall by one per step down: a corrupt child pointer cannot loop.
    let mut stack = vec![(tree.root, tree.height.saturating_sub(1) as u16)];
    while let Some((page, level)) = stack.pop() {
        store.read_page_into(page, PageKind::RtreeNode, &mut buf)?;
        result.pages.push(page);
        let node = NodeView::parse(&buf).map_err(|w| corrupt(store, page, w))?;
        if node.level != level {
            return Err(corrupt(store, page, format!("node at level {} where level {level} was expected", node.level)));
        }
        if node.is_leaf() {
            for i in 0..node.len() {
                if sel.select(&node.mbr(i)) {
                    result.objects.push(node.object(i));
                }
            }
        } else {
            for i in (0..node.len()).rev() {
                let child = node.child(i);
                if sel.descend(&child.mbr) {
                    stack.push((child.page, level - 1));
                }
            }
        }
    }
    Ok(result)
}
