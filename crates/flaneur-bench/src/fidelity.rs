//! How faithful a walk mode's pictures are (the thesis's Figs. 5.26 and 6.6, as
//! numbers): each frame of a walk is drawn twice, once with what the mode selected (its
//! object buffer after culling, at the detail it chose) and once at full detail with
//! every object in the view frustum read from the database, and the two images are
//! compared: PSNR over the RGB channels and the share of pixels that differ, beside the
//! triangles each drew.
//!
//! With LOD selection (`lod_tau`), each object the mode drew is at the level the walk's
//! LOD selection chose ([`flaneur::walk::lod_select`]); without it, REVIEW and BOX draw
//! what they loaded at full detail, and their pictures differ from the reference only
//! where an object in view was not yet loaded (a visual miss). The PVS walk draws its
//! current viewcell's PVS: its pictures also lose what the precomputation judged
//! hidden (and got wrong), and everything while the eye is outside every cell. VISUAL
//! draws what the HDoV-tree found, each object at the level its DoV deserves and the
//! groups it stopped at as their nodes' internal LODs: its pictures lose what those
//! coarser shapes change. The scene tree's traversals (VSC, PB, CONV) draw what they
//! chose, at the representation they chose.
//!
//! The full-detail pictures may come from another file holding the same city
//! ([`run_against`]): a format-version-2 file's walk, its meshes quantised, is then
//! judged against its version-1 twin's raw floats, so that what the codec changes shows
//! beside what the mode's selection does. The two files are checked to hold the same
//! objects first ([`same_city`]).

use std::path::Path;

use crate::plot::{line_plot, LinePlot, Series};
use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::geom::{Aabb, Camera};
use flaneur::path::CameraPath;
use flaneur::walk::lod_select::LodCounts;
use flaneur::walk::{self, FrameSink, Frames, ObjectBuffer, Playback, Selection, WalkConfig};
use flaneur_render::{Frame, FrameWriter, Gpu, GpuMeshes, Offscreen};

/// The PSNR the quantised geometry of format version 2 is held to against version 1's
/// (the codec issue's "pictures unchanged by quantisation": every frame identical or
/// above it), dB; the summary counts the frames either side.
pub const QUANTISATION_PSNR_DB: f64 = 50.0;

/// The file the full-detail reference pictures are drawn from, when it is not the walked
/// database: another file holding the same city.
#[derive(Clone, Copy)]
pub struct Reference<'a> {
    /// The reference's database.
    pub db: &'a Database,
    /// How the report names it: the file or URL as given.
    pub name: &'a str,
}

/// One frame's comparison.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FidelityRow {
    pub frame: usize,
    /// Triangles the mode drew, and the full-detail reference.
    pub triangles: u64,
    pub reference_triangles: u64,
    /// Peak signal to noise ratio of the mode's image against the reference, dB;
    /// infinite where they are the same.
    pub psnr: f64,
    /// Share of pixels whose colour differs.
    pub differ: f64,
    /// Objects the mode drew coarser than full detail.
    pub coarse: usize,
}

/// How the experiment draws: the image size, and the LOD selection's threshold (a
/// fraction of the viewport; `None`: the mode's objects at full detail).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drawing {
    pub width: u32,
    pub height: u32,
    pub lod_tau: Option<f32>,
}

/// What the experiment measured.
#[derive(Clone, Debug)]
pub struct FidelityReport {
    pub mode: String,
    pub width: u32,
    pub height: u32,
    pub adapter: String,
    pub lod_tau: Option<f32>,
    /// The file the full-detail pictures came from, when not the walked database.
    pub reference: Option<String>,
    /// What LOD selection read, when it ran.
    pub lod: Option<LodCounts>,
    pub rows: Vec<FidelityRow>,
}

