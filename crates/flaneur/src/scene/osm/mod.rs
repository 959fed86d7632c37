//! OpenStreetMap import (`.osm.pbf`, the `osmpbf` crate): one object per building, from
//! closed ways and multipolygon relations tagged `building`, holes kept.
//!
//! Each footprint is extruded from its base to its top (see `height`), with a flat roof;
//! a `roof:shape` other than flat is drawn flat and counted. Real extracts are messy, so
//! every building is repaired where that is safe (repeated nodes, stray inner rings,
//! unreadable heights) and skipped where it is not (nodes cut off by the extract's edge,
//! unclosed or crossing rings, no area), each counted by reason in [`OsmReport`].
//!
//! # Projection
//!
//! Coordinates are projected to metres by the equirectangular projection about the
//! centre of the buildings' nodes' bounds (latitude φ₀, longitude λ₀), on the sphere of
//! the Earth's mean radius R = 6,371,008.8 m: east = R·(λ − λ₀)·cos φ₀, north =
//! R·(φ − φ₀). East is +x, north is −z, up is +y. Distances north–south are true;
//! east–west ones are off by about tan φ₀ × Δφ (0.1 % at 5 km from the centre at 60°
//! north), which a city-sized extract can afford.

mod extrude;
mod height;
mod read;
mod report;
mod rings;

use std::collections::{HashMap, HashSet};
use std::io::Cursor;
use std::path::Path;

use osmpbf::BlobReader;

pub use report::{OsmReport, Repair, Skip};

use crate::error::{Error, Result};
use crate::scene::Mesh;
use read::{BuildingTags, Gathered};
use rings::{join_ways, place_ring, polygons, P2};

/// The Earth's mean radius in metres (IUGG).
const EARTH_RADIUS: f64 = 6_371_008.8;

/// How an OpenStreetMap import makes buildings of footprints.
///
/// ```
/// let opts = flaneur::scene::OsmOptions::default();
/// assert_eq!((opts.storey_height, opts.default_height), (3.0, 9.0));
/// assert!(opts.validate().is_ok());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct OsmOptions {
    /// Metres per storey, for `building:levels` and `building:min_level`.
    pub storey_height: f32,
    /// Metres of a building that has neither `height` nor `building:levels`.
    pub default_height: f32,
    /// Heights above this many metres are taken as mistakes (the tallest building is
    /// 828 m): the levels or the default are used instead.
    pub max_height: f32,
}

impl Default for OsmOptions {
    fn default() -> OsmOptions {
        OsmOptions {
            storey_height: 3.0,
            default_height: 9.0,
            max_height: 1000.0,
        }
    }
}

impl OsmOptions {
    /// Checks that every height is a positive number of metres and the default no more
    /// than the maximum; the error names the bad one.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("storey height", self.storey_height),
            ("default height", self.default_height),
            ("maximum height", self.max_height),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::Invalid(format!(
                    "OSM {name} {v} is not a positive number of metres"
                )));
            }
        }
        if self.default_height > self.max_height {
            return Err(Error::Invalid(format!(
                "OSM default height {} m is above the maximum {} m",
                self.default_height, self.max_height
            )));
        }
        Ok(())
    }
}

/// The buildings of an extract and what the import did.
#[derive(Clone, Debug, Default)]
pub struct OsmImport {
    /// One `(name, mesh)` per building: the name is its OpenStreetMap element, as
    /// `way/123` or `relation/45`; ways first, then relations, each in file order.
    pub objects: Vec<(String, Mesh)>,
    /// What was imported, repaired and skipped.
    pub report: OsmReport,
}

/// Imports the buildings of an `.osm.pbf` extract. A file that is not a readable PBF, or
/// one with no building left to import, is an error naming it.
///
/// ```no_run
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::scene::{load_osm, OsmOptions};
/// let city = load_osm("helsinki.osm.pbf".as_ref(), &OsmOptions::default())?;
/// println!("{} buildings, {} skipped", city.report.buildings(), city.report.skipped_total());
/// # Ok(()) }
/// ```
pub fn load_osm(path: &Path, opts: &OsmOptions) -> Result<OsmImport> {
    opts.validate()?;
    let bad = |what: String| Error::BadInput {
        path: path.to_path_buf(),
        what,
    };
    let open = || BlobReader::seekable_from_path(path).map_err(|e| format!("cannot read it: {e}"));
    let gathered = read::gather(&open).map_err(bad)?;
    let import = assemble(gathered, opts);
    if import.objects.is_empty() {
        return Err(bad(format!(
            "no building to import ({} skipped)",
            import.report.skipped_total()
        )));
    }
    Ok(import)
}

/// [`load_osm`] on the bytes of a PBF file; what the fuzz target drives. An extract
/// without buildings is an empty import here.
pub(crate) fn osm_from_bytes(
    bytes: &[u8],
    opts: &OsmOptions,
) -> std::result::Result<OsmImport, String> {
    let open = || {
        BlobReader::new_seekable(Cursor::new(bytes))
            .map_err(|e| format!("not a readable OSM PBF file: {e}"))
    };
    Ok(assemble(read::gather(&open)?, opts))
}

/// A building's rings as node ids: its outer rings, then its inner ones.
type NodeRings = (Vec<Vec<i64>>, Vec<Vec<i64>>);

/// Where the extract's nodes lie on the map, in metres, and which lie off the globe.
struct Map {
    at: HashMap<i64, P2>,
    off_globe: HashSet<i64>,
}

