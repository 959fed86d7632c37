//! Conservative from-region visibility (Shou 2002 §5.5.1): the objects that no point
//! of a viewcell can see are dropped, and nothing that one point can see is.
//!
//! The thesis takes occluders from a belt around the cell and drops an object only
//! where one occluder hides it from all eight corners (each occluder's hidden set
//! intersected over the corners, then unioned over occluders). In a city of detached
//! buildings, where what hides a far object is a row of buildings with gaps between
//! them at several depths, a single occluder rarely hides anything from a whole cell.
//! The first version here made that test exactly in object space, halving cell and box
//! up to 12 times so that a row could hide together; on a 2,000-object city with 20 m
//! cells it left 39 % of the scene at 0.51 s a cell, and on the 20,000-object demo
//! city with 40 m cells 54 % at 8.7 s a cell.
//!
//! This test fuses occluders instead, by occluder shrinking (Wonka, Wimmer and
//! Schmalstieg 2000): the cell is covered by patches, each with a sample point at its
//! centre no further than ε from any point of the patch; from each sample point the
//! occluders, shrunk by ε, give an occlusion horizon ([`Horizon`]); what some sample's
//! horizon does not hide is in the cell's PVS. On the same two cities it leaves 34 %
//! at 0.10 s a cell and 17 % at 0.58 s (2 m patches, occluders within 600 m).
//!
//! Why it is conservative: take a sight line from a point x of the cell to q, x within
//! ε of the sample s in plan and no higher (samples stand at the cell's top). The line
//! from s to q meets an occluder shrunk by ε in plan at a, a fraction t along it; the
//! line from x to q is, at the same fraction, at a + (1 − t)(x − s): within ε of a in
//! plan, so over the unshrunk footprint, and no higher than a, so under the occluder's
//! top, which is therefore not shrunk. Each sight line is blocked on its own, so
//! occluders fuse freely, across gaps and depths. (Sampling the cell's height range as
//! a third dimension of the patches, as a first version did, cost ε and the occluders'
//! tops the half-height of the cell: on the 3,000-object city a PVS 1.26 times larger.)
//!
//! Choices made here:
//! - Occluders are prisms: each building's occluder boxes ([`occluders`]), in a frame
//!   turned to its walls, that
//!   stand on the ground, or on such a box within its footprint, taken down to the
//!   ground. The ground is the city's lowest point; no sight line between an eye and
//!   an object passes under it. The centimetres between stacked boxes (their safety
//!   margins) lie inside the same building, and are far thinner than the shrinking.
//! - Blocks of patches first. The argument above holds for any part of the cell with
//!   its sample at its centre and ε the half-diagonal of its plan: an object hidden from
//!   the sample of a block of 2 × 2 patches, by the occluders shrunk by the block's ε,
//!   is hidden from every point of the block, and is not tested again at its patches.
//!   Only what a block leaves goes on to its four patches' samples, at the patches' ε;
//!   an object is visible when one of those leaves it too. So the PVS holds no object
//!   that testing every patch alone would drop, and may hold fewer; a patch left with
//!   nothing undecided builds no horizon. One level of blocks, as measured on the
//!   3,000-object city (40 m cells, 3 m patches, ε 2.0 m): blocks of 2 × 2 patches
//!   (ε 4.0 m) hide 93 % of what reaches them, blocks of 3 or 4 patches a side (ε 6 to
//!   8 m) 2 %, the whole cell nothing: a shrinking of a few metres leaves nothing of
//!   the narrow buildings that make most of a street's walls. With the two savings
//!   below, the test of a cell there took 53 ms of one core instead of 89 (24 cells
//!   spread over the city, no rays told, both in one run on busy cores), its PVS 847.7
//!   objects instead of 847.9, none of them new.
//! - A patch's horizon is built for its undecided objects only ([`Wanted`]): in the
//!   bins none of them touches, and beyond the furthest of them in a bin, no occluder
//!   is entered. It answers for them exactly as the whole horizon would. It stops
//!   once the occluders entered so far hide all of them: on the 3,000-object city (73
//!   cells, every tenth, no rays told) a patch's horizon was asked about 262 objects on
//!   average and hid all but 5; 45 % of them stopped so, after 228 of some 530 groups.
//!   How each object lies from the eye (its bins, nearest point, corners' angles),
//!   worked out when it is asked, is kept for its answer rather than worked out again:
//!   on the demo city (115 cells, every fortieth walkable, no rays told, one core) the
//!   test took 118 and 112 ms a cell against 125 and 124, the same PVSs.
//! - A sample's horizon takes the occluders within `radius` of it, 600 m by default:
//!   on the 3,000-object city (73 cells, every tenth walkable, no rays told, one core
//!   of a busy machine) radii of 200, 300, 400, 600 and 800 m left PVSs of 1,093.6,
//!   953.4, 898.6, 863.3 and 854.5 objects, the test taking 36, 42, 48, 56 and 55 ms
//!   a cell: a horizon that stops once its objects are hidden seldom reaches the far
//!   occluders, so a shorter radius saves less than it loses.
//! - A sample inside a shrunk occluder is skipped: every point of its patch (or block)
//!   is inside a building's solid, where no viewer stands.
//! - The occluders within reach of a cell (`radius` beyond it) are found once per cell,
//!   and shrunk once per size of patch or block, not per sample.
//! - The prisms are grouped by squares of ground 40 m a side (`GROUP_TILE`), and the
//!   groups taken nearest the cell's centre first; a group whose bounds are behind the
//!   horizon built so far in every bin it spans is passed over whole (it cannot change
//!   what the horizon hides: see [`Horizon::rebuild`]). Two ways to pass over more for
//!   less gave the same PVSs and no gain that showed over the noise (50 to 57 ms a
//!   cell either way, same runs as above): bounds on each group's and prism's bins
//!   worked out once per cell for all its eyes (the box of the differences between
//!   cell and bounds, seen from the origin), checked before the eye's own; and regions
//!   of 2 × 2 or 4 × 4 groups, each looked at whole when its first group comes. From a
//!   40 m cell a group's bins widen several times over, so the wider check passes over
//!   fewer and costs more; and what either saves is a small share of the test.
//! - The object hierarchy is an R-tree, laid out flat in preorder ([`flat`]): a subtree
//!   whose box a block's horizon hides is dropped whole, as the thesis drops hidden
//!   nodes; objects already known visible (a ray of the DoV met them, or an earlier
//!   patch's horizon left them) are not tested again.
//!
//! [`occluders`]: super::occluder::occluders

