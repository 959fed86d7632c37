//! One large mesh simplified on all cores — El-Sana & Varshney, "Parallel processing for
//! view-dependent polygonal virtual environments", §3.
//!
//! The mesh's positions are binned into the cells of an octree whose leaves hold a few
//! thousand triangles. The paper's rules, as this module keeps them:
//! - an edge c → p belongs to the cell of its first position c (the one that goes);
//! - a cell collapses only edges shorter than its side, and leaves the rest — here
//!   shorter than `reach` (0.45) of its side, and no collapse may make a longer edge
//!   either, so that cells of one colour, a side apart, never reach each other;
//! - two adjacent cells are never processed at once: cells are taken by their octant
//!   within their parent (the 8 colours of a 2×2×2 pattern), one colour at a time, so
//!   the 8 siblings of a group run one after another while the groups run side by side;
//! - when a level's groups are done, what their cells left merges into the parent
//!   cells, and the parents are processed in turn, up to the root, which takes every
//!   edge that is left;
//! - within a colour, the heaviest cells (most triangles) are started first.
//!
//! The paper's cells share one mesh in memory and trust the two rules to keep
//! concurrent collapses apart. Here each cell is simplified on its own copy: the
//! triangles within two rings of its positions (all that a collapse there reads), and
//! what changed is merged back in cell order. Two cells run at once only when their
//! first rings share no position (a collapse writes only there, and reads only
//! triangles that touch it) — checked, not assumed, so that a long edge of the input
//! reaching past a neighbouring cell only delays a cell to the next round. Every collapse is checked
//! by the same rules as the serial build's, on a neighbourhood that is complete, so the
//! result is a valid progressive mesh that refines back to the original exactly; and
//! since cells merge in a fixed order, it is the same on any number of threads.
//!
//! Unlike the serial build's, the splits are not in one global order of error: a leaf
//! cell simplifies its edges up to its own size before the coarser cells start. The
//! order is by scale (leaf sizes first) — what view-dependent refinement through the
//! DAG needs — but a prefix of the splits is not the best level at its triangle count:
//! take discrete levels from the serial build.

use std::time::{Duration, Instant};

use glam::DVec3;
use rayon::prelude::*;

use crate::scene::Mesh;

use super::progressive::{assemble, check_input, ProgressiveMesh};
use super::quadric::Quadric;
use super::simplify::{Collapse, Domain, RemovedFace, Setup, Simplifier};
use super::topology::Adjacency;
use crate::error::Result;

/// How to split a mesh for the parallel build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParallelOptions {
    /// The octree is deepened until its occupied leaves hold at most this many
    /// triangles on average.
    pub leaf_triangles: usize,
    /// The deepest octree allowed.
    pub max_depth: u32,
    /// The longest edge a cell may collapse or make, as a share of its side. Cells of
    /// one colour are a side apart, and a cell reaches one edge beyond itself, so below
    /// one half two such cells never touch what the other reads.
    pub reach: f64,
}

impl Default for ParallelOptions {
    fn default() -> ParallelOptions {
        ParallelOptions {
            leaf_triangles: 2048,
            max_depth: 10,
            reach: 0.45,
        }
    }
}

/// What one level of the octree did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LevelReport {
    /// Cells with positions at this level.
    pub cells: usize,
    /// Cells that had to wait for a later round, their rings overlapping another's.
    pub deferred: usize,
    /// Position collapses made at this level.
    pub collapses: usize,
    /// Wall time of the level.
    pub time: Duration,
}

/// What a parallel build did, and where its time went.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParallelReport {
    /// Octree depth (0: the root is the only cell).
    pub depth: u32,
    /// The levels, leaves first, root last.
    pub levels: Vec<LevelReport>,
    /// Welding, quadrics and cell binning before the first cell.
    pub setup: Duration,
    /// Turning the collapses into the progressive mesh after the last.
    pub assemble: Duration,
    /// Time each worker thread spent on cells (copying out and simplifying), by thread:
    /// the paper's load balance (Table 2).
    pub busy: Vec<Duration>,
    /// Wall time of the whole build.
    pub total: Duration,
}

impl ParallelReport {
    /// Counts `t` of work to rayon thread `thread`.
    fn add_busy(&mut self, thread: usize, t: Duration) {
        if let Some(b) = self.busy.get_mut(thread) {
            *b += t;
        }
    }

