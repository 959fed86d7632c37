//! The build's side of stored LODs: each object's progressive mesh built as its mesh is
//! written, its chain of coarse levels stored (`chain`), and above a size threshold its
//! progressive mesh and mini-redundant DAG too (`pm::codec`, `dag::codec`); at the end,
//! the table that finds them by id (`table`).
//!
//! Objects stream through the build, so they are simplified as they come: each object
//! is one task on the thread pool (objects are independent), while the build reads and
//! writes the next meshes; the results are appended in the order the objects came, a
//! batch behind, so the same input gives the same file whichever thread finishes
//! first. At most two batches of objects are in flight, so memory stays bounded
//! whatever the size of the city.
//!
//! An object the simplifier refuses (`ProgressiveMesh::build` fails: a mesh of points
//! and no triangles, say) gets no LOD data: it is counted, and the first refusal's
//! reason is kept for the build's report. Its full mesh is stored as always.

use std::collections::BTreeMap;
use std::panic::AssertUnwindSafe;
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::Yield;

use super::chain::{encode_chain_with, head_len, ChainDirectory};
use super::table::{encode_table, LodEntry, LodStats, LodTable};
use crate::error::{Error, Result};
use crate::lod::dag::{Dag, DagConstruction};
use crate::lod::pm::ProgressiveMesh;
use crate::scene::{
    encode_levels_v2, squeeze, Dictionaries, Framing, Mesh, MeshCodec, DEFAULT_ZSTD_LEVEL,
};
use crate::store::{Extent, PageKind, Store};

/// How a build makes and stores LODs.
#[derive(Clone, Debug, PartialEq)]
pub struct LodOptions {
    /// Triangles of each level over the next finer one's (as `flaneur lod --ratio`).
    pub ratio: f32,
    /// A chain stops at this many triangles (as `flaneur lod --min-triangles`).
    pub min_triangles: usize,
    /// Objects with more triangles than this also store their progressive mesh and
    /// mini-redundant DAG, for view-dependent refinement.
    pub pm_threshold: usize,
    /// The LODs of each batch of this many objects are written once the next batch has
    /// been handed to the thread pool: at most two batches are in flight. Bounds the
    /// build's memory; large enough to keep every core busy.
    pub batch: usize,
}

/// Triangles above which a build stores an object's progressive mesh and DAG.
pub const DEFAULT_PM_THRESHOLD: usize = 20_000;

impl Default for LodOptions {
    fn default() -> LodOptions {
        LodOptions {
            ratio: 0.5,
            min_triangles: 100,
            pm_threshold: DEFAULT_PM_THRESHOLD,
            batch: 128,
        }
    }
}

impl LodOptions {
    /// An `Error::Invalid` for a ratio not strictly between 0 and 1, a batch of 0, or a
    /// floor that does not fit 32 bits.
    pub fn validate(&self) -> Result<()> {
        if !(self.ratio > 0.0 && self.ratio < 1.0) {
            return Err(Error::Invalid(format!(
                "LOD ratio {} is not between 0 and 1",
                self.ratio
            )));
        }
        if self.batch == 0 {
            return Err(Error::Invalid("LOD batch of 0 objects".into()));
        }
        if u32::try_from(self.min_triangles).is_err() {
            return Err(Error::Invalid(format!(
                "LOD floor of {} triangles",
                self.min_triangles
            )));
        }
        Ok(())
    }
}

/// What a build stored as LODs, for its summary.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct LodReport {
    /// The counts the database keeps (`Database::lod_stats`).
    #[serde(flatten)]
    pub stats: LodStats,
    /// Bytes of `lod` pages: `stats.pages` times the page size.
    pub bytes: u64,
    /// Wall-clock seconds the build spent on LODs beyond its meshes: waiting for
    /// simplifications to finish, and writing LOD pages.
    pub seconds: f64,
    /// Seconds of simplifying and encoding, summed over the tasks that did it (wall
    /// clock per task: on a busy machine it counts time the task waited for a core).
    pub task_seconds: f64,
    /// Threads of the pool that simplified.
    pub threads: usize,
    /// The first refused object and why, when any was.
    pub first_refusal: Option<String>,
}

