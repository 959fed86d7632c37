//! Precomputed visibility end to end: `flaneur build --visibility` stores each walkable
//! viewcell's PVS with DoVs, the database reads them back, `info` reports them, and a
//! damaged table is an error that names its page.

mod common;

use common::flaneur;

use std::os::unix::fs::FileExt;

use flaneur::store::PAGE_HEADER_LEN;
use flaneur::visibility::VisibilityOptions;
use flaneur::{BuildOptions, Database, Error};

fn with_visibility() -> BuildOptions {
    BuildOptions {
        lod: None,
        visibility: Some(VisibilityOptions {
            cell_size: 12.0,
            resolution: 32,
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// A generated city's scene file in `dir`.
fn scene_in(dir: &std::path::Path, objects: u64, seed: u64) -> std::path::PathBuf {
    let scene = dir.join("c.scene");
    let config = citygen::CityConfig {
        objects,
        seed,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    scene
}

/// `flaneur build SCENE -o DB -q` with `extra` arguments.
fn build_cli(
    scene: &std::path::Path,
    db: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "build",
        scene.to_str().unwrap(),
        "-o",
        db.to_str().unwrap(),
        "-q",
    ];
    args.extend(extra);
    flaneur(&args)
}

#[test]
fn every_walkable_cell_has_a_pvs_with_dovs() {
    let city = common::city(80, 5, &with_visibility());
    let db = Database::open(&city.db).unwrap();
    assert!(db.has_visibility());
    let head = db.visibility().unwrap().unwrap().clone();
    assert!(head.cells.len() > 10, "{} cells", head.cells.len());
    let ids: Vec<u64> = city.boxes.iter().map(|b| b.0).collect();
    let mut shares = 0.0;
    for c in &head.cells {
        let pvs = db.pvs(c.id).unwrap().expect("walkable");
        assert_eq!(pvs.ids.len(), c.count as usize);
        assert!(!pvs.ids.is_empty(), "cell {} sees nothing", c.id);
        assert!(pvs.ids.iter().all(|id| ids.binary_search(id).is_ok()));
        assert!(pvs.dov.iter().all(|&d| d > 0.0 && d <= 1.0));
        shares += pvs.ids.len() as f64 / ids.len() as f64;
        // The cell is found again from a point in it.
        let (r, col) = head.grid.place(c.id);
        let centre = head.grid.cell_bounds(r, col).center();
        assert_eq!(db.viewcell_at(centre).unwrap(), Some(c.id));
    }
    // Occluders hide something somewhere.
    assert!(shares / (head.cells.len() as f64) < 1.0);
    // Unwalkable and outside cells have none.
    let outside = (0..head.grid.len() as u32).find(|&id| head.cell(id).is_none());
    if let Some(id) = outside {
        assert!(db.pvs(id).unwrap().is_none());
    }
    assert!(db.pvs(u32::MAX).unwrap().is_none());
    // A walk through the cells stays in them; bad settings are errors.
    use flaneur::path::cell_walk;
    let walk = cell_walk(&db, 600, 0.5, 30.0, 3).unwrap();
    assert_eq!(walk.poses.len(), 600);
    for p in &walk.poses {
        assert!(db.viewcell_at(p.position).unwrap().is_some(), "{p:?}");
    }
    for (frames, step, fps) in [
        (0, 0.5, 30.0),
        (10, 0.0, 30.0),
        (10, f32::NAN, 30.0),
        (10, 0.5, 0.0),
    ] {
        assert!(
            cell_walk(&db, frames, step, fps, 3).is_err(),
            "{frames} {step} {fps}"
        );
    }
    let info = db.info().unwrap().visibility.unwrap();
    assert_eq!(info.cells, head.cells.len());
    assert!(info.rays > 0 && info.seconds > 0.0);
}

#[test]
fn a_database_without_visibility_says_so() {
    let city = common::city(
        20,
        1,
        &BuildOptions {
            lod: None,
            ..Default::default()
        },
    );
    let db = Database::open(&city.db).unwrap();
    assert!(!db.has_visibility());
    assert!(db.visibility().unwrap().is_none());
    assert!(db.pvs(0).unwrap().is_none());
    let out = flaneur(&["info", city.db.to_str().unwrap()]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("visibility  none"), "{text}");
}

#[test]
fn build_and_info_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_in(dir.path(), 40, 1);
    let db = dir.path().join("c.flaneur");
    let args = [
        "--no-lod",
        "--visibility",
        "--cell-size",
        "15",
        "--dov-resolution",
        "16",
    ];
    let out = build_cli(&scene, &db, &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("walkable cells"));
    let out = flaneur(&["info", db.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("PVS"), "{text}");
    assert!(text.contains("s per cell"), "{text}");
    for prefetch in ["pbnp", "snp"] {
        let out = flaneur(&[
            "walk",
            db.to_str().unwrap(),
            "--mode",
            "pvs",
            "--prefetch",
            prefetch,
            "--frames",
            "3000",
            "-q",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains(&format!("{prefetch} prefetch")), "{text}");
        assert!(text.contains("prefetch transactions"), "{text}");
        assert!(text.contains("0 outside any walkable cell"), "{text}");
    }
    let out = flaneur(&[
        "walk",
        db.to_str().unwrap(),
        "--mode",
        "pvs",
        "--prefetch",
        "xyz",
    ]);
    assert!(!out.status.success());
    // The prefetch experiment over this database's visibility as well.
    let bench = dir.path().join("bench");
    let out = flaneur(&[
        "bench",
        "pvs-prefetch",
        "--blocks",
        "10",
        "--steps",
        "300",
        "--borders",
        "0.25",
        "--db",
        db.to_str().unwrap(),
        "--out",
        bench.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("walkable viewcells of"), "{text}");
    // Table 7.2's CSV, the steps of Figs. 7.7–7.8 and their plots, for the database too.
    let on_db = bench.join("pvs-prefetch-db");
    let csv = std::fs::read_to_string(on_db.join("pvs-prefetch.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    for row in rows {
        let transactions: u64 = row.split(',').nth(2).unwrap().parse().unwrap();
        assert!(transactions >= 1, "{row}");
    }
    let steps = std::fs::read_to_string(on_db.join("pvs-prefetch-steps.csv")).unwrap();
    assert_eq!(steps.lines().count(), 302, "a header and 301 positions");
    assert!(on_db.join("pvs-prefetch-route2-pbnp.png").exists());
    let summary = std::fs::read_to_string(on_db.join("pvs-prefetch.md")).unwrap();
    assert!(summary.contains("| pages read (PVS records)"), "{summary}");
    // The ray-cast reference builds the same cells on request; a method it does not
    // know is refused by the option's name.
    let rays = dir.path().join("rays.flaneur");
    let out = build_cli(
        &scene,
        &rays,
        &[&args[..], &["--dov-method", "ray-cast"]].concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (a, b) = (Database::open(&db).unwrap(), Database::open(&rays).unwrap());
    let cells = |d: &Database| d.visibility().unwrap().unwrap().cells.len();
    assert_eq!(cells(&a), cells(&b));
    let out = build_cli(
        &scene,
        &rays,
        &[&args[..], &["--dov-method", "gpu"]].concat(),
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--dov-method"));
    let out = build_cli(&scene, &db, &["--visibility", "--cell-size", "0"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("viewcell size"));
    // A database without visibility cannot walk in PVS mode, and says why.
    let plain = dir.path().join("plain.flaneur");
    let out = build_cli(&scene, &plain, &["--no-lod"]);
    assert!(out.status.success());
    let out = flaneur(&["walk", plain.to_str().unwrap(), "--mode", "pvs", "-q"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--visibility"));
}

#[test]
fn a_damaged_table_is_an_error_naming_its_page() {
    let city = common::city(40, 2, &with_visibility());
    let db = Database::open(&city.db).unwrap();
    let seg = db
        .store()
        .header()
        .segment(flaneur::visibility::VISIBILITY_SEGMENT)
        .unwrap()
        .clone();
    let page_size = db.store().page_size() as u64;
    drop(db);
    // A byte of the table's first page flipped: its checksum fails on read.
    let file = std::fs::OpenOptions::new()
        .write(true)
        .read(true)
        .open(&city.db)
        .unwrap();
    let at = seg.a * page_size + PAGE_HEADER_LEN as u64 + 10;
    let mut byte = [0u8];
    file.read_exact_at(&mut byte, at).unwrap();
    file.write_all_at(&[byte[0] ^ 0x40], at).unwrap();
    drop(file);
    let db = Database::open(&city.db).unwrap();
    match db.visibility() {
        Err(Error::CorruptPage { page, .. }) => assert_eq!(page, seg.a),
        other => panic!("expected a corrupt page, got {other:?}"),
    }
    assert!(db.pvs(0).is_err());
}

#[test]
fn buildings_occlude_and_the_prefetcher_reads_the_table() {
    use flaneur::prefetch::pvs::{Pbnp, Position, Snp, StoredPvs, DEFAULT_BORDER, THESIS_CAPACITY};
    use flaneur_bench::pvs_prefetch::simulate;
    let dir = tempfile::tempdir().unwrap();
    let (scene, path) = (scene_in(dir.path(), 120, 4), dir.path().join("c.flaneur"));
    let summary = flaneur::build_from_scene(&scene, &path, &with_visibility()).unwrap();
    let v = summary.visibility.unwrap();
    assert!(v.occluders >= 100, "{v:?}");

    let db = Database::open(&path).unwrap();
    let source = StoredPvs::new(&db).unwrap();
    // A walk from cell centre to cell centre along the longest run of walkable cells
    // side by side in one row.
    let size = db.visibility().unwrap().unwrap().grid.size as f64;
    let centres = source.walkable_centres().unwrap();
    let mut best: &[Position] = &centres[..1];
    let mut start = 0;
    for i in 1..=centres.len() {
        let joined = i < centres.len()
            && centres[i].z == centres[i - 1].z
            && (centres[i].x - centres[i - 1].x - size).abs() < 1e-3;
        if !joined {
            if i - start > best.len() {
                best = &centres[start..i];
            }
            start = i;
        }
    }
    assert!(best.len() >= 3, "a run of {} cells", best.len());
    let mut route = Vec::new();
    for w in best.windows(2) {
        for k in 0..4 {
            let t = k as f64 / 4.0;
            route.push(Position::new(w[0].x + t * (w[1].x - w[0].x), w[0].z));
        }
    }
    let before = db.io().page_reads;
    let pbnp = simulate(
        &source,
        &Pbnp::new(DEFAULT_BORDER).unwrap(),
        &route,
        THESIS_CAPACITY,
    )
    .unwrap();
    let snp = simulate(&source, &Snp, &route, THESIS_CAPACITY).unwrap();
    assert!(pbnp.totals.transactions >= 1 && snp.totals.transactions >= 1);
    assert!(
        db.io().page_reads > before,
        "PVS pages are read through the store"
    );
}