/// PSNR (dB) and the share of differing pixels of RGBA images `a` and `b` of the same
/// size; alpha is not compared.
///
/// ```
/// use flaneur_bench::fidelity::compare;
/// let a = [10u8, 20, 30, 255, 0, 0, 0, 255];
/// let (psnr, differ) = compare(&a, &a).unwrap();
/// assert!(psnr.is_infinite() && differ == 0.0);
/// let b = [10u8, 20, 31, 255, 0, 0, 0, 255];
/// let (psnr, differ) = compare(&a, &b).unwrap();
/// assert!((psnr - 10.0 * (255f64.powi(2) / (1.0 / 6.0)).log10()).abs() < 1e-9);
/// assert_eq!(differ, 0.5);
/// ```
pub fn compare(a: &[u8], b: &[u8]) -> Result<(f64, f64)> {
    if a.len() != b.len() || !a.len().is_multiple_of(4) || a.is_empty() {
        return Err(Error::Invalid(format!(
            "images of {} and {} bytes cannot be compared",
            a.len(),
            b.len()
        )));
    }
    let (mut squares, mut differ) = (0f64, 0usize);
    for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        let mut any = false;
        for k in 0..3 {
            let d = p[k] as f64 - q[k] as f64;
            squares += d * d;
            any |= d != 0.0;
        }
        differ += any as usize;
    }
    let pixels = a.len() / 4;
    let mse = squares / (3 * pixels) as f64;
    let psnr = if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255f64 * 255.0 / mse).log10()
    };
    Ok((psnr, differ as f64 / pixels as f64))
}

/// Checks that `reference` holds the city `db` holds, before any picture is drawn: the
/// same object count, triangle count and bounds, and, read from both R-trees' leaves,
/// the same ids, each with the same triangle count, kind and box. Boxes and bounds are
/// compared within 1 mm plus 1e-4 of the object's (the city's) size along each axis:
/// quantised positions move a vertex by at most half a 16-bit step of its object's box
/// (1/131,070 of it), and a box built from them by as much, while another city's boxes
/// differ by metres. The error names the first thing that differs.
///
/// ```
/// # fn main() -> flaneur::error::Result<()> {
/// let dir = tempfile::tempdir().unwrap();
/// let build = |objects: u64, name: &str| -> flaneur::error::Result<flaneur::Database> {
///     let scene = dir.path().join(format!("{name}.scene"));
///     let config = citygen::CityConfig { objects, seed: 1, ..Default::default() };
///     citygen::write_city(&config, &scene)?;
///     let db = dir.path().join(format!("{name}.flaneur"));
///     let opts = flaneur::BuildOptions { lod: None, ..Default::default() };
///     flaneur::build_from_scene(&scene, &db, &opts)?;
///     flaneur::Database::open(&db)
/// };
/// let (a, b, c) = (build(20, "a")?, build(20, "b")?, build(30, "c")?);
/// flaneur_bench::fidelity::same_city(&a, &b)?;
/// let e = flaneur_bench::fidelity::same_city(&a, &c).unwrap_err();
/// assert!(e.to_string().contains("objects: 20 in the database, 30 in the reference"), "{e}");
/// # Ok(())
/// # }
/// ```
pub fn same_city(db: &Database, reference: &Database) -> Result<()> {
    let differ = |what: &str, mine: String, theirs: String| {
        Err(Error::Invalid(format!(
            "the reference holds another city than the walked database: {what} \
             {mine} in the database, {theirs} in the reference"
        )))
    };
    if db.objects() != reference.objects() {
        let (a, b) = (db.objects(), reference.objects());
        return differ("objects:", a.to_string(), b.to_string());
    }
    if db.triangles() != reference.triangles() {
        let (a, b) = (db.triangles(), reference.triangles());
        return differ("triangles:", a.to_string(), b.to_string());
    }
    if db.objects() == 0 {
        return Ok(());
    }
    let (a, b) = (db.bounds(), reference.bounds());
    if !boxes_agree(&a, &b) {
        return differ("bounds:", show(&a), show(&b));
    }
    let leaves = |d: &Database| -> Result<Vec<flaneur::rtree::ObjectEntry>> {
        let mut all = d.range(&d.bounds())?.objects;
        all.sort_unstable_by_key(|o| o.id);
        Ok(all)
    };
    let (mine, theirs) = (leaves(db)?, leaves(reference)?);
    if mine.len() != theirs.len() {
        let (a, b) = (mine.len(), theirs.len());
        return differ("objects in the R-tree:", a.to_string(), b.to_string());
    }
    for (o, r) in mine.iter().zip(&theirs) {
        if o.id != r.id {
            // Sorted by id, the smaller of the two is missing from the other file.
            let (id, only) = if o.id < r.id {
                (o.id, "the database")
            } else {
                (r.id, "the reference")
            };
            return Err(Error::Invalid(format!(
                "the reference holds another city than the walked database: object {id} is \
                 in {only} only"
            )));
        }
        if o.triangles != r.triangles || o.kind != r.kind {
            return differ(
                &format!("object {}'s triangles and kind:", o.id),
                format!("{} of kind {}", o.triangles, o.kind),
                format!("{} of kind {}", r.triangles, r.kind),
            );
        }
        if !boxes_agree(&o.bounds, &r.bounds) {
            return differ(
                &format!("object {}'s box:", o.id),
                show(&o.bounds),
                show(&r.bounds),
            );
        }
    }
    Ok(())
}

