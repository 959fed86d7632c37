//! The refining lane of a never-wait REVIEW walk: the full meshes of objects drawn at
//! their coarsest level, read on a thread of their own while the viewer's lane is idle,
//! and handed back to take the coarse levels' place.
//!
//! One object's failure costs that object, not its batch: the meshes read are handed
//! back, and each failure after them on its own. A mesh that cannot be read where the
//! viewer walks on past damage is left out (the object stays drawn coarse, and is told
//! of once); any other failure goes back to the walk, which goes on past a network's
//! and stops at the rest. The meshes a network failed to bring are asked for again
//! once the job's others are read, a pause later, until they come or the walk ends.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Mutex};
use std::time::Duration;

use super::mesh_batch::read_meshes;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::rtree::ObjectEntry;
use crate::walk::sink::LeftOut;
use crate::walk::Loaded;

/// Meshes whose pages a loader asks for in one go: enough for a few full waves of
/// parallel requests over HTTP, few enough that a walk that ends stops it soon.
pub(crate) const MESHES_ASKED_TOGETHER: usize = 256;

/// What the lane hands back: a batch's meshes, or one object's failure.
pub(crate) type Refined = Result<Vec<Loaded>>;

/// Reads the full meshes of `job`, a batch at a time, each batch once the viewer's lane
/// (`now_busy`) is idle, until the walk has `ended`. `Err` when the walk no longer
/// listens.
pub(crate) fn refine(
    db: &Database,
    job: &[ObjectEntry],
    left_out: Option<&Mutex<LeftOut>>,
    (now_busy, ended): (&AtomicBool, &AtomicBool),
    tx: &mpsc::Sender<Refined>,
) -> std::result::Result<(), mpsc::SendError<Refined>> {
    let mut job = job.to_vec();
    while !job.is_empty() {
        let mut again = Vec::new();
        for batch in job.chunks(MESHES_ASKED_TOGETHER) {
            while now_busy.load(Ordering::Relaxed) && !ended.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(2));
            }
            if ended.load(Ordering::Relaxed) {
                return Ok(());
            }
            let mut failed: Vec<Error> = Vec::new();
            let loaded = read_meshes(db, batch, left_out, |e, err| {
                if matches!(err, Error::Remote { .. }) {
                    again.push(*e);
                }
                failed.push(err);
                Ok(())
            });
            tx.send(loaded)?;
            for err in failed {
                tx.send(Err(err))?;
            }
        }
        job = again;
        if !job.is_empty() {
            pause(ended);
        }
    }
    Ok(())
}

/// How long the lane waits before it asks again for meshes the network failed to
/// bring (each ask already retried with the client's backoff).
const ASK_AGAIN_AFTER: Duration = Duration::from_millis(200);

/// Waits [`ASK_AGAIN_AFTER`], or less when the walk ends meanwhile.
fn pause(ended: &AtomicBool) {
    let until = std::time::Instant::now() + ASK_AGAIN_AFTER;
    while std::time::Instant::now() < until && !ended.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BuildOptions;

    /// A small city's database with the first mesh page of one object flipped; the
    /// objects, and the damaged one.
    fn damaged() -> (tempfile::TempDir, Database, Vec<ObjectEntry>, ObjectEntry) {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("c.scene");
        let config = citygen::CityConfig {
            objects: 40,
            seed: 5,
            ..Default::default()
        };
        citygen::write_city(&config, &scene).unwrap();
        let path = dir.path().join("c.flaneur");
        // One mesh to a page, so that damage to a page is damage to one object (packed
        // meshes share pages, and a damaged page costs each of them).
        let opts = BuildOptions {
            page_size: 1024,
            lod: None,
            codec: crate::scene::MeshCodec::Raw,
            ..Default::default()
        };
        crate::build_from_scene(&scene, &path, &opts).unwrap();
        let db = Database::open(&path).unwrap();
        let all = db.range(&db.bounds()).unwrap().objects;
        let victim = all[all.len() / 2];
        let offset = victim.mesh.first_page * db.store().page_size() as u64 + 40;
        drop(db);
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[offset as usize] ^= 0x5a;
        std::fs::write(&path, bytes).unwrap();
        (dir, Database::open(&path).unwrap(), all, victim)
    }

    fn run(db: &Database, job: &[ObjectEntry], left_out: Option<&Mutex<LeftOut>>) -> Vec<Refined> {
        let (tx, rx) = mpsc::channel();
        let idle = AtomicBool::new(false);
        refine(db, job, left_out, (&idle, &idle), &tx).unwrap();
        drop(tx);
        rx.into_iter().collect()
    }

    #[test]
    fn one_damaged_mesh_costs_that_object_not_its_batch() {
        let (_dir, db, all, victim) = damaged();
        // A walk that stops at damage: every other mesh, then the failure, naming the page.
        let got = run(&db, &all, None);
        assert_eq!(got.len(), 2, "{got:?}");
        let loaded = got[0].as_ref().unwrap();
        assert_eq!(loaded.len(), all.len() - 1);
        assert!(loaded.iter().all(|o| o.entry.id != victim.id));
        assert!(
            matches!(&got[1], Err(Error::CorruptPage { page, .. }) if *page == victim.mesh.first_page),
            "{:?}",
            got[1]
        );
        // A walk that goes on past damage: the others, and the victim left out, told once.
        let left = Mutex::new(LeftOut::default());
        let got = run(&db, &all, Some(&left));
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].as_ref().unwrap().len(), all.len() - 1);
        let mut left = left.into_inner().unwrap();
        assert!(left.contains(victim.id));
        let told = left.take_untold();
        assert_eq!(told.len(), 1);
        assert!(
            told[0].contains(&format!("object {} left out", victim.id)),
            "{told:?}"
        );
    }
}
