//! One-by-one insertion (Guttman 1984) with the Ang–Tan linear split, so a library
//! user can add objects to an open database's index. Nothing is rewritten in place:
//! every node on the path from the changed leaf to the root is appended anew (a
//! copy-on-write path copy, height pages an insert), and only the header, written last,
//! names the new root. An insert cut short anywhere leaves the old tree whole, and
//! readers of the old root are never disturbed.
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

    let (_, mut node, _) = path.pop().expect("the path holds the leaf");
    if let Node::Leaf(objects) = &mut node {
        objects.push(entry);
    }
    // Copy-on-write: each node on the path is appended anew, never rewritten, so the
    // old tree stays whole until the header names the new root.
    loop {
        let max = tree.fanout.max(node.level());
        let (copy, sibling) = if node.len() > max {
            let (keep, moved) = split(node, ((max as f32 * MIN_FILL) as usize).max(1));
            let keep_page = store.append_page(PageKind::RtreeNode, &keep.encode())?;
            let moved_page = store.append_page(PageKind::RtreeNode, &moved.encode())?;
            (
                ChildEntry {
                    mbr: keep.mbr(),
                    page: keep_page,
                },
                Some(ChildEntry {
                    mbr: moved.mbr(),
                    page: moved_page,
                }),
            )
        } else {
            let page = store.append_page(PageKind::RtreeNode, &node.encode())?;
            (
                ChildEntry {
                    mbr: node.mbr(),
                    page,
                },
                None,
            )
        };
        match path.pop() {
            Some((_, mut parent, idx)) => {
                let Node::Internal { children, .. } = &mut parent else {
                    unreachable!("parents are internal")
                };
                children[idx] = copy;
                children.extend(sibling);
                node = parent;
            }
            None => {
                tree.root = match sibling {
                    Some(sibling) => {
                        let root = Node::Internal {
                            level: tree.height as u16,
                            children: vec![copy, sibling],
                        };
                        tree.height += 1;
                        store.append_page(PageKind::RtreeNode, &root.encode())?
                    }
                    None => copy.page,
                };
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
