//! A walk through a database's walkable viewcells (the cells its precomputed
//! visibility covers), for the PVS walk (Zheng 2007 ch. 7) on a real city.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{CameraPath, Pose};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::visibility::TableHead;

/// A walk through the walkable viewcells of `db`: from a cell's centre to a
/// neighbouring walkable cell's centre, `step` metres a frame at `fps`, going straight
/// on where it can (four times in five) and turning or, at a dead end, going back;
/// deterministic from `seed`. The eye is at the middle of the cells' height range.
/// The poses of [`cell_poses`], kept.
pub fn cell_walk(
    db: &Database,
    frames: usize,
    step: f32,
    fps: f32,
    seed: u64,
) -> Result<CameraPath> {
    CameraPath::new(cell_poses(db, frames, step, fps, seed)?.collect())
}

/// [`cell_walk`]'s poses, made as they are asked for: a walk of any length in constant
/// memory.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
/// # let mut opts = flaneur::BuildOptions::default();
/// # opts.visibility = Some(flaneur::visibility::VisibilityOptions { cell_size: 40.0, ..Default::default() });
/// # flaneur::build_from_scene(&scene, &path, &opts)?;
/// use flaneur::path::{cell_poses, cell_walk};
/// let db = flaneur::Database::open(&path)?;
/// let lazy: Vec<_> = cell_poses(&db, 300, 0.5, 30.0, 4)?.collect();
/// assert_eq!(lazy, cell_walk(&db, 300, 0.5, 30.0, 4)?.poses);
/// assert_eq!(cell_poses(&db, 1_000_000_000, 0.5, 30.0, 4)?.len(), 1_000_000_000);
/// # Ok(()) }
/// ```
pub fn cell_poses(
    db: &Database,
    frames: usize,
    step: f32,
    fps: f32,
    seed: u64,
) -> Result<CellPoses<'_>> {
    let head = db.visibility()?.ok_or_else(|| {
        Error::Invalid(format!(
            "{} has no precomputed visibility: build it with --visibility",
            db.store().path().display()
        ))
    })?;
    if !(step.is_finite() && step > 0.0 && fps.is_finite() && fps > 0.0) || frames == 0 {
        return Err(Error::Invalid(format!(
            "a cell walk needs frames > 0, a positive step and fps (got {frames}, {step} m, {fps})"
        )));
    }
    if head.cells.is_empty() {
        return Err(Error::Invalid(format!(
            "{} has no walkable viewcell to walk through",
            db.store().path().display()
        )));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let start = head.cells[rng.gen_range(0..head.cells.len())].id;
    let (r, c) = head.grid.place(start);
    let (r, c) = (r as i64, c as i64);
    let d = rng.gen_range(0..4usize);
    let at = centre(head, r, c);
    Ok(CellPoses {
        head,
        rng,
        cell: (r, c),
        d,
        at,
        target: at,
        step,
        fps,
        next: 0,
        frames,
    })
}

/// Right, down, left, up, in (row, column) steps.
const DIRS: [(i64, i64); 4] = [(0, 1), (1, 0), (0, -1), (-1, 0)];

fn centre(head: &TableHead, r: i64, c: i64) -> Vec3 {
    head.grid.cell_bounds(r as u32, c as u32).center()
}

fn walkable(head: &TableHead, r: i64, c: i64) -> bool {
    let grid = &head.grid;
    r >= 0
        && c >= 0
        && (r as u32) < grid.rows()
        && (c as u32) < grid.columns()
        && head.cell(grid.id(r as u32, c as u32)).is_some()
}

/// The poses of a walk through viewcells, made as they are asked for ([`cell_poses`]).
pub struct CellPoses<'a> {
    head: &'a TableHead,
    rng: ChaCha8Rng,
    /// The cell walked towards (row, column), and the direction taken to it.
    cell: (i64, i64),
    d: usize,
    at: Vec3,
    target: Vec3,
    step: f32,
    fps: f32,
    next: usize,
    frames: usize,
}

impl CellPoses<'_> {
    /// At a centre: chooses the next cell.
    fn choose(&mut self) {
        let (r, c) = self.cell;
        let open: Vec<usize> = (0..4)
            .filter(|&k| walkable(self.head, r + DIRS[k].0, c + DIRS[k].1))
            .collect();
        if open.is_empty() {
            return;
        }
        let ahead = open.contains(&self.d) && self.rng.gen_bool(0.8);
        if !ahead {
            let back = (self.d + 2) % 4;
            let turns: Vec<usize> = open.iter().copied().filter(|&k| k != back).collect();
            self.d = if turns.is_empty() {
                open[0]
            } else {
                turns[self.rng.gen_range(0..turns.len())]
            };
        }
        self.cell = (r + DIRS[self.d].0, c + DIRS[self.d].1);
        self.target = centre(self.head, self.cell.0, self.cell.1);
    }
}

impl Iterator for CellPoses<'_> {
    type Item = Pose;

    fn next(&mut self) -> Option<Pose> {
        if self.next >= self.frames {
            return None;
        }
        if (self.target - self.at).length() < 1e-3 {
            self.choose();
        }
        let to = self.target - self.at;
        if to.length() > self.step {
            self.at += to.normalize() * self.step;
        } else {
            self.at = self.target;
        }
        let (dr, dc) = DIRS[self.d];
        let pose = Pose {
            time: self.next as f64 / self.fps as f64,
            position: self.at,
            yaw: (dr as f32).atan2(dc as f32),
            pitch: 0.0,
        };
        self.next += 1;
        Some(pose)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.frames - self.next;
        (left, Some(left))
    }
}

impl ExactSizeIterator for CellPoses<'_> {}