use glam::{Vec2, Vec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use rayon::prelude::*;

use std::ops::Range;

use super::horizon::{Group, Horizon, Prism, Wanted};
use super::occluder::{occluders, Occluders};
use super::shown::shown;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::scene::Mesh;
use flat::FlatTree;

type PlanEntry = GeomWithData<Rectangle<[f32; 2]>, u32>;

/// The side of the squares of ground by which prisms are grouped, metres: about a city
/// block, so that a block behind a street's walls is passed over whole.
const GROUP_TILE: f32 = 40.0;

/// The blocks of patches tested first, patches across and along (see the module's
/// notes).
const TOP_BLOCK: u32 = 2;

/// The most sample points the conservative test may take in one viewcell (2²⁰, a
/// 1024 × 1024 grid of patches): each builds an occlusion horizon, about a millisecond,
/// so a cell at this limit takes a quarter of an hour.
pub const MAX_SAMPLES_PER_CELL: u64 = 1 << 20;

/// How a cell is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleOptions {
    /// The widest a patch may be across the ground, in metres.
    pub spacing: f32,
    /// Occluders further than this from a sample (in plan, metres) are not used.
    pub radius: f32,
}

impl Default for SampleOptions {
    fn default() -> Self {
        SampleOptions {
            spacing: 3.0,
            radius: 600.0,
        }
    }
}

