//! Times the visibility build's setup alone: every object's occluder boxes and the
//! conservative test's scene over them, on all cores, as `flaneur build --visibility`
//! does before its first viewcell.
//!
//! `cargo run --release -p flaneur --example occluder_setup -- CITY.scene [RUNS]`
//! (`RAYON_NUM_THREADS=1` for one core). Prints the objects, triangles, occluding
//! objects and prisms beside the best wall-clock and CPU times of the runs.

use std::path::PathBuf;
use std::time::Instant;

use flaneur::scene::SceneReader;
use flaneur::visibility::ConservativeScene;

fn main() -> flaneur::Result<()> {
    let mut args = std::env::args().skip(1);
    let usage = || flaneur::Error::Invalid("usage: occluder_setup CITY.scene [RUNS]".into());
    let path = PathBuf::from(args.next().ok_or_else(usage)?);
    let runs: usize = match args.next() {
        Some(n) => n.parse().map_err(|_| usage())?,
        None => 1,
    };
    let objects = SceneReader::open(&path)?
        .map(|o| o.map(|o| (o.id, o.mesh)))
        .collect::<Result<Vec<_>, _>>()?;
    let triangles: usize = objects.iter().map(|(_, m)| m.triangle_count()).sum();
    let mut times = Vec::new();
    let mut counts = (0, 0);
    for _ in 0..runs.max(1) {
        let (start, cpu) = (Instant::now(), cpu_seconds());
        let scene = ConservativeScene::from_meshes(&objects)?;
        times.push((start.elapsed().as_secs_f64(), cpu_seconds() - cpu));
        counts = (scene.occluding_objects(), scene.prism_count());
    }
    let best = |f: fn(&(f64, f64)) -> f64| times.iter().map(f).fold(f64::INFINITY, f64::min);
    println!(
        "{} objects, {triangles} triangles: {} occluding, {} prisms; setup best of {} runs {:.3} s, {:.3} s of CPU",
        objects.len(),
        counts.0,
        counts.1,
        times.len(),
        best(|t| t.0),
        best(|t| t.1),
    );
    Ok(())
}

/// The CPU time this process has used, all its threads together: on a shared machine
/// a steadier figure than the wall clock.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes only the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    seconds(usage.ru_utime) + seconds(usage.ru_stime)
}
