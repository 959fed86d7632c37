//! DoV micro benches (Shou 2002, §5.5.2), the ray-cast reference beside the rasterised
//! item buffers on the same viewpoints: one viewpoint's cubic projection at N = 256
//! (393,216 pixels) from street height in a 400-object generated city, reported as
//! pixels (rays) per second; and a 2×2 grid of 3 m viewcells (18 distinct corners).
//! Before the timed runs it prints one pass of each over the 36 street cells nearest the
//! centre, whose shared corners bring the cost under 8 corners per cell: seconds per cell
//! as a precomputation would see them, each scene's build time, and how far the raster's
//! DoVs are from the reference's (per cell, the sum over objects of the absolute
//! differences, as a share of the sphere).

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use flaneur::geom::Aabb;
use flaneur::visibility::{cell_dovs, CellDovs, CubicProjection, DovSource, RasterScene, RayScene};

const OBJECTS: u64 = 400;

struct Fixture {
    scene: RayScene,
    raster: RasterScene,
    /// An eye-height point in a street, 3 m from every building, near the city's centre.
    eye: [f32; 3],
    /// The 36 street cells nearest the centre: 4 m squares of a city-wide grid, eye height
    /// 1.2–2.0 m, whose corners are all at least 1 m from every building's box.
    cells: Vec<Aabb>,
}

fn fixture() -> Fixture {
    let config = citygen::CityConfig {
        objects: OBJECTS,
        landmarks: 0.0,
        ..Default::default()
    };
    let objects: Vec<citygen::SceneObject> = (0..OBJECTS)
        .map(|id| citygen::object(&config, id).unwrap())
        .collect();
    let scene = RayScene::new(objects.iter().map(|o| (o.id, &o.mesh))).unwrap();
    let raster = RasterScene::new(objects.iter().map(|o| (o.id, &o.mesh))).unwrap();
    let boxes: Vec<([f32; 3], [f32; 3])> = objects.iter().map(|o| o.mesh.bounds()).collect();
    let (lo, hi) = boxes
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(l, h), (a, b)| {
            (
                std::array::from_fn(|k| l[k].min(a[k])),
                std::array::from_fn(|k| h[k].max(b[k])),
            )
        });
    let free = |x: f32, z: f32, clear: f32| {
        boxes.iter().all(|(a, b)| {
            x < a[0] - clear || x > b[0] + clear || z < a[2] - clear || z > b[2] + clear
        })
    };
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[2] + hi[2]) / 2.0];
    let from_centre = |x: f32, z: f32| (x - centre[0]).powi(2) + (z - centre[1]).powi(2);
    let (mut points, mut cells) = (Vec::new(), Vec::new());
    let (i0, i1) = ((lo[0] / 4.0).floor() as i32, (hi[0] / 4.0).ceil() as i32);
    let (j0, j1) = ((lo[2] / 4.0).floor() as i32, (hi[2] / 4.0).ceil() as i32);
    for i in i0..i1 {
        for j in j0..j1 {
            let (x, z) = (i as f32 * 4.0, j as f32 * 4.0);
            if free(x, z, 3.0) {
                points.push([x, 1.7, z]);
            }
            let square = [(x, z), (x + 4.0, z), (x, z + 4.0), (x + 4.0, z + 4.0)];
            if square.iter().all(|&(x, z)| free(x, z, 1.0)) {
                cells.push(Aabb::new([x, 1.2, z], [x + 4.0, 2.0, z + 4.0]).unwrap());
            }
        }
    }
    let eye = *points
        .iter()
        .min_by(|p, q| from_centre(p[0], p[2]).total_cmp(&from_centre(q[0], q[2])))
        .expect("a city has streets");
    cells.sort_by(|a, b| from_centre(a.min.x, a.min.z).total_cmp(&from_centre(b.min.x, b.min.z)));
    cells.truncate(36);
    Fixture {
        scene,
        raster,
        eye,
        cells,
    }
}

/// Per cell, the sum over objects of the absolute difference of two runs' DoVs.
fn differences(a: &CellDovs, b: &CellDovs) -> Vec<f64> {
    a.cells
        .iter()
        .zip(&b.cells)
        .map(|(x, y)| {
            let mut all: Vec<(u32, f64)> = x.iter().map(|&(o, d)| (o, d as f64)).collect();
            all.extend(y.iter().map(|&(o, d)| (o, -(d as f64))));
            all.sort_unstable_by_key(|p| p.0);
            all.chunk_by(|p, q| p.0 == q.0)
                .map(|same| same.iter().map(|p| p.1).sum::<f64>().abs())
                .sum()
        })
        .collect()
}

/// A 2×2 grid of `size`-metre cells, eye height 1.2–2.0 m, centred on `p`.
fn grid(p: [f32; 3], size: f32) -> Vec<Aabb> {
    (0..4)
        .map(|c| {
            let x = p[0] + size * ((c % 2) as f32 - 1.0);
            let z = p[2] + size * ((c / 2) as f32 - 1.0);
            Aabb::new([x, 1.2, z], [x + size, 2.0, z + size]).unwrap()
        })
        .collect()
}

fn benches(c: &mut Criterion) {
    let f = fixture();
    let cube = CubicProjection::default();
    let eye = f.eye;

    let reference = cell_dovs(&f.scene, &cube, &f.cells).unwrap();
    let drawn = cell_dovs(&f.raster, &cube, &f.cells).unwrap();
    let s = reference.stats;
    eprintln!(
        "dov: {} objects, {} triangles; {} street cells at N = {}: {} corners ({:.2} per cell), \
         on {} threads",
        f.scene.object_count(),
        f.scene.triangle_count(),
        s.cells,
        cube.resolution(),
        s.corners,
        s.corners_per_cell(),
        rayon::current_num_threads(),
    );
    for (name, built, run) in [
        ("ray-cast", f.scene.build_time(), &reference),
        ("raster", f.raster.build_time(), &drawn),
    ] {
        eprintln!(
            "dov: {name:>8}: scene built in {:.0} ms; {:.4} s per cell, {:.2} M pixels/s",
            built.as_secs_f64() * 1e3,
            run.stats.seconds_per_cell(),
            run.stats.rays_per_second() / 1e6,
        );
    }
    let diffs = differences(&reference, &drawn);
    eprintln!(
        "dov: raster against ray-cast, per cell the sum of |DoV difference|: mean {:.2e}, \
         largest {:.2e} (of the whole sphere, 1)",
        diffs.iter().sum::<f64>() / diffs.len().max(1) as f64,
        diffs.iter().copied().fold(0.0, f64::max),
    );

    let mut g = c.benchmark_group("dov");
    g.sample_size(10);
    g.throughput(Throughput::Elements(cube.rays_per_point()));
    for (name, scene) in [
        ("raycast", &f.scene as &dyn DovSource),
        ("raster", &f.raster as &dyn DovSource),
    ] {
        g.throughput(Throughput::Elements(cube.rays_per_point()));
        g.bench_function(format!("point_n256_{name}"), |b| {
            b.iter(|| black_box(scene.point_dov(&cube, eye).unwrap()))
        });
        let cells = grid(eye, 3.0);
        g.throughput(Throughput::Elements(18 * cube.rays_per_point()));
        g.bench_function(format!("cells_2x2_n256_{name}"), |b| {
            b.iter(|| black_box(cell_dovs(scene, &cube, &cells).unwrap()))
        });
    }
    g.finish();
}

criterion_group! {
    name = dov;
    config = Criterion::default().measurement_time(Duration::from_secs(5)).warm_up_time(Duration::from_secs(1));
    targets = benches
}
criterion_main!(dov);
