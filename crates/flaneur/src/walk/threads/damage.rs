//! What a never-wait walk's loaders could not read for damage, and went on without
//! (ours). A loader that never keeps the viewer waiting must not stop the walk for one
//! damaged page, nor hide it: each object is named once with the error that names the
//! page, the viewer counts the names as they come (its frame's figure, the window's
//! message), and the walk's summary lists them all, so that a headless walk can end in
//! failure as a waiting walk would have.

use std::collections::HashSet;
use std::sync::Mutex;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::rtree::ObjectEntry;
use crate::walk::buffer::Loaded;

/// The damage met so far, shared by a walk's loader threads and its viewer.
#[derive(Debug, Default)]
pub(crate) struct Damaged {
    /// Objects named, so that each is named once and not read again where it failed.
    ids: HashSet<u64>,
    /// Each object's damage in words, in the order met.
    named: Vec<String>,
}

impl Damaged {
    /// Whether object `id`'s damage is known.
    pub fn contains(&self, id: u64) -> bool {
        self.ids.contains(&id)
    }

    /// Object `id` could not be read (`what` the walk did instead) for `e`, which names
    /// the page; named once.
    pub fn note(&mut self, id: u64, what: &str, e: &Error) {
        if self.ids.insert(id) {
            self.named.push(format!("object {id} {what}: {e}"));
        }
    }

    /// Damage met where no object is known (a loader's failure after the walk ended).
    pub fn note_words(&mut self, words: String) {
        self.named.push(words);
    }

    /// Named so far.
    pub fn len(&self) -> usize {
        self.named.len()
    }

    /// The names from `from` on.
    pub fn since(&self, from: usize) -> &[String] {
        self.named.get(from..).unwrap_or(&[])
    }

    /// Every name, in the order met.
    pub fn into_named(self) -> Vec<String> {
        self.named
    }
}

/// How far a viewer has counted and told the damage of a walk's [`Damaged`].
#[derive(Debug, Default)]
pub(crate) struct DamageCursor {
    counted: usize,
    told: usize,
}

impl DamageCursor {
    /// Objects named since the last frame counted.
    pub fn count_new(&mut self, damaged: &Mutex<Damaged>) -> usize {
        let n = damaged.lock().map_or(self.counted, |d| d.len());
        let new = n.saturating_sub(self.counted);
        self.counted += new;
        new
    }

    /// The names not yet told (to a window, beside its picture).
    pub fn take_untold(&mut self, damaged: &Mutex<Damaged>) -> Vec<String> {
        let Ok(d) = damaged.lock() else {
            return Vec::new();
        };
        let new = d.since(self.told).to_vec();
        self.told += new.len();
        new
    }
}

/// The damaged [`Mutex`] taken whole at the walk's end (a poisoned one as it stood).
pub(crate) fn named(damaged: Mutex<Damaged>) -> Vec<String> {
    damaged
        .into_inner()
        .unwrap_or_else(|p| p.into_inner())
        .into_named()
}

/// The coarsest stored levels of `batch`, as `Database::coarsest_meshes` reads them,
/// when damage may be among them: the batch asked for together, and if that fails on
/// damage, each object on its own, so that the damage costs its object's coarse level
/// alone. Returns the objects read coarse, and those to read at full detail instead:
/// objects whose coarse level is damaged (each named in `damaged`) or already known to
/// be. A network's failure, or a file changed under the walk, is the caller's.
pub(crate) fn coarsest_or_full(
    db: &Database,
    batch: &[ObjectEntry],
    damaged: &Mutex<Damaged>,
) -> Result<(Vec<Loaded>, Vec<ObjectEntry>)> {
    let known = |e: &ObjectEntry| damaged.lock().is_ok_and(|d| d.contains(e.id));
    let (mut full, asked): (Vec<ObjectEntry>, Vec<ObjectEntry>) =
        batch.iter().copied().partition(known);
    let at_level = |entries: &[ObjectEntry], meshes: Vec<(usize, _)>| {
        entries
            .iter()
            .zip(meshes)
            .map(|(e, (level, mesh))| Loaded::at_level(*e, mesh, level))
            .collect::<Vec<_>>()
    };
    match db.coarsest_meshes(&asked) {
        Ok(meshes) => return Ok((at_level(&asked, meshes), full)),
        Err(e @ (Error::Remote { .. } | Error::RemoteChanged { .. })) => return Err(e),
        Err(_) => {}
    }
    let mut coarse = Vec::with_capacity(asked.len());
    for e in asked {
        match db.coarsest_meshes(std::slice::from_ref(&e)) {
            Ok(meshes) => coarse.extend(at_level(&[e], meshes)),
            Err(err @ (Error::Remote { .. } | Error::RemoteChanged { .. })) => return Err(err),
            Err(err) => {
                if let Ok(mut d) = damaged.lock() {
                    d.note(e.id, "coarse level unreadable, loaded at full detail", &err);
                }
                full.push(e);
            }
        }
    }
    Ok((coarse, full))
}