/// Whether two boxes are the same but for quantisation: each corner's coordinates within
/// 1 mm plus 1e-4 of the larger box's size along that axis (see [`same_city`]).
fn boxes_agree(a: &Aabb, b: &Aabb) -> bool {
    let size = a.extent().max(b.extent());
    let tolerance = glam::Vec3::splat(1e-3) + 1e-4 * size;
    let (lo, hi) = ((a.min - b.min).abs(), (a.max - b.max).abs());
    lo.cmple(tolerance).all() && hi.cmple(tolerance).all()
}

/// A box as its two corners, in metres to the millimetre.
fn show(b: &Aabb) -> String {
    format!(
        "({:.3}, {:.3}, {:.3})–({:.3}, {:.3}, {:.3})",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    )
}

/// The sink that draws each frame twice and compares.
struct Twice<'a> {
    /// Where the full-detail pictures' objects are read.
    source: &'a Database,
    gpu: &'a Gpu,
    mode: FrameWriter<'a>,
    reference: Offscreen,
    resident: GpuMeshes,
    rows: Vec<FidelityRow>,
}

impl Twice<'_> {
    /// The full-detail picture: every object whose box meets the frustum, read from the
    /// database; the GPU keeps only the current frame's.
    fn reference(&mut self, camera: &Camera) -> Result<(Frame, u64)> {
        let inside = self.source.in_view(camera)?;
        let keep: std::collections::HashSet<u64> = inside.iter().map(|o| o.id).collect();
        self.resident.retain(|(id, _)| keep.contains(&id));
        for o in &inside {
            if self.resident.get((o.id, 0)).is_none() {
                self.resident
                    .upload(self.gpu, (o.id, 0), &self.source.mesh(o)?)?;
            }
        }
        let ids: Vec<_> = inside.iter().map(|o| (o.id, 0)).collect();
        let frame = self
            .reference
            .render_camera(self.gpu, camera, &self.resident, &ids)?;
        Ok((frame, inside.iter().map(|o| o.triangles as u64).sum()))
    }
}

impl FrameSink for Twice<'_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut Selection<'_>,
    ) -> Result<()> {
        let mine = self.mode.draw(camera, buffer, selection)?;
        let (reference, reference_triangles) = self.reference(camera)?;
        let (psnr, differ) = compare(&mine.rgba, &reference.rgba)?;
        self.rows.push(FidelityRow {
            frame: index,
            triangles: *self.mode.times.triangles.last().unwrap_or(&0),
            reference_triangles,
            psnr,
            differ,
            coarse: *self.mode.times.coarse.last().unwrap_or(&0),
        });
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        self.mode.lod_tau()
    }

    fn lod_settled(&self) -> bool {
        self.mode.lod_settled()
    }

    fn lod_adapt_ahead(&self) -> bool {
        self.mode.lod_adapt_ahead()
    }
}

/// Walks `path` through `db` with `walk` (`mode` names it in the report), drawing each
/// frame twice on `gpu` as `drawing` says, the full-detail pictures from `db` too.
pub fn run(
    db: &Database,
    gpu: &Gpu,
    path: &CameraPath,
    walk: &WalkConfig,
    mode: &str,
    drawing: &Drawing,
    progress: impl FnMut(usize),
) -> Result<FidelityReport> {
    draw_twice(db, None, gpu, path, (walk, mode), drawing, progress)
}

/// [`run`] with the full-detail pictures drawn from `reference`, which must hold the
/// same city ([`same_city`], checked before anything is drawn): the mode's pictures
/// from `db`, each frame's reference from the other file.
pub fn run_against(
    db: &Database,
    reference: Reference<'_>,
    gpu: &Gpu,
    path: &CameraPath,
    (walk, mode): (&WalkConfig, &str),
    drawing: &Drawing,
    progress: impl FnMut(usize),
) -> Result<FidelityReport> {
    same_city(db, reference.db).map_err(|e| match e {
        Error::Invalid(m) => Error::Invalid(format!("{}: {m}", reference.name)),
        e => e,
    })?;
    draw_twice(
        db,
        Some(reference),
        gpu,
        path,
        (walk, mode),
        drawing,
        progress,
    )
}

