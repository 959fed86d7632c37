//! The HDoV-tree: its head, every node with its internal LODs, and each storage
//! scheme's V-pages for every cell.

use super::claims::Claims;
use super::objects::Objects;
use crate::cache::Hint;
use crate::hdov::{HNodeKind, HdovTree, Scheme};
use crate::lod::stored::chain_levels;
use crate::store::{PageKind, Store};

pub(super) fn check(store: &Store, tree: &HdovTree, objects: &Objects, c: &mut Claims) {
    let part = "the HDoV-tree's head";
    if !c.claim_extent(&tree.extent(), PageKind::HdovNode, part) {
        return;
    }
    let head = match tree.head(store) {
        Ok(h) => h.clone(),
        Err(e) => return c.problem(&e, part),
    };
    c.count_kind(PageKind::Lod, head.lod_pages);
    if !c.claim(
        head.first_node,
        head.nodes as u64,
        PageKind::HdovNode,
        "the HDoV-tree's nodes",
    ) {
        return;
    }
    for number in 0..head.nodes {
        let node_part = format!("HDoV node {number}");
        let node = match tree.node_through(store, None, number, &Hint::UNKNOWN) {
            Ok(n) => n,
            Err(e) => {
                c.problem(&e, &node_part);
                continue;
            }
        };
        let page = Some(head.first_node + number as u64);
        match &node.kind {
            HNodeKind::Leaf(entries) => {
                for o in entries {
                    if objects.get(&o.id).map(|r| r.mesh) != Some(o.mesh) {
                        c.found(
                            page,
                            &node_part,
                            format!(
                                "object {} is not the R-tree's object of that id and mesh",
                                o.id
                            ),
                        );
                    }
                }
            }
            HNodeKind::Internal { children, .. } => {
                for child in children.iter().filter(|ch| !ch.lods.is_empty()) {
                    let what = format!("internal LODs of HDoV node {}", child.node);
                    if c.claim_extent(&child.lods, PageKind::Lod, &what) {
                        if let Err(e) = chain_levels(store, &child.lods, &what) {
                            c.problem(&e, &what);
                        }
                    }
                }
            }
        }
    }
    let vpages = |scheme: Scheme| format!("the HDoV-tree's V-pages ({} scheme)", scheme.name());
    // Claimed from the head first, so that a damaged scheme head is named as its own.
    let mut whole = true;
    for (scheme, extent) in &head.schemes {
        whole &= c.claim_extent(extent, PageKind::VPage, &vpages(*scheme));
    }
    if !whole {
        return;
    }
    let schemes = match tree.schemes(store) {
        Ok(s) => s,
        Err(e) => return c.problem(&e, part),
    };
    for scheme in schemes {
        let what = vpages(scheme.scheme);
        'cells: for (slot, cell) in head.cells.iter().enumerate() {
            let entered = match scheme.enter(store, slot) {
                Ok(e) => e,
                Err(e) => {
                    c.problem(&e, &format!("{what}, cell {cell}"));
                    continue;
                }
            };
            for node in 0..head.nodes {
                if let Err(e) = scheme.vpage(store, &entered, node) {
                    c.problem(&e, &format!("{what}, cell {cell}, node {node}"));
                    continue 'cells;
                }
            }
        }
    }
}
