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
//! - A sample's horizon takes the occluders within `radius` of it.
//! - A sample inside a shrunk occluder is skipped: every point of its patch is inside
//!   a building's solid, where no viewer stands.
//! - The occluders within reach of a cell (`radius` beyond it) are found and shrunk once
//!   per cell, not per sample.
//! - The object hierarchy is an R-tree: a subtree whose box a horizon hides is dropped
//!   whole, as the thesis drops hidden nodes; objects already known visible (a ray of
//!   the DoV met them, or an earlier sample's horizon left them) are not tested again.
//!
//! [`occluders`]: super::occluder::occluders

use glam::{Vec2, Vec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, SelectionFunction, AABB};

use rayon::prelude::*;

use super::horizon::{Horizon, Prism};
use super::occluder::{occluders, Occluders};
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::scene::Mesh;

type Entry = GeomWithData<Rectangle<[f32; 3]>, u32>;
type PlanEntry = GeomWithData<Rectangle<[f32; 2]>, u32>;

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
    ///
    /// [`MAX_SAMPLES_PER_CELL`]: super::MAX_SAMPLES_PER_CELL
    pub fn samples(&self, cell: &Aabb) -> Result<(Vec<Vec3>, f32)> {
        let e = cell.extent();
        // In f32, as the patches are laid out, so that the count is theirs.
        let across = |len: f32| (len / self.spacing).ceil().max(1.0);
        let count = across(e.x) as f64 * across(e.z) as f64;
        if !(count <= super::MAX_SAMPLES_PER_CELL as f64) {
            return Err(Error::Invalid(format!(
                "sample spacing {} m (--sample-spacing) makes {count:.3e} sample points in a \
                 {} × {} m viewcell: more than the {} a cell takes",
                super::cost::shown(self.spacing),
                e.x,
                e.z,
                super::MAX_SAMPLES_PER_CELL
            )));
        }
        let (nx, nz) = (across(e.x) as u32, across(e.z) as u32);
        let (dx, dz) = (e.x / nx as f32, e.z / nz as f32);
        // In plan only, the samples at the cell's top: see the module's notes.
        let eps = 0.5 * Vec2::new(dx, dz).length();
        let y = cell.max.y;
        let mut points = Vec::new();
        points.try_reserve_exact(count as usize).map_err(|_| {
            Error::Invalid(format!(
                "{count} sample points of a viewcell do not fit in memory (--sample-spacing {})",
                super::cost::shown(self.spacing)
            ))
        })?;
        points.extend((0..nz).flat_map(|j| {
            (0..nx).map(move |i| {
                Vec3::new(
                    cell.min.x + (i as f32 + 0.5) * dx,
                    y,
                    cell.min.z + (j as f32 + 0.5) * dz,
                )
            })
        }));
        Ok((points, eps))
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
    objects: RTree<Entry>,
    prisms: Vec<Prism>,
    prism_index: RTree<PlanEntry>,
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
        let prisms: Vec<Prism> = occluders.iter().flat_map(|o| prisms(o, ground)).collect();
        let prism_index = RTree::bulk_load(
            prisms
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let (lo, hi) = p.bounds();
                    GeomWithData::new(
                        Rectangle::from_corners(lo.to_array(), hi.to_array()),
                        i as u32,
                    )
                })
                .collect(),
        );
        let objects_index = RTree::bulk_load(
            objects
                .iter()
                .enumerate()
                .map(|(i, b)| {
                    GeomWithData::new(
                        Rectangle::from_corners(b.min.to_array(), b.max.to_array()),
                        i as u32,
                    )
                })
                .collect(),
        );
        Ok(Scene {
            boxes: objects.to_vec(),
            objects: objects_index,
            prisms,
            prism_index,
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
        let (points, eps) = opts.samples(cell)?;
        // The shrunk prisms within reach of any sample, once per cell, with their plan
        // bounds: each sample takes those whose bounds meet the square of side 2·radius
        // about it.
        let r = opts.radius;
        let reach = AABB::from_corners(
            [cell.min.x - r, cell.min.z - r],
            [cell.max.x + r, cell.max.z + r],
        );
        // Nearest the cell's centre first: each sample's horizon prunes best taking its
        // prisms nearest first, and this order is near enough to each sample's own.
        let centre = Vec2::new(cell.center().x, cell.center().z);
        let mut shrunk: Vec<(Prism, Vec2, Vec2)> = self
            .prism_index
            .locate_in_envelope_intersecting(&reach)
            .filter_map(|e| {
                let unshrunk = &self.prisms[e.data as usize];
                let (lo, hi) = unshrunk.bounds();
                unshrunk.shrunk(eps).map(|o| (o, lo, hi))
            })
            .collect();
        let from_centre =
            |(_, lo, hi): &(Prism, Vec2, Vec2)| (centre.clamp(*lo, *hi) - centre).length_squared();
        shrunk.sort_by_cached_key(|e| ordered(from_centre(e)));
        for p in points {
            if shrunk.iter().any(|(o, _, _)| o.contains(p)) {
                continue;
            }
            let (lo, hi) = (Vec2::new(p.x - r, p.z - r), Vec2::new(p.x + r, p.z + r));
            let near = shrunk
                .iter()
                .filter(|(_, a, b)| a.cmple(hi).all() && lo.cmple(*b).all())
                .map(|(o, _, _)| *o);
            let horizon = Horizon::nearly_ordered(p, near);
            let found: Vec<u32> = self
                .objects
                .locate_with_selection_function(Unhidden {
                    horizon: &horizon,
                    visible: &visible,
                })
                .map(|e| e.data)
                .collect();
            for i in found {
                visible[i as usize] = true;
            }
        }
        Ok((0..visible.len() as u32)
            .filter(|&i| visible[i as usize])
            .collect())
    }
}

