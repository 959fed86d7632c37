//! A bounding-volume hierarchy over the objects' boxes, for visiting them front to back
//! and skipping whole groups hidden behind what is already drawn. Built once per scene
//! by median splits of the boxes' centres along the widest axis: a city's objects are
//! spread over the ground, so the tree is balanced and shallow (about log₂ of the
//! objects' count).

/// Objects per leaf at most.
const LEAF: usize = 4;

/// A node: its box, and either two children or a run of objects.
#[derive(Clone, Debug)]
pub(super) struct Node {
    pub lo: [f32; 3],
    pub hi: [f32; 3],
    pub kind: Kind,
}

#[derive(Clone, Debug)]
pub(super) enum Kind {
    /// Child nodes by index.
    Inner(u32, u32),
    /// `order[first..first + count]` are its objects.
    Leaf { first: u32, count: u32 },
}

/// The hierarchy: node 0 is the root (absent when there are no objects).
#[derive(Clone, Debug, Default)]
pub(super) struct ObjectTree {
    pub nodes: Vec<Node>,
    /// Object indices, each leaf's a run.
    pub order: Vec<u32>,
}

impl ObjectTree {
    /// The tree over `boxes` (`(lo, hi)` by object index).
    pub fn new(boxes: &[([f32; 3], [f32; 3])]) -> ObjectTree {
        let mut tree = ObjectTree {
            nodes: Vec::with_capacity(2 * boxes.len() / LEAF + 1),
            order: (0..boxes.len() as u32).collect(),
        };
        if !boxes.is_empty() {
            tree.build(boxes, 0, boxes.len());
        }
        tree
    }

    /// Builds the node over `order[first..end]`; returns its index.
    fn build(&mut self, boxes: &[([f32; 3], [f32; 3])], first: usize, end: usize) -> u32 {
        let objects = &mut self.order[first..end];
        let (lo, hi) = objects.iter().fold(
            ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
            |(l, h), &o| {
                let (a, b) = boxes[o as usize];
                (
                    std::array::from_fn(|k| l[k].min(a[k])),
                    std::array::from_fn(|k| h[k].max(b[k])),
                )
            },
        );
        let at = self.nodes.len() as u32;
        self.nodes.push(Node {
            lo,
            hi,
            kind: Kind::Leaf {
                first: first as u32,
                count: (end - first) as u32,
            },
        });
        if end - first <= LEAF {
            return at;
        }
        let centre = |o: u32, k: usize| boxes[o as usize].0[k] + boxes[o as usize].1[k];
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        let mid = objects.len() / 2;
        objects.select_nth_unstable_by(mid, |&a, &b| centre(a, axis).total_cmp(&centre(b, axis)));
        let left = self.build(boxes, first, first + mid);
        let right = self.build(boxes, first + mid, end);
        self.nodes[at as usize].kind = Kind::Inner(left, right);
        at
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_object_is_in_one_leaf_inside_every_box_above_it() {
        let boxes: Vec<([f32; 3], [f32; 3])> = (0..37)
            .map(|k| {
                let x = (k * 7 % 37) as f32;
                ([x, 0.0, -x], [x + 1.0, 2.0, 1.0 - x])
            })
            .collect();
        let tree = ObjectTree::new(&boxes);
        let mut seen = vec![0; boxes.len()];
        let mut stack = vec![(0u32, ([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]))];
        while let Some((node, (lo, hi))) = stack.pop() {
            let n = &tree.nodes[node as usize];
            assert!((0..3).all(|k| lo[k] <= n.lo[k] && n.hi[k] <= hi[k]));
            match n.kind {
                Kind::Inner(a, b) => stack.extend([(a, (n.lo, n.hi)), (b, (n.lo, n.hi))]),
                Kind::Leaf { first, count } => {
                    assert!(count as usize <= LEAF);
                    for &o in &tree.order[first as usize..(first + count) as usize] {
                        let (a, b) = boxes[o as usize];
                        assert!((0..3).all(|k| n.lo[k] <= a[k] && b[k] <= n.hi[k]));
                        seen[o as usize] += 1;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        assert!(ObjectTree::new(&[]).nodes.is_empty());
    }
}
