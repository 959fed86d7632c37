//! One-by-one insertion (Guttman 1984) with the Ang–Tan linear split, so a library
//! user can add objects to an open database's index. Changed nodes are rewritten in
//! place and new nodes appended, all through the store.
//!
//! ChooseLeaf takes the child whose MBR grows least in volume, ties to the least
//! growth in margin (city boxes can be flat), then to the smaller child.

use super::node::{ChildEntry, Node, ObjectEntry};
use super::split::linear_split;
use super::{corrupt, RTree};
use crate::error::Result;
use crate::geom::Aabb;
use crate::store::{PageKind, Store};

/// Minimum fill of a node after a split, as a share of its fan-out.
const MIN_FILL: f32 = 0.3;

pub(crate) fn insert(tree: &mut RTree, store: &mut Store, entry: ObjectEntry) -> Result<()> {
    // Descend, remembering the path and the child taken at each level.
    let mut path: Vec<(u64, Node, usize)> = Vec::new();
    let mut page = tree.root;
    let mut level = tree.height.saturating_sub(1) as u16;
    loop {
        let payload = store.read_page(page, PageKind::RtreeNode)?;
        let node = Node::decode(&payload).map_err(|w| corrupt(store.path(), page, w))?;
        if node.level() != level {
            return Err(corrupt(
                store.path(),
                page,
                format!(
                    "node at level {} where level {level} was expected",
                    node.level()
                ),
            ));
        }
        match &node {
            Node::Leaf(_) => {
                path.push((page, node, usize::MAX));
                break;
            }
            Node::Internal { children, .. } => {
                if children.is_empty() {
                    return Err(corrupt(
                        store.path(),
                        page,
                        "internal node without children",
                    ));
                }
                let idx = choose(children, &entry.bounds);
                let next = children[idx].page;
                path.push((page, node, idx));
                page = next;
                level -= 1;
            }
        }
    }

    let (mut page, mut node, _) = path.pop().expect("the path holds the leaf");
    if let Node::Leaf(objects) = &mut node {
        objects.push(entry);
    }
    loop {
        let max = tree.fanout.max(node.level());
        let (mbr, sibling) = if node.len() > max {
            let (keep, moved) = split(node, ((max as f32 * MIN_FILL) as usize).max(1));
            store.write_page(page, PageKind::RtreeNode, &keep.encode())?;
            let moved_page = store.append_page(PageKind::RtreeNode, &moved.encode())?;
            (
                keep.mbr(),
                Some(ChildEntry {
                    mbr: moved.mbr(),
                    page: moved_page,
                }),
            )
        } else {
            store.write_page(page, PageKind::RtreeNode, &node.encode())?;
            (node.mbr(), None)
        };
        match path.pop() {
            Some((parent_page, mut parent, idx)) => {
                let Node::Internal { children, .. } = &mut parent else {
                    unreachable!("parents are internal")
                };
                let unchanged = children[idx].mbr == mbr && sibling.is_none();
                if unchanged {
                    break;
                }
                children[idx].mbr = mbr;
                children.extend(sibling);
                page = parent_page;
                node = parent;
            }
            None => {
                if let Some(sibling) = sibling {
                    let root = Node::Internal {
                        level: tree.height as u16,
                        children: vec![ChildEntry { mbr, page }, sibling],
                    };
                    tree.root = store.append_page(PageKind::RtreeNode, &root.encode())?;
                    tree.height += 1;
                }
                break;
            }
        }
    }
    tree.objects += 1;
    tree.save(store)
}

fn choose(children: &[ChildEntry], b: &Aabb) -> usize {
    let margin = |a: &Aabb| a.extent().x + a.extent().y + a.extent().z;
    let cost = |c: &ChildEntry| {
        let grown = c.mbr.union(b);
        (
            grown.volume() - c.mbr.volume(),
            margin(&grown) - margin(&c.mbr),
            c.mbr.volume(),
        )
    };
    let mut best = 0;
    let mut best_cost = cost(&children[0]);
    for (i, c) in children.iter().enumerate().skip(1) {
        let k = cost(c);
        if k < best_cost {
            best = i;
            best_cost = k;
        }
    }
    best
}

fn split(node: Node, min_fill: usize) -> (Node, Node) {
    fn pick<T: Clone>(items: &[T], idx: &[usize]) -> Vec<T> {
        idx.iter().map(|&i| items[i].clone()).collect()
    }
    match node {
        Node::Leaf(objects) => {
            let mbrs: Vec<Aabb> = objects.iter().map(|o| o.bounds).collect();
            let (a, b) = linear_split(&mbrs, min_fill);
            (
                Node::Leaf(pick(&objects, &a)),
                Node::Leaf(pick(&objects, &b)),
            )
        }
        Node::Internal { level, children } => {
            let mbrs: Vec<Aabb> = children.iter().map(|c| c.mbr).collect();
            let (a, b) = linear_split(&mbrs, min_fill);
            (
                Node::Internal {
                    level,
                    children: pick(&children, &a),
                },
                Node::Internal {
                    level,
                    children: pick(&children, &b),
                },
            )
        }
    }
}