/// One object's LOD data, encoded, before it is written.
struct Baked {
    chain: Option<Vec<u8>>,
    levels: u32,
    pm_dag: Option<(Vec<u8>, Vec<u8>)>,
}

/// One object's mesh, encoded by the task that made its levels (format version 2):
/// written with its LODs, a batch's meshes side by side.
type MeshBytes = Option<Result<Vec<u8>>>;

/// An object simplified as a build stores it: `flaneur build`'s chain and, split across
/// machines, a visibility shard's far objects (`build::shards`) both come from here, so
/// that a shard draws an object at the levels the whole build stores for it.
pub(crate) struct Simplified {
    /// Kept for the DAG of a large object.
    pm: ProgressiveMesh,
    /// Each coarse level's mesh and error (metres), finest first; level 0, the full
    /// mesh, is the object's own mesh and not among them.
    pub(crate) levels: Vec<(Mesh, f32)>,
    /// The levels encoded as the store keeps them; `None` when there are none.
    chain: Option<Vec<u8>>,
}

/// The coarse levels of object `id` (finest first, with their errors) as a reader of a
/// file built in `codec` gets them back: quantised by meshoptimizer's codec. A visibility
/// shard draws far objects through these, so that its DoVs are the whole build's, which
/// reads them from its file.
pub(crate) fn simplify_stored(
    id: u64,
    mesh: &Mesh,
    opts: &LodOptions,
    codec: MeshCodec,
) -> Result<Vec<(Mesh, f32)>> {
    // Without the build's dictionaries: they change the bytes, not the meshes read back.
    let simplified = simplify_as(id, mesh, opts, codec, None)?;
    let Some(chain) = simplified
        .chain
        .as_deref()
        .filter(|_| codec != MeshCodec::Raw)
    else {
        return Ok(simplified.levels);
    };
    let dir = ChainDirectory::decode(chain, chain.len())?;
    let infos = dir.levels();
    (1..=dir.stored_levels())
        .map(|level| {
            let (start, end) = dir.read_range(level)?;
            let mesh = dir.decode_level(level, &chain[start..end], None)?;
            Ok((mesh, infos[level].error))
        })
        .collect()
}

/// Simplifies object `id` into its coarse levels and encodes their chain in `codec` (with
/// `dict`'s dictionary for levels, when there is one): an `Err` when the simplifier
/// refuses the object (or panics on it) or the chain would not encode, and the object
/// then gets no LODs.
fn simplify_as(
    id: u64,
    mesh: &Mesh,
    opts: &LodOptions,
    codec: MeshCodec,
    dict: Option<&Dictionaries>,
) -> Result<Simplified> {
    caught(|| {
        let pm = ProgressiveMesh::build(mesh)?;
        let levels = pm.levels(opts.ratio, opts.min_triangles)?;
        let coarse = levels.get(1..).unwrap_or(&[]);
        let chain = if coarse.is_empty() {
            None
        } else {
            Some(encode_chain_with(
                id,
                mesh.triangle_count(),
                coarse,
                codec,
                dict,
            )?)
        };
        let levels = levels
            .into_iter()
            .skip(1)
            .map(|l| (l.mesh, l.error))
            .collect();
        Ok(Simplified { pm, levels, chain })
    })
}

/// Simplifies one object and encodes what it stores: its LOD data, and in format
/// version 2 its mesh too (whether or not the simplifier took it), which the LOD writer
/// writes beside its chain.
fn bake(
    id: u64,
    mesh: &Mesh,
    opts: &LodOptions,
    codec: MeshCodec,
    dict: Option<&Dictionaries>,
) -> (Result<Baked>, MeshBytes) {
    let mesh_bytes = match codec {
        MeshCodec::Raw => None,
        MeshCodec::Meshopt { .. } => Some(
            codec
                .encode_with(mesh, dict)
                .map_err(|w| Error::Invalid(format!("object {id}: {w}"))),
        ),
    };
    let baked = simplify_as(id, mesh, opts, codec, dict)
        .and_then(|simplified| bake_dag(mesh, opts, simplified, codec));
    (baked, mesh_bytes)
}