fn draw_twice(
    db: &Database,
    reference: Option<Reference<'_>>,
    gpu: &Gpu,
    path: &CameraPath,
    (walk, mode): (&WalkConfig, &str),
    drawing: &Drawing,
    mut progress: impl FnMut(usize),
) -> Result<FidelityReport> {
    let (width, height) = (drawing.width, drawing.height);
    // Both pictures' ground and height colours from the walked database's bounds, so
    // that a reference file's pictures differ only in the objects drawn.
    let bounds = db.bounds();
    let far = walk.far();
    let mut full = Offscreen::new(gpu, width, height)?;
    full.set_ground(gpu, &bounds, far);
    let mut sink = Twice {
        source: reference.map_or(db, |r| r.db),
        gpu,
        mode: match drawing.lod_tau {
            Some(tau) => {
                FrameWriter::drawing(gpu, (width, height), (&bounds, far))?.with_lod_tau(tau)?
            }
            None => FrameWriter::drawing(gpu, (width, height), (&bounds, far))?,
        },
        reference: full,
        resident: GpuMeshes::default(),
        rows: Vec::with_capacity(path.poses.len()),
    };
    // The figures are the sink's rows, not the walk's report. The viewer, which holds
    // the sink, ends with the statement, so that the rows can be taken below.
    walk::run(
        db,
        walk,
        &mut Playback::path(path)
            .drawn_by(&mut sink)
            .with_progress(&mut progress),
        Frames::Keep,
    )?;
    Ok(FidelityReport {
        mode: mode.into(),
        width,
        height,
        adapter: format!("{} ({:?})", gpu.adapter.name, gpu.adapter.backend),
        lod_tau: drawing.lod_tau,
        reference: reference.map(|r| r.name.to_string()),
        lod: sink.mode.times.lod,
        rows: sink.rows,
    })
}

impl FidelityReport {
    /// The mean share of pixels that differ from the reference over the frames (0
    /// when there are none).
    pub fn mean_differ(&self) -> f64 {
        self.rows.iter().map(|r| r.differ).sum::<f64>() / self.rows.len().max(1) as f64
    }

    /// The frame of lowest PSNR and its PSNR, dB (infinite: identical); `None` without
    /// frames.
    pub fn worst(&self) -> Option<(usize, f64)> {
        self.rows
            .iter()
            .map(|r| (r.frame, r.psnr))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// Frames identical to the reference, the others at `db` dB or more, and those below.
    pub fn frames_by_psnr(&self, db: f64) -> (usize, usize, usize) {
        let same = self.rows.iter().filter(|r| r.psnr.is_infinite()).count();
        let above = (self.rows.iter())
            .filter(|r| r.psnr.is_finite() && r.psnr >= db)
            .count();
        (same, above, self.rows.len() - same - above)
    }
}

impl Report for FidelityReport {
    fn name(&self) -> &'static str {
        "fidelity"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from(
            "frame,triangles,reference_triangles,psnr_db,differing_pixels,coarse_objects\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{},{:.6},{}\n",
                r.frame,
                r.triangles,
                r.reference_triangles,
                if r.psnr.is_finite() {
                    format!("{:.3}", r.psnr)
                } else {
                    "inf".into()
                },
                r.differ,
                r.coarse
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let n = self.rows.len().max(1) as f64;
        let same = self.rows.iter().filter(|r| r.psnr.is_infinite()).count();
        let finite: Vec<f64> = self
            .rows
            .iter()
            .map(|r| r.psnr)
            .filter(|p| p.is_finite())
            .collect();
        let worst = finite.iter().copied().fold(f64::INFINITY, f64::min);
        let mean_differ = self.mean_differ();
        let max_differ = self.rows.iter().map(|r| r.differ).fold(0.0, f64::max);
        let tri = self.rows.iter().map(|r| r.triangles as f64).sum::<f64>() / n;
        let ref_tri = self
            .rows
            .iter()
            .map(|r| r.reference_triangles as f64)
            .sum::<f64>()
            / n;
        let (walked, source) = match &self.reference {
            Some(r) => (
                " from the walked file",
                format!(" from {r}, checked to hold the same city"),
            ),
            None => ("", String::new()),
        };
        let mut s = format!(
            "# fidelity — {} against full detail{}\n\n{} frames of {} × {} on {}; each drawn with \
             the mode's selection{walked} and with every object in the frustum at full \
             detail{source}.\n\n",
            self.mode,
            self.reference
                .as_ref()
                .map_or(String::new(), |r| format!(" from {r}")),
            self.rows.len(),
            self.width,
            self.height,
            self.adapter
        );
        let lod = match (self.lod_tau, self.lod) {
            (Some(tau), Some(c)) => format!(
                "The mode's objects are drawn at the level LOD selection chose under τ = {tau} \
                 of the viewport: {} draws coarser than full detail, {} levels read; {} draws \
                 refined view by view ({} vertex splits and edge collapses); {} pages.\n\n",
                c.coarse_draws, c.levels_read, c.refined_draws, c.refine_ops, c.pages
            ),
            _ => "The mode's objects are drawn at full detail.\n\n".into(),
        };
        s.push_str(&lod);
        s.push_str("| | value |\n|---|---|\n");
        s.push_str(&format!(
            "| frames identical to the reference | {same} ({:.1} %) |\n",
            100.0 * same as f64 / n
        ));
        if finite.is_empty() {
            s.push_str("| PSNR of the others, mean / worst | — |\n");
        } else {
            s.push_str(&format!(
                "| PSNR of the others, mean / worst | {:.1} / {:.1} dB (frame {}) |\n",
                finite.iter().sum::<f64>() / finite.len() as f64,
                worst,
                self.worst().map_or(0, |w| w.0)
            ));
        }
        let (_, above, below) = self.frames_by_psnr(QUANTISATION_PSNR_DB);
        s.push_str(&format!(
            "| the others at {QUANTISATION_PSNR_DB} dB or more / below | {above} / {below} |\n"
        ));
        s.push_str(&format!(
            "| pixels that differ, mean / most | {:.3} % / {:.3} % |\n",
            100.0 * mean_differ,
            100.0 * max_differ
        ));
        s.push_str(&format!(
            "| triangles drawn, mean: mode / reference | {tri:.0} / {ref_tri:.0} |\n"
        ));
        s
    }

