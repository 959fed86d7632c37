//! A REVIEW walk set up: its index cache, the misses' ground truth, the prefetch thread
//! and (never waiting) the viewer's own loader and the refining thread, then the walk
//! session with the REVIEW mode.

use super::counts::Counts;
use super::loader::{fetch, Answer, Request, SharedSets};
use super::mode::Lane;
use super::mode::{Channels, Review};
use crate::cache::{policy_by_name, BufferPool};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::rtree::ObjectEntry;
use crate::store::PageSource;
use crate::walk::buffer::Loaded;
use crate::walk::review::tally::ReviewTally;
use crate::walk::review::{FrameStats, Retrieval, ReviewConfig, WalkReport};
use crate::walk::session::{self};
use crate::walk::sink::{LeftOut, Viewer};
use crate::walk::threads::damage::{self, Damaged};
use crate::walk::threads::refining::{refine, Refined};
use crate::walk::walk_lods::WalkLods;
use std::collections::HashSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Mutex};

/// A REVIEW walk under `cfg` with the poses coming from `viewer`: the walk session with
/// the REVIEW mode, its index cache and its loader threads, each frame's figures handed
/// to `each` as the frame ends and none kept (the report's `frames` is empty, its
/// summary whole).
pub(crate) fn walk<'db>(
    db: &'db Database,
    cfg: &ReviewConfig,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(&FrameStats) -> Result<()>,
) -> Result<WalkReport> {
    cfg.validate()?;
    // The misses' ground truth, read (once a handle) before the walk's counters start.
    let boxes = db.box_index()?;
    db.reset_io();
    let pool = index_cache(db, cfg)?;
    let source: &(dyn PageSource + Sync) = match &pool {
        Some(p) => p,
        None => db.store(),
    };
    // The ids in the object buffer, which no fetch loads again — read when the meshes
    // are, so a prefetch asked for before the viewer's own query skips what it loaded.
    let resident = Mutex::new(HashSet::new());
    let resident = &resident;
    // Objects whose meshes could not be read, when the viewer walks on without them;
    // shared with the prefetch thread, and told of from here (a prefetch that finds
    // one may be dropped as stale).
    let left_out = viewer
        .skips_damaged()
        .then(|| Mutex::new(LeftOut::default()));
    let left_out = left_out.as_ref();
    // Coarse levels the loaders could not read for damage (their objects loaded at full
    // detail), named for the summary.
    let met = Mutex::new(Damaged::default());
    let damaged = &met;
    // Set when the walk ends: a loader stops reading for a result no one will take.
    let ended = AtomicBool::new(false);
    let ended = &ended;
    // Set while the viewer's own lane loads: the refining thread gives way to it.
    let now_busy = AtomicBool::new(false);
    let now_busy = &now_busy;
    let (tally, counts) = std::thread::scope(|scope| -> Result<(ReviewTally, Counts)> {
        let (res_tx, res_rx) = mpsc::channel::<(Lane, Answer)>();
        let sets = (resident, left_out, damaged);
        let shared = Shared {
            sets,
            ended,
            now_busy,
        };
        let lane = |on: bool, lane: Lane| {
            on.then(|| {
                spawn_lane(
                    scope,
                    lane,
                    db,
                    source,
                    cfg.retrieval,
                    shared,
                    res_tx.clone(),
                )
            })
        };
        let lanes = [
            lane(cfg.prefetch_k.is_some(), Lane::Ahead),
            lane(cfg.never_wait, Lane::Now),
        ];
        drop(res_tx);
        let (fine_tx, fine_rx) = mpsc::channel::<Vec<ObjectEntry>>();
        let (refined_tx, refined_rx) = mpsc::channel::<Refined>();
        let refining = cfg.never_wait && db.has_lods();
        if refining {
            scope.spawn(move || {
                for job in fine_rx {
                    if refine(db, &job, left_out, (now_busy, ended), &refined_tx).is_err() {
                        break;
                    }
                }
            });
        }
        let channels = Channels {
            lanes,
            res_rx,
            fine_tx: refining.then_some(fine_tx),
            refined_rx,
        };
        let mut mode = Review::new((db, source, cfg), boxes, pool.as_ref(), sets, channels);
        let mut tally = ReviewTally::default();
        let walked = session::run_each(&mut mode, viewer, lods, |f| {
            tally.add(&f);
            each(&f)
        });
        ended.store(true, Ordering::Relaxed);
        walked?;
        if tally.frames() == 0 {
            return Err(Error::Invalid("the walk had no poses".into()));
        }
        Ok((tally, mode.close(refining)))
    })?;
    let mut summary = tally.summary(counts, pool.as_ref().map(|p| p.stats()));
    summary.damaged = damage::named(met);
    let trace = pool
        .as_ref()
        .filter(|_| cfg.record_trace)
        .map(|p| p.take_trace());
    Ok(WalkReport {
        config: cfg.clone(),
        frames: Vec::new(),
        summary,
        trace,
    })
}

/// The walk's index cache, when it has one, recording its trace when asked to.
fn index_cache<'db>(db: &'db Database, cfg: &ReviewConfig) -> Result<Option<BufferPool<'db>>> {
    let Some((policy, bytes)) = &cfg.index_cache else {
        return Ok(None);
    };
    let pool = BufferPool::new(db.store(), *bytes, policy_by_name(policy)?)?;
    pool.set_trace(cfg.record_trace);
    Ok(Some(pool))
}

/// What the loader threads share with the viewer's: the sets the mode keeps too,
/// whether the walk has ended and whether the viewer's own lane is loading.
#[derive(Clone, Copy)]
struct Shared<'a> {
    sets: SharedSets<'a>,
    ended: &'a AtomicBool,
    now_busy: &'a AtomicBool,
}

/// A loader thread for `lane` in `scope`: it takes its requests in turn, hands each
/// part of an answer on as it comes and then the whole, and stops when its requests'
/// channel closes or no one takes its answers. Returns where its requests go.
fn spawn_lane<'scope, 'a: 'scope>(
    scope: &'scope std::thread::Scope<'scope, '_>,
    lane: Lane,
    db: &'a Database,
    source: &'a (dyn PageSource + Sync),
    retrieval: Retrieval,
    shared: Shared<'a>,
    res_tx: mpsc::Sender<(Lane, Answer)>,
) -> mpsc::Sender<Request> {
    let (req_tx, req_rx) = mpsc::channel::<Request>();
    scope.spawn(move || {
        for req in req_rx {
            shared.now_busy.store(lane == Lane::Now, Ordering::Relaxed);
            let mut part = |objects: &[Loaded]| {
                let part = Answer::Part {
                    epoch: req.epoch,
                    objects: objects.to_vec(),
                };
                let _ = res_tx.send((lane, part));
            };
            let fetched = fetch(
                db,
                source,
                retrieval,
                &req,
                shared.sets,
                shared.ended,
                &mut part,
            );
            shared.now_busy.store(false, Ordering::Relaxed);
            if res_tx.send((lane, Answer::Done(fetched))).is_err() {
                break;
            }
        }
    });
    req_tx
}
