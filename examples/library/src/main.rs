use flaneur::{geom::Aabb, BuildOptions, Database, History};

fn main() -> flaneur::Result<()> {
    let dir = tempfile::tempdir().unwrap();
    let (scene, path) = (dir.path().join("city.scene"), dir.path().join("city.flaneur"));
    citygen::write_city(&citygen::CityConfig { objects: 300, ..Default::default() }, &scene)?;
    flaneur::build_from_scene(&scene, &path, &BuildOptions::default())?;

    let db = Database::open(&path)?;                    // read-only, mmap
    let first: Aabb = "0,0,0,120,50,120".parse()?;
    let all = db.range(&first)?;                        // BOX: every object in the cell
    let mut history = History::default();              // the cells already queried
    for cell in ["0,0,0,120,50,120", "40,0,0,160,50,120", "80,0,0,200,50,120"] {
        let new = db.csearch_step(&mut history, &cell.parse::<Aabb>()?)?;   // only what this cell adds
        for object in &new.objects {
            let mesh = db.mesh(object)?;                // its geometry, read from its extent
            assert!(mesh.triangle_count() > 0);
        }
        println!("{} new objects, {} index pages read", new.objects.len(), new.pages.len());
    }
    println!("{} pages read in all", db.io().page_reads);

    // The level a viewer 300 m away should see it at (τ 0.1 % of a 60° view), as a walk chooses it.
    let eye = all.objects[0].bounds.center() + flaneur::glam::Vec3::new(300.0, 0.0, 0.0);
    let seen = db.lod_level_for(&all.objects[0], eye, 60f32.to_radians(), 0.001)?;
    println!("level {} of {} triangles", seen.level, seen.triangles);

    let id = all.objects[0].id;
    if let Some(levels) = db.lod_levels(id)? {          // None: --no-lod, or inserted later
        let last = levels.last().expect("level 0 is always there");
        println!("{} levels, the coarsest {} triangles within {} m", levels.len(), last.triangles, last.error);
        let _coarse = db.lod_mesh(id, last.level)?;     // a page or two, not the whole mesh
    }
    if let Some((pm, dag)) = db.progressive(id)? {      // objects above the PM threshold
        let _refiner = flaneur::lod::Refiner::new(&pm, &dag)?;   // view-dependent refinement
    }
    Ok(())
}
