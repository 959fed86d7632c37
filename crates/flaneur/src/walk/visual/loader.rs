//! The loader thread of a VISUAL walk that never waits (ours): it does every read the
//! walk needs, the HDoV-tree's searches and the finds' meshes, while the viewer's
//! thread only posts where it stands and takes what has arrived.
//!
//! It searches the place the viewer stands in first (a viewcell, or outside every one
//! the fallback's disk cell, queried as the waiting walk queries it), then the viewcell
//! the viewer goes to when the walk prefetches. A place's finds load in the order a
//! never-wait REVIEW walk loads in (`load_order`: ahead before behind, nearest first),
//! each first at its coarsest level (an object's coarsest stored level, a node's
//! coarsest internal LOD; a few pages, asked for a batch at a time), then at the level
//! its DoV deserves once nothing coarse is left to load. A newer position reorders what
//! is still to load; finds that neither the viewer's place nor the next one want are
//! let go once the new place's finds are known.
//!
//! A read that fails on the network is asked for again a pause later, the walk going on;
//! a file changed under the walk stops it; damage stops it too, unless the viewer walks
//! on past damage, when the find is left out as the waiting walk leaves it out.

use std::collections::{HashMap, HashSet};
use std::sync::{mpsc, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;

use super::search::{key_of, loaded, Finds, Piece, Searcher};
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::hdov::{Found, Loader};
use crate::walk::buffer::Loaded;
use crate::walk::sink::LeftOut;
use crate::walk::threads::load_order::order_of;
use crate::walk::threads::mailbox::Mailbox;

/// Coarsest levels asked for at once: a few pages each, so that a cell's worth comes in
/// the round trips of one batch.
const COARSE_ASKED_TOGETHER: usize = 256;

/// Finds asked for at the level they deserve at once: few, so that the loader looks
/// from the viewer's latest position again soon.
const FINE_ASKED_TOGETHER: usize = 32;

/// How long a read the network failed waits before it is asked for again (each ask
/// already retried with the client's backoff).
const ASK_AGAIN_AFTER: Duration = Duration::from_millis(200);

/// A loader's two passes over a place's finds.
#[derive(Clone, Copy, Debug)]
enum Pass {
    /// Finds the viewer does not hold, at their coarsest level.
    Coarse,
    /// Finds held at another level than they deserve, at that level.
    Fine,
}

/// Where the viewer is: a viewcell, or outside every one (the fallback's disk cell,
/// numbered by the viewer as it asks for new ones).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Place {
    Cell(u32),
    Outside(u64),
}

/// Where the viewer stands at one frame, as it posts it to the loader.
#[derive(Clone, Copy, Debug)]
pub(super) struct Stand {
    pub eye: Vec3,
    pub aim: Vec3,
    pub here: Place,
    /// Outside every viewcell: the fallback's disk cell, queried for its objects.
    pub outside: Option<Aabb>,
    /// The viewcell the viewer goes to, when the walk prefetches and it is another.
    pub ahead: Option<u32>,
}

/// What the loader tells the viewer, in the order it happened.
pub(super) enum Update {
    /// A place's finds, each find's key at the level it deserves, in the search's order.
    Found {
        place: Place,
        finds: Vec<(u64, usize)>,
    },
    /// Finds arrived with their meshes: at their coarsest level, or at the level they
    /// deserve.
    Loaded(Vec<Loaded>),
    /// Places the viewer has left, whose finds the loader forgot, and the finds that
    /// neither the viewer's place nor the next one want: let go.
    LetGo { places: Vec<Place>, keys: Vec<u64> },
    /// A read failed on the network; what it was for is asked for again.
    Retrying(String),
    /// The loader cannot go on.
    Stopped(Error),
}

/// Runs the loader until the walk ends, telling `tx` what it does. `left_out` is kept
/// when the viewer walks on past damaged finds.
pub(super) fn run(
    search: &Searcher<'_>,
    mailbox: &Mailbox<Stand>,
    left_out: Option<&Mutex<LeftOut>>,
    tx: mpsc::Sender<Update>,
) {
    let mut loader = VisualLoader {
        search,
        loader: search.db.hdov_loader(),
        left_out,
        tx: &tx,
        finds: HashMap::new(),
        sent: HashMap::new(),
        stand: None,
        done: false,
        again_at: HashMap::new(),
    };
    while !mailbox.ended() {
        if let Err(e) = loader.turn(mailbox) {
            let _ = tx.send(Update::Stopped(e));
            return;
        }
    }
}

