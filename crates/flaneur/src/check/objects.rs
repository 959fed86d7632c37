//! The R-tree and the objects it holds: every node, every object's mesh, and the
//! header's counts of them.

use std::collections::BTreeMap;

use super::claims::Claims;
use crate::catalog::{read_mesh, Meta};
use crate::geom::Aabb;
use crate::rtree::{Node, ObjectEntry, RTree};
use crate::store::{PageKind, Store};

/// The objects the R-tree holds, by id.
pub(super) type Objects = BTreeMap<u64, ObjectEntry>;

/// Walks the tree from its root: each node read, decoded and checked against the entry
/// that points at it; each object's mesh read and checked against its entry.
pub(super) fn check(store: &Store, tree: &RTree, c: &mut Claims) -> Objects {
    let mut objects = Objects::new();
    let root_level = tree.height.saturating_sub(1) as u16;
    // (page, the level it must be at, the box its parent's entry gives it)
    let mut stack: Vec<(u64, u16, Option<Aabb>)> = vec![(tree.root, root_level, None)];
    while let Some((page, level, entry_box)) = stack.pop() {
        let part = format!("r-tree node at level {level}");
        if !c.claim(page, 1, PageKind::RtreeNode, &part) {
            continue;
        }
        let payload = match store.read_page(page, PageKind::RtreeNode) {
            Ok(p) => p,
            Err(e) => {
                c.problem(&e, &part);
                continue;
            }
        };
        let node = match Node::decode(&payload) {
            Ok(n) => n,
            Err(what) => {
                c.found(Some(page), &part, what);
                continue;
            }
        };
        if node.level() != level {
            c.found(
                Some(page),
                &part,
                format!("the node says it is at level {}", node.level()),
            );
            continue;
        }
        if let Some(b) = entry_box.filter(|b| node.len() > 0 && !b.contains(&node.mbr())) {
            c.found(
                Some(page),
                &part,
                format!(
                    "its parent's entry box {b:?} does not hold its box {:?}",
                    node.mbr()
                ),
            );
        }
        match node {
            Node::Internal { children, .. } => {
                if level == 0 || children.is_empty() {
                    c.found(
                        Some(page),
                        &part,
                        "an internal node without children".into(),
                    );
                }
                for child in children.iter().rev() {
                    stack.push((child.page, level.saturating_sub(1), Some(child.mbr)));
                }
            }
            Node::Leaf(entries) => {
                for o in entries {
                    object(store, page, &o, c);
                    if objects.insert(o.id, o).is_some() {
                        c.found(Some(page), &part, format!("object {} is there twice", o.id));
                    }
                }
            }
        }
    }
    objects
}

/// One object's mesh: where it lies, that it decodes, and that it is what the entry
/// says.
fn object(store: &Store, leaf: u64, o: &ObjectEntry, c: &mut Claims) {
    let part = format!("mesh of object {}", o.id);
    if !c.claim_extent(&o.mesh, PageKind::Mesh, &part) {
        return;
    }
    let mesh = match read_mesh(store, o) {
        Ok(m) => m,
        Err(e) => return c.problem(&e, &part),
    };
    let at = Some(o.mesh.first_page);
    if mesh.triangle_count() != o.triangles as usize {
        c.found(
            at,
            &part,
            format!(
                "{} triangles, its leaf entry (page {leaf}) says {}",
                mesh.triangle_count(),
                o.triangles
            ),
        );
    }
    let (min, max) = mesh.bounds();
    match Aabb::new(min, max) {
        Ok(b) if o.bounds.contains(&b) => {}
        _ => c.found(
            at,
            &part,
            format!(
                "its vertices span {min:?}..{max:?}, outside the box {:?} of its leaf entry \
                 (page {leaf})",
                o.bounds
            ),
        ),
    }
}

/// The header's counts of objects and triangles and its bounds against the tree's.
pub(super) fn agree_with_header(meta: &Meta, tree: &RTree, objects: &Objects, c: &mut Claims) {
    let header = "the file header";
    let found = objects.len() as u64;
    if meta.objects != found || tree.objects != found {
        c.found(
            Some(0),
            header,
            format!(
                "it counts {} objects (the R-tree's segment {}), the R-tree holds {found}",
                meta.objects, tree.objects
            ),
        );
    }
    let triangles: u64 = objects.values().map(|o| o.triangles as u64).sum();
    if meta.triangles != triangles {
        c.found(
            Some(0),
            header,
            format!(
                "it counts {} triangles, the objects hold {triangles}",
                meta.triangles
            ),
        );
    }
    let bounds = objects
        .values()
        .fold(Aabb::EMPTY, |b, o| b.union(&o.bounds));
    if found > 0 && !meta.bounds.contains(&bounds) {
        c.found(
            Some(0),
            header,
            format!(
                "its bounds {:?} do not hold the objects' {bounds:?}",
                meta.bounds
            ),
        );
    }
}
