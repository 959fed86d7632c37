//! Building the HDoV-tree at the end of `flaneur build --visibility --hdov …`, from what
//! the build has written: the objects' index entries, their stored LODs and the
//! visibility table (Shou 2002 Fig. 5.13).
//!
//! 1. **Pack.** The objects are packed by Sort-Tile-Recursive into nodes of the
//!    HDoV-node page's fan-out (the R-tree's packing; the tree has its own pages because
//!    its entries are wider), and numbered in depth-first preorder.
//! 2. **Internal LODs.** Bottom-up, a level at a time, every node's on all cores
//!    (`lods`); each parent entry gets its child's h, s and LOD chain.
//! 3. **Nodes.** Written back to back in preorder.
//! 4. **V-pages.** For every walkable viewcell, its PVS's DoVs summed up the tree
//!    (`vd`), then stored under each scheme asked for (`scheme`).

use std::collections::HashMap;
use std::time::Instant;

use rayon::prelude::*;

use super::lods::{aggregate, error_above, internal_levels, Reference, DIRECT_TRIANGLES};
use super::node::{capacity, ChildRef, HNode, HNodeKind};
use super::scheme::{self, Scheme, Shape};
use super::tree::{ProxyErrors, TreeHead, HDOV_SEGMENT};
use super::vd::{CellVd, Topology, VENTRY_LEN};
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::lod::stored::encode_chain_with;
use crate::lod::stored::{level_mesh, LodTable};
use crate::progress::{Progress, Step};
use crate::rtree::{str_tile, ObjectEntry};
use crate::scene::Mesh;
use crate::store::{Extent, PageKind, Segment, Store};
use crate::visibility::VisibilityTable;

/// How to build the HDoV-tree.
#[derive(Clone, Debug, PartialEq)]
pub struct HdovOptions {
    /// The storage schemes to write (at least one).
    pub schemes: Vec<Scheme>,
    /// Share of a node's fan-out that packing fills.
    pub fill: f32,
    /// Entries a node holds (M), from 2 up to what a page holds (72 in a 4 KiB page);
    /// `None`: what a page holds, times [`fill`](Self::fill). Eqs. 5.3–5.4 and the
    /// V-pages' size follow it: a V-page holds M V-entries.
    pub fanout: Option<u32>,
}

impl Default for HdovOptions {
    /// Every scheme, full nodes.
    fn default() -> HdovOptions {
        HdovOptions {
            schemes: Scheme::ALL.to_vec(),
            fill: 1.0,
            fanout: None,
        }
    }
}

impl HdovOptions {
    /// Checks the settings: at least one scheme, a fill factor in 0.1..=1.
    pub fn validate(&self) -> Result<()> {
        if self.schemes.is_empty() {
            return Err(Error::Invalid(
                "an HDoV-tree needs at least one storage scheme".into(),
            ));
        }
        if !(0.1..=1.0).contains(&self.fill) {
            return Err(Error::Invalid(format!(
                "HDoV fill factor {} is outside 0.1..=1",
                self.fill
            )));
        }
        if let Some(m) = self.fanout {
            if m < 2 {
                return Err(Error::Invalid(format!(
                    "HDoV fan-out {m} (--hdov-fanout) must be at least 2"
                )));
            }
        }
        Ok(())
    }

    /// The entries a node holds when a page's payload holds `max` of them: the fan-out
    /// asked for, or `max` times the fill. An error names a fan-out a page cannot hold.
    pub(crate) fn node_capacity(&self, max: usize, page_size: usize) -> Result<usize> {
        if max < 2 {
            return Err(Error::Invalid(format!(
                "page size {page_size} is too small for HDoV nodes"
            )));
        }
        match self.fanout {
            Some(m) if m as usize > max => Err(Error::Invalid(format!(
                "HDoV fan-out {m} (--hdov-fanout) is more than the {max} entries a node page \
                 of {page_size} bytes holds: choose at most {max}, or a larger --page-size"
            ))),
            Some(m) => Ok((m as usize).max(2)),
            None => Ok(((max as f32 * self.fill).floor() as usize).clamp(2, max)),
        }
    }
}

/// One scheme as stored, against its estimate (eqs. 5.7–5.9).
#[derive(Clone, Debug, serde::Serialize)]
pub struct SchemeReport {
    /// The scheme.
    pub scheme: Scheme,
    /// Bytes its extent takes, head included.
    pub bytes: u64,
    /// Pages of its extent.
    pub pages: u64,
    /// V-pages it stores.
    pub vpages: u64,
    /// What eqs. 5.7–5.9 estimate (its head and directory aside), bytes.
    pub estimate_bytes: u64,
}

