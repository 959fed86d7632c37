//! Bulk loading by Sort-Tile-Recursive packing (Leutenegger, Lopez, Edgington 1997).
//!
//! The thesis built its trees by one-by-one insertion (§4.1); packing is our default
//! because it fills pages and keeps sibling MBRs apart, so queries read fewer pages.
//! `flaneur bench csearch` runs both trees. Departure from plain STR: the tiling uses
//! the axes along which the entries' centres spread, in order of spread, and skips an
//! axis whose spread is under a tenth of the largest — a city is flat, and slicing
//! its height would only make thin, wide nodes.

use super::node::{ChildEntry, Fanout, Node, ObjectEntry};
use super::RTree;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::store::{PageKind, Store};
use glam::Vec3;

/// Share of a node's fan-out that packing fills.
pub const DEFAULT_FILL: f32 = 1.0;

pub(crate) fn bulk_load(store: &mut Store, entries: Vec<ObjectEntry>, fill: f32) -> Result<RTree> {
    if !(0.1..=1.0).contains(&fill) {
        return Err(Error::Invalid(format!(
            "fill factor {fill} is outside 0.1..=1"
        )));
    }
    for e in &entries {
        e.bounds.validate()?;
    }
    let fanout = Fanout::for_payload(store.payload_size());
    if fanout.leaf < 2 || fanout.internal < 2 {
        return Err(Error::Invalid(format!(
            "page size {} is too small for R-tree nodes",
            store.page_size()
        )));
    }
    let cap = |max: usize| ((max as f32 * fill).floor() as usize).clamp(2, max);
    let objects = entries.len() as u64;

    if entries.is_empty() {
        let root = store.append_page(PageKind::RtreeNode, &Node::Leaf(Vec::new()).encode())?;
        return Ok(RTree {
            root,
            height: 1,
            objects,
            fanout,
        });
    }

    let mut level_nodes = Vec::new();
    for group in tile(entries, cap(fanout.leaf), |e| e.bounds.center()) {
        let node = Node::Leaf(group);
        let page = store.append_page(PageKind::RtreeNode, &node.encode())?;
        level_nodes.push(ChildEntry {
            mbr: node.mbr(),
            page,
        });
    }
    let mut height = 1u32;
    while level_nodes.len() > 1 {
        let mut parents = Vec::new();
        for group in tile(level_nodes, cap(fanout.internal), |c| c.mbr.center()) {
            let node = Node::Internal {
                level: height as u16,
                children: group,
            };
            let page = store.append_page(PageKind::RtreeNode, &node.encode())?;
            parents.push(ChildEntry {
                mbr: node.mbr(),
                page,
            });
        }
        level_nodes = parents;
        height += 1;
    }
    Ok(RTree {
        root: level_nodes[0].page,
        height,
        objects,
        fanout,
    })
}

/// Splits `items` into runs of at most `cap`, tiled along the axes of spread.
pub(crate) fn tile<T>(
    mut items: Vec<T>,
    cap: usize,
    center: impl Fn(&T) -> Vec3 + Copy,
) -> Vec<Vec<T>> {
    let bounds = Aabb::from_points(items.iter().map(center));
    let spread = bounds.extent().to_array();
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| spread[b].total_cmp(&spread[a]));
    let largest = spread[axes[0]];
    let axes: Vec<usize> = axes
        .into_iter()
        .filter(|&a| spread[a] >= 0.1 * largest && spread[a] > 0.0)
        .collect();
    let axes = if axes.is_empty() { vec![0] } else { axes };

    let mut out = Vec::with_capacity(items.len().div_ceil(cap));
    let mut bounds_of_runs = Vec::new();
    tile_axes(&mut items, cap, &axes, center, &mut bounds_of_runs);
    let mut rest = items.into_iter();
    for len in bounds_of_runs {
        out.push(rest.by_ref().take(len).collect());
    }
    out
}

/// Sorts `items` in place into tiles and records the tile lengths in order.
fn tile_axes<T>(
    items: &mut [T],
    cap: usize,
    axes: &[usize],
    center: impl Fn(&T) -> Vec3 + Copy,
    runs: &mut Vec<usize>,
) {
    let n = items.len();
    if n <= cap {
        runs.push(n);
        return;
    }
    let axis = axes[0];
    items.sort_unstable_by(|a, b| center(a)[axis].total_cmp(&center(b)[axis]));
    if axes.len() == 1 {
        let mut left = n;
        while left > 0 {
            let len = left.min(cap);
            runs.push(len);
            left -= len;
        }
        return;
    }
    let pages = n.div_ceil(cap);
    let slabs = (pages as f64).powf(1.0 / axes.len() as f64).ceil() as usize;
    let slab_len = cap * pages.div_ceil(slabs);
    for slab in items.chunks_mut(slab_len) {
        tile_axes(slab, cap, &axes[1..], center, runs);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_are_full_and_cover_everything() {
        let items: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::new((i % 37) as f32, 0.0, (i / 37) as f32))
            .collect();
        let runs = tile(items, 10, |p| *p);
        assert_eq!(runs.iter().map(Vec::len).sum::<usize>(), 1000);
        assert!(runs.iter().all(|r| r.len() <= 10 && !r.is_empty()));
        // STR leaves at most one short tile per slab.
        assert!(runs.len() <= 100 + 11);
    }
}
