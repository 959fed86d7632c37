//! The conservative PVS against a dense sampling, on every walkable cell of a small
//! generated city: no object that a ray from one of 32 viewpoints of a cell (its
//! corners, its side faces' centres, seeded interior points) meets first is missing
//! from the cell's PVS, stored or recomputed by this binary's test. The check is shown
//! to catch a PVS broken on purpose, and the command to write its report and refuse
//! what it cannot measure.

mod common;

use flaneur::visibility::VisibilityOptions;
use flaneur::{BuildOptions, Database};
use flaneur_bench::pvs_tightness::{self, PvsSource, PvsTightnessConfig};

/// 80 objects in 20 m viewcells, the conservative test at its defaults.
fn city() -> common::City {
    common::city(
        80,
        5,
        &BuildOptions {
            lod: None,
            visibility: Some(VisibilityOptions {
                cell_size: 20.0,
                resolution: 16,
                ..Default::default()
            }),
            ..Default::default()
        },
    )
}

/// Every cell, 32 viewpoints, 64 × 64 rays a cube face.
fn every_cell() -> PvsTightnessConfig {
    PvsTightnessConfig {
        cells: usize::MAX,
        resolution: 64,
        ..PvsTightnessConfig::default()
    }
}

#[test]
fn no_object_seen_from_a_cell_is_missing_from_its_pvs() {
    let city = city();
    let db = Database::open(&city.db).unwrap();
    let walkable = db.visibility().unwrap().unwrap().cells.len();
    let sampling = pvs_tightness::sample(&db, &every_cell()).unwrap();
    let stored = pvs_tightness::measure(&db, &sampling, &PvsSource::Stored).unwrap();
    assert_eq!(stored.rows.len(), walkable);
    assert!(walkable > 20, "{walkable} walkable cells");
    assert_eq!(stored.missing(), vec![], "seen but not in the PVS");
    // The check is not empty: cells see things, and the PVS keeps more than they see.
    assert!(stored.rows.iter().all(|r| r.seen > 0 && r.pvs >= r.seen));
    assert!(stored.ratio_of_means >= 1.0);
    // This binary's test, recomputed, is conservative too (it is what a build now
    // stores).
    let recomputed = PvsSource::Recomputed(sampling.stored_samples);
    let now = pvs_tightness::measure(&db, &sampling, &recomputed).unwrap();
    assert_eq!(now.missing(), vec![], "seen but not in the recomputed PVS");
    assert_eq!(now.source, "recomputed");
    assert!(now.prisms > 0 && now.occluding_objects > 0);

    // Each cell's PVS with the object whose box is nearest the cell's centre taken
    // out: the check names the cells where that object is seen, and nothing else.
    let head = db.visibility().unwrap().unwrap().clone();
    let nearest = |cell: u32| {
        let (r, c) = head.grid.place(cell);
        let centre = head.grid.cell_bounds(r, c).center();
        city.boxes
            .iter()
            .map(|(id, b)| {
                let d = (centre.clamp(b.min, b.max) - centre).length();
                (d, *id)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap()
            .1
    };
    let broken = |cell: u32| {
        let mut ids = db.pvs(cell)?.map(|p| p.ids).unwrap_or_default();
        ids.retain(|&id| id != nearest(cell));
        Ok(ids)
    };
    let r = pvs_tightness::measure(&db, &sampling, &PvsSource::Given(&broken)).unwrap();
    let missing = r.missing();
    assert!(
        missing.len() * 2 > r.rows.len(),
        "only {} of {} cells miss their nearest object",
        missing.len(),
        r.rows.len()
    );
    for (cell, id) in missing {
        assert_eq!(id, nearest(cell), "cell {cell}");
    }
}

/// `flaneur bench EXPERIMENT DB` on three cells at N = `resolution` into `out`: its
/// printed summary, after it succeeded.
fn three_cells(experiment: &str, db: &str, resolution: &str, out: &std::path::Path) -> String {
    let out = out.to_str().unwrap();
    let run = common::flaneur(&[
        "bench",
        experiment,
        db,
        "--cells",
        "3",
        "--resolution",
        resolution,
        "--out",
        out,
    ]);
    common::succeeded(&run)
}

/// `flaneur bench EXPERIMENT DB ARGS` fails for each of `cases`, its error naming
/// what it says; and a database built without visibility is refused by name.
fn refuses(experiment: &str, db: &str, cases: &[(&[&str], &str)]) {
    for (args, says) in cases {
        let mut all = vec!["bench", experiment, db];
        all.extend_from_slice(args);
        let run = common::flaneur(&all);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(
            !run.status.success() && err.contains(says),
            "{all:?}: {err}"
        );
    }
    let plain = common::city(10, 1, &BuildOptions::default());
    let run = common::flaneur(&["bench", experiment, plain.db.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && err.contains("--visibility"),
        "{err}"
    );
}

#[test]
fn the_command_writes_its_report_and_refuses_what_it_cannot_measure() {
    let city = city();
    let out = city.dir.path().join("out");
    let db = city.db.to_str().unwrap();
    let text = three_cells("pvs-tightness", db, "32", &out);
    assert!(text.contains("mean PVS / mean seen"), "{text}");
    let csv = common::Csv::read(&out.join("pvs-tightness.csv"));
    assert_eq!(csv.rows.len(), 3);
    for row in &csv.rows {
        assert!(csv.num(row, "pvs") >= csv.num(row, "seen"));
        assert_eq!(csv.get(row, "missing"), "");
    }
    assert!(out.join("pvs-tightness.md").exists());
    refuses(
        "pvs-tightness",
        db,
        &[
            (&["--cells", "0"], "--cells"),
            (&["--resolution", "0"], "--resolution"),
            (
                &["--recompute", "--sample-spacing", "-1"],
                "--sample-spacing",
            ),
        ],
    );
}

/// `bench dov-accuracy` on the same city: the raster against the rays on three cells,
/// within the criterion, and what it cannot measure refused by name.
#[test]
fn the_dov_accuracy_command_compares_the_raster_with_the_rays() {
    let city = city();
    let out = city.dir.path().join("dov");
    let db = city.db.to_str().unwrap();
    let text = three_cells("dov-accuracy", db, "64", &out);
    assert!(text.contains("a corner (all cores)"), "{text}");
    let csv = common::Csv::read(&out.join("dov-accuracy.csv"));
    assert_eq!(csv.rows.len(), 3);
    for row in &csv.rows {
        assert!(csv.num(row, "raster_objects") > 0.0);
        assert!(csv.num(row, "difference") <= 0.01, "{:?}", row);
    }
    refuses(
        "dov-accuracy",
        db,
        &[
            (&["--cells", "0"], "--cells"),
            (&["--resolution", "0"], "--resolution"),
            (&["--limit", "-1"], "--limit"),
        ],
    );
}