    /// The paper's load imbalance: the busiest thread's time over the mean, less one.
    pub fn imbalance(&self) -> f64 {
        let busy: Vec<f64> = self.busy.iter().map(Duration::as_secs_f64).collect();
        let mean = busy.iter().sum::<f64>() / busy.len().max(1) as f64;
        let max = busy.iter().copied().fold(0.0, f64::max);
        if mean > 0.0 {
            max / mean - 1.0
        } else {
            0.0
        }
    }
}

impl ProgressiveMesh {
    /// Simplifies one mesh on all of rayon's threads (El-Sana & Varshney §3; see the
    /// module comment), with the serial build's collapse rules and the same exactness:
    /// every split applied to the base gives back `mesh`. The result does not depend on
    /// the number of threads.
    ///
    /// The same errors as [`ProgressiveMesh::build`].
    ///
    /// ```
    /// use flaneur::lod::{ParallelOptions, ProgressiveMesh};
    /// let torus = flaneur::lod::bumpy_torus(20_000);
    /// let options = ParallelOptions { leaf_triangles: 1_000, ..Default::default() };
    /// let (pm, report) = ProgressiveMesh::build_parallel(&torus, &options)?;
    /// assert!(report.depth >= 1);
    /// assert!(pm.base.triangle_count() < 100);
    /// let full = pm.cursor_at(pm.splits.len())?;
    /// assert_eq!(full.triangle_count(), torus.triangle_count());
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn build_parallel(
        mesh: &Mesh,
        options: &ParallelOptions,
    ) -> Result<(ProgressiveMesh, ParallelReport)> {
        check_input(mesh)?;
        let started = Instant::now();
        let mut report = ParallelReport::default();
        let mut state = State::new(mesh);
        let octree = Octree::new(&state.setup.adj, mesh.triangle_count(), options);
        report.depth = octree.depth;
        let threads = rayon::current_num_threads();
        report.busy = vec![Duration::ZERO; threads.max(1)];
        report.setup = started.elapsed();

        for level in 0..=octree.depth {
            let level_started = Instant::now();
            let before = state.groups;
            let cells = octree.cells(&state.setup.adj, level);
            let root = level == octree.depth;
            let max_edge = if root {
                f64::INFINITY
            } else {
                octree.side(level) * options.reach
            };
            let mut lr = LevelReport {
                cells: cells.len(),
                ..Default::default()
            };
            for colour in 0..8u8 {
                let mut pending: Vec<&Cell> = cells.iter().filter(|c| c.colour == colour).collect();
                // Heaviest first, so that no thread is left with a big cell at the end.
                pending.sort_by_key(|c| (std::cmp::Reverse(c.weight), c.key));
                while !pending.is_empty() {
                    let parts: Vec<(Part, Duration, usize)> = pending
                        .par_iter()
                        // One cell a task, so that a thread out of work steals cells.
                        .with_max_len(1)
                        .map(|cell| timed(|| Part::extract(&state, cell, max_edge)))
                        .collect();
                    for (_, t, thread) in &parts {
                        report.add_busy(*thread, *t);
                    }
                    let (run, wait) = state.claim(parts.into_iter().map(|p| p.0), &pending);
                    lr.deferred += wait.len();
                    let done: Vec<(Done, Duration, usize)> = run
                        .into_par_iter()
                        .with_max_len(1)
                        .map(|part| timed(|| part.simplify()))
                        .collect();
                    for (done, t, thread) in done {
                        report.add_busy(thread, t);
                        state.merge(done);
                    }
                    pending = wait;
                }
            }
            lr.collapses = (state.groups - before) as usize;
            lr.time = level_started.elapsed();
            report.levels.push(lr);
        }

        let assembling = Instant::now();
        let adj = &state.setup.adj;
        let pm = assemble(mesh, &state.collapses, &adj.faces, &adj.alive);
        report.assemble = assembling.elapsed();
        report.total = started.elapsed();
        Ok((pm, report))
    }
}

/// Runs `f`, with its time and the rayon thread it ran on (0 outside a pool).
fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration, usize) {
    let started = Instant::now();
    let out = f();
    (
        out,
        started.elapsed(),
        rayon::current_thread_index().unwrap_or(0),
    )
}

/// The octree over the mesh's bounding cube.
struct Octree {
    depth: u32,
    side: f64,
    /// Each position's leaf cell.
    leaf: Vec<[u32; 3]>,
}