/// What building the HDoV-tree made and cost.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovReport {
    /// Nodes of the tree.
    pub nodes: u32,
    /// Levels of nodes.
    pub height: u32,
    /// The entries packing put in a node (M).
    pub fanout: u32,
    /// Nodes (the root left out) with internal LODs, their levels and triangles, and
    /// the pages they take.
    pub nodes_with_lods: u32,
    /// Internal LOD levels stored, over all nodes.
    pub lod_levels: u64,
    /// Their triangles.
    pub lod_triangles: u64,
    /// Pages they take.
    pub lod_pages: u64,
    /// Pages of the nodes and of the head.
    pub node_pages: u64,
    /// Pages of the tree's head.
    pub head_pages: u64,
    /// Viewcells, and N_vnode summed over them.
    pub cells: u32,
    /// Visible nodes summed over the cells (N_vnode).
    pub visible_nodes: u64,
    /// Each scheme stored.
    pub schemes: Vec<SchemeReport>,
    /// Wall-clock seconds of the whole step, and of its internal LODs.
    pub seconds: f64,
    /// Seconds of the internal LODs.
    pub lod_seconds: f64,
}

/// A node as packing makes it, before it is numbered.
pub(super) struct Packed {
    pub(super) level: u16,
    mbr: Aabb,
    objects_below: u32,
    /// Leaf: its objects; internal: its children (indices into the packed nodes).
    objects: Vec<ObjectEntry>,
    children: Vec<usize>,
}

/// Packs `objects` into leaves and levels above of at most `cap` entries; the root is
/// the last node.
pub(super) fn pack(objects: Vec<ObjectEntry>, cap: usize) -> Vec<Packed> {
    let mut nodes = Vec::new();
    let mut level: Vec<usize> = Vec::new();
    for group in str_tile(objects, cap, |o| o.bounds.center()) {
        level.push(nodes.len());
        nodes.push(Packed {
            level: 0,
            mbr: group.iter().fold(Aabb::EMPTY, |b, o| b.union(&o.bounds)),
            objects_below: group.len() as u32,
            objects: group,
            children: Vec::new(),
        });
    }
    let mut height = 0u16;
    while level.len() > 1 {
        height += 1;
        let centres: Vec<(usize, glam::Vec3)> =
            level.iter().map(|&i| (i, nodes[i].mbr.center())).collect();
        let mut next = Vec::new();
        for group in str_tile(centres, cap, |c| c.1) {
            let children: Vec<usize> = group.into_iter().map(|c| c.0).collect();
            next.push(nodes.len());
            nodes.push(Packed {
                level: height,
                mbr: children
                    .iter()
                    .fold(Aabb::EMPTY, |b, &c| b.union(&nodes[c].mbr)),
                objects_below: children.iter().map(|&c| nodes[c].objects_below).sum(),
                objects: Vec::new(),
                children,
            });
        }
        level = next;
    }
    nodes
}

/// Where each packed node (numbered by `number`) and object sits: what a cell's VDs
/// are summed up by.
pub(super) fn topology(packed: &[Packed], number: &[u32]) -> Topology {
    let objects = packed.iter().map(|p| p.objects.len()).sum();
    let mut topology = Topology {
        entries: vec![0; packed.len()],
        parent: vec![None; packed.len()],
        level: vec![0; packed.len()],
        object: HashMap::with_capacity(objects),
    };
    for (n, p) in packed.iter().enumerate() {
        let k = number[n] as usize;
        topology.level[k] = p.level;
        if p.level == 0 {
            topology.entries[k] = p.objects.len() as u16;
            for (slot, o) in p.objects.iter().enumerate() {
                topology.object.insert(o.id, (k as u32, slot as u16));
            }
        } else {
            topology.entries[k] = p.children.len() as u16;
            for (slot, &c) in p.children.iter().enumerate() {
                topology.parent[number[c] as usize] = Some((k as u32, slot as u16));
            }
        }
    }
    topology
}

/// The packed nodes in depth-first preorder from the root (the last one).
pub(super) fn preorder(nodes: &[Packed]) -> Vec<usize> {
    let mut order = Vec::with_capacity(nodes.len());
    let mut stack = vec![nodes.len() - 1];
    while let Some(n) = stack.pop() {
        order.push(n);
        stack.extend(nodes[n].children.iter().rev());
    }
    order
}