    /// PSNR per frame (identical frames at the plot's top), and the differing pixels
    /// beside the triangles drawn.
    fn plot(&self, dir: &Path) -> Result<()> {
        let cap = self
            .rows
            .iter()
            .map(|r| r.psnr)
            .filter(|p| p.is_finite())
            .fold(40.0, f64::max)
            + 10.0;
        line_plot(
            &dir.join("fidelity-psnr.png"),
            &LinePlot {
                title: format!(
                    "PSNR against full detail, {} (identical frames drawn at {cap:.0} dB)",
                    self.mode
                ),
                x_label: "frame".into(),
                y_label: "PSNR (dB)".into(),
                series: vec![Series {
                    name: self.mode.clone(),
                    points: self
                        .rows
                        .iter()
                        .map(|r| (r.frame as f64, r.psnr.min(cap)))
                        .collect(),
                }],
            },
        )?;
        let most = self
            .rows
            .iter()
            .map(|r| r.reference_triangles)
            .max()
            .unwrap_or(1)
            .max(1) as f64;
        line_plot(
            &dir.join("fidelity-pixels.png"),
            &LinePlot {
                title: format!("Pixels that differ and triangles drawn, {}", self.mode),
                x_label: "frame".into(),
                y_label: "share".into(),
                series: vec![
                    Series {
                        name: "pixels that differ".into(),
                        points: self
                            .rows
                            .iter()
                            .map(|r| (r.frame as f64, r.differ))
                            .collect(),
                    },
                    Series {
                        name: format!("triangles drawn / {most:.0}"),
                        points: self
                            .rows
                            .iter()
                            .map(|r| (r.frame as f64, r.triangles as f64 / most))
                            .collect(),
                    },
                ],
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_agree_within_quantisation_not_beyond() {
        let b = Aabb::new([100.0, 0.0, -50.0], [112.5, 40.0, -37.0]).unwrap();
        // Half a 16-bit step of a 40 m tall box: 0.3 mm.
        let q = Aabb::new([100.0, 0.0, -50.0], [112.5, 40.0003, -37.0]).unwrap();
        assert!(boxes_agree(&b, &q) && boxes_agree(&q, &b));
        // Another building's box is metres away; a centimetre is already too much.
        let moved = Aabb::new([100.0, 0.0, -50.0], [112.51, 40.0, -37.0]).unwrap();
        assert!(!boxes_agree(&b, &moved));
    }
}