impl SampleOptions {
    /// Checks the settings: a positive spacing and a radius from 0 up, both finite; the
    /// error names the bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.spacing.is_finite() && self.spacing > 0.0) {
            return Err(Error::Invalid(format!(
                "sample spacing {} m (--sample-spacing) must be a positive number",
                self.spacing
            )));
        }
        if !(self.radius.is_finite() && self.radius >= 0.0) {
            return Err(Error::Invalid(format!(
                "occluder radius {} m (--occluder-radius) must be a number from 0 up",
                self.radius
            )));
        }
        Ok(())
    }

    /// The sample points of `cell` and their ε: patch centres at the cell's top, at
    /// most `spacing` apart, each within ε in plan of every point of its patch. An error, before anything is
    /// allocated, when they would be more than [`MAX_SAMPLES_PER_CELL`] (a build checks
    /// that before it starts: see `VisibilityOptions::cost`) or do not fit in memory.
    pub fn samples(&self, cell: &Aabb) -> Result<(Vec<Vec3>, f32)> {
        let patches = self.patches(cell)?;
        let count = patches.nx as usize * patches.nz as usize;
        let mut points = Vec::new();
        points.try_reserve_exact(count).map_err(|_| {
            Error::Invalid(format!(
                "{count} sample points of a viewcell do not fit in memory (--sample-spacing {})",
                shown(self.spacing)
            ))
        })?;
        points.extend((0..patches.nz).flat_map(|j| {
            (0..patches.nx).map(move |i| {
                patches.sample(Block {
                    i0: i,
                    i1: i + 1,
                    j0: j,
                    j1: j + 1,
                })
            })
        }));
        let eps = patches.eps(Block {
            i0: 0,
            i1: 1,
            j0: 0,
            j1: 1,
        });
        Ok((points, eps))
    }

    /// How `cell` is cut into patches; an error when they would be more than
    /// [`MAX_SAMPLES_PER_CELL`].
    fn patches(&self, cell: &Aabb) -> Result<Patches> {
        let e = cell.extent();
        // In f32, as the patches are laid out, so that the count is theirs.
        let across = |len: f32| (len / self.spacing).ceil().max(1.0);
        let count = across(e.x) as f64 * across(e.z) as f64;
        if !(count <= MAX_SAMPLES_PER_CELL as f64) {
            return Err(Error::Invalid(format!(
                "sample spacing {} m (--sample-spacing) makes {count:.3e} sample points in a \
                 {} × {} m viewcell: more than the {} a cell takes",
                shown(self.spacing),
                e.x,
                e.z,
                MAX_SAMPLES_PER_CELL
            )));
        }
        let (nx, nz) = (across(e.x) as u32, across(e.z) as u32);
        Ok(Patches {
            min: Vec2::new(cell.min.x, cell.min.z),
            // The samples at the cell's top: see the module's notes.
            y: cell.max.y,
            nx,
            nz,
            dx: e.x / nx as f32,
            dz: e.z / nz as f32,
        })
    }
}

/// A cell's patches: `nx` × `nz` rectangles of `dx` × `dz` metres from its corner
/// `min` (in plan), their samples at height `y`.
#[derive(Clone, Copy, Debug)]
struct Patches {
    min: Vec2,
    y: f32,
    nx: u32,
    nz: u32,
    dx: f32,
    dz: f32,
}

/// A rectangle of patches, `i0..i1` across and `j0..j1` along.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Block {
    i0: u32,
    i1: u32,
    j0: u32,
    j1: u32,
}