/// Each object's coarsest stored level (its full mesh when it has none), and whether
/// it is a stored level, read from the store being built.
fn coarsest_meshes(store: &Store, objects: &[ObjectEntry]) -> Result<HashMap<u64, (Mesh, bool)>> {
    let table = LodTable::open(store)?;
    let mut out = HashMap::with_capacity(objects.len());
    for o in objects {
        let entry = match &table {
            Some(t) => t.find(store, o.id)?,
            None => None,
        };
        let coarse = match entry {
            Some(e) if e.levels > 0 => (level_mesh(store, &e, e.levels as usize)?, true),
            _ => (crate::catalog::read_mesh(store, o)?, false),
        };
        out.insert(o.id, coarse);
    }
    Ok(out)
}

/// The objects below packed node `n`.
fn objects_below<'p>(packed: &'p [Packed], n: usize, out: &mut Vec<&'p ObjectEntry>) {
    out.extend(packed[n].objects.iter());
    for &c in &packed[n].children {
        objects_below(packed, c, out);
    }
}

/// A node's internal LODs once made: its levels, and the geometry its parent is made
/// from (its coarsest level, or its source when it has none) with that geometry's
/// error against the node's full geometry (metres).
struct Made {
    levels: Vec<crate::lod::Level>,
    source_triangles: usize,
    coarsest: Mesh,
    coarsest_error: f32,
}

impl Made {
    /// Its faces for s: its finest internal LOD's, or its source's.
    fn faces(&self) -> usize {
        self.levels
            .first()
            .map_or(self.source_triangles, |l| l.mesh.triangle_count())
    }
}

/// Node `n`'s internal LODs, its children's made. Its proxies are measured against its
/// objects' full meshes when they have at most [`DIRECT_TRIANGLES`] together, else
/// bounded through its parts' errors (`lods`).
fn make_node(
    store: &Store,
    packed: &[Packed],
    n: usize,
    coarse: &HashMap<u64, (Mesh, bool)>,
    made: &[Option<Made>],
) -> Result<Made> {
    let p = &packed[n];
    let child = |c: usize| made[c].as_ref().expect("made below");
    let parts: Vec<&Mesh> = if p.level == 0 {
        p.objects.iter().map(|o| &coarse[&o.id].0).collect()
    } else {
        p.children.iter().map(|&c| &child(c).coarsest).collect()
    };
    let source = aggregate(parts);
    // The largest distance of a part of the source from its own full geometry.
    let parts_error = || -> Result<f32> {
        if p.level > 0 {
            return Ok(p
                .children
                .iter()
                .map(|&c| child(c).coarsest_error)
                .fold(0.0, f32::max));
        }
        let mut worst = 0.0f32;
        for o in &p.objects {
            let (mesh, stored) = &coarse[&o.id];
            if *stored && !mesh.indices.is_empty() {
                let full = crate::catalog::read_mesh(store, o)?;
                worst = error_above(mesh, &full, worst)?;
            }
        }
        Ok(worst)
    };
    let mut below = Vec::new();
    objects_below(packed, n, &mut below);
    let full_triangles: usize = below.iter().map(|o| o.triangles as usize).sum();
    let levels = if source.indices.is_empty() {
        Vec::new()
    } else if full_triangles <= DIRECT_TRIANGLES {
        let meshes = below
            .iter()
            .map(|o| crate::catalog::read_mesh(store, o))
            .collect::<Result<Vec<Mesh>>>()?;
        internal_levels(&source, Reference::Full(&aggregate(&meshes)))?
    } else {
        internal_levels(
            &source,
            Reference::Source {
                parts_error: parts_error()?,
            },
        )?
    };
    let (coarsest, coarsest_error) = match levels.last() {
        Some(l) => (l.mesh.clone(), l.error),
        None => (source.clone(), parts_error()?),
    };
    Ok(Made {
        source_triangles: source.triangle_count(),
        coarsest,
        coarsest_error,
        levels,
    })
}

