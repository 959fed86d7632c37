//! `flaneur bench hdov-search` and `hdov-cache` on a small city built with the HDoV-tree:
//! every method and threshold present, the naive list flat across η, the tree's I/O
//! falling as η grows, η = 0 finding the naive method's objects, no cache policy above
//! Belady's, and the commands' files written.

mod common;

use flaneur::hdov::HdovOptions;
use flaneur::visibility::VisibilityOptions;
use flaneur::{BuildOptions, Database};
use flaneur_bench::hdov_cache::{self, HdovCacheConfig};
use flaneur_bench::hdov_search::{self, HdovSearchConfig, HdovSearchRow, PLOT_SEARCH, PLOT_TOTAL};
use flaneur_bench::report::Report;

/// Format version 1's raw meshes, whose page counts the thesis's comparison (Fig. 5.22)
/// was measured on: an object barely seen costs fewer pages at a coarse level than at full
/// detail. In version 2, whose full meshes pack several to a page, the tree at η = 0 read
/// no fewer pages than the naive list on this city.
fn city() -> common::City {
    common::city(
        400,
        9,
        &BuildOptions {
            page_size: 1024,
            visibility: Some(VisibilityOptions {
                resolution: 16,
                ..Default::default()
            }),
            hdov: Some(HdovOptions::default()),
            codec: flaneur::scene::MeshCodec::Raw,
            ..Default::default()
        },
    )
}

const ETAS: [f32; 3] = [0.0, 0.002, 0.05];

#[test]
fn hdov_search_reads_less_as_eta_grows_and_beats_the_naive_total() {
    let city = city();
    let db = Database::open(&city.db).unwrap();
    let cfg = HdovSearchConfig {
        queries: 300,
        load_queries: 30,
        etas: ETAS.to_vec(),
        seed: 4,
    };
    let mut ticks = 0;
    let r = hdov_search::run(&db, &cfg, |_, _| ticks += 1).unwrap();
    assert_eq!(r.rows.len(), 4 * ETAS.len());
    assert_eq!(ticks, r.rows.len());
    let of = |m: &str| -> Vec<&HdovSearchRow> { r.rows.iter().filter(|x| x.method == m).collect() };
    let naive = of("naive");
    assert!(naive
        .windows(2)
        .all(|w| w[0].search_pages == w[1].search_pages));
    for scheme in ["horizontal", "vertical", "indexed"] {
        let rows = of(scheme);
        assert_eq!(rows.len(), ETAS.len());
        // η = 0 finds every object of the PVS, and nothing at an internal LOD.
        assert_eq!(rows[0].internal, 0.0);
        assert!(
            (rows[0].objects - naive[0].objects).abs() < 1e-9,
            "{scheme}"
        );
        // The search falls (or stays) as η grows, and stops somewhere. The total need
        // not fall at every step: a node's internal LOD stands for all its objects, the
        // hidden ones too, and may take more pages than its few visible objects at their
        // coarse levels; over the sweep it falls.
        for w in rows.windows(2) {
            assert!(w[1].search_pages <= w[0].search_pages, "{scheme}: {w:?}");
        }
        assert!(
            rows[2].total_pages < rows[0].total_pages,
            "{scheme}: {rows:?}"
        );
        assert!(rows[2].internal > 0.0, "{scheme}: {:?}", rows[2]);
        // Objects barely seen come at coarse levels: fewer pages than the naive method
        // reading every object at full detail, at any η.
        assert!(rows[0].total_pages < naive[0].total_pages, "{scheme}");
        // A tree costs more to search than a list to read (Fig. 5.22b).
        assert!(rows[0].search_pages > naive[0].search_pages, "{scheme}");
    }
    let dir = tempfile::tempdir().unwrap();
    r.plot(dir.path()).unwrap();
    for f in [PLOT_TOTAL, PLOT_SEARCH] {
        let b = std::fs::read(dir.path().join(f)).unwrap();
        assert!(b.starts_with(b"\x89PNG\r\n\x1a\n"), "{f}");
    }
    assert_eq!(r.to_csv().lines().count(), 1 + r.rows.len());
    assert!(r.markdown().contains("| 0.002 |"));
}