impl Patches {
    /// The patches in blocks of `step` × `step` (fewer at the far sides).
    fn blocks(&self, step: u32) -> impl Iterator<Item = Block> + '_ {
        (0..self.nz).step_by(step as usize).flat_map(move |j0| {
            (0..self.nx).step_by(step as usize).map(move |i0| Block {
                i0,
                i1: (i0 + step).min(self.nx),
                j0,
                j1: (j0 + step).min(self.nz),
            })
        })
    }

    /// The block's sample point: its centre, at the cell's top.
    fn sample(&self, b: Block) -> Vec3 {
        Vec3::new(
            self.min.x + ((b.i0 + b.i1) as f32 * 0.5) * self.dx,
            self.y,
            self.min.y + ((b.j0 + b.j1) as f32 * 0.5) * self.dz,
        )
    }

    /// The block's ε: the distance in plan from its sample to its corners.
    fn eps(&self, b: Block) -> f32 {
        let (w, h) = b.size();
        0.5 * Vec2::new(w as f32 * self.dx, h as f32 * self.dz).length()
    }
}

impl Block {
    /// Patches across and along.
    fn size(&self) -> (u32, u32) {
        (self.i1 - self.i0, self.j1 - self.j0)
    }

    /// The block halved across and along where it is more than one patch: up to four
    /// parts; `None` for one patch.
    fn parts(&self) -> Option<[Option<Block>; 4]> {
        let (w, h) = self.size();
        if w == 1 && h == 1 {
            return None;
        }
        let (mi, mj) = (self.i0 + w / 2, self.j0 + h / 2);
        let across = if w > 1 {
            [(self.i0, mi), (mi, self.i1)]
        } else {
            [(self.i0, self.i1), (0, 0)]
        };
        let along = if h > 1 {
            [(self.j0, mj), (mj, self.j1)]
        } else {
            [(self.j0, self.j1), (0, 0)]
        };
        let mut parts = [None; 4];
        for (k, &(j0, j1)) in along.iter().enumerate() {
            for (l, &(i0, i1)) in across.iter().enumerate() {
                if i1 > i0 && j1 > j0 {
                    parts[2 * k + l] = Some(Block { i0, i1, j0, j1 });
                }
            }
        }
        Some(parts)
    }
}

/// The prisms among one object's occluder boxes (see the module's notes).
pub fn prisms(occluders: &Occluders, ground: f32) -> Vec<Prism> {
    const TOUCH: f32 = 0.05;
    // Footprints in the boxes' own frame first, where they are plan rectangles.
    let mut out: Vec<(Vec2, Vec2, f32)> = Vec::new();
    for b in &occluders.boxes {
        let (min, max) = (Vec2::new(b.min.x, b.min.z), Vec2::new(b.max.x, b.max.z));
        let on_ground = b.min.y <= ground + TOUCH;
        let on_prism = out.iter().any(|&(lo, hi, top)| {
            b.min.y <= top + TOUCH
                && min.x >= lo.x - TOUCH
                && min.y >= lo.y - TOUCH
                && max.x <= hi.x + TOUCH
                && max.y <= hi.y + TOUCH
        });
        if on_ground || on_prism {
            out.push((min, max, b.max.y));
        }
    }
    out.into_iter()
        .map(|(min, max, top)| {
            let mut p = Prism::aligned(min, max, top);
            p.centre = occluders.plan_of(p.centre);
            p.axis = occluders.axis;
            p
        })
        .collect()
}

/// The objects and their occluders, indexed for the conservative test of many cells
/// (see the module's notes).
pub struct Scene {
    boxes: Vec<Aabb>,
    objects: FlatTree,
    /// The prisms, group by group.
    prisms: Vec<Prism>,
    /// Groups of prisms near one another, each with its prisms in `prisms`.
    groups: Vec<(Group, Range<u32>)>,
    group_index: RTree<PlanEntry>,
    /// Objects with at least one occluder box.
    occluding: usize,
}