/// Builds the HDoV-tree over `objects` into `store` as `opts` say.
pub(crate) fn build_hdov(
    store: &mut Store,
    objects: Vec<ObjectEntry>,
    opts: &HdovOptions,
    record_seconds: bool,
    progress: &dyn Progress,
) -> Result<HdovReport> {
    let start = Instant::now();
    opts.validate()?;
    let visibility = VisibilityTable::open(store)?.ok_or_else(|| {
        Error::Invalid(
            "the HDoV-tree needs the viewcells' visibility: build with --visibility".into(),
        )
    })?;
    let cap = opts.node_capacity(capacity(store.payload_size()), store.page_size())?;
    let object_count = objects.len() as u64;
    let coarse = coarsest_meshes(store, &objects)?;
    let packed = pack(objects, cap);
    let order = preorder(&packed);
    let mut number = vec![0u32; packed.len()];
    for (k, &n) in order.iter().enumerate() {
        number[n] = k as u32;
    }

    let lod_start = Instant::now();
    let made = make_internal_lods(store, &packed, &coarse, progress)?;
    let lod_seconds = lod_start.elapsed().as_secs_f64();
    let top = packed[packed.len() - 1].level;

    // The chains, then the nodes, whose entries point at them.
    let lod_pages_before = store.pages_written(PageKind::Lod);
    let (chains, written) = write_chains(store, &order, &number, &made)?;
    let lod_pages = store.pages_written(PageKind::Lod) - lod_pages_before;
    let topology = topology(&packed, &number);
    let first_node = write_nodes(store, &packed, &order, &number, (&made, &chains), cap)?;
    let node_pages = packed.len() as u64;

    // Each cell's VDs, then every scheme asked for.
    let (cells, vds) = cell_vds(store, &visibility, &topology, progress)?;
    let shape = Shape {
        cells: cells.len(),
        nodes: packed.len(),
        vpage_len: cap * VENTRY_LEN,
    };
    let visible_nodes: u64 = vds.iter().map(|v| v.len() as u64).sum();
    let (schemes, stored) = write_schemes(store, &opts.schemes, shape, &vds)?;
    let head = TreeHead {
        first_node,
        nodes: packed.len() as u32,
        height: top as u32 + 1,
        fanout: cap as u32,
        objects: object_count,
        vpage_len: shape.vpage_len as u32,
        // A reproducible build stores no time.
        seconds: if record_seconds {
            start.elapsed().as_secs_f64()
        } else {
            0.0
        },
        lod_pages,
        visible_nodes,
        schemes: stored,
        cells,
        proxy_errors: ProxyErrors::Hausdorff,
    };
    let e = store.append_extent(PageKind::HdovNode, &head.encode())?;
    store.set_segment(Segment::new(
        HDOV_SEGMENT,
        e.first_page,
        e.byte_len as u64,
        e.page_count as u64,
    ))?;
    Ok(HdovReport {
        nodes: head.nodes,
        height: head.height,
        fanout: head.fanout,
        nodes_with_lods: written.nodes,
        lod_levels: written.levels,
        lod_triangles: written.triangles,
        lod_pages,
        node_pages,
        head_pages: e.page_count as u64,
        cells: head.cells.len() as u32,
        visible_nodes,
        schemes,
        seconds: start.elapsed().as_secs_f64(),
        lod_seconds,
    })
}

/// Every node's page, in preorder from `first_node` (returned), each internal node's
/// entries pointing at its children's pages and internal LODs: h and s (§5.4) from
/// what each child holds and was made of.
fn write_nodes(
    store: &mut Store,
    packed: &[Packed],
    order: &[usize],
    number: &[u32],
    (made, chains): (&[Option<Made>], &[Extent]),
    cap: usize,
) -> Result<u64> {
    let log_m = (cap as f64).ln();
    let child_ref = |c: usize| {
        let m = made[c].as_ref().expect("every child is made");
        let p = &packed[c];
        let below: usize = if p.level == 0 {
            p.objects.iter().map(|o| o.triangles as usize).sum()
        } else {
            p.children
                .iter()
                .map(|&g| made[g].as_ref().expect("made").faces())
                .sum()
        };
        ChildRef {
            mbr: p.mbr,
            node: number[c],
            objects: p.objects_below,
            h: ((p.objects_below as f64).ln() / log_m) as f32,
            s: (m.faces() as f64 / below.max(1) as f64).max(f64::MIN_POSITIVE) as f32,
            lods: chains[c],
        }
    };
    let first_node = store.page_count();
    for &n in order {
        let p = &packed[n];
        let kind = if p.level == 0 {
            HNodeKind::Leaf(p.objects.clone())
        } else {
            HNodeKind::Internal {
                level: p.level,
                children: p.children.iter().map(|&c| child_ref(c)).collect(),
            }
        };
        let node = HNode {
            number: number[n],
            kind,
        };
        let page = store.append_page(PageKind::HdovNode, &node.encode())?;
        debug_assert_eq!(page, first_node + number[n] as u64);
    }
    Ok(first_node)
}

