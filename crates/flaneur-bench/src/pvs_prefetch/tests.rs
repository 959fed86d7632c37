// The experiment's own checks: a small run writes every figure, bad settings are named,
// and the thesis's columns are Table 7.2's.
use super::*;

fn small() -> PvsPrefetchConfig {
    PvsPrefetchConfig {
        city: SyntheticConfig {
            blocks: 10,
            ..Default::default()
        },
        route: RouteConfig {
            steps: 400,
            ..Default::default()
        },
        borders: vec![0.1, 0.25, 0.5],
        latencies: vec![0, 5],
        ..Default::default()
    }
}

#[test]
fn small_run_writes_every_figure() {
    let r = run(&small()).unwrap();
    assert_eq!(r.routes.len(), 2);
    assert_eq!(r.sweep.len(), 6);
    for route in &r.routes {
        assert_eq!(route.positions.len(), 401);
        assert!(route.pbnp.totals.swaps <= route.snp.totals.swaps);
        assert_eq!(route.snp.totals.visual_misses, 0);
    }
    // A 2 m band is narrower than a 4 m step: PBNP is sometimes late.
    let narrow: usize = r
        .sweep
        .iter()
        .filter(|w| w.border == 0.1)
        .map(|w| w.totals.visual_misses)
        .sum();
    assert!(narrow > 0);
    assert_eq!(r.to_csv().lines().count(), 5);
    assert_eq!(r.steps_csv().lines().count(), 402);
    assert_eq!(r.regions_csv().lines().count(), 7);
    assert_eq!(r.routes_csv().lines().count(), 402);
    // Two routes × two latencies × three algorithms, and a header.
    assert_eq!(r.latency.len(), 12);
    assert_eq!(r.latency_csv().lines().count(), 13);
    for route in &r.routes {
        let snp = r.at_latency(route.route, 0, "SNP").unwrap();
        assert_eq!(snp, &route.snp.totals);
        let late = r.at_latency(route.route, 5, "PBNP").unwrap();
        assert!(late.visual_misses > 0);
    }
    let md = r.markdown();
    for word in [
        "Table 7.2",
        "585",
        "1785",
        "876",
        "route 2 PBNP",
        "| 0.25 | 5 |",
        "Under latency",
        "LANP misses (steps)",
    ] {
        assert!(md.contains(word), "{word} missing from\n{md}");
    }
    let dir = tempfile::tempdir().unwrap();
    r.plot(dir.path()).unwrap();
    for route in [1, 2] {
        for alg in ["SNP", "PBNP"] {
            assert!(dir.path().join(steps_plot(route, alg)).exists());
        }
        assert!(dir.path().join(cumulative_plot(route)).exists());
    }
    for f in [
        ROUTES_PLOT,
        REGIONS_PLOT,
        MISSES_PLOT,
        LATENCY_MISSES_PLOT,
        LATENCY_SWAPS_PLOT,
    ] {
        assert!(dir.path().join(f).exists(), "{f}");
    }
}

#[test]
fn bad_settings_are_named() {
    let err = |f: fn(&mut PvsPrefetchConfig)| {
        let mut c = small();
        f(&mut c);
        run(&c).unwrap_err().to_string()
    };
    assert!(err(|c| c.border = 0.0).contains("region border"));
    assert!(err(|c| c.borders = vec![0.2, 0.8]).contains("region border"));
    assert!(err(|c| c.capacity = 4).contains("too small"));
    assert!(err(|c| c.route.steps = 0).contains("steps"));
    assert!(err(|c| c.city.cell = 0.0).contains("viewcell size"));
    assert!(err(|c| c.city.overlap = 1.0).contains("overlap"));
    assert!(err(|c| c.route.step = f64::NAN).contains("step length"));
    assert!(err(|c| c.latencies = vec![3, MAX_LATENCY + 1]).contains("latency"));
}

#[test]
fn thesis_columns_are_table_7_2() {
    assert_eq!(thesis(1, "SNP").unwrap().swaps, 1785);
    assert_eq!(thesis(2, "PBNP").unwrap().transactions, 600);
    assert_eq!(thesis(3, "SNP"), None);
}