/// The progressive mesh and DAG of a large simplified object, and what it stores.
/// In format version 2 each is a zstd frame around its packed encoding (the progressive
/// mesh on the object's 16-bit grid, `lod::pm::compact`; the DAG as varints and byte
/// planes, `lod::dag::compact`).
fn bake_dag(
    mesh: &Mesh,
    opts: &LodOptions,
    simplified: Simplified,
    codec: MeshCodec,
) -> Result<Baked> {
    let Simplified { pm, levels, chain } = simplified;
    // The chain holds the levels: their meshes need not wait for the DAG.
    let levels = levels.len() as u32;
    let pm_dag = if mesh.triangle_count() > opts.pm_threshold {
        Some(caught(|| match codec {
            MeshCodec::Raw => {
                let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
                Ok((pm.to_bytes()?, dag.to_bytes()))
            }
            MeshCodec::Meshopt { zstd } => {
                // The DAG's spheres, cones and errors are those of the quantised mesh
                // a reader decodes, not of the floats it was simplified from.
                let pm_bytes = pm.to_quantised_bytes()?;
                let stored = ProgressiveMesh::from_bytes(&pm_bytes)?;
                let dag = Dag::build(&stored, DagConstruction::MiniRedundant)?;
                // Framed even at no zstd level: a reader tells the two apart by it.
                let level = zstd.unwrap_or(DEFAULT_ZSTD_LEVEL);
                let frame = |b: &[u8]| squeeze(b, Some(level)).map_err(Error::Invalid);
                Ok((frame(&pm_bytes)?, frame(&dag.to_packed_bytes())?))
            }
        })?)
    } else {
        None
    };
    Ok(Baked {
        chain,
        levels,
        pm_dag,
    })
}

/// `f`, with a panic turned into an error: a simplifier bug on one odd mesh should cost
/// that object its LODs, not the build.
fn caught<T>(f: impl FnOnce() -> Result<T>) -> Result<T> {
    std::panic::catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| {
        let why = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        Err(Error::Invalid(format!("the simplifier panicked: {why}")))
    })
}

/// Objects the LOD writer holds back to train the dictionaries on: enough for zstd to
/// find what the city's buffers repeat, few enough that simplifying them twice costs a
/// second or two of a build. On the 3,000-object city 256 objects make the file 0.03
/// bytes a triangle larger than 512, and 1,024 no smaller.
pub(crate) const TRAINING_OBJECTS: usize = 512;

/// Whether the LOD writer has its dictionaries.
enum Training {
    /// Objects held back until enough have come to train on.
    Waiting(Vec<(u64, Extent, Mesh)>),
    /// Trained, or none (no zstd, too little to train on, or a raw file).
    Done(Option<Dictionaries>),
}

/// The dictionaries trained on `objects`: their full meshes' buffers for one, their
/// coarse levels' (simplified as the build does) for the other, each level alone. An
/// object the simplifier refuses gives its mesh only.
fn train_dictionaries(
    objects: &[(u64, Extent, Mesh)],
    opts: &LodOptions,
    level: i32,
) -> Option<Dictionaries> {
    use rayon::prelude::*;
    let spans_of = |levels: &[&Mesh]| -> Vec<Vec<u8>> {
        match encode_levels_v2(levels, Framing::Plain) {
            Ok((blob, spans)) => spans
                .iter()
                .map(|s| blob[s.start..s.end].to_vec())
                .collect(),
            Err(_) => Vec::new(),
        }
    };
    let samples: Vec<(Vec<Vec<u8>>, Vec<Vec<u8>>)> = objects
        .par_iter()
        .map(|(_, _, mesh)| {
            let levels = caught(|| {
                let pm = ProgressiveMesh::build(mesh)?;
                pm.levels(opts.ratio, opts.min_triangles)
            })
            .map(|levels| {
                let coarsest_first: Vec<&Mesh> =
                    levels.iter().skip(1).rev().map(|l| &l.mesh).collect();
                if coarsest_first.is_empty() {
                    Vec::new()
                } else {
                    spans_of(&coarsest_first)
                }
            })
            .unwrap_or_default();
            (spans_of(&[mesh]), levels)
        })
        .collect();
    let (meshes, levels): (Vec<_>, Vec<_>) = samples.into_iter().unzip();
    let flat = |v: Vec<Vec<Vec<u8>>>| v.into_iter().flatten().collect::<Vec<_>>();
    let d = Dictionaries::train(&flat(meshes), &flat(levels), level);
    (!d.is_empty()).then_some(d)
}

