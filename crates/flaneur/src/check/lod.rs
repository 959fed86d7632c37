//! The LOD table: each entry's extents, chains, progressive meshes and DAGs.

use super::claims::Claims;
use super::objects::Objects;
use crate::lod::stored::{level_mesh, levels, progressive, LodTable};
use crate::store::{PageKind, Store};

pub(super) fn check(store: &Store, table: &LodTable, objects: &Objects, c: &mut Claims) {
    let part = "the LOD table";
    c.claim_extent(&table.extent(), PageKind::Lod, part);
    c.count_kind(PageKind::Lod, table.pages());
    let entries = match table.entry_count(store) {
        Ok(n) => n,
        Err(e) => return c.problem(&e, part),
    };
    let mut found = 0u64;
    for (&id, o) in objects {
        let e = match table.find(store, id) {
            Ok(Some(e)) => e,
            Ok(None) => continue,
            Err(e) => {
                c.problem(&e, part);
                continue;
            }
        };
        found += 1;
        if e.mesh != o.mesh || e.triangles != o.triangles {
            c.found(
                Some(table.extent().first_page),
                part,
                format!(
                    "object {id}'s entry names a mesh of {} triangles at page {}, its \
                     R-tree entry one of {} at page {}",
                    e.triangles, e.mesh.first_page, o.triangles, o.mesh.first_page
                ),
            );
        }
        let chain = format!("LOD chain of object {id}");
        let mut whole = true;
        for (ext, what) in [
            (e.chain, chain.clone()),
            (e.chain_rest, format!("{chain} (its finer levels)")),
            (e.pm, format!("progressive mesh of object {id}")),
            (e.dag, format!("DAG of object {id}")),
        ] {
            if !ext.is_empty() {
                whole &= c.claim_extent(&ext, PageKind::Lod, &what);
            }
        }
        if !whole {
            continue;
        }
        match levels(store, &e) {
            Ok(infos) => {
                for level in 1..infos.len() {
                    if let Err(err) = level_mesh(store, &e, level) {
                        c.problem(&err, &chain);
                    }
                }
            }
            Err(err) => c.problem(&err, &chain),
        }
        if let Err(err) = progressive(store, &e) {
            c.problem(&err, &format!("progressive mesh and DAG of object {id}"));
        }
    }
    if found != entries {
        c.found(
            Some(table.extent().first_page),
            part,
            format!("it holds {entries} entries, {found} of the R-tree's objects have one"),
        );
    }
}