#[test]
fn the_command_writes_its_report_and_refuses_a_database_without_the_tree() {
    let city = city();
    let out = tempfile::tempdir().unwrap();
    let run = |db: &std::path::Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
            .args(["bench", "hdov-search"])
            .arg(db)
            .args([
                "--queries",
                "40",
                "--load-queries",
                "5",
                "--etas",
                "0,0.01",
                "--out",
            ])
            .arg(out.path())
            .output()
            .unwrap()
    };
    let done = run(&city.db);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    for f in ["hdov-search.csv", "hdov-search.md", PLOT_TOTAL, PLOT_SEARCH] {
        assert!(out.path().join(f).exists(), "{f}");
    }
    let plain = common::city(20, 1, &BuildOptions::default());
    let refused = run(&plain.db);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("no HDoV-tree"), "{err}");
}

#[test]
fn hdov_cache_policies_stay_at_or_below_belady() {
    let city = city();
    let db = Database::open(&city.db).unwrap();
    let nodes = db.hdov().unwrap().unwrap().nodes as usize;
    assert!(nodes > 10, "{nodes} nodes");
    let cfg = HdovCacheConfig {
        queries: 300,
        etas: vec![1e-4],
        sizes: vec![2, 5, nodes],
        ..Default::default()
    };
    let r = hdov_cache::run(&db, &cfg, |_, _| {}).unwrap();
    // Two query sets × one η × three sizes × (three policies and Belady).
    assert_eq!(r.rows.len(), 2 * 3 * 4);
    for set in ["continuous", "random"] {
        for size in &cfg.sizes {
            let at: Vec<_> = r
                .rows
                .iter()
                .filter(|x| x.queries == set && x.size == *size)
                .collect();
            let belady = at.iter().find(|x| x.policy == "belady").unwrap().hit_rate;
            for x in &at {
                assert!(
                    x.hit_rate <= belady + 1e-12,
                    "{x:?} above Belady's {belady}"
                );
                assert!(
                    x.working_set <= nodes && x.accesses > x.working_set,
                    "{x:?}"
                );
            }
            // A cache holding the whole tree misses only each node's first access.
            if *size == nodes {
                for x in &at {
                    let ceiling = 1.0 - x.working_set as f64 / x.accesses as f64;
                    assert!((x.hit_rate - ceiling).abs() < 1e-9, "{x:?}");
                }
            }
        }
    }
    // Continuous queries revisit the same nodes more than random ones.
    let rate = |set: &str| {
        r.rows
            .iter()
            .find(|x| x.queries == set && x.size == 5 && x.policy == "lru")
            .unwrap()
            .hit_rate
    };
    assert!(
        rate("continuous") >= rate("random"),
        "{} < {}",
        rate("continuous"),
        rate("random")
    );
    let dir = tempfile::tempdir().unwrap();
    r.plot(dir.path()).unwrap();
    assert!(dir.path().join(hdov_cache::plot_file("random")).exists());
    assert!(r.markdown().contains("## continuous queries"));
}