/// One cell of one level: the positions it holds.
struct Cell {
    key: [u32; 3],
    colour: u8,
    /// Triangles around its positions.
    weight: usize,
    /// Sorted.
    positions: Vec<u32>,
}

impl Octree {
    fn new(adj: &Adjacency, triangles: usize, options: &ParallelOptions) -> Octree {
        let (mut min, mut max) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for &c in &adj.coords {
            min = min.min(c);
            max = max.max(c);
        }
        let side = (max - min).max_element().max(f64::MIN_POSITIVE);
        let bin = |depth: u32| -> Vec<[u32; 3]> {
            let n = (1u64 << depth) as f64;
            let last = (1u32 << depth) - 1;
            adj.coords
                .iter()
                .map(|&c| {
                    ((c - min) / side * n)
                        .to_array()
                        .map(|x| (x as u32).min(last))
                })
                .collect()
        };
        let mut depth = 0;
        let mut leaf = bin(0);
        while depth < options.max_depth.min(20) {
            let mut occupied: Vec<[u32; 3]> = (0..leaf.len())
                .filter(|&p| !adj.face_lists[p].is_empty())
                .map(|p| leaf[p])
                .collect();
            occupied.sort_unstable();
            occupied.dedup();
            if triangles <= options.leaf_triangles.max(1) * occupied.len().max(1) {
                break;
            }
            depth += 1;
            leaf = bin(depth);
        }
        Octree { depth, side, leaf }
    }

    /// The side of a cell at `level` (0: the leaves).
    fn side(&self, level: u32) -> f64 {
        self.side / (1u64 << (self.depth - level)) as f64
    }

    /// The cells of `level` that hold positions with triangles, in key order.
    fn cells(&self, adj: &Adjacency, level: u32) -> Vec<Cell> {
        let mut keyed: Vec<([u32; 3], u32)> = (0..adj.position_count())
            .filter(|&p| !adj.face_lists[p].is_empty())
            .map(|p| (self.leaf[p].map(|k| k >> level), p as u32))
            .collect();
        keyed.par_sort_unstable();
        let mut cells: Vec<Cell> = Vec::new();
        for (key, p) in keyed {
            match cells.last_mut() {
                Some(cell) if cell.key == key => cell.positions.push(p),
                _ => cells.push(Cell {
                    key,
                    colour: ((key[0] & 1) | (key[1] & 1) << 1 | (key[2] & 1) << 2) as u8,
                    weight: 0,
                    positions: vec![p],
                }),
            }
        }
        for cell in &mut cells {
            cell.weight = cell
                .positions
                .iter()
                .map(|&p| adj.face_lists[p as usize].len())
                .sum();
        }
        cells
    }
}

/// The whole mesh as the cells leave it.
struct State<'a> {
    mesh: &'a Mesh,
    setup: Setup,
    collapses: Vec<Collapse>,
    /// Position collapses so far (a collapse's wedges share a group).
    groups: u32,
    /// Claim marks per position, valid where the first half is `generation`.
    claims: Vec<u32>,
    generation: u32,
}

/// One cell's copy of its neighbourhood, in local numbers, with the maps back.
struct Part {
    mesh: Mesh,
    setup: Setup,
    domain: Domain,
    /// Local vertex (wedge) → the mesh's.
    wedges: Vec<u32>,
    /// Local triangle → the mesh's.
    faces: Vec<u32>,
    /// Local position → the mesh's.
    positions: Vec<u32>,
    /// The mesh's positions that are ring 1's corners: all whose triangles or quadrics
    /// a collapse in the cell can change, and all whose triangles it reads.
    ring1: Vec<u32>,
}

/// What a part did, in the whole mesh's numbers.
struct Done {
    /// (triangle, corners, alive) for each triangle of the copy that changed.
    faces: Vec<(u32, [u32; 3], bool)>,
    /// (position, its live triangles, its quadric) for each position whose fan the copy
    /// held whole: only those can have changed, and the copy knows them completely.
    positions: Vec<(u32, Vec<u32>, Quadric)>,
    /// Groups numbered from 0 within the part.
    collapses: Vec<Collapse>,
    groups: u32,
}