impl Scene {
    /// The scene of `objects` (their ids aside, in the order given, which is the order
    /// of the indices [`Scene::visible_from`] answers with): each mesh's box and
    /// occluders, the occluders found on all cores.
    pub fn from_meshes(objects: &[(u64, Mesh)]) -> Result<Scene> {
        let boxes = objects
            .iter()
            .map(|(id, m)| {
                let (lo, hi) = m.bounds();
                Aabb::new(lo, hi).map_err(|e| Error::Invalid(format!("object {id}: {e}")))
            })
            .collect::<Result<Vec<Aabb>>>()?;
        let found: Vec<Occluders> = objects.par_iter().map(|(_, m)| occluders(m)).collect();
        Scene::new(&boxes, &found)
    }

    /// The objects' boxes, and each object's occluder boxes (see
    /// [`occluders`](super::occluder::occluders); none for an object that occludes nothing).
    pub(crate) fn new(objects: &[Aabb], occluders: &[Occluders]) -> Result<Scene> {
        if objects.len() != occluders.len() {
            return Err(Error::Invalid(format!(
                "{} objects but {} occluder entries",
                objects.len(),
                occluders.len()
            )));
        }
        for (i, b) in objects.iter().enumerate() {
            b.validate()
                .map_err(|e| Error::Invalid(format!("object {i}: {e}")))?;
        }
        for (i, o) in occluders.iter().enumerate() {
            o.validate()
                .map_err(|e| Error::Invalid(format!("object {i}'s occluders: {e}")))?;
        }
        let ground = objects
            .iter()
            .map(|b| b.min.y)
            .fold(f32::INFINITY, f32::min);
        let mut prisms: Vec<Prism> = occluders.iter().flat_map(|o| prisms(o, ground)).collect();
        // Grouped by the square of the ground their centres stand on.
        let tile = |o: &Prism| {
            let t = (o.centre / GROUP_TILE).floor();
            (t.x as i64, t.y as i64)
        };
        prisms.sort_by_key(tile);
        let mut groups = Vec::new();
        for run in prisms.chunk_by(|a, b| tile(a) == tile(b)) {
            let start = groups
                .last()
                .map_or(0, |(_, r): &(Group, Range<u32>)| r.end);
            if let Some(g) = Group::around(run) {
                groups.push((g, start..start + run.len() as u32));
            }
        }
        let group_index = RTree::bulk_load(
            groups
                .iter()
                .enumerate()
                .map(|(i, (g, _))| {
                    GeomWithData::new(
                        Rectangle::from_corners(g.lo.to_array(), g.hi.to_array()),
                        i as u32,
                    )
                })
                .collect(),
        );
        Ok(Scene {
            boxes: objects.to_vec(),
            objects: FlatTree::new(objects),
            prisms,
            groups,
            group_index,
            occluding: occluders.iter().filter(|o| !o.boxes.is_empty()).count(),
        })
    }

    /// Objects in the scene.
    pub fn object_count(&self) -> usize {
        self.boxes.len()
    }

    /// Objects with at least one occluder box.
    pub fn occluding_objects(&self) -> usize {
        self.occluding
    }

    /// Occluder prisms found among the objects' occluder boxes.
    pub fn prism_count(&self) -> usize {
        self.prisms.len()
    }