/// The loader's state between turns.
struct VisualLoader<'a> {
    search: &'a Searcher<'a>,
    loader: Loader<'a>,
    left_out: Option<&'a Mutex<LeftOut>>,
    tx: &'a mpsc::Sender<Update>,
    /// The finds of the places searched, those the viewer's place and the next one.
    finds: HashMap<Place, Vec<Piece>>,
    /// The level of each find the viewer holds, as sent to it.
    sent: HashMap<u64, usize>,
    /// The viewer's latest position.
    stand: Option<Stand>,
    /// Nothing was left to do from `stand`.
    done: bool,
    /// Finds the network failed to bring, and when to ask for them again.
    again_at: HashMap<u64, Instant>,
}

impl VisualLoader<'_> {
    /// One turn: take the viewer's latest position, then search one place or load one
    /// batch; waits for a position when there is nothing to do.
    fn turn(&mut self, mailbox: &Mailbox<Stand>) -> Result<()> {
        if let Some(stand) = mailbox.take(self.stand.is_none() || self.done) {
            self.stand = Some(stand);
            self.done = false;
        }
        let Some(stand) = self.stand else {
            return Ok(());
        };
        let ahead = stand.ahead.map(Place::Cell).filter(|&p| p != stand.here);
        let places: Vec<Place> = std::iter::once(stand.here).chain(ahead).collect();
        for &place in &places {
            if !self.finds.contains_key(&place) {
                return self.find(place, &stand);
            }
        }
        // Both places coarse before either at the levels deserved: entering the next
        // cell with its finds held coarse beats holding this one's finer.
        for pass in [Pass::Coarse, Pass::Fine] {
            for &place in &places {
                if self.load_batch(place, &stand, pass)? {
                    return Ok(());
                }
            }
        }
        self.done = true;
        Ok(())
    }

    /// Searches `place` (or queries the fallback's disk cell), tells the viewer its
    /// finds, and lets go of what no place wanted now wants.
    fn find(&mut self, place: Place, stand: &Stand) -> Result<()> {
        let found = match (place, stand.outside) {
            (Place::Cell(cell), _) => self.search.finds(&mut self.loader, cell),
            (Place::Outside(_), Some(cell)) => self.query(&cell),
            (Place::Outside(_), None) => Err(Error::Invalid(
                "a place outside every viewcell came without its disk cell".into(),
            )),
        };
        let Finds {
            pieces, mut failed, ..
        } = match found {
            Err(e @ Error::Remote { .. }) => return self.retry(None, e),
            other => other?,
        };
        // A find whose level the network kept from the search: the place is searched
        // again, rather than known without it.
        if let Some(k) = failed
            .iter()
            .position(|(_, e)| matches!(e, Error::Remote { .. }))
        {
            let (_, e) = failed.swap_remove(k);
            return self.retry(None, e);
        }
        for (key, e) in failed {
            self.leave_out(key, e)?;
        }
        let finds = pieces.iter().map(|p| (p.key, p.level)).collect();
        self.finds.insert(place, pieces);
        self.send(Update::Found { place, finds });
        // After the new place's finds, so that the viewer always has a place to draw.
        if place == stand.here {
            self.let_go(stand);
        }
        Ok(())
    }

    /// The fallback's finds outside every viewcell: the objects of `cell`, at full
    /// detail, as the waiting walk loads them.
    fn query(&mut self, cell: &Aabb) -> Result<Finds> {
        let t = Instant::now();
        let found: Vec<Found> = self
            .search
            .db
            .range(cell)?
            .objects
            .into_iter()
            .map(|entry| Found::Object {
                entry,
                dov: 0.0,
                detail: 1.0,
            })
            .collect();
        self.loader.learn(&found);
        let pieces = found
            .into_iter()
            .map(|found| {
                Ok(Piece {
                    key: key_of(&found)?,
                    level: 0,
                    found,
                })
            })
            .collect::<Result<_>>()?;
        Ok(Finds {
            pieces,
            failed: Vec::new(),
            ms: t.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// Drops the finds of places the viewer has left, and tells the viewer to let go of
    /// those neither its place nor the next one want.
    fn let_go(&mut self, stand: &Stand) {
        let keep: HashSet<Place> = [Some(stand.here), stand.ahead.map(Place::Cell)]
            .into_iter()
            .flatten()
            .collect();
        let places: Vec<Place> = self
            .finds
            .keys()
            .copied()
            .filter(|p| !keep.contains(p))
            .collect();
        self.finds.retain(|p, _| keep.contains(p));
        let wanted: HashSet<u64> = self.finds.values().flatten().map(|p| p.key).collect();
        let keys: Vec<u64> = self
            .sent
            .keys()
            .copied()
            .filter(|k| !wanted.contains(k))
            .collect();
        for k in &keys {
            self.sent.remove(k);
        }
        if !(places.is_empty() && keys.is_empty()) {
            self.send(Update::LetGo { places, keys });
        }
    }

    /// Loads one batch of `place`'s finds in `pass`; `false` when nothing of it is left
    /// to load in that pass.
    fn load_batch(&mut self, place: Place, stand: &Stand, pass: Pass) -> Result<bool> {
        let now = Instant::now();
        let left_out = self.left_out.and_then(|l| l.lock().ok());
        let loadable = |p: &&Piece| {
            !left_out.as_ref().is_some_and(|l| l.contains(p.key))
                && self.again_at.get(&p.key).is_none_or(|t| *t <= now)
        };
        // The viewer's place decides the level of a find the next place wants too.
        let theirs: HashSet<u64> = match self.finds.get(&stand.here) {
            Some(here) if place != stand.here => here.iter().map(|p| p.key).collect(),
            _ => HashSet::new(),
        };
        let mut pieces: Vec<&Piece> = self.finds[&place]
            .iter()
            .filter(|p| !theirs.contains(&p.key))
            .filter(loadable)
            .collect();
        drop(left_out);
        pieces.sort_by(|a, b| {
            let at = |p: &Piece| order_of(&bounds(&p.found), stand.eye, stand.aim);
            at(a).total_cmp(&at(b))
        });
        let batch = match pass {
            Pass::Coarse => {
                let coarse: Vec<Piece> = pieces
                    .iter()
                    .filter(|p| !self.sent.contains_key(&p.key))
                    .take(COARSE_ASKED_TOGETHER)
                    .map(|p| (*p).clone())
                    .collect();
                let mut batch = Vec::with_capacity(coarse.len());
                for p in coarse {
                    match self.loader.coarsest(&p.found) {
                        Ok(level) => batch.push((level, p)),
                        Err(e) => self.failed(p.key, e)?,
                    }
                }
                batch
            }
            Pass::Fine => pieces
                .iter()
                .filter(|p| self.sent.get(&p.key).is_some_and(|&l| l != p.level))
                .take(FINE_ASKED_TOGETHER)
                .map(|p| (p.level, (*p).clone()))
                .collect(),
        };
        if batch.is_empty() {
            return Ok(false);
        }
        let wanted: Vec<(&Found, usize)> = batch.iter().map(|(l, p)| (&p.found, *l)).collect();
        let meshes = self.loader.meshes(&wanted);
        let mut arrived = Vec::with_capacity(batch.len());
        for ((level, p), mesh) in batch.iter().zip(meshes) {
            match mesh {
                Ok(mesh) => {
                    arrived.push(loaded(p, mesh, *level, self.search));
                    self.sent.insert(p.key, *level);
                    self.again_at.remove(&p.key);
                }
                Err(e) => self.failed(p.key, e)?,
            }
        }
        if !arrived.is_empty() {
            self.send(Update::Loaded(arrived));
        }
        Ok(true)
    }

    /// A find's read failed: asked for again later on the network, the walk stopped on
    /// a file changed under it, damage left out when the viewer walks on past it.
    fn failed(&mut self, key: u64, e: Error) -> Result<()> {
        match e {
            e @ Error::Remote { .. } => self.retry(Some(key), e),
            e => self.leave_out(key, e),
        }
    }

    /// The network failed to bring what `key` (or a place's search) needed: told, and
    /// asked for again a pause later.
    fn retry(&mut self, key: Option<u64>, e: Error) -> Result<()> {
        self.send(Update::Retrying(e.to_string()));
        match key {
            Some(k) => {
                self.again_at.insert(k, Instant::now() + ASK_AGAIN_AFTER);
            }
            None => std::thread::sleep(ASK_AGAIN_AFTER),
        }
        Ok(())
    }

    /// Damage: left out where the viewer walks on past it, else the walk's end.
    fn leave_out(&mut self, key: u64, e: Error) -> Result<()> {
        match (self.left_out, e) {
            (_, e @ Error::RemoteChanged { .. }) | (None, e) => Err(e),
            (Some(l), e) => {
                if let Ok(mut l) = l.lock() {
                    l.leave_out(key, &e);
                }
                Ok(())
            }
        }
    }

    fn send(&self, update: Update) {
        // A viewer that no longer listens has ended the walk.
        let _ = self.tx.send(update);
    }
}

/// A find's box: an object's, or the box of the objects below a node.
fn bounds(found: &Found) -> Aabb {
    match found {
        Found::Object { entry, .. } => entry.bounds,
        Found::Node { mbr, .. } => *mbr,
    }
}