/// An object whose LODs were made, waiting to be written in the order objects came.
struct Done {
    seq: u64,
    id: u64,
    mesh_extent: Extent,
    triangles: u32,
    baked: Result<Baked>,
    mesh_bytes: MeshBytes,
    task_seconds: f64,
}

/// Takes objects as the build writes their meshes, simplifies them on the thread pool
/// while the build reads on, and appends their LOD extents in the order the objects
/// came (so the same input gives the same file); [`LodWriter::finish`] writes the table.
///
/// At most two batches (`LodOptions::batch` objects each) are in flight: memory stays
/// bounded however large the city, and the pool is not left idle while the build reads
/// the next objects or waits for a batch's slowest one, as it would be with batches in
/// lockstep.
pub(crate) struct LodWriter {
    opts: Arc<LodOptions>,
    codec: MeshCodec,
    /// The zstd dictionaries, or the objects held back to train them on.
    training: Training,
    /// The extents of the meshes this writer wrote (format version 2), in the order the
    /// objects came, not yet taken by the build.
    meshes: Vec<Extent>,
    /// `Lod` pages written by the store before this writer's first.
    lod_pages_before: u64,
    sender: Sender<Done>,
    receiver: Receiver<Done>,
    /// Objects handed to the pool, and the next one to write.
    sent: u64,
    next: u64,
    /// Made, not yet written: those behind an object still in flight.
    ready: BTreeMap<u64, Done>,
    entries: Vec<LodEntry>,
    stats: LodStats,
    first_refusal: Option<String>,
    seconds: f64,
    task_seconds: f64,
}

impl LodWriter {
    /// A writer of LODs in `codec`. For meshoptimizer's codec it writes the objects'
    /// meshes too, encoded on the thread pool with their levels, and the build takes
    /// their extents with [`LodWriter::take_meshes`].
    ///
    /// With zstd, the first [`TRAINING_OBJECTS`] objects are held back, simplified and
    /// encoded once to train the file's dictionaries (`scene::Dictionaries`) on, and then
    /// handed on as every other: each frame is then compressed with them. A store that
    /// has its dictionaries already keeps them.
    pub(crate) fn new(opts: &LodOptions, codec: MeshCodec, store: &Store) -> Result<LodWriter> {
        opts.validate()?;
        let (sender, receiver) = channel();
        let training = match (codec, store.dictionaries()?) {
            (_, Some(d)) => Training::Done(Some(d)),
            (MeshCodec::Meshopt { zstd: Some(_) }, None) => Training::Waiting(Vec::new()),
            _ => Training::Done(None),
        };
        Ok(LodWriter {
            opts: Arc::new(opts.clone()),
            codec,
            training,
            meshes: Vec::new(),
            lod_pages_before: store.pages_written(PageKind::Lod),
            sender,
            receiver,
            sent: 0,
            next: 0,
            ready: BTreeMap::new(),
            entries: Vec::new(),
            stats: LodStats {
                ratio: opts.ratio,
                min_triangles: opts.min_triangles as u32,
                pm_threshold: opts.pm_threshold as u64,
                ..LodStats::default()
            },
            first_refusal: None,
            seconds: 0.0,
            task_seconds: 0.0,
        })
    }

    /// Hands an object whose mesh was written at `mesh_extent` to the pool; after every
    /// batch, writes the LODs of the batch before, waiting for those still in flight.
    /// Returns how many objects had their LODs written.
    pub(crate) fn push(
        &mut self,
        store: &mut Store,
        id: u64,
        mesh_extent: Extent,
        mesh: Mesh,
    ) -> Result<usize> {
        if let Training::Waiting(held) = &mut self.training {
            held.push((id, mesh_extent, mesh));
            if held.len() < TRAINING_OBJECTS {
                return Ok(0);
            }
            return self.train(store);
        }
        self.spawn(store, id, mesh_extent, mesh)
    }

