//! A series of generated cities of growing size, for the experiments that scale with the
//! database (Shou 2002 Fig. 4.22). Each city is made by citygen with its default layout
//! (the demo's city, only the object count and the seed set) and built into a database
//! in one folder, where a later run finds and reuses it: building is the slow part, and
//! the same seed gives the same city.
//!
//! A database is named after what determines it — objects, seed, page size, and for a
//! series with the HDoV-tree the DoV resolution — so a file of another series is never
//! taken for this one. Its scene file is written beside it, built from, and deleted: the
//! database holds everything the experiments need.
//!
//! Two kinds of series ([`SeriesKind`]): plain cities without LODs, for the walks that
//! read index and mesh pages only; and cities with LODs, visibility and the HDoV-tree
//! (every scheme), for the HDoV-tree's scaling (Fig. 5.23).

use std::path::{Path, PathBuf};

use flaneur::build::{build_from_scene, BuildOptions};
use flaneur::database::Database;
use flaneur::error::{Error, Result};

/// One city of the series.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SeriesCity {
    /// Objects in the city.
    pub objects: u64,
    /// Its database file.
    pub path: PathBuf,
    /// Whether this call generated and built it (false: reused).
    pub built: bool,
}

/// What a series' databases hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeriesKind {
    /// Meshes and the R-tree, no LODs.
    Plain,
    /// LODs, visibility with DoV at this resolution, and the HDoV-tree.
    Hdov {
        /// The DoV's cube-map resolution.
        resolution: u32,
    },
}

/// The database file of the city of `objects` objects, generated from `seed`, with pages
/// of `page_size` bytes, in `dir`.
pub fn city_path(dir: &Path, objects: u64, seed: u64, page_size: usize) -> PathBuf {
    city_path_of(dir, objects, seed, page_size, SeriesKind::Plain)
}

/// [`city_path`] for a series of `kind`.
pub fn city_path_of(
    dir: &Path,
    objects: u64,
    seed: u64,
    page_size: usize,
    kind: SeriesKind,
) -> PathBuf {
    match kind {
        SeriesKind::Plain => dir.join(format!("city-{objects}-seed{seed}-{page_size}B.flaneur")),
        SeriesKind::Hdov { resolution } => dir.join(format!(
            "city-{objects}-seed{seed}-{page_size}B-hdov{resolution}.flaneur"
        )),
    }
}

/// Makes sure that `dir` holds a database of each size in `sizes` (generating and
/// building the missing ones, in the order given) and returns them in that order;
/// `progress(size, built)` is told after each.
///
/// A database already there is reused if it opens and holds the expected number of
/// objects with the expected page size; otherwise this is an error naming the file, to
/// be deleted by hand, rather than a silent rebuild.
pub fn ensure(
    dir: &Path,
    sizes: &[u64],
    seed: u64,
    page_size: usize,
    progress: impl FnMut(u64, bool),
) -> Result<Vec<SeriesCity>> {
    ensure_of(dir, sizes, seed, page_size, SeriesKind::Plain, progress)
}

/// [`ensure`] for a series of `kind`.
pub fn ensure_of(
    dir: &Path,
    sizes: &[u64],
    seed: u64,
    page_size: usize,
    kind: SeriesKind,
    mut progress: impl FnMut(u64, bool),
) -> Result<Vec<SeriesCity>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let mut cities = Vec::with_capacity(sizes.len());
    for &objects in sizes {
        let path = city_path_of(dir, objects, seed, page_size, kind);
        let built = !path.exists();
        if built {
            build(dir, &path, objects, seed, page_size, kind)?;
        }
        check(&path, objects, page_size)?;
        progress(objects, built);
        cities.push(SeriesCity {
            objects,
            path,
            built,
        });
    }
    Ok(cities)
}

fn build(
    dir: &Path,
    db: &Path,
    objects: u64,
    seed: u64,
    page_size: usize,
    kind: SeriesKind,
) -> Result<()> {
    let scene = dir.join(format!("city-{objects}-seed{seed}.scene"));
    let city = citygen::CityConfig {
        objects,
        seed,
        ..Default::default()
    };
    citygen::write_city(&city, &scene)?;
    let opts = match kind {
        SeriesKind::Plain => BuildOptions {
            page_size,
            // The search-time walks read index and mesh pages only.
            lod: None,
            ..Default::default()
        },
        SeriesKind::Hdov { resolution } => BuildOptions {
            page_size,
            visibility: Some(flaneur::visibility::VisibilityOptions {
                resolution,
                ..Default::default()
            }),
            hdov: Some(flaneur::hdov::HdovOptions::default()),
            ..Default::default()
        },
    };
    let built = build_from_scene(&scene, db, &opts);
    // The scene is as large as the database and no longer needed, built or not.
    let removed = std::fs::remove_file(&scene).map_err(|e| Error::io(&scene, e));
    built?;
    removed
}

fn check(path: &Path, objects: u64, page_size: usize) -> Result<()> {
    let db = Database::open(path)?;
    let (found, page) = (db.objects(), db.store().page_size());
    if found != objects || page != page_size {
        return Err(Error::BadInput {
            path: path.to_path_buf(),
            what: format!(
                "expected a city of {objects} objects in {page_size}-byte pages, found {found} objects in {page}-byte pages; \
                 delete it to rebuild"
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_once_then_reuses() {
        let dir = tempfile::tempdir().unwrap();
        let mut told = Vec::new();
        let first = ensure(dir.path(), &[120, 60], 3, 1024, |n, b| told.push((n, b))).unwrap();
        assert_eq!(told, [(120, true), (60, true)]);
        assert!(first.iter().all(|c| c.built && c.path.exists()));
        assert_eq!(Database::open(&first[1].path).unwrap().objects(), 60);
        // Only the databases are left.
        let files = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(files, 2);

        let again = ensure(dir.path(), &[60], 3, 1024, |_, _| {}).unwrap();
        assert!(!again[0].built);
        assert_eq!(again[0].path, first[1].path);

        // A file under the name of another city is an error, not a silent rebuild.
        std::fs::copy(&first[0].path, city_path(dir.path(), 90, 3, 1024)).unwrap();
        let err = ensure(dir.path(), &[90], 3, 1024, |_, _| {}).unwrap_err();
        assert!(
            err.to_string().contains("expected a city of 90 objects"),
            "{err}"
        );
    }
}
