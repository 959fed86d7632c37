//! What a build's options imply for its inputs, checked before its slow steps.
//!
//! `BuildOptions::validate` checks each option alone. What a visibility option costs
//! depends on the city too: a viewcell size or a sample spacing fine for a street is
//! trillions of cells or sample points over a city. So a build with visibility makes one
//! pass over its objects first ([`Survey`]: their boxes, their meshes' bytes), and
//! before its LODs or anything else slow [`check_costs`] puts the counts
//! ([`VisibilityOptions::cost`]) and the memory they imply against the limits and
//! against the memory available (`MemAvailable` of `/proc/meminfo`, where it can be
//! read): a refusal names the option, its value and what it would need.
//!
//! [`VisibilityOptions::cost`]: crate::visibility::VisibilityOptions::cost

use std::mem::size_of;

use super::BuildOptions;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::hdov::node::capacity;
use crate::hdov::vd::VENTRY_LEN;
use crate::hdov::{HdovOptions, Scheme};
use crate::scene::Mesh;
use crate::store::PAGE_HEADER_LEN;
use crate::visibility::{shown, walkable_cells, VisibilityCost, VisibilityOptions};

/// What the one pass over a build's objects learns for [`check_costs`]; it records
/// nothing for a build without visibility, whose costs do not depend on the city.
pub(super) struct Survey {
    on: bool,
    /// Each valid object box (a box the build refuses later is left out here).
    boxes: Vec<Aabb>,
    /// Bytes of the meshes, as the precomputation keeps them all.
    mesh_bytes: u64,
    /// Their triangles, each of which the ray scene holds.
    triangles: u64,
}

/// What the checked work is: a whole build, one shard of the visibility, or a build
/// whose visibility is merged from shards (which casts nothing).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Work {
    Build,
    Shard,
    Merge,
}

impl Work {
    /// A build's work: a merge where it takes its visibility from shards.
    pub fn of_build(merging: bool) -> Work {
        if merging {
            Work::Merge
        } else {
            Work::Build
        }
    }
}

impl Survey {
    /// A survey for a build under `opts`.
    pub fn new(opts: &BuildOptions) -> Survey {
        Survey {
            on: opts.visibility.is_some(),
            boxes: Vec::new(),
            mesh_bytes: 0,
            triangles: 0,
        }
    }

    /// Whether the build needs the pass at all.
    pub fn wanted(&self) -> bool {
        self.on
    }

    /// Takes one object's mesh into account.
    pub fn add(&mut self, mesh: &Mesh) {
        if !self.on {
            return;
        }
        let (lo, hi) = mesh.bounds();
        if let Ok(b) = Aabb::new(lo, hi) {
            self.boxes.push(b);
        }
        self.mesh_bytes += (mesh.positions.len() * size_of::<[f32; 3]>()
            + mesh.normals.len() * size_of::<[f32; 3]>()
            + mesh.indices.len() * size_of::<u32>()) as u64;
        self.triangles += (mesh.indices.len() / 3) as u64;
    }
}

/// Checks what `opts` imply over the objects `survey` saw, for `work`: the grid's
/// cells, the samples per cell and the memory of the precomputation (and of the
/// HDoV-tree's V-pages) against the memory available. An error names the option.
pub(super) fn check_costs(opts: &BuildOptions, survey: &Survey, work: Work) -> Result<()> {
    check_within(opts, survey, work, crate::memory::available)
}

/// [`check_costs`] against the bytes `available` says (asked only when needed).
fn check_within(
    opts: &BuildOptions,
    survey: &Survey,
    work: Work,
    available: impl FnOnce() -> Option<u64>,
) -> Result<()> {
    let Some(v) = opts.visibility.as_ref().filter(|_| survey.on) else {
        return Ok(());
    };
    let city = survey.boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
    if city.is_empty() {
        // No object with a box: the build refuses its inputs with its own words.
        return Ok(());
    }
    let objects = survey.boxes.len() as u64;
    let cost = v.cost(&city, objects, None)?;
    let Some(available) = available() else {
        return Ok(());
    };
    if needs(opts, v, survey, &cost, work).total() <= available {
        return Ok(());
    }
    // Over on the grid's every cell: count the walkable ones, the precomputation's own.
    let walkable = walkable_cells(v, &survey.boxes)?;
    let cost = v.cost(&city, objects, Some(walkable))?;
    let need = needs(opts, v, survey, &cost, work);
    if need.total() <= available {
        return Ok(());
    }
    Err(Error::Invalid(need.refusal(v, &city, &cost, available)))
}

/// The parts of a build's memory that a check counts, in bytes, each with the options
/// that size it.
struct Needs {
    parts: Vec<(u64, &'static str, String)>,
}

/// What `work` under `opts` (its visibility `v`) holds at least over the city of
/// `survey` with `cost`.
fn needs(
    opts: &BuildOptions,
    v: &VisibilityOptions,
    survey: &Survey,
    cost: &VisibilityCost,
    work: Work,
) -> Needs {
    let mut parts = vec![(
        cost.cell_bytes,
        "the viewcells' lists",
        format!("--cell-size {}", shown(v.cell_size)),
    )];
    // The meshes are kept for the rays (or the shards' fingerprint), with each
    // triangle's three corners again in the ray scene.
    let rays = if work == Work::Merge {
        0
    } else {
        survey.triangles * size_of::<[[f32; 3]; 3]>() as u64
    };
    parts.push((
        survey.mesh_bytes + rays,
        "the meshes kept for the rays",
        "the inputs".into(),
    ));
    if work != Work::Merge {
        parts.push((
            cost.dov_bytes,
            "the DoV's buffers",
            format!(
                "--cell-size {}, --dov-resolution {}",
                shown(v.cell_size),
                v.resolution
            ),
        ));
        parts.push((
            cost.sample_bytes,
            "the sample points",
            format!("--sample-spacing {}", shown(v.samples.spacing)),
        ));
    }
    if let (Some(h), false) = (&opts.hdov, work == Work::Shard) {
        parts.push((
            vpage_bytes(
                opts,
                &h.schemes,
                h,
                cost.walkable,
                survey.boxes.len() as u64,
            ),
            "the HDoV-tree's V-pages",
            format!("--hdov, --cell-size {}", shown(v.cell_size)),
        ));
    }
    Needs { parts }
}

impl Needs {
    fn total(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |t, (b, _, _)| t.saturating_add(*b))
    }

