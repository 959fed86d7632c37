//! A REVIEW walk's loader: what a loader thread is asked for (a disk cell, searched with
//! BOX or CSearch against the history) and what it hands back, the cell's new objects
//! with their meshes (or, for a never-wait walk on a database with LODs, their coarsest
//! levels), a batch at a time in the order `load_order` gives when the walk never waits.

use std::collections::HashSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use glam::Vec3;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::rtree::{Coverlap, ObjectEntry, QueryResult};
use crate::store::PageSource;
use crate::walk::buffer::Loaded;
use crate::walk::review::Retrieval;
use crate::walk::sink::LeftOut;
use crate::walk::threads::damage::{coarsest_or_full, Damaged};
use crate::walk::threads::load_order::load_order;
use crate::walk::threads::mesh_batch::read_meshes;
use crate::walk::threads::refining::MESHES_ASKED_TOGETHER;

/// A query's result with its meshes, loaded on the thread that ran it.
pub(super) struct Fetched {
    pub(super) cell: Aabb,
    pub(super) epoch: u64,
    pub(super) objects: Vec<Loaded>,
    /// What CSearch retrieved for the cell (for the history).
    pub(super) retrieved: Vec<ObjectEntry>,
    /// Objects of `retrieved` the network failed to bring, where the viewer walks on
    /// past a failure (then the cell is not held whole, and is asked for again), and the
    /// last such failure's words.
    pub(super) unloaded: usize,
    pub(super) failure: Option<String>,
    /// Time in the index, and reading meshes, on the thread that fetched.
    pub(super) query_ms: f64,
    pub(super) load_ms: f64,
}

/// What a loader is asked for: a cell, and how to load its objects.
pub(super) struct Request {
    pub(super) cell: Aabb,
    /// Load each object's coarsest stored level, not its full mesh.
    pub(super) coarse: bool,
    pub(super) history: Vec<Aabb>,
    pub(super) epoch: u64,
    /// Where the viewer stood and looked when it asked (never-wait walks): the objects
    /// are loaded in view first, nearest first, and handed over a batch at a time.
    pub(super) priority: Option<(Vec3, Vec3)>,
}

/// What a loader thread hands back for a request.
pub(super) enum Answer {
    /// A batch of the request's objects, loaded before the rest (never-wait walks): drawn
    /// at once, and handed over again with the whole result.
    Part { epoch: u64, objects: Vec<Loaded> },
    /// The whole result.
    Done(Result<Fetched>),
}

/// What the viewer's thread shares with the loaders: the ids in the object buffer, the
/// objects left out (a viewer that walks on past them), the coarse levels found damaged.
pub(super) type SharedSets<'a> = (
    &'a Mutex<HashSet<u64>>,
    Option<&'a Mutex<LeftOut>>,
    &'a Mutex<Damaged>,
);

/// Runs one query and loads the meshes of what it returned (those it had time for, when
/// `ended` says the walk is over and no one will take them). Coarse levels that cannot
/// be read for damage are named in `damaged`, their objects read at full detail.
pub(super) fn fetch(
    db: &Database,
    source: &(dyn PageSource + Sync),
    retrieval: Retrieval,
    req: &Request,
    (resident, left_out, damaged): SharedSets<'_>,
    ended: &AtomicBool,
    part: &mut dyn FnMut(&[Loaded]),
) -> Result<Fetched> {
    let t = Instant::now();
    let result: QueryResult = match retrieval {
        Retrieval::Box => db.tree().range(source, &req.cell)?,
        Retrieval::CSearch => {
            db.tree()
                .csearch_with(source, &req.cell, &req.history, Coverlap::default())?
        }
    };
    let query_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let mut wanted: Vec<&ObjectEntry> = result
        .objects
        .iter()
        .filter(|entry| {
            !(resident.lock().is_ok_and(|r| r.contains(&entry.id))
                || left_out.is_some_and(|l| l.lock().is_ok_and(|l| l.contains(entry.id))))
        })
        .collect();
    if let Some((eye, aim)) = req.priority {
        wanted.sort_by(|a, b| load_order(a, eye, aim).total_cmp(&load_order(b, eye, aim)));
    }
    let mut objects = Vec::with_capacity(wanted.len());
    // Objects handed over as parts so far (never-wait walks): each batch is drawn while
    // the next loads; the last comes with the whole result.
    let mut handed = 0;
    let (mut unloaded, mut failure) = (0, None);
    for batch in wanted.chunks(MESHES_ASKED_TOGETHER) {
        if ended.load(Ordering::Relaxed) {
            break;
        }
        if req.priority.is_some() && objects.len() > handed {
            part(&objects[handed..]);
            handed = objects.len();
        }
        let entries: Vec<ObjectEntry> = batch.iter().map(|e| **e).collect();
        // Coarse first: an object whose coarse level is damaged comes at full detail,
        // named, rather than costing its batch's coarse levels.
        let full = match req.coarse {
            true => {
                let (coarse, full) = coarsest_or_full(db, &entries, damaged)?;
                objects.extend(coarse);
                full
            }
            false => entries,
        };
        if full.is_empty() {
            continue;
        }
        // A viewer that walks on past damage walks on past a network's failure too, but
        // without the object only until the cell is asked for again.
        objects.extend(read_meshes(db, full.iter(), left_out, |_, err| {
            match (err, left_out) {
                (err @ Error::Remote { .. }, Some(_)) => {
                    unloaded += 1;
                    failure = Some(err.to_string());
                    Ok(())
                }
                (err, _) => Err(err),
            }
        })?);
    }
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(Fetched {
        cell: req.cell,
        epoch: req.epoch,
        objects,
        retrieved: result.objects,
        unloaded,
        failure,
        query_ms,
        load_ms,
    })
}