    /// Trains the dictionaries on the objects held back, records them in the store, and
    /// hands those objects on. Returns how many objects had their LODs written.
    fn train(&mut self, store: &mut Store) -> Result<usize> {
        let held = match std::mem::replace(&mut self.training, Training::Done(None)) {
            Training::Waiting(held) => held,
            done => {
                self.training = done;
                return Ok(0);
            }
        };
        let start = Instant::now();
        let level = match self.codec {
            MeshCodec::Meshopt { zstd: Some(level) } => level,
            _ => DEFAULT_ZSTD_LEVEL,
        };
        let dict = train_dictionaries(&held, &self.opts, level);
        if let Some(d) = &dict {
            store.save_dictionaries(d, level)?;
        }
        self.training = Training::Done(dict);
        self.seconds += start.elapsed().as_secs_f64();
        let mut written = 0;
        for (id, mesh_extent, mesh) in held {
            written += self.spawn(store, id, mesh_extent, mesh)?;
        }
        Ok(written)
    }

    /// Hands one object to the pool; after every batch, writes the batch before.
    fn spawn(
        &mut self,
        store: &mut Store,
        id: u64,
        mesh_extent: Extent,
        mesh: Mesh,
    ) -> Result<usize> {
        let (seq, sender, opts) = (self.sent, self.sender.clone(), Arc::clone(&self.opts));
        let codec = self.codec;
        let dict = match &self.training {
            Training::Done(d) => d.clone(),
            Training::Waiting(_) => None,
        };
        self.sent += 1;
        rayon::spawn_fifo(move || {
            let start = Instant::now();
            let (baked, mesh_bytes) = bake(id, &mesh, &opts, codec, dict.as_ref());
            // The build stops listening only when it failed; nothing to do then.
            let _ = sender.send(Done {
                seq,
                id,
                mesh_extent,
                triangles: mesh.triangle_count() as u32,
                baked,
                mesh_bytes,
                task_seconds: start.elapsed().as_secs_f64(),
            });
        });
        // Writes happen at fixed points — after every batch of objects, the LODs of the
        // batch before it — so that the file's layout never depends on which thread
        // finished first; the batch in between keeps the pool busy meanwhile.
        let batch = self.opts.batch as u64;
        if !self.sent.is_multiple_of(batch) {
            return Ok(0);
        }
        let start = Instant::now();
        let written = self.write_up_to(store, self.sent.saturating_sub(batch))?;
        self.seconds += start.elapsed().as_secs_f64();
        Ok(written)
    }

    /// Writes, in order, the LODs of every object before `end`, waiting for those still
    /// in flight: first the heads of all their chains, side by side, then the rest of
    /// each object's data.
    fn write_up_to(&mut self, store: &mut Store, end: u64) -> Result<usize> {
        let mut dones = Vec::new();
        while self.next < end {
            match self.ready.remove(&self.next) {
                Some(done) => {
                    self.next += 1;
                    dones.push(done);
                }
                None => {
                    let done = self.receive()?;
                    self.ready.insert(done.seq, done);
                }
            }
        }
        let written = dones.len();
        // A batch's meshes (format version 2) come first, side by side, as the build
        // would have written them one by one.
        let mut batch = Vec::with_capacity(dones.len());
        for done in dones {
            self.task_seconds += done.task_seconds;
            let mesh_extent = match done.mesh_bytes {
                None => done.mesh_extent,
                Some(bytes) => {
                    let e = store.append_packed(PageKind::Mesh, &bytes?)?;
                    self.meshes.push(e);
                    e
                }
            };
            match done.baked {
                Ok(baked) => batch.push((done.id, mesh_extent, done.triangles, baked)),
                Err(e) => {
                    self.stats.refused += 1;
                    self.first_refusal
                        .get_or_insert_with(|| format!("object {}: {e}", done.id));
                }
            }
        }
        self.write_batch(store, batch)?;
        Ok(written)
    }

    /// The extents of the meshes written since the last call, in the order their
    /// objects came (format version 2; none in version 1, where the build writes them).
    pub(crate) fn take_meshes(&mut self) -> Vec<Extent> {
        std::mem::take(&mut self.meshes)
    }

