//! The thesis's two routes over its synthetic city: they keep to its walkways, and
//! route 2 is seven lines with six right angles. Here rather than beside the routes in
//! `flaneur::prefetch::pvs::routes`, because the city is the experiment's.

use flaneur::prefetch::pvs::routes::{
    random_route, straight_route, RouteConfig, THESIS_STEP, THESIS_STEPS,
};
use flaneur::prefetch::pvs::Position;

use super::{SyntheticCity, SyntheticConfig};

fn city() -> SyntheticCity {
    SyntheticCity::generate(&SyntheticConfig::default()).unwrap()
}

#[test]
fn route_1_walks_4_m_steps_on_the_streets() {
    let c = city();
    let start = c.intersection(15, 15);
    let walk = |cfg: &RouteConfig| random_route(start, cfg, |p| Ok(c.on_walkway(p)));
    let r = walk(&RouteConfig::default()).unwrap();
    assert_eq!(r.len(), THESIS_STEPS + 1);
    assert_eq!(r[0], start);
    assert!(r.iter().all(|&p| c.on_walkway(p) && c.is_street(p)));
    assert!(r
        .windows(2)
        .all(|w| (w[0].distance(w[1]) - THESIS_STEP).abs() < 1e-9));
    // Back and forth: many steps go straight back the way the last one came.
    let back = r.windows(3).filter(|w| w[0].distance(w[2]) < 1e-9).count();
    assert!(back > 20, "{back} reversals");
    assert_eq!(r, walk(&RouteConfig::default()).unwrap());
    assert_ne!(
        r,
        walk(&RouteConfig {
            seed: 2,
            ..Default::default()
        })
        .unwrap()
    );
}

#[test]
fn route_2_is_seven_lines_with_six_right_angles() {
    let c = city();
    for seed in 1..=5 {
        let r = straight_route(
            &c.street_grid(),
            &RouteConfig {
                seed,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(r.corners.len(), 8);
        assert_eq!(r.positions.len(), THESIS_STEPS + 1);
        assert_eq!(r.positions[0], r.corners[0]);
        let d: Vec<(f64, f64)> = r
            .corners
            .windows(2)
            .map(|w| (w[1].x - w[0].x, w[1].z - w[0].z))
            .collect();
        for (i, &(dx, dz)) in d.iter().enumerate() {
            assert!(
                (dx == 0.0) != (dz == 0.0),
                "line {i} is not straight along an axis"
            );
            if i > 0 {
                let (px, pz) = d[i - 1];
                assert!(px * dx + pz * dz == 0.0, "turn {i} is not a right angle");
            }
        }
        let length: f64 = d.iter().map(|(x, z)| x.hypot(*z)).sum();
        assert!((length - THESIS_STEPS as f64 * THESIS_STEP).abs() < 1e-6);
        assert!(r.positions.iter().all(|&p| c.on_walkway(p)), "seed {seed}");
        // Steps of 4 m, but those that cut a corner.
        let short = r
            .positions
            .windows(2)
            .filter(|w| (w[0].distance(w[1]) - THESIS_STEP).abs() > 1e-6)
            .count();
        assert!(short <= 6, "{short}");
        assert!(r
            .positions
            .windows(2)
            .all(|w| w[0].distance(w[1]) <= THESIS_STEP + 1e-9));
    }
}

#[test]
fn bad_routes_are_errors() {
    let c = SyntheticCity::generate(&SyntheticConfig {
        blocks: 2,
        ..Default::default()
    })
    .unwrap();
    let on = |p: Position| Ok(c.on_walkway(p));
    let e = random_route(Position::new(110.0, 110.0), &RouteConfig::default(), on)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a walkable position"), "{e}");
    let e = random_route(Position::new(f64::NAN, 30.0), &RouteConfig::default(), on)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a walkable position"), "{e}");
    let e = straight_route(&c.street_grid(), &RouteConfig::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("does not fit"), "{e}");
    for cfg in [
        RouteConfig {
            steps: 0,
            ..Default::default()
        },
        RouteConfig {
            step: 0.0,
            ..Default::default()
        },
        RouteConfig {
            step: f64::NAN,
            ..Default::default()
        },
    ] {
        assert!(random_route(c.intersection(0, 0), &cfg, on).is_err());
        assert!(straight_route(&c.street_grid(), &cfg).is_err());
    }
}
