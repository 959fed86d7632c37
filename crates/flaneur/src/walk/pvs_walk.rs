//! The PVS walk (`flaneur walk DB --mode pvs`): a camera path over a database built with
//! `--visibility`, the viewer drawing its current viewcell's PVS while a client
//! prefetches neighbours' PVS rows with SNP or PBNP (Zheng 2007 ch. 7) from the stored
//! table, every page read counted.
//!
//! A pose whose eye is in no walkable cell (above a roof, off the grid) draws nothing
//! new and asks for nothing: the client keeps what it holds and the frame counts as
//! outside. That is the walk's choice; the prefetcher itself refuses such positions.
//!
//! Drawn ([`walk_pvs_into`] with a renderer), the objects the client holds are loaded
//! into an object buffer as they arrive and dropped when it evicts them, and each frame
//! draws the current cell's PVS (the last cell's, outside cells) within the frustum.
//! Those mesh reads are the renderer's: a frame's page count is taken before them.

use serde::Serialize;

use std::collections::HashMap;
use std::sync::Arc;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::prefetch::pvs::{Cell, Pbnp, Position, PrefetchArea, PvsClient, Snp, StoredPvs};
use crate::rtree::ObjectEntry;
use crate::walk::buffer::{mesh_bytes, Loaded, ObjectBuffer};
use crate::walk::path::CameraPath;
use crate::walk::sink::{LeftOut, Played};
use crate::walk::{FrameFigures, FrameSink, NoSink, Viewer};

/// The walk through a database's walkable viewcells, under its former path; see
/// [`crate::walk::path::cell_walk`].
pub use crate::walk::path::cell_walk;

/// Which neighbours the client prefetches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum PvsPrefetch {
    /// All eight on every cell change.
    Snp,
    /// Those the viewer leans towards; the border band as a share of the cell's side.
    Pbnp { border: f64 },
}

impl PvsPrefetch {
    pub fn name(&self) -> &'static str {
        match self {
            PvsPrefetch::Snp => "snp",
            PvsPrefetch::Pbnp { .. } => "pbnp",
        }
    }
}

/// One frame of a PVS walk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PvsFrame {
    /// The viewcell the eye is in, if walkable.
    pub cell: Option<u32>,
    /// Objects drawn: the current cell's PVS (0 outside cells).
    pub drawn: usize,
    /// Whether a prefetch transaction ran, and what it sent and evicted.
    pub transaction: bool,
    pub sent: usize,
    pub swaps: usize,
    /// On entering a cell, objects of its PVS the client did not hold.
    pub visual_misses: usize,
    /// Pages read during the frame (visibility pages included).
    pub pages: u64,
}

/// What a PVS walk did, frame by frame and in all.
#[derive(Clone, Debug, Serialize)]
pub struct PvsWalkReport {
    pub prefetch: PvsPrefetch,
    pub frames: Vec<PvsFrame>,
    pub frames_outside: usize,
    pub cells_entered: usize,
    pub transactions: usize,
    pub swaps: usize,
    pub objects_sent: usize,
    pub visual_misses: usize,
    pub mean_drawn: f64,
    pub pages: u64,
}

impl PvsWalkReport {
    /// Objects sent per transaction.
    pub fn objects_per_transaction(&self) -> f64 {
        self.objects_sent as f64 / self.transactions.max(1) as f64
    }
}

/// Walks `path` over `db`'s precomputed visibility with `prefetch`, calling `tick`
/// after each frame.
pub fn walk_pvs(
    db: &Database,
    path: &CameraPath,
    prefetch: PvsPrefetch,
    tick: impl FnMut(usize),
) -> Result<PvsWalkReport> {
    walk_pvs_into(db, path, prefetch, tick, &mut NoSink)
}

/// [`walk_pvs`], handing each frame to `sink` (a renderer).
pub fn walk_pvs_into(
    db: &Database,
    path: &CameraPath,
    prefetch: PvsPrefetch,
    tick: impl FnMut(usize),
    sink: &mut dyn FrameSink,
) -> Result<PvsWalkReport> {
    walk_pvs_live(db, prefetch, tick, &mut Played { path, sink })
}