#[test]
fn hdov_storage_reads_each_scheme_and_its_estimate() {
    let city = city();
    let db = Database::open(&city.db).unwrap();
    let fanout = db.hdov_head().unwrap().fanout;
    let r = flaneur_bench::hdov_storage::run(&db, &[4, fanout]).unwrap();
    assert_eq!(r.rows.len(), 3);
    // Sized at the tree's own fan-out, each scheme is what the build stored, and the
    // visible nodes are the same; a smaller fan-out makes more nodes.
    let own = &r.fanouts[1];
    assert_eq!((own.nodes, own.visible_nodes), (r.nodes, r.visible_nodes));
    for row in &r.rows {
        let sized = own.schemes.iter().find(|s| s.0 == row.scheme).unwrap().1;
        assert_eq!(sized, row.estimate_bytes, "{row:?}");
    }
    assert!(r.fanouts[0].nodes > own.nodes && r.fanouts[0].visible_nodes > own.visible_nodes);
    assert!(r.markdown().contains("## At other fan-outs"));
    assert_eq!(r.extra_csvs()[0].1.lines().count(), 3);
    for row in &r.rows {
        // Each scheme is its estimate plus a 44-byte head (and the indexed scheme's
        // directory of 12 bytes a cell).
        let extra = row.bytes - row.estimate_bytes;
        assert!(extra == 44 || extra == 44 + 12 * r.cells as u64, "{row:?}");
    }
    assert_eq!(r.rows[0].share_of_horizontal, 1.0);
    assert!(r.visible_share > 0.0 && r.visible_share <= 1.0);
    assert!(r.markdown().contains("| indexed |"), "{}", r.markdown());
    assert_eq!(r.to_csv().lines().count(), 4);
}

#[test]
fn a_tree_built_at_a_fanout_packs_that_many_and_refuses_more_than_a_page_holds() {
    let opts = |fanout| BuildOptions {
        page_size: 1024,
        visibility: Some(VisibilityOptions {
            resolution: 16,
            ..Default::default()
        }),
        hdov: Some(HdovOptions {
            fanout: Some(fanout),
            ..Default::default()
        }),
        ..Default::default()
    };
    let city = common::city(120, 9, &opts(5));
    let db = Database::open(&city.db).unwrap();
    let head = db.hdov_head().unwrap();
    // 120 objects in leaves of 5, and V-pages of 5 entries.
    assert_eq!((head.fanout, head.vpage_len), (5, 40));
    assert!(head.nodes >= 24 + 5 + 1, "{}", head.nodes);
    let sized = db.hdov_sizes_at(5).unwrap();
    assert_eq!(
        (sized.nodes, sized.visible_nodes),
        (head.nodes, head.visible_nodes)
    );
    // A 1 KiB page holds 17 entries: 18 is refused by name, before any work.
    let dir = tempfile::tempdir().unwrap();
    let err = flaneur::build_from_scene(&city.scene, &dir.path().join("x.flaneur"), &opts(18))
        .unwrap_err()
        .to_string();
    assert!(err.contains("--hdov-fanout") && err.contains("17"), "{err}");
}

#[test]
fn hdov_scaling_searches_each_city_of_the_series_against_the_naive_list() {
    use flaneur_bench::hdov_scaling::{self, HdovScalingConfig};
    let dir = tempfile::tempdir().unwrap();
    let cfg = HdovScalingConfig {
        sizes: vec![60, 240],
        page_size: 1024,
        resolution: 8,
        search: HdovSearchConfig {
            queries: 40,
            load_queries: 4,
            etas: vec![0.0, 0.01],
            seed: 2,
        },
        ..Default::default()
    };
    let mut ticks = 0;
    let r = hdov_scaling::run(dir.path(), &cfg, |_, _| ticks += 1).unwrap();
    assert_eq!(ticks, 2);
    // Per city: the naive list and the smallest scheme, at each η.
    assert_eq!(r.rows.len(), 2 * 2 * 2);
    let nodes = |n: u64| {
        r.rows
            .iter()
            .find(|x| x.objects == n && x.method != "naive")
            .unwrap()
            .nodes
    };
    assert!(nodes(240) > nodes(60), "a larger city, a larger tree");
    assert!(r
        .rows
        .iter()
        .all(|x| x.search_pages > 0.0 && x.total_pages > 0.0));
    // A second run finds the cities built.
    let again = hdov_scaling::run(dir.path(), &cfg, |_, _| {}).unwrap();
    assert_eq!(again.rows.len(), r.rows.len());
    assert!(r.markdown().contains("Fig. 5.23"));
}