    /// The conservative PVS of the viewcell `cell`: indices (into the objects given to
    /// [`Scene::new`]) of the objects not hidden, ascending. `seen` (ascending) are
    /// objects known to be visible from the cell — a ray from one of its points met
    /// them — kept without a test.
    pub fn visible_from(
        &self,
        cell: &Aabb,
        opts: &SampleOptions,
        seen: &[u32],
    ) -> Result<Vec<u32>> {
        cell.validate()?;
        opts.validate()?;
        if let Some(w) = seen.windows(2).find(|w| w[0] >= w[1]) {
            return Err(Error::Invalid(format!(
                "seen objects must ascend: {} follows {}",
                w[1], w[0]
            )));
        }
        let mut visible = vec![false; self.boxes.len()];
        for &i in seen {
            *visible
                .get_mut(i as usize)
                .ok_or_else(|| Error::Invalid(format!("seen object {i} is not in the scene")))? =
                true;
        }
        let patches = opts.patches(cell)?;
        // The groups of prisms within reach of any sample, once per cell: each sample
        // takes the prisms whose bounds meet the square of side 2·radius about it.
        let r = opts.radius;
        let reach = AABB::from_corners(
            [cell.min.x - r, cell.min.z - r],
            [cell.max.x + r, cell.max.z + r],
        );
        // Nearest the cell's centre first: each sample's horizon prunes best taking its
        // prisms nearest first, and this order is near enough to each sample's own.
        let centre = Vec2::new(cell.center().x, cell.center().z);
        let mut tiles: Vec<Tile> = self
            .group_index
            .locate_in_envelope_intersecting(&reach)
            .map(|e| {
                let (group, prisms) = self.groups[e.data as usize].clone();
                Tile {
                    group,
                    prisms,
                    from_centre: (centre.clamp(group.lo, group.hi) - centre).length(),
                }
            })
            .collect();
        tiles.sort_by_key(|t| ordered(t.from_centre));
        let mut walk = Walk {
            scene: self,
            patches,
            centre,
            radius: r,
            tiles,
            levels: Vec::new(),
            visible,
            horizon: Horizon::empty(),
            wanted: Wanted::new(Vec3::ZERO),
        };
        for block in patches.blocks(TOP_BLOCK) {
            walk.visit(block, None);
        }
        let visible = walk.visible;
        Ok((0..visible.len() as u32)
            .filter(|&i| visible[i as usize])
            .collect())
    }
}

/// A group of prisms within reach of a cell, and how far its bounds are from the cell's
/// centre.
struct Tile {
    group: Group,
    /// Its prisms in the scene's.
    prisms: Range<u32>,
    from_centre: f32,
}

/// The prisms within reach of a cell shrunk for blocks of one size: tile k's in
/// `prisms[starts[k]..starts[k + 1]]`, each with its unshrunk plan bounds.
struct Level {
    /// Patches across and along.
    size: (u32, u32),
    prisms: Vec<(Prism, Vec2, Vec2)>,
    starts: Vec<u32>,
}

impl Level {
    /// Tile `t`'s prisms.
    fn of_tile(&self, t: usize) -> &[(Prism, Vec2, Vec2)] {
        &self.prisms[self.starts[t] as usize..self.starts[t + 1] as usize]
    }
}

/// One cell's test, block by block of patches (see the module's notes).
struct Walk<'a> {
    scene: &'a Scene,
    patches: Patches,
    centre: Vec2,
    radius: f32,
    /// The groups of prisms within reach of the cell, nearest its centre first.
    tiles: Vec<Tile>,
    /// Their prisms shrunk for each size of block, made when first needed.
    levels: Vec<Level>,
    visible: Vec<bool>,
    horizon: Horizon,
    wanted: Wanted,
}

