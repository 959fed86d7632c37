//! Shape of a tree: nodes and entries per level, and how full its pages are. Reads
//! every node once (through the store, so the reads are counted).

use super::node::NodeView;
use super::{corrupt, RTree};
use crate::error::Result;
use crate::store::{PageKind, Store};

/// The shape of a tree, as [`RTree::stats`] walks it: nodes and entries per level,
/// and how full the nodes are.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct TreeStats {
    /// Levels, leaves included.
    pub height: u32,
    /// Nodes per level, leaves first.
    pub nodes: Vec<u64>,
    /// Entries per level, leaves first.
    pub entries: Vec<u64>,
    /// Mean share of a node's fan-out that is used, over all nodes.
    pub fill: f64,
}

pub(crate) fn collect(tree: &RTree, store: &Store) -> Result<TreeStats> {
    let h = tree.height as usize;
    let mut stats = TreeStats {
        height: tree.height,
        nodes: vec![0; h],
        entries: vec![0; h],
        fill: 0.0,
    };
    let mut capacity = 0u64;
    let mut buf = Vec::new();
    let mut stack = vec![(tree.root, tree.height.saturating_sub(1) as u16)];
    while let Some((page, level)) = stack.pop() {
        store.read_page_into(page, PageKind::RtreeNode, &mut buf)?;
        let node = NodeView::parse(&buf).map_err(|w| corrupt(store.path(), page, w))?;
        if node.level != level {
            return Err(corrupt(
                store.path(),
                page,
                format!(
                    "node at level {} where level {level} was expected",
                    node.level
                ),
            ));
        }
        stats.nodes[level as usize] += 1;
        stats.entries[level as usize] += node.len() as u64;
        capacity += tree.fanout.max(level) as u64;
        if !node.is_leaf() {
            let children: Vec<u64> = (0..node.len()).map(|i| node.child(i).page).collect();
            store.announce(&children);
            stack.extend(children.into_iter().map(|p| (p, level - 1)));
        }
    }
    let used: u64 = stats.entries.iter().sum();
    stats.fill = if capacity == 0 {
        0.0
    } else {
        used as f64 / capacity as f64
    };
    Ok(stats)
}
