//! What a server streams: objects with a progressive mesh and a DAG, each held once and
//! shared read-only by every session.

use std::sync::Arc;

use flaneur::lod::{Dag, ProgressiveMesh};
use flaneur::Database;

use crate::error::StreamError;

/// An object a server streams: its progressive mesh and DAG.
#[derive(Clone, Debug)]
pub struct Landmark {
    /// The object's id in its database (or whatever the caller numbers it by).
    pub id: u64,
    pub pm: Arc<ProgressiveMesh>,
    pub dag: Arc<Dag>,
}

impl Landmark {
    /// Every object of `db` the build stored a progressive mesh and DAG for (those above
    /// `--pm-threshold`), by id; at most `max` of them, the largest first when there are
    /// more.
    pub fn all_in(db: &Database, max: usize) -> Result<Vec<Landmark>, StreamError> {
        let mut ids: Vec<u64> = db
            .range(&db.bounds())?
            .objects
            .iter()
            .map(|o| o.id)
            .collect();
        ids.sort_unstable();
        let mut found = Vec::new();
        for id in ids {
            if let Some((pm, dag)) = db.progressive(id)? {
                found.push(Landmark {
                    id,
                    pm: Arc::new(pm),
                    dag: Arc::new(dag),
                });
            }
        }
        if found.len() > max {
            found.sort_by_key(|l| std::cmp::Reverse(l.pm.splits.len()));
            found.truncate(max);
            found.sort_by_key(|l| l.id);
        }
        Ok(found)
    }

    /// Triangles of its full mesh.
    pub fn triangles(&self) -> usize {
        self.pm.triangles_after(self.pm.splits.len())
    }
}