    /// The refusal: what the work needs, what there is, and its largest part.
    fn refusal(
        &self,
        v: &VisibilityOptions,
        city: &Aabb,
        cost: &VisibilityCost,
        available: u64,
    ) -> String {
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        let (bytes, what, options) = self
            .parts
            .iter()
            .max_by_key(|p| p.0)
            .expect("at least the cells");
        let e = city.extent();
        format!(
            "visibility over this city ({:.0} × {:.0} m, {} walkable viewcells of {} m, {} sample \
             points each) needs at least {:.0} MiB, more than the {:.0} MiB of memory available; \
             the most, {:.0} MiB, is {what} ({options})",
            e.x,
            e.z,
            cost.walkable,
            shown(v.cell_size),
            cost.samples_per_cell,
            mib(self.total()),
            mib(available),
            mib(*bytes)
        )
    }
}

/// Bytes the largest of the HDoV-tree's `schemes` holds at least while it is encoded
/// for `walkable` cells over `objects` objects: the horizontal scheme a V-page of at
/// least one entry for every node and cell, the vertical one a pointer for each; the
/// nodes counted are the leaves alone.
fn vpage_bytes(
    opts: &BuildOptions,
    schemes: &[Scheme],
    hdov: &HdovOptions,
    walkable: u64,
    objects: u64,
) -> u64 {
    let max = capacity(opts.page_size.saturating_sub(PAGE_HEADER_LEN)).max(2);
    let cap = hdov.node_capacity(max, opts.page_size).unwrap_or(max) as u64;
    let leaves = objects.div_ceil(cap);
    let per = |s: &Scheme| match s {
        Scheme::Horizontal => VENTRY_LEN as u64,
        Scheme::Vertical => size_of::<u32>() as u64,
        Scheme::Indexed => 0,
    };
    let widest = schemes.iter().map(per).max().unwrap_or(0);
    walkable.saturating_mul(leaves).saturating_mul(widest)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_horizontal_scheme_costs_a_vpage_per_node_and_cell() {
        let opts = BuildOptions::default();
        let all = HdovOptions::default();
        let horizontal = vpage_bytes(&opts, &[Scheme::Horizontal], &all, 1000, 10_000);
        let vertical = vpage_bytes(&opts, &[Scheme::Vertical], &all, 1000, 10_000);
        assert_eq!(horizontal, 2 * vertical);
        assert_eq!(vpage_bytes(&opts, &[Scheme::Indexed], &all, 1000, 10_000), 0);
        assert_eq!(
            vpage_bytes(&opts, &all.schemes, &all, 1000, 10_000),
            horizontal
        );
        // Leaves of 10 entries rather than a page's 72: 7.2 times the nodes.
        let ten = HdovOptions {
            fanout: Some(10),
            ..HdovOptions::default()
        };
        let leaves = |o: &HdovOptions| vpage_bytes(&opts, &[Scheme::Vertical], o, 1, 10_000) / 4;
        assert_eq!((leaves(&all), leaves(&ten)), (139, 1000));
    }

    /// A survey of boxes, each given by its two corners.
    fn survey_of(opts: &BuildOptions, boxes: &[([f32; 3], [f32; 3])]) -> Survey {
        let mut survey = Survey::new(opts);
        for &(lo, hi) in boxes {
            survey.add(&Mesh {
                positions: vec![lo, hi],
                ..Mesh::default()
            });
        }
        survey
    }

    #[test]
    fn memory_is_refused_on_the_walkable_cells_naming_the_largest_part() {
        let opts = BuildOptions {
            visibility: Some(VisibilityOptions {
                cell_size: 1.0,
                ..Default::default()
            }),
            ..BuildOptions::default()
        };
        let mib = |n: u64| move || Some(n << 20);
        // A million one-metre cells, open ground but for a shed in a corner: their
        // lists alone are some 90 MB.
        let open = survey_of(
            &opts,
            &[([0.0; 3], [1000.0, 0.0, 1000.0]), ([0.0; 3], [1.0; 3])],
        );
        let e = check_within(&opts, &open, Work::Build, mib(50))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("MiB of memory available") && e.contains("--cell-size 1"),
            "{e}"
        );
        assert!(e.contains("the viewcells' lists"), "{e}");
        check_within(&opts, &open, Work::Build, mib(1 << 20)).unwrap();
        check_within(&opts, &open, Work::Build, || None).unwrap();
        // The same grid over one building that covers it: no cell is walkable, so
        // nothing is refused although every cell of the grid would not fit.
        let covered = survey_of(&opts, &[([0.0; 3], [1000.0, 30.0, 1000.0])]);
        check_within(&opts, &covered, Work::Build, mib(50)).unwrap();
    }
}
