//! Writers killed at random points, as SQLite tests its own: `flaneur insert` and
//! `flaneur build` are sent SIGKILL after a random delay, again and again, and every
//! time the database at the path opens and holds either the old objects or the new
//! ones — for insert, a prefix of the inserts, each whole — never a mix. The number of
//! kills is `FLANEUR_KILLS` (default sized for CI).

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

use flaneur::scene::Mesh;
use flaneur::{BuildOptions, Database};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The inserts the killed `flaneur insert` is asked for.
const INSERTS: usize = 24;
const FIRST_ID: u64 = 1_000_000;

fn kills() -> usize {
    std::env::var("FLANEUR_KILLS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(120)
}

fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

/// Runs `args` to the end and returns how long it took.
fn timed(args: &[&str]) -> Duration {
    let t = Instant::now();
    let status = spawn(args).wait().unwrap();
    assert!(status.success(), "flaneur {args:?}");
    t.elapsed()
}

/// Runs `args` and kills it with SIGKILL after a random share of `full`; whether it
/// finished first.
fn run_killed(args: &[&str], full: Duration, rng: &mut ChaCha8Rng) -> bool {
    let mut child = spawn(args);
    std::thread::sleep(full.mul_f64(rng.gen_range(0.0..1.1)));
    let _ = child.kill();
    child.wait().unwrap().success()
}

/// An OBJ file of `INSERTS` small boxes along the city's south edge, one group each.
fn boxes_obj(dir: &Path, db: &Database) -> PathBuf {
    use std::io::Write;
    let b = db.bounds();
    let path = dir.join("boxes.obj");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let mut first = 1;
    for i in 0..INSERTS {
        let (x, z) = (b.min.x + 2.0 * i as f32, b.min.z - 3.0);
        let mesh = common::box_mesh([x, 0.0, z], [x + 1.5, 2.0 + i as f32, z + 1.5]);
        writeln!(f, "o box{i}").unwrap();
        flaneur::scene::write_mesh_obj(&mut f, &mesh, first).unwrap();
        first += mesh.positions.len() as u64;
    }
    drop(f);
    path
}

#[test]
fn insert_killed_at_random_points_keeps_a_prefix_of_whole_inserts() {
    let city = common::city(120, 5, &BuildOptions::default());
    let pristine = std::fs::read(&city.db).unwrap();
    let base = Database::open(&city.db).unwrap();
    let base_ids = base.range(&base.bounds()).unwrap().ids();
    let obj = boxes_obj(city.dir.path(), &base);
    let meshes: Vec<Mesh> = flaneur::scene::load_obj(&obj)
        .unwrap()
        .into_iter()
        .map(|(_, m)| m)
        .collect();
    assert_eq!(meshes.len(), INSERTS);
    drop(base);

    let work = city.dir.path().join("work.flaneur");
    let first = FIRST_ID.to_string();
    let args = [
        "insert",
        work.to_str().unwrap(),
        obj.to_str().unwrap(),
        "--first-id",
        &first,
    ];
    std::fs::write(&work, &pristine).unwrap();
    let mut full = timed(&args);
    // The meshes as the file stores them (quantised by the default codec), from the run
    // that was not killed.
    let stored: Vec<_> = {
        let db = Database::open(&work).unwrap();
        let all = db.range(&db.bounds()).unwrap();
        let mut inserted: Vec<_> = all.objects.iter().filter(|o| o.id >= FIRST_ID).collect();
        inserted.sort_by_key(|o| o.id);
        assert_eq!(inserted.len(), meshes.len());
        inserted.iter().map(|o| db.mesh(o).unwrap()).collect()
    };

    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let mut committed: BTreeMap<usize, usize> = BTreeMap::new();
    for run in 0..kills() {
        std::fs::write(&work, &pristine).unwrap();
        let finished = run_killed(&args, full, &mut rng);
        let db = Database::open(&work)
            .unwrap_or_else(|e| panic!("run {run}: the database does not open: {e}"));
        let k = (db.objects() - base_ids.len() as u64) as usize;
        assert!(k <= INSERTS, "run {run}: {k} inserts");
        let mut want = base_ids.clone();
        want.extend((0..k as u64).map(|i| FIRST_ID + i));
        let all = db.range(&db.bounds()).unwrap();
        assert_eq!(all.ids(), want, "run {run}: the index holds a mix");
        for o in all.objects.iter().filter(|o| o.id >= FIRST_ID) {
            let i = (o.id - FIRST_ID) as usize;
            assert_eq!(db.mesh(o).unwrap(), stored[i], "run {run}: object {}", o.id);
        }
        assert_eq!(
            db.triangles(),
            Database::open(&city.db).unwrap().triangles()
                + meshes[..k]
                    .iter()
                    .map(|m| m.triangle_count() as u64)
                    .sum::<u64>(),
            "run {run}: the header's counts"
        );
        *committed.entry(k).or_default() += 1;
        // A busy machine runs the writer slower or faster than the first, timed run:
        // the kills follow it, so that they keep landing among the inserts.
        if finished || k == INSERTS {
            full = full.mul_f64(0.9);
        } else if k == 0 {
            full = full.mul_f64(1.1);
        }
        drop(db);
        // The next writer cuts the interrupted one's tail and goes on.
        if run % 10 == 0 {
            let mut db = Database::open_writable(&work, flaneur::Backend::Mmap).unwrap();
            db.insert(7, &meshes[0]).unwrap();
            drop(db);
            assert_eq!(
                Database::open(&work).unwrap().store().uncommitted_bytes(),
                0
            );
        }
    }
    eprintln!("inserts committed when killed (count → runs): {committed:?}");
    let between = committed
        .iter()
        .filter(|(&k, _)| k > 0 && k < INSERTS)
        .map(|(_, n)| n)
        .sum::<usize>();
    assert!(
        between * 5 >= kills(),
        "a fifth of the kills must land between the first insert and the last: {committed:?}"
    );
}

#[test]
fn build_killed_at_random_points_leaves_the_old_database_or_the_new() {
    let old = common::city(60, 1, &BuildOptions::default());
    let new = common::city(90, 2, &BuildOptions::default());
    let old_bytes = std::fs::read(&old.db).unwrap();
    let new_bytes = std::fs::read(&new.db).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("city.flaneur");
    let args = [
        "build",
        new.scene.to_str().unwrap(),
        "-o",
        target.to_str().unwrap(),
    ];
    std::fs::write(&target, &old_bytes).unwrap();
    let full = timed(&args);
    assert_eq!(std::fs::read(&target).unwrap(), new_bytes, "builds repeat");

    let mut rng = ChaCha8Rng::seed_from_u64(24);
    let (mut olds, mut news) = (0, 0);
    for run in 0..kills() / 4 {
        std::fs::write(&target, &old_bytes).unwrap();
        run_killed(&args, full, &mut rng);
        let bytes = std::fs::read(&target).unwrap();
        if bytes == old_bytes {
            olds += 1;
        } else {
            assert!(
                bytes == new_bytes,
                "run {run}: neither the old file nor the new"
            );
            news += 1;
        }
        Database::open(&target).unwrap();
    }
    eprintln!("killed builds: {olds} left the old database, {news} the new");
    // The temporaries the killed builds left are never reused: a build goes on beside them.
    std::fs::write(&target, &old_bytes).unwrap();
    timed(&args);
    assert_eq!(std::fs::read(&target).unwrap(), new_bytes);
}

#[test]
fn bytes_past_the_last_page_are_a_warning_and_the_next_insert_cuts_them() {
    let city = common::city(40, 3, &BuildOptions::default());
    let db = city.db.to_str().unwrap();
    let len = std::fs::metadata(&city.db).unwrap().len();
    let page = Database::open(&city.db).unwrap().store().page_size() as u64;
    // A whole zero page appended: the database opens, and says so.
    std::fs::OpenOptions::new()
        .write(true)
        .open(&city.db)
        .unwrap()
        .set_len(len + page)
        .unwrap();
    let out = common::flaneur(&["info", db]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stderr.contains(&format!("warning: {page} bytes past")),
        "{stderr}"
    );
    let out = common::flaneur(&["info", db, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["uncommitted_bytes"], page);

    let obj = boxes_obj(city.dir.path(), &Database::open(&city.db).unwrap());
    let text = common::succeeded(&common::flaneur(&["insert", db, obj.to_str().unwrap()]));
    assert!(
        text.contains(&format!(
            "inserted {INSERTS} objects (ids 40..{})",
            40 + INSERTS
        )),
        "{text}"
    );
    let out = common::flaneur(&["info", db]);
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let db = Database::open(&city.db).unwrap();
    assert_eq!(db.objects(), 40 + INSERTS as u64);
    assert_eq!(db.store().uncommitted_bytes(), 0);
}