impl<'a> State<'a> {
    fn new(mesh: &'a Mesh) -> State<'a> {
        let setup = Setup::of(mesh);
        let np = setup.adj.position_count();
        State {
            mesh,
            setup,
            collapses: Vec::new(),
            groups: 0,
            claims: vec![0; np],
            generation: 0,
        }
    }

    /// Splits `parts` (of `cells`, in order) into those that can run together (their
    /// first rings disjoint from every earlier part's) and the cells that must wait.
    fn claim<'c>(
        &mut self,
        parts: impl IntoIterator<Item = Part>,
        cells: &[&'c Cell],
    ) -> (Vec<Part>, Vec<&'c Cell>) {
        self.generation += 1;
        if self.generation == u32::MAX {
            self.claims.fill(0);
            self.generation = 1;
        }
        let g = self.generation;
        let (mut run, mut wait) = (Vec::new(), Vec::new());
        for (part, &cell) in parts.into_iter().zip(cells) {
            if part.ring1.iter().any(|&p| self.claims[p as usize] == g) {
                wait.push(cell);
                continue;
            }
            for &p in &part.ring1 {
                self.claims[p as usize] = g;
            }
            run.push(part);
        }
        (run, wait)
    }

    /// Takes what a part did into the whole mesh. The copying and renumbering were
    /// done on the part's thread; this only stores, since it runs alone.
    fn merge(&mut self, done: Done) {
        let adj = &mut self.setup.adj;
        for (f, corners, alive) in done.faces {
            adj.set_face(f, corners, alive);
        }
        for (p, faces, quadric) in done.positions {
            adj.face_lists[p as usize] = faces;
            self.setup.quadrics[p as usize] = quadric;
        }
        let offset = self.groups;
        self.collapses
            .extend(done.collapses.into_iter().map(|c| Collapse {
                group: c.group + offset,
                ..c
            }));
        self.groups += done.groups;
    }
}

impl Part {
    /// Copies out what collapses in `cell` read: the triangles around its positions
    /// (ring 1), and around every corner of those (ring 2), so that the fans of c, p and
    /// the pivots, and the links of p, are complete in the copy.
    fn extract(state: &State, cell: &Cell, max_edge: f64) -> Part {
        let adj = &state.setup.adj;
        let around = |ps: &mut dyn Iterator<Item = u32>| -> Vec<u32> {
            let mut fs: Vec<u32> = ps
                .flat_map(|p| adj.face_lists[p as usize].iter().copied())
                .collect();
            fs.sort_unstable();
            fs.dedup();
            fs
        };
        let ring1 = around(&mut cell.positions.iter().copied());
        let mut r1: Vec<u32> = ring1
            .iter()
            .flat_map(|&f| adj.corner_positions(f))
            .collect();
        r1.sort_unstable();
        r1.dedup();
        let faces = around(&mut r1.iter().copied());
        let mut wedges: Vec<u32> = faces.iter().flat_map(|&f| adj.faces[f as usize]).collect();
        wedges.sort_unstable();
        wedges.dedup();
        let mut positions: Vec<u32> = wedges.iter().map(|&v| adj.pos_of[v as usize]).collect();
        positions.sort_unstable();
        positions.dedup();

        let local = |sorted: &[u32], x: u32| sorted.binary_search(&x).unwrap_or(0) as u32;
        let src = state.mesh;
        let mesh = Mesh {
            positions: wedges.iter().map(|&v| src.positions[v as usize]).collect(),
            normals: wedges.iter().map(|&v| src.normals[v as usize]).collect(),
            indices: faces
                .iter()
                .flat_map(|&f| adj.faces[f as usize].map(|v| local(&wedges, v)))
                .collect(),
        };
        let pos_of = wedges
            .iter()
            .map(|&v| local(&positions, adj.pos_of[v as usize]))
            .collect();
        let coords = positions.iter().map(|&p| adj.coords[p as usize]).collect();
        let setup = Setup {
            adj: Adjacency::from_welded(&mesh, pos_of, coords),
            quadrics: positions
                .iter()
                .map(|&p| state.setup.quadrics[p as usize])
                .collect(),
            locked: positions
                .iter()
                .map(|&p| state.setup.locked[p as usize])
                .collect(),
            face_normals: faces
                .iter()
                .map(|&f| state.setup.face_normals[f as usize])
                .collect(),
        };
        let free = positions
            .iter()
            .map(|p| cell.positions.binary_search(p).is_ok())
            .collect();
        Part {
            mesh,
            setup,
            domain: Domain {
                free: Some(free),
                max_edge,
            },
            wedges,
            faces,
            positions,
            ring1: r1,
        }
    }