/// [`walk_pvs_into`] with the poses coming from `viewer` frame by frame (a person at a
/// window), until it has no more.
pub fn walk_pvs_live(
    db: &Database,
    prefetch: PvsPrefetch,
    mut tick: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<PvsWalkReport> {
    let sink = &mut *viewer;
    let source = StoredPvs::new(db)?;
    let (snp, pbnp);
    let rule: &dyn PrefetchArea = match prefetch {
        PvsPrefetch::Snp => {
            snp = Snp;
            &snp
        }
        PvsPrefetch::Pbnp { border } => {
            pbnp = Pbnp::new(border)?;
            &pbnp
        }
    };
    let mut client = PvsClient::new(&source, rule, crate::prefetch::pvs::THESIS_CAPACITY)?;
    let mut frames = Vec::new();
    // For a renderer: every object's index entry, and what the client holds, loaded.
    let entries: HashMap<u64, ObjectEntry> = if sink.draws() {
        db.range(&db.bounds())?
            .objects
            .into_iter()
            .map(|o| (o.id, o))
            .collect()
    } else {
        HashMap::new()
    };
    let mut held = ObjectBuffer::new(usize::MAX);
    // Objects whose meshes could not be read, when the viewer walks on without them.
    let mut left_out = sink.skips_damaged().then(LeftOut::default);
    let mut shown: Option<Cell> = None;
    for i in 0.. {
        let Some(pose) = sink.next_pose(i)? else {
            break;
        };
        let pose = &pose;
        let before = db.io().page_reads;
        let mut frame = PvsFrame::default();
        if let Some(id) = db.viewcell_at(pose.position)? {
            let p = Position::new(pose.position.x as f64, pose.position.z as f64);
            let out = client.step(p)?;
            shown = Some(out.cell);
            frame.cell = Some(id);
            frame.drawn = client.cache().pvs(out.cell).map_or(0, |s| s.len());
            frame.visual_misses = out.visual_misses;
            if let Some(t) = &out.transaction {
                frame.transaction = true;
                frame.sent = t.sent.len();
                frame.swaps = t.evicted.len();
            }
        }
        frame.pages = db.io().page_reads - before;
        if sink.draws() {
            let at = Drawing {
                shown,
                pose,
                index: i,
            };
            draw_pvs(db, &entries, &client, &mut held, &mut left_out, &at, sink)?;
        }
        sink.figures(&FrameFigures {
            pages: frame.pages,
            objects_buffered: held.len(),
            objects_drawn: frame.drawn,
            visual_misses: frame.visual_misses,
            cell: frame.cell.map_or_else(
                || "outside every viewcell".into(),
                |c| format!("viewcell {c}"),
            ),
            damaged: left_out
                .as_mut()
                .map(LeftOut::take_untold)
                .unwrap_or_default(),
            ..Default::default()
        });
        frames.push(frame);
        tick(i);
    }
    let inside: Vec<&PvsFrame> = frames.iter().filter(|f| f.cell.is_some()).collect();
    let cells_entered = frames
        .windows(2)
        .filter(|w| w[1].cell.is_some() && w[1].cell != w[0].cell)
        .count();
    Ok(PvsWalkReport {
        prefetch,
        frames_outside: frames.len() - inside.len(),
        cells_entered,
        transactions: frames.iter().filter(|f| f.transaction).count(),
        swaps: frames.iter().map(|f| f.swaps).sum(),
        objects_sent: frames.iter().map(|f| f.sent).sum(),
        visual_misses: frames.iter().map(|f| f.visual_misses).sum(),
        mean_drawn: inside.iter().map(|f| f.drawn as f64).sum::<f64>() / inside.len().max(1) as f64,
        pages: frames.iter().map(|f| f.pages).sum(),
        frames,
    })
}

/// What a frame draws: the PVS of `shown`, from `pose`.
struct Drawing<'p> {
    shown: Option<Cell>,
    pose: &'p crate::walk::Pose,
    index: usize,
}

/// Brings `held` to what the client holds (loading new objects' meshes, dropping what
/// it evicted; leaving out, when `left_out` is kept, those that cannot be read) and
/// hands `sink` the PVS of `at.shown` within the frustum.
fn draw_pvs<S: crate::prefetch::pvs::PvsSource, A: PrefetchArea + ?Sized>(
    db: &Database,
    entries: &HashMap<u64, ObjectEntry>,
    client: &PvsClient<'_, S, A>,
    held: &mut ObjectBuffer,
    left_out: &mut Option<LeftOut>,
    at: &Drawing<'_>,
    sink: &mut dyn FrameSink,
) -> Result<()> {
    let cache = client.cache();
    let gone: Vec<u64> = held
        .iter()
        .map(|o| o.entry.id)
        .filter(|&id| !cache.holds(id))
        .collect();
    for id in gone {
        held.remove(id);
    }
    for id in cache.objects() {
        if held.get(id).is_none() && !left_out.as_ref().is_some_and(|l| l.contains(id)) {
            let entry = entries.get(&id).ok_or_else(|| {
                Error::Invalid(format!(
                    "object {id} of a PVS is not in the database's index"
                ))
            })?;
            let mesh = match (db.mesh(entry), left_out.as_mut()) {
                (Ok(m), _) => m,
                (Err(e), Some(l)) => {
                    l.leave_out(id, &e);
                    continue;
                }
                (Err(e), None) => return Err(e),
            };
            held.insert(Loaded {
                entry: *entry,
                bytes: mesh_bytes(&mesh),
                mesh: Arc::new(mesh),
            });
        }
    }
    let camera = at.pose.camera()?;
    let frustum = camera.frustum();
    let drawn: Vec<&Loaded> = at
        .shown
        .and_then(|c| cache.pvs(c))
        .unwrap_or(&[])
        .iter()
        .filter_map(|id| held.get(*id))
        .filter(|o| frustum.overlaps_aabb(&o.entry.bounds))
        .collect();
    sink.frame(at.index, &camera, held, &drawn)
}