    /// The next object whose LODs are made, in whatever order they finish.
    fn receive(&self) -> Result<Done> {
        let gone = || Error::Invalid("LOD build: the thread pool went away".into());
        loop {
            match self.receiver.try_recv() {
                Ok(done) => return Ok(done),
                Err(TryRecvError::Disconnected) => return Err(gone()),
                Err(TryRecvError::Empty) => {}
            }
            match rayon::yield_now() {
                // Not a pool thread: block until a task reports.
                None => return self.receiver.recv().map_err(|_| gone()),
                // A build run from inside the pool must not block a thread its own
                // tasks may need: it runs pool work (perhaps those tasks) meanwhile.
                Some(Yield::Executed) => {}
                Some(Yield::Idle) => match self.receiver.recv_timeout(Duration::from_millis(1)) {
                    Ok(done) => return Ok(done),
                    Err(RecvTimeoutError::Disconnected) => return Err(gone()),
                    Err(RecvTimeoutError::Timeout) => {}
                },
            }
        }
    }

    /// Writes the LODs of a batch of objects, in order: the heads of their chains
    /// first, so that the coarsest levels of neighbouring objects (the build's order is
    /// along a space-filling curve) are one run of pages, then each one's chain rest,
    /// progressive mesh and DAG.
    fn write_batch(
        &mut self,
        store: &mut Store,
        batch: Vec<(u64, Extent, u32, Baked)>,
    ) -> Result<()> {
        let payload = store.payload_size();
        // Format version 2 packs every chain whole: its head is beside its
        // neighbours' without being cut at a page.
        let packed = self.codec.packs();
        let append = |store: &mut Store, bytes: &[u8]| -> Result<Extent> {
            if bytes.is_empty() {
                Ok(Extent::default())
            } else {
                store.append_packed_or_whole(PageKind::Lod, bytes, packed)
            }
        };
        let mut heads = Vec::with_capacity(batch.len());
        for (_, _, _, b) in &batch {
            let split = match &b.chain {
                Some(bytes) if packed => bytes.len(),
                Some(bytes) => head_len(bytes, payload)?,
                None => 0,
            };
            let chain = b.chain.as_deref().unwrap_or(&[]);
            heads.push((append(store, &chain[..split])?, split));
        }
        for ((id, mesh, triangles, b), (chain, split)) in batch.into_iter().zip(heads) {
            let chain_rest = append(store, b.chain.as_deref().map_or(&[], |c| &c[split..]))?;
            let (pm, dag) = match &b.pm_dag {
                Some((pm, dag)) => (append(store, pm)?, append(store, dag)?),
                None => (Extent::default(), Extent::default()),
            };
            self.stats.objects += 1;
            self.stats.levels += b.levels as u64;
            self.stats.with_levels += (b.levels > 0) as u64;
            self.stats.with_pm += b.pm_dag.is_some() as u64;
            self.entries.push(LodEntry {
                id,
                mesh,
                chain,
                chain_rest,
                pm,
                dag,
                triangles,
                levels: b.levels,
            });
        }
        Ok(())
    }

    /// Writes the LODs of the objects still in flight and the table, and names the
    /// table in the header. Returns what was stored, how many objects had their LODs
    /// written by this call, and the meshes it wrote (as [`LodWriter::take_meshes`]).
    pub(crate) fn finish(mut self, store: &mut Store) -> Result<(LodReport, usize, Vec<Extent>)> {
        // A city of fewer objects than the training takes trains on them all.
        let trained = self.train(store)?;
        let start = Instant::now();
        let written = trained + self.write_up_to(store, self.sent)?;
        self.entries.sort_unstable_by_key(|e| e.id);
        // Packed extents share pages: the store counts the pages themselves.
        let lod_pages = |store: &Store| store.pages_written(PageKind::Lod) - self.lod_pages_before;
        self.stats.pages = lod_pages(store);
        let bytes = encode_table(&self.entries, &self.stats, store.payload_size())?;
        let table = store.append_extent(PageKind::Lod, &bytes)?;
        self.stats.pages = lod_pages(store);
        LodTable::save(store, &table, self.stats.pages)?;
        self.seconds += start.elapsed().as_secs_f64();
        Ok((
            LodReport {
                stats: self.stats,
                bytes: self.stats.pages * store.page_size() as u64,
                seconds: self.seconds,
                task_seconds: self.task_seconds,
                threads: rayon::current_num_threads(),
                first_refusal: self.first_refusal,
            },
            written,
            self.meshes,
        ))
    }
}