    fn simplify(self) -> Done {
        let Part {
            mesh,
            setup,
            domain,
            wedges,
            faces,
            positions,
            ring1,
        } = self;
        let mut s = Simplifier::new(&mesh, setup, domain);
        s.run();
        let (w, f) = (|v: u32| wedges[v as usize], |t: u32| faces[t as usize]);
        // The copy's mesh keeps the corners the triangles had before.
        let before = |lf: usize| &mesh.indices[3 * lf..3 * lf + 3];
        let changed = (0..faces.len())
            .filter(|&lf| !s.adj.alive[lf] || s.adj.faces[lf][..] != *before(lf))
            .map(|lf| (faces[lf], s.adj.faces[lf].map(w), s.adj.alive[lf]))
            .collect();
        let whole = (0..positions.len())
            // Ring 1's corners: the positions whose every triangle the copy holds.
            .filter(|&lp| ring1.binary_search(&positions[lp]).is_ok())
            .map(|lp| {
                let list = s.adj.face_lists[lp].iter().map(|&t| f(t)).collect();
                (positions[lp], list, s.quadrics[lp])
            })
            .collect();
        let removed = |r: Option<RemovedFace>| {
            r.map(|r| RemovedFace {
                face: f(r.face),
                pivot: w(r.pivot),
                corner: r.corner,
            })
        };
        let collapses = s
            .collapses
            .iter()
            .map(|c| Collapse {
                v_c: w(c.v_c),
                v_p: w(c.v_p),
                left: removed(c.left),
                right: removed(c.right),
                adjusted: c.adjusted.iter().map(|&t| f(t)).collect(),
                error: c.error,
                group: c.group,
            })
            .collect();
        Done {
            faces: changed,
            positions: whole,
            collapses,
            groups: s.groups,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::bumpy_torus;
    use crate::lod::fixtures::{building, check_exact, cube};

    fn options(leaf_triangles: usize) -> ParallelOptions {
        ParallelOptions {
            leaf_triangles,
            ..Default::default()
        }
    }

    #[test]
    fn torus_refines_back_exactly_and_simplifies_as_far() {
        let torus = bumpy_torus(30_000);
        let (pm, report) = ProgressiveMesh::build_parallel(&torus, &options(500)).unwrap();
        assert!(report.depth >= 2, "{report:?}");
        assert!(
            report.levels[0].collapses > pm.splits.len() / 4,
            "{report:?}"
        );
        check_exact(&torus, &pm);
        let serial = ProgressiveMesh::build(&torus).unwrap();
        assert!(
            pm.base.triangle_count() <= serial.base.triangle_count() + 8,
            "{} against {}",
            pm.base.triangle_count(),
            serial.base.triangle_count()
        );
    }

    #[test]
    fn seams_and_pieces_survive_the_cells() {
        let mut m = building();
        m.append(&cube([30.0, 0.0, 0.0], 3));
        let (pm, _) = ProgressiveMesh::build_parallel(&m, &options(64)).unwrap();
        check_exact(&m, &pm);
        assert!(pm.splits.iter().any(|s| s.joins_previous));
    }

    #[test]
    fn the_same_on_one_thread_and_on_many() {
        let torus = bumpy_torus(8_000);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| ProgressiveMesh::build_parallel(&torus, &options(200)))
                .unwrap()
                .0
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn one_cell_is_the_serial_build() {
        let bunny = crate::scene::bunny();
        let (pm, report) =
            ProgressiveMesh::build_parallel(&bunny, &options(usize::MAX / 16)).unwrap();
        assert_eq!(report.depth, 0);
        check_exact(&bunny, &pm);
        assert_eq!(
            pm.base.triangle_count(),
            ProgressiveMesh::build(&bunny)
                .unwrap()
                .base
                .triangle_count()
        );
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut nan = crate::scene::bunny();
        nan.positions[3][1] = f32::NAN;
        let e = ProgressiveMesh::build_parallel(&nan, &options(100))
            .unwrap_err()
            .to_string();
        assert!(e.contains("position 3"), "{e}");
        assert!(ProgressiveMesh::build_parallel(&Mesh::default(), &options(100)).is_err());
    }
}