impl Walk<'_> {
    /// The prisms shrunk for blocks of `block`'s size.
    fn level(&mut self, block: Block) -> usize {
        let size = block.size();
        if let Some(k) = self.levels.iter().position(|l| l.size == size) {
            return k;
        }
        let eps = self.patches.eps(block);
        let mut level = Level {
            size,
            prisms: Vec::new(),
            starts: Vec::with_capacity(self.tiles.len() + 1),
        };
        level.starts.push(0);
        for t in &self.tiles {
            let of_tile = &self.scene.prisms[t.prisms.start as usize..t.prisms.end as usize];
            level.prisms.extend(of_tile.iter().filter_map(|o| {
                let (lo, hi) = o.bounds();
                o.shrunk(eps).map(|s| (s, lo, hi))
            }));
            level.starts.push(level.prisms.len() as u32);
        }
        self.levels.push(level);
        self.levels.len() - 1
    }

    /// Tests `undecided` (none hidden from a block around this one, by the occluders
    /// shrunk for it; `None` for every object not known visible) against `block`'s
    /// sample: those it leaves go on to its parts, or, when it is one patch, are
    /// visible.
    fn visit(&mut self, block: Block, undecided: Option<Vec<u32>>) {
        let mut undecided = undecided;
        if let Some(u) = &mut undecided {
            u.retain(|&i| !self.visible[i as usize]);
            if u.is_empty() {
                return;
            }
        }
        let k = self.level(block);
        let eye = self.patches.sample(block);
        let p = Vec2::new(eye.x, eye.z);
        // No prism nearer the eye than this lies nearer the cell's centre than `off`.
        let off = (p - self.centre).length() * (1.0 + 1e-5) + 1e-3;
        // An eye inside a shrunk prism: every point of the block is inside a building's
        // solid, where no viewer stands.
        let level = &self.levels[k];
        if self
            .tiles
            .iter()
            .take_while(|t| t.from_centre <= off)
            .enumerate()
            .any(|(t, _)| level.of_tile(t).iter().any(|n| n.0.contains(eye)))
        {
            return;
        }
        let boxes = &self.scene.boxes;
        let left = match undecided {
            None => {
                // Every object: through the R-tree, a subtree the horizon hides dropped
                // whole.
                self.rebuild(eye, k, off, false);
                let (horizon, visible) = (&self.horizon, &self.visible);
                self.scene.objects.select(
                    |b| !horizon.hides(b),
                    |i, b| !visible[i as usize] && !horizon.hides(b),
                )
            }
            Some(undecided) => {
                self.wanted.reset(eye);
                let mut left = Vec::new();
                let mut asked = Vec::with_capacity(undecided.len());
                for i in undecided {
                    if self.wanted.add(&boxes[i as usize]) {
                        asked.push(i);
                    } else {
                        left.push(i);
                    }
                }
                if !asked.is_empty() {
                    self.rebuild(eye, k, off, true);
                    let (horizon, wanted) = (&self.horizon, &self.wanted);
                    left.extend(asked.into_iter().enumerate().filter_map(|(k, i)| {
                        (!horizon.hides_wanted(wanted, k, &boxes[i as usize])).then_some(i)
                    }));
                }
                left
            }
        };
        match block.parts() {
            None => {
                for i in left {
                    self.visible[i as usize] = true;
                }
            }
            Some(parts) => {
                for part in parts.into_iter().flatten() {
                    self.visit(part, Some(left.clone()));
                }
            }
        }
    }

    /// The horizon of `eye` (`off` from the cell's centre, a hair over) over the prisms
    /// of level `k` within the radius, for the boxes wanted when `wanted`, else for
    /// every box.
    fn rebuild(&mut self, eye: Vec3, k: usize, off: f32, wanted: bool) {
        let level = &self.levels[k];
        let p = Vec2::new(eye.x, eye.z);
        let r = self.radius;
        let (lo, hi) = (p - r, p + r);
        let meets = move |a: Vec2, b: Vec2| a.cmple(hi).all() && lo.cmple(b).all();
        let wanted = wanted.then_some(&self.wanted);
        let reach = wanted.map_or(f32::INFINITY, |w| w.reach() + off);
        let groups = self
            .tiles
            .iter()
            .take_while(|t| t.from_centre < reach)
            .enumerate()
            .filter(|(_, t)| meets(t.group.lo, t.group.hi))
            .map(|(t, tile)| {
                let prisms = level
                    .of_tile(t)
                    .iter()
                    .filter(move |n| meets(n.1, n.2))
                    .map(|n| n.0);
                (tile.group, prisms)
            });
        self.horizon.rebuild(eye, groups, wanted);
    }
}

/// A key that orders finite non-negative floats as they compare.
fn ordered(x: f32) -> u32 {
    x.to_bits()
}

mod flat;

#[cfg(test)]
mod tests;

#[cfg(test)]
mod city_tests;