impl Map {
    /// One building's prism, adding what was repaired on the way to `repairs`, or why it
    /// is skipped.
    fn building(
        &self,
        (outer, inner): &NodeRings,
        tags: &BuildingTags,
        opts: &OsmOptions,
        repairs: &mut Vec<Repair>,
    ) -> std::result::Result<Mesh, Skip> {
        let mut nodes = outer.iter().chain(inner).flatten();
        if nodes.any(|n| self.off_globe.contains(n)) {
            return Err(Skip::BadCoordinates);
        }
        let mut place = |rings: &[Vec<i64>]| {
            rings
                .iter()
                .map(|r| place_ring(r, &self.at, repairs))
                .collect::<std::result::Result<Vec<_>, Skip>>()
        };
        let (outer, inner) = (place(outer)?, place(inner)?);
        let polys = polygons(outer, inner, repairs)?;
        let (base, top) = height::base_and_top(tags, opts, repairs)?;
        if tags.roof_shape.as_deref().is_some_and(|s| s != "flat") {
            repairs.push(Repair::RoofDrawnFlat);
        }
        extrude::extrude(&polys, base, top)
    }
}

/// A multipolygon's member ways joined into rings.
fn relation_rings(
    r: &read::BuildingRelation,
    ways: &HashMap<i64, Vec<i64>>,
) -> std::result::Result<NodeRings, Skip> {
    let members = |ids: &[i64]| {
        ids.iter()
            .map(|id| ways.get(id).cloned().ok_or(Skip::MissingWays))
            .collect::<std::result::Result<Vec<_>, Skip>>()
    };
    Ok((
        join_ways(members(&r.outer)?)?,
        join_ways(members(&r.inner)?)?,
    ))
}

/// The buildings of what was gathered, projected, repaired or skipped, and extruded.
fn assemble(g: Gathered, opts: &OsmOptions) -> OsmImport {
    let mut report = OsmReport::default();
    let (map, centre) = project(&g.nodes);
    report.centre = centre;
    // A building made, its repairs counted; or its skip counted.
    let mut made = |built: std::result::Result<Mesh, Skip>, repairs: &mut Vec<Repair>| match built {
        Ok(mesh) => {
            report.count_repairs(repairs);
            Some(mesh)
        }
        Err(why) => {
            report.skip(why);
            None
        }
    };
    let mut repairs = Vec::new();
    // Relations first, so that a way drawn by one is known; their objects go last.
    let mut drawn_by_relation = HashSet::new();
    let mut relations = Vec::new();
    for r in &g.relations {
        repairs.clear();
        let built = relation_rings(r, &g.member_ways)
            .and_then(|rings| map.building(&rings, &r.tags, opts, &mut repairs));
        if let Some(mesh) = made(built, &mut repairs) {
            drawn_by_relation.extend(r.outer.iter().copied());
            relations.push((format!("relation/{}", r.id), mesh));
        }
    }
    let mut objects = Vec::new();
    for w in &g.ways {
        repairs.clear();
        let built = if drawn_by_relation.contains(&w.id) {
            Err(Skip::DrawnByRelation)
        } else if w.nodes.len() < 2 || w.nodes.first() != w.nodes.last() {
            Err(Skip::Unclosed)
        } else {
            map.building(
                &(vec![w.nodes.clone()], Vec::new()),
                &w.tags,
                opts,
                &mut repairs,
            )
        };
        if let Some(mesh) = made(built, &mut repairs) {
            objects.push((format!("way/{}", w.id), mesh));
        }
    }
    report.from_ways = objects.len() as u64;
    report.from_relations = relations.len() as u64;
    objects.extend(relations);
    OsmImport { objects, report }
}

/// Every node on the map, and the centre (latitude, longitude) the projection is taken
/// about.
fn project(nodes: &HashMap<i64, (f64, f64)>) -> (Map, [f64; 2]) {
    let on_globe =
        |&(lat, lon): &(f64, f64)| (-90.0..=90.0).contains(&lat) && (-180.0..=180.0).contains(&lon);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for c in nodes.values().filter(|c| on_globe(c)) {
        lo = [lo[0].min(c.0), lo[1].min(c.1)];
        hi = [hi[0].max(c.0), hi[1].max(c.1)];
    }
    let centre = if lo[0].is_finite() {
        [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0]
    } else {
        [0.0; 2]
    };
    let (lat0, lon0) = (centre[0].to_radians(), centre[1].to_radians());
    let mut at = HashMap::with_capacity(nodes.len());
    let mut off_globe = HashSet::new();
    for (&id, c) in nodes {
        if on_globe(c) {
            let east = EARTH_RADIUS * (c.1.to_radians() - lon0) * lat0.cos();
            let north = EARTH_RADIUS * (c.0.to_radians() - lat0);
            at.insert(id, [east, north]);
        } else {
            off_globe.insert(id);
        }
    }
    (Map { at, off_globe }, centre)
}

/// A footprint (map metres; the outer ring counter-clockwise seen from above, holes
/// clockwise) extruded from the ground to `top` as the import draws a building: for
/// other modules' tests.
#[cfg(test)]
pub(crate) fn extruded(outer: Vec<[f64; 2]>, holes: Vec<Vec<[f64; 2]>>, top: f64) -> Mesh {
    extrude::extrude(&[rings::Polygon { outer, holes }], 0.0, top)
        .expect("a footprint that triangulates")
}
