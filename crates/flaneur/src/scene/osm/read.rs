//! The three passes over a PBF extract that gather what the import needs and nothing
//! else: the building multipolygon relations (pass 1), the building ways and the ways
//! those relations name (pass 2), and the coordinates of the nodes all of them name
//! (pass 3). A PBF lists nodes, then ways, then relations, so a way's nodes and a
//! relation's ways are only known to be wanted after they have gone by; three passes
//! keep memory to the buildings' own nodes, however large the extract.

use std::collections::{HashMap, HashSet};
use std::io::{Read, Seek, SeekFrom};
use std::panic::{catch_unwind, AssertUnwindSafe};

use osmpbf::{BlobDecode, BlobReader, Element, RelMemberType};

/// The tags of a building the import reads, from a way or a relation.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct BuildingTags {
    pub height: Option<String>,
    pub min_height: Option<String>,
    pub levels: Option<String>,
    pub min_level: Option<String>,
    pub roof_shape: Option<String>,
}

impl BuildingTags {
    /// The building tags of an element, or `None` when it is not a building: `building`
    /// present and not `no`. A `building:part` alone is a piece of a building drawn
    /// inside its outline, not a building.
    fn of<'a>(tags: impl Iterator<Item = (&'a str, &'a str)>) -> Option<BuildingTags> {
        let mut building = false;
        let mut t = BuildingTags::default();
        for (k, v) in tags {
            match k {
                "building" => building = v != "no",
                "height" => t.height = Some(v.to_string()),
                "min_height" => t.min_height = Some(v.to_string()),
                "building:levels" => t.levels = Some(v.to_string()),
                "building:min_level" => t.min_level = Some(v.to_string()),
                "roof:shape" => t.roof_shape = Some(v.to_string()),
                _ => {}
            }
        }
        building.then_some(t)
    }
}

/// A way tagged as a building: its nodes in order.
#[derive(Clone, Debug)]
pub(super) struct BuildingWay {
    pub id: i64,
    pub nodes: Vec<i64>,
    pub tags: BuildingTags,
}

/// A multipolygon relation tagged as a building: its member ways by role.
#[derive(Clone, Debug)]
pub(super) struct BuildingRelation {
    pub id: i64,
    pub outer: Vec<i64>,
    pub inner: Vec<i64>,
    pub tags: BuildingTags,
}

/// Everything the import takes from an extract.
#[derive(Debug, Default)]
pub(super) struct Gathered {
    pub ways: Vec<BuildingWay>,
    pub relations: Vec<BuildingRelation>,
    /// The nodes of the relations' member ways, by way id (building ways among them).
    pub member_ways: HashMap<i64, Vec<i64>>,
    /// Latitude and longitude in degrees, of every node the buildings name that the
    /// extract holds.
    pub nodes: HashMap<i64, (f64, f64)>,
}

/// Reads the extract three times through `open`, which makes a fresh reader of it.
pub(super) fn gather<R: Read + Seek + Send>(
    open: &dyn Fn() -> Result<BlobReader<R>, String>,
) -> Result<Gathered, String> {
    let mut g = Gathered::default();
    // Pass 1: building multipolygons.
    let mut wanted_ways = HashSet::new();
    each(open()?, |e| {
        if let Element::Relation(r) = e {
            let mut multipolygon = false;
            let tags = BuildingTags::of(r.tags().inspect(|&(k, v)| {
                multipolygon |= k == "type" && v == "multipolygon";
            }));
            let (Some(tags), true) = (tags, multipolygon) else {
                return;
            };
            let (mut outer, mut inner) = (Vec::new(), Vec::new());
            for m in r.members() {
                if m.member_type != RelMemberType::Way {
                    continue;
                }
                // An empty role is the old style's outer ring.
                match m.role() {
                    Ok("inner") => inner.push(m.member_id),
                    Ok("outer" | "") => outer.push(m.member_id),
                    _ => continue,
                }
                wanted_ways.insert(m.member_id);
            }
            g.relations.push(BuildingRelation {
                id: r.id(),
                outer,
                inner,
                tags,
            });
        }
    })?;
    // Pass 2: building ways, and the relations' member ways.
    let mut wanted_nodes = HashSet::new();
    each(open()?, |e| {
        if let Element::Way(w) = e {
            let tags = BuildingTags::of(w.tags());
            let member = wanted_ways.contains(&w.id());
            if tags.is_none() && !member {
                return;
            }
            let nodes: Vec<i64> = w.refs().collect();
            wanted_nodes.extend(nodes.iter().copied());
            if member {
                g.member_ways.insert(w.id(), nodes.clone());
            }
            if let Some(tags) = tags {
                g.ways.push(BuildingWay {
                    id: w.id(),
                    nodes,
                    tags,
                });
            }
        }
    })?;
    // Pass 3: the nodes named.
    each(open()?, |e| {
        let (id, lat, lon) = match e {
            Element::Node(n) => (n.id(), n.lat(), n.lon()),
            Element::DenseNode(n) => (n.id(), n.lat(), n.lon()),
            _ => return,
        };
        if wanted_nodes.contains(&id) {
            g.nodes.insert(id, (lat, lon));
        }
    })?;
    Ok(g)
}

/// Runs `f` over every element of one reader, and checks that the file ends where its
/// last blob does.
///
/// osmpbf 0.3 takes one to three bytes after the last blob for the end of the file, so a
/// file cut inside a blob's length would read as a shorter extract: the end is checked
/// here. And it unwraps a relation member's type, so a member type the format does not
/// define panics inside the reader: that is malformed input, reported as such.
fn each<R: Read + Seek + Send>(
    mut reader: BlobReader<R>,
    mut f: impl FnMut(Element<'_>),
) -> Result<(), String> {
    let bad = |e: osmpbf::Error| format!("not a readable OSM PBF file: {e}");
    let mut read = || -> Result<(), String> {
        let mut end = 0;
        while let Some(blob) = reader.next() {
            let blob = blob.map_err(bad)?;
            end = reader.seek_raw(SeekFrom::Current(0)).map_err(bad)?;
            if let BlobDecode::OsmData(block) = blob.decode().map_err(bad)? {
                block.for_each_element(&mut f);
            }
        }
        let len = reader.seek_raw(SeekFrom::End(0)).map_err(bad)?;
        if end != len {
            return Err(format!(
                "not a readable OSM PBF file: {} bytes after its last whole blob, which ends at byte {end} (a cut or damaged file)",
                len - end
            ));
        }
        Ok(())
    };
    match catch_unwind(AssertUnwindSafe(&mut read)) {
        Ok(done) => done,
        Err(_) => {
            Err("not a readable OSM PBF file: the PBF reader failed on malformed data".into())
        }
    }
}
