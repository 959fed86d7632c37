//! A walk through a database's walkable viewcells (the cells its precomputed
//! visibility covers), for the PVS walk (Zheng 2007 ch. 7) on a real city.

use super::{CameraPath, Pose};
use crate::database::Database;
use crate::error::{Error, Result};

/// A walk through the walkable viewcells of `db`: from a cell's centre to a
/// neighbouring walkable cell's centre, `step` metres a frame at `fps`, going straight
/// on where it can (four times in five) and turning or, at a dead end, going back;
/// deterministic from `seed`. The eye is at the middle of the cells' height range.
pub fn cell_walk(
    db: &Database,
    frames: usize,
    step: f32,
    fps: f32,
    seed: u64,
) -> Result<CameraPath> {
    use rand::{Rng, SeedableRng};
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
    let grid = &head.grid;
    let walkable = |r: i64, c: i64| {
        r >= 0
            && c >= 0
            && (r as u32) < grid.rows()
            && (c as u32) < grid.columns()
            && head.cell(grid.id(r as u32, c as u32)).is_some()
    };
    let centre = |r: i64, c: i64| grid.cell_bounds(r as u32, c as u32).center();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let start = head.cells[rng.gen_range(0..head.cells.len())].id;
    let (r0, c0) = grid.place(start);
    let (mut r, mut c) = (r0 as i64, c0 as i64);
    let dirs = [(0i64, 1i64), (1, 0), (0, -1), (-1, 0)];
    let mut d = rng.gen_range(0..4usize);
    let mut p = centre(r, c);
    let mut poses = Vec::with_capacity(frames);
    let mut target = p;
    for f in 0..frames {
        if (target - p).length() < 1e-3 {
            // At a centre: choose the next cell.
            let open: Vec<usize> = (0..4)
                .filter(|&k| walkable(r + dirs[k].0, c + dirs[k].1))
                .collect();
            if !open.is_empty() {
                let ahead = open.contains(&d) && rng.gen_bool(0.8);
                if !ahead {
                    let turns: Vec<usize> =
                        open.iter().copied().filter(|&k| k != (d + 2) % 4).collect();
                    d = if turns.is_empty() {
                        open[0]
                    } else {
                        turns[rng.gen_range(0..turns.len())]
                    };
                }
                r += dirs[d].0;
                c += dirs[d].1;
                target = centre(r, c);
            }
        }
        let to = target - p;
        let yaw = (dirs[d].0 as f32).atan2(dirs[d].1 as f32);
        if to.length() > step {
            p += to.normalize() * step;
        } else {
            p = target;
        }
        poses.push(Pose {
            time: f as f64 / fps as f64,
            position: p,
            yaw,
            pitch: 0.0,
        });
    }
    CameraPath::new(poses)
}