/// A key that orders finite non-negative floats as they compare.
fn ordered(x: f32) -> u32 {
    x.to_bits()
}

struct Unhidden<'a> {
    horizon: &'a Horizon,
    visible: &'a [bool],
}

fn aabb(e: &AABB<[f32; 3]>) -> Aabb {
    Aabb {
        min: Vec3::from(e.lower()),
        max: Vec3::from(e.upper()),
    }
}

impl SelectionFunction<Entry> for Unhidden<'_> {
    fn should_unpack_parent(&self, envelope: &AABB<[f32; 3]>) -> bool {
        !self.horizon.hides(&aabb(envelope))
    }

    fn should_unpack_leaf(&self, leaf: &Entry) -> bool {
        !self.visible[leaf.data as usize]
            && !self
                .horizon
                .hides(&aabb(&rstar::RTreeObject::envelope(leaf)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(min: [f32; 3], max: [f32; 3]) -> Aabb {
        Aabb::new(min, max).unwrap()
    }

    #[test]
    fn a_wall_hides_what_is_behind_it_only() {
        let cell = b([0.0, 1.2, 0.0], [10.0, 2.0, 10.0]);
        let wall = b([-50.0, 0.0, 20.0], [60.0, 30.0, 28.0]);
        let behind = b([2.0, 0.0, 40.0], [6.0, 5.0, 44.0]);
        let tall_behind = b([2.0, 0.0, 40.0], [6.0, 80.0, 44.0]);
        let beside = b([200.0, 0.0, 40.0], [204.0, 5.0, 44.0]);
        let front = b([2.0, 0.0, 12.0], [6.0, 5.0, 16.0]);
        let objects = [wall, behind, tall_behind, beside, front];
        let none = || Occluders::aligned(vec![]);
        let occluders = [
            Occluders::aligned(vec![wall]),
            none(),
            none(),
            none(),
            none(),
        ];
        let scene = Scene::new(&objects, &occluders).unwrap();
        assert_eq!(scene.prism_count(), 1);
        let opts = SampleOptions::default();
        assert_eq!(
            scene.visible_from(&cell, &opts, &[]).unwrap(),
            vec![0, 2, 3, 4]
        );
        // What a ray saw is kept untested, and nothing else changes.
        let told = scene.visible_from(&cell, &opts, &[1, 3]).unwrap();
        assert_eq!(told, vec![0, 1, 2, 3, 4]);
        assert!(scene.visible_from(&cell, &opts, &[3, 1]).is_err());
        assert!(scene.visible_from(&cell, &opts, &[9]).is_err());
        // Occluders further than the radius are not used.
        let short = SampleOptions {
            radius: 5.0,
            ..opts
        };
        assert_eq!(
            scene.visible_from(&cell, &short, &[]).unwrap(),
            vec![0, 1, 2, 3, 4]
        );
    }

    #[test]
    fn a_floating_box_is_no_prism() {
        let ground = b([0.0, 0.0, 0.0], [10.0, 10.0, 10.0]);
        let on_it = b([2.0, 10.0, 2.0], [8.0, 20.0, 8.0]);
        let floating = b([20.0, 5.0, 0.0], [30.0, 10.0, 10.0]);
        let overhang = b([-5.0, 10.0, 2.0], [8.0, 20.0, 8.0]);
        let boxes = vec![ground, on_it, floating, overhang];
        let p = prisms(&Occluders::aligned(boxes.clone()), 0.0);
        assert_eq!(p.len(), 2);
        assert_eq!(p[1].top, 20.0);
        // The same boxes in a frame turned a quarter: the same prisms, turned.
        let turned = Occluders {
            origin: Vec2::ZERO,
            axis: Vec2::Y,
            boxes,
        };
        let q = prisms(&turned, 0.0);
        assert_eq!(q.len(), 2);
        assert!(
            (q[0].centre - Vec2::new(-5.0, 5.0)).length() < 1e-5,
            "{q:?}"
        );
        assert!(
            (q[1].bounds().0 - Vec2::new(-8.0, 2.0)).length() < 1e-5,
            "{q:?}"
        );
        // And with the frame's origin moved: moved with it.
        let moved = Occluders {
            origin: Vec2::new(1000.0, -2000.0),
            ..turned
        };
        let r = prisms(&moved, 0.0);
        assert!(
            (r[0].centre - Vec2::new(995.0, -1995.0)).length() < 1e-3,
            "{r:?}"
        );
    }

    #[test]
    fn bad_input_is_refused() {
        let ok = b([0.0; 3], [1.0; 3]);
        assert!(Scene::new(&[ok], &[]).is_err());
        let nan = Aabb {
            min: Vec3::splat(f32::NAN),
            max: Vec3::ONE,
        };
        let none = || Occluders::aligned(vec![]);
        assert!(Scene::new(&[nan], &[none()]).is_err());
        for axis in [Vec2::ZERO, Vec2::NAN, Vec2::new(1.0, 1.0)] {
            let bad = Occluders {
                origin: Vec2::ZERO,
                axis,
                boxes: vec![],
            };
            assert!(Scene::new(&[ok], &[bad]).is_err(), "{axis}");
        }
        let far = Occluders {
            origin: Vec2::new(f32::INFINITY, 0.0),
            ..Occluders::aligned(vec![])
        };
        assert!(Scene::new(&[ok], &[far]).is_err());
        assert!(Scene::new(&[ok], &[Occluders::aligned(vec![nan])]).is_err());
        let scene = Scene::new(&[ok], &[none()]).unwrap();
        let opts = SampleOptions::default();
        assert!(scene.visible_from(&nan, &opts, &[]).is_err());
        for bad in [
            SampleOptions {
                spacing: 0.0,
                ..opts
            },
            SampleOptions {
                spacing: f32::NAN,
                ..opts
            },
            SampleOptions {
                radius: -1.0,
                ..opts
            },
        ] {
            assert!(scene.visible_from(&ok, &bad, &[]).is_err());
        }
    }
}

#[cfg(test)]
mod city_tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::visibility::cells::{ViewcellGrid, DEFAULT_EYE_RANGE};
    use crate::visibility::intersect::{ray_triangle_distance, triangles};
    use crate::visibility::occluder::occluders;

    /// Rays from random walkable points of random cells of a small generated city: the
    /// first object each ray meets is in the cell's PVS.
    #[test]
    fn no_object_a_ray_from_inside_the_cell_meets_is_dropped() {
        let objects = crate::visibility::tests::city(64);
        let boxes: Vec<Aabb> = objects
            .iter()
            .map(|o| {
                let (lo, hi) = o.mesh.bounds();
                Aabb::new(lo, hi).unwrap()
            })
            .collect();
        let occluders: Vec<Occluders> = objects.iter().map(|o| occluders(&o.mesh)).collect();
        let triangles: Vec<Vec<[Vec3; 3]>> = objects.iter().map(|o| triangles(&o.mesh)).collect();
        let scene = Scene::new(&boxes, &occluders).unwrap();
        let city = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
        let grid = ViewcellGrid::new(&city, 10.0, DEFAULT_EYE_RANGE).unwrap();
        let cells = grid.walkable(&boxes);
        assert!(cells.len() > 20);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut rays, mut hidden_total, mut hits) = (0, 0, 0);
        for _ in 0..60 {
            let cell = cells[rng.gen_range(0..cells.len())];
            let pvs = scene
                .visible_from(&cell.bounds, &SampleOptions::default(), &[])
                .unwrap();
            hidden_total += objects.len() - pvs.len();
            for _ in 0..100 {
                let f = Vec3::new(rng.gen(), rng.gen(), rng.gen());
                let p = cell.bounds.min + f * cell.bounds.extent();
                if boxes.iter().any(|b| b.contains_point(p)) {
                    continue; // not where a walker stands
                }
                let dir = loop {
                    let d = Vec3::new(
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(-1.0..1.0),
                    );
                    if (0.01..1.0).contains(&d.length_squared()) {
                        break d.normalize();
                    }
                };
                rays += 1;
                let mut nearest: Option<(f32, usize)> = None;
                for (i, tris) in triangles.iter().enumerate() {
                    for t in tris {
                        if let Some(d) = ray_triangle_distance(p, dir, t) {
                            if nearest.is_none_or(|(n, _)| d < n) {
                                nearest = Some((d, i));
                            }
                        }
                    }
                }
                if let Some((_, i)) = nearest {
                    hits += 1;
                    assert!(
                        pvs.binary_search(&(i as u32)).is_ok(),
                        "cell {}: a ray from {p} along {dir} meets object {i}, not in its PVS",
                        cell.id
                    );
                }
            }
        }
        assert!(rays > 3000 && hits > 1500, "{rays} rays, {hits} hits");
        // The test is not empty: occluders do hide objects.
        assert!(hidden_total > 0, "nothing was ever hidden");
    }
}