/// Every scheme asked for, once each in order, its V-pages written from the cells'
/// VDs; returns each scheme's figures and its extent.
fn write_schemes(
    store: &mut Store,
    asked: &[Scheme],
    shape: Shape,
    vds: &[CellVd],
) -> Result<(Vec<SchemeReport>, Vec<(Scheme, Extent)>)> {
    let visible_nodes: u64 = vds.iter().map(|v| v.len() as u64).sum();
    let mut schemes = Vec::new();
    let mut stored = Vec::new();
    let mut asked = asked.to_vec();
    asked.sort();
    asked.dedup();
    for s in asked {
        let bytes = scheme::encode(s, shape, vds);
        let e = store.append_extent(PageKind::VPage, &bytes)?;
        let vpages = match s {
            Scheme::Horizontal => (shape.cells * shape.nodes) as u64,
            _ => visible_nodes,
        };
        schemes.push(SchemeReport {
            scheme: s,
            bytes: bytes.len() as u64,
            pages: e.page_count as u64,
            vpages,
            estimate_bytes: scheme::estimate(s, shape, visible_nodes),
        });
        stored.push((s, e));
    }
    Ok((schemes, stored))
}

/// Every node's internal LODs but the root's, a level at a time from the leaves up,
/// each level's nodes at once.
fn make_internal_lods(
    store: &Store,
    packed: &[Packed],
    coarse: &HashMap<u64, (Mesh, bool)>,
    progress: &dyn Progress,
) -> Result<Vec<Option<Made>>> {
    let root = packed.len() - 1;
    let mut made: Vec<Option<Made>> = (0..packed.len()).map(|_| None).collect();
    let top = packed[root].level;
    let mut done = 0u64;
    for level in 0..=top {
        let at: Vec<usize> = (0..packed.len())
            .filter(|&n| packed[n].level == level && n != root)
            .collect();
        let results: Vec<Result<Made>> = at
            .par_iter()
            .map(|&n| make_node(store, packed, n, coarse, &made))
            .collect();
        for (&n, r) in at.iter().zip(results) {
            made[n] = Some(r?);
        }
        done += at.len() as u64;
        progress.update(Step::HdovLods, done, Some(packed.len() as u64 - 1));
    }
    progress.finish(Step::HdovLods);
    Ok(made)
}

/// What [`write_chains`] wrote: the nodes with internal LODs, their levels and
/// triangles.
#[derive(Default)]
struct Written {
    nodes: u32,
    levels: u64,
    triangles: u64,
}

/// Each node's chain of internal LODs, in preorder, coded as the objects' meshes are
/// (they share no vertices); returns each node's extent (empty for a node without).
fn write_chains(
    store: &mut Store,
    order: &[usize],
    number: &[u32],
    made: &[Option<Made>],
) -> Result<(Vec<Extent>, Written)> {
    let mut chains: Vec<Extent> = vec![Extent::default(); made.len()];
    let mut written = Written::default();
    let codec = crate::catalog::load_codec(store)?;
    for &n in order {
        let Some(m) = &made[n] else { continue };
        if m.levels.is_empty() {
            continue;
        }
        let bytes =
            encode_chain_with(number[n] as u64, m.source_triangles, &m.levels, codec, None)?;
        chains[n] = store.append_packed_or_whole(PageKind::Lod, &bytes, codec.packs())?;
        written.nodes += 1;
        written.levels += m.levels.len() as u64;
        written.triangles += m
            .levels
            .iter()
            .map(|l| l.mesh.triangle_count() as u64)
            .sum::<u64>();
    }
    Ok((chains, written))
}

/// Each viewcell's id and its VDs: its PVS aggregated up the tree.
fn cell_vds(
    store: &Store,
    visibility: &VisibilityTable,
    topology: &Topology,
    progress: &dyn Progress,
) -> Result<(Vec<u32>, Vec<CellVd>)> {
    let cells: Vec<u32> = visibility.head(store)?.cells.iter().map(|c| c.id).collect();
    let mut vds: Vec<CellVd> = Vec::with_capacity(cells.len());
    for (i, &id) in cells.iter().enumerate() {
        let pvs = visibility.pvs(store, id)?.ok_or_else(|| {
            Error::Invalid(format!("viewcell {id} is in the directory but has no PVS"))
        })?;
        vds.push(
            topology
                .aggregate(&pvs.ids, &pvs.dov)
                .map_err(|e| Error::Invalid(format!("viewcell {id}: {e}")))?,
        );
        progress.update(Step::HdovCells, i as u64 + 1, Some(cells.len() as u64));
    }
    progress.finish(Step::HdovCells);
    Ok((cells, vds))
}
