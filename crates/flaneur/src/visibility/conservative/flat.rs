//! The objects' boxes as an R-tree laid out flat, in preorder, for the conservative
//! test, which walks the whole hierarchy from every block of every cell (some 8,500
//! boxes asked about a block on the demo city): a node's subtree is the run of nodes
//! after it up to its `next`, so a walk reads the nodes in the order they lie in
//! memory and drops a subtree with one jump, where a walk of `rstar`'s tree chases a
//! pointer and pushes a stack entry for every child. The tree itself is `rstar`'s bulk
//! load; the bounds are its envelopes, bit for bit, so a walk keeps what a walk of
//! `rstar`'s tree with the same tests keeps.

use glam::Vec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{ParentNode, RTree, RTreeNode, RTreeObject, AABB};

use crate::geom::Aabb;

type Entry = GeomWithData<Rectangle<[f32; 3]>, u32>;

/// `object` of an inner node.
const INNER: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// The node after this one's subtree.
    next: u32,
    /// The object's index for a leaf; `INNER` for an inner node.
    object: u32,
}

/// An R-tree over object boxes in preorder (see the module's notes).
pub(super) struct FlatTree {
    nodes: Vec<Node>,
}

impl FlatTree {
    /// The tree of `boxes`, object `i` being `boxes[i]`.
    pub(super) fn new(boxes: &[Aabb]) -> FlatTree {
        let tree = rtree(boxes);
        let mut nodes = Vec::with_capacity(2 * boxes.len() + 1);
        if !tree.root().children().is_empty() {
            push(tree.root(), &mut nodes);
        }
        FlatTree { nodes }
    }

    /// The objects, in the tree's order, that `take` keeps (given each object's index
    /// and box), below the inner nodes whose bounds `enter` keeps: an inner node it
    /// drops is passed over with all below it.
    pub(super) fn select(
        &self,
        mut enter: impl FnMut(&Aabb) -> bool,
        mut take: impl FnMut(u32, &Aabb) -> bool,
    ) -> Vec<u32> {
        let mut out = Vec::new();
        let mut i = 0;
        while let Some(n) = self.nodes.get(i) {
            if n.object == INNER {
                i = if enter(&n.bounds) {
                    i + 1
                } else {
                    n.next as usize
                };
            } else {
                if take(n.object, &n.bounds) {
                    out.push(n.object);
                }
                i += 1;
            }
        }
        out
    }
}

/// `rstar`'s tree of `boxes`, object `i` being `boxes[i]`.
fn rtree(boxes: &[Aabb]) -> RTree<Entry> {
    RTree::bulk_load(
        boxes
            .iter()
            .enumerate()
            .map(|(i, b)| {
                GeomWithData::new(
                    Rectangle::from_corners(b.min.to_array(), b.max.to_array()),
                    i as u32,
                )
            })
            .collect(),
    )
}

fn bounds(e: &AABB<[f32; 3]>) -> Aabb {
    Aabb {
        min: Vec3::from(e.lower()),
        max: Vec3::from(e.upper()),
    }
}

/// `p` and all below it, in preorder.
fn push(p: &ParentNode<Entry>, nodes: &mut Vec<Node>) {
    let at = nodes.len();
    nodes.push(Node {
        bounds: bounds(&p.envelope()),
        next: 0,
        object: INNER,
    });
    for child in p.children() {
        match child {
            RTreeNode::Leaf(e) => nodes.push(Node {
                bounds: bounds(&e.envelope()),
                next: nodes.len() as u32 + 1,
                object: e.data,
            }),
            RTreeNode::Parent(q) => push(q, nodes),
        }
    }
    nodes[at].next = nodes.len() as u32;
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A walk of the flat tree keeps, with the same tests, what a walk of `rstar`'s
    /// tree keeps, and skips the subtrees it drops.
    #[test]
    fn it_selects_what_rstar_selects() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let boxes: Vec<Aabb> = (0..3000)
            .map(|_| {
                let min = Vec3::new(rng.gen_range(0.0..1000.0), 0.0, rng.gen_range(0.0..1000.0));
                Aabb {
                    min,
                    max: min + Vec3::new(10.0, rng.gen_range(3.0..40.0), 12.0),
                }
            })
            .collect();
        let flat = FlatTree::new(&boxes);
        assert!(FlatTree::new(&[]).select(|_| true, |_, _| true).is_empty());
        let all = flat.select(|_| true, |_, _| true);
        assert_eq!(all.len(), boxes.len());
        for (k, &i) in all.iter().enumerate() {
            assert_eq!(
                flat.nodes.iter().filter(|n| n.object == i).count(),
                1,
                "{k}"
            );
        }
        // Drop what lies under a plane, whole subtrees at a time.
        let tree = rtree(&boxes);
        struct Above(f32);
        impl rstar::SelectionFunction<Entry> for Above {
            fn should_unpack_parent(&self, e: &AABB<[f32; 3]>) -> bool {
                e.upper()[0] + e.upper()[2] > self.0
            }
            fn should_unpack_leaf(&self, l: &Entry) -> bool {
                self.should_unpack_parent(&l.envelope())
            }
        }
        let (mut entered, mut taken) = (0, 0);
        let mut kept = flat.select(
            |b| {
                entered += 1;
                b.max.x + b.max.z > 1200.0
            },
            |_, b| {
                taken += 1;
                b.max.x + b.max.z > 1200.0
            },
        );
        let mut expected: Vec<u32> = tree
            .locate_with_selection_function(Above(1200.0))
            .map(|e| e.data)
            .collect();
        kept.sort_unstable();
        expected.sort_unstable();
        assert_eq!(kept, expected);
        assert!(!kept.is_empty() && kept.len() < boxes.len());
        assert!(
            taken < boxes.len() / 2,
            "{taken} leaves tested, {entered} inner nodes"
        );
    }
}
