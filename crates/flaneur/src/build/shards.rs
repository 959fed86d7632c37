//! The long step of a build split across machines: each shard of the viewcells computed
//! by a process of its own into a shard file (`flaneur build --visibility --shard K/N`),
//! then the database built with its visibility merged from the shards (`flaneur
//! merge`): with `--reproducible`, the same bytes as one build on one machine.

use std::path::{Path, PathBuf};

use super::check::{check_costs, Survey, Work};
use super::{model_format, models_build, scene_build, BuildOptions, BuildSummary};
use crate::error::{Error, Result};
use crate::lod::stored::simplify_stored;
use crate::lod::LodOptions;
use crate::progress::{Progress, Step};
use crate::scene::{Mesh, MeshCodec, SceneReader};
use crate::visibility::{precompute_shard, Shard, ShardCells, ShardLod};

/// Computes shard `shard` of the visibility `opts.visibility` asks for, over the objects
/// of `inputs` (one scene file, or model files, as a build takes them), and writes it to
/// `out`; `progress` is told the shard's cells done. Nothing else of a database is made.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let scene = dir.path().join("c.scene");
/// # citygen::write_city(&citygen::CityConfig { objects: 30, landmarks: 0.0, ..Default::default() }, &scene)?;
/// use flaneur::visibility::{Shard, VisibilityOptions};
/// let opts = flaneur::BuildOptions {
///     visibility: Some(VisibilityOptions { cell_size: 20.0, resolution: 16, ..Default::default() }),
///     reproducible: true,
///     ..Default::default()
/// };
/// let progress = flaneur::progress::Silent;
/// let mut parts = Vec::new();
/// for k in 0..2 {
///     let part = dir.path().join(format!("part{k}.shard"));
///     let shard = Shard { index: k, count: 2 };
///     flaneur::build_visibility_shard(&[scene.clone()], &part, &opts, shard, &progress)?;
///     parts.push(part);
/// }
/// let (merged, whole) = (dir.path().join("merged.flaneur"), dir.path().join("whole.flaneur"));
/// flaneur::merge_visibility_shards(&[scene.clone()], &parts, &merged, &opts, &progress)?;
/// flaneur::build_from_scene(&scene, &whole, &opts)?;
/// assert!(std::fs::read(&merged).unwrap() == std::fs::read(&whole).unwrap());
/// # Ok(()) }
/// ```
pub fn build_visibility_shard(
    inputs: &[PathBuf],
    out: &Path,
    opts: &BuildOptions,
    shard: Shard,
    progress: &dyn Progress,
) -> Result<ShardCells> {
    opts.validate()?;
    let v = opts.visibility.as_ref().ok_or_else(|| {
        Error::Invalid("a visibility shard computes visibility: give --visibility too".into())
    })?;
    let objects = input_objects(inputs, opts, progress)?;
    let mut survey = Survey::new(opts);
    objects.iter().for_each(|(_, m)| survey.add(m));
    check_costs(opts, &survey, Work::Shard)?;
    let levels = match &opts.lod {
        Some(lod) => made_levels(&objects, lod, opts.codec),
        None => Vec::new(),
    };
    let lod = shard_lod(opts.lod.as_ref());
    let made = precompute_shard(&objects, &levels, lod, v, shard, &|done, total| {
        progress.update(Step::Visibility, done as u64, Some(total as u64));
    })?;
    progress.finish(Step::Visibility);
    made.write(out)?;
    Ok(made)
}

/// Builds the database of `inputs` as [`build_from_scene_with_progress`] or
/// [`build_from_obj_with_progress`] would, its visibility merged from the shard files
/// `shards` (every shard of one split, computed from these inputs) instead of computed:
/// the visibility settings are the shards', `opts.visibility` is not read. With
/// `opts.reproducible`, the file is byte for byte the one-machine build's. Shards whose
/// DoVs drew far objects through other LOD levels than `opts.lod` makes (or through
/// none where it makes some, `--no-lod`, or the other way round) are refused before any
/// work, naming the shard: the merge could not give the one-machine build's DoVs.
///
/// [`build_from_scene_with_progress`]: crate::build_from_scene_with_progress
/// [`build_from_obj_with_progress`]: crate::build_from_obj_with_progress
pub fn merge_visibility_shards(
    inputs: &[PathBuf],
    shards: &[PathBuf],
    db: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<BuildSummary> {
    let cells = shards
        .iter()
        .map(|p| ShardCells::read(p))
        .collect::<Result<Vec<_>>>()?;
    for (path, shard) in shards.iter().zip(&cells) {
        shard
            .check_lod(shard_lod(opts.lod.as_ref()))
            .map_err(|what| Error::BadInput {
                path: path.clone(),
                what,
            })?;
    }
    let first = cells
        .first()
        .ok_or_else(|| Error::Invalid("no shard file to merge".into()))?;
    let opts = BuildOptions {
        visibility: Some(first.options),
        ..opts.clone()
    };
    match Inputs::of(inputs)? {
        Inputs::Models(files) => models_build(files, db, &opts, progress, Some(&cells)),
        Inputs::Scene(scene) => scene_build(scene, db, &opts, progress, Some(&cells)),
    }
}

/// The objects of `inputs` in id order, as a build of them keeps them for visibility.
fn input_objects(
    inputs: &[PathBuf],
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<(u64, Mesh)>> {
    match Inputs::of(inputs)? {
        Inputs::Models(files) => {
            let models = super::load_models(files, opts)?;
            Ok((0u64..).zip(models.meshes).collect())
        }
        Inputs::Scene(scene) => {
            let reader = SceneReader::open(scene)?;
            let total = reader.object_count();
            let mut objects = Vec::with_capacity(total.min(10_000_000) as usize);
            for object in reader {
                let object = object?;
                objects.push((object.id, object.mesh));
                progress.update(Step::Objects, objects.len() as u64, Some(total));
            }
            progress.finish(Step::Objects);
            objects.sort_unstable_by_key(|(id, _)| *id);
            Ok(objects)
        }
    }
}

/// Each object's coarse levels with their errors, finest first, made as a whole build
/// makes and stores them and reads them back (`lod::stored::simplify_stored`: quantised
/// by meshoptimizer's codec), so that a shard draws far objects as the whole build's DoV
/// does: none for an object the simplifier refuses (or panics on),
/// or whose chain would not encode. (A build also refuses an object over `pm_threshold`
/// whose DAG fails; that DAG is not built here.)
fn made_levels(
    objects: &[(u64, Mesh)],
    lod: &LodOptions,
    codec: MeshCodec,
) -> Vec<Vec<(Mesh, f32)>> {
    use rayon::prelude::*;
    objects
        .par_iter()
        .map(|(id, mesh)| simplify_stored(*id, mesh, lod, codec).unwrap_or_default())
        .collect()
}

/// What a build reads: one scene file, or model files (OBJ, glTF, OpenStreetMap).
enum Inputs<'a> {
    Scene(&'a Path),
    Models(&'a [PathBuf]),
}

impl Inputs<'_> {
    fn of(inputs: &[PathBuf]) -> Result<Inputs<'_>> {
        match inputs {
            _ if !inputs.is_empty() && inputs.iter().all(|p| model_format(p).is_some()) => {
                Ok(Inputs::Models(inputs))
            }
            [scene] => Ok(Inputs::Scene(scene)),
            _ => Err(Error::Invalid(
                "give one scene file, or OBJ, glTF and OpenStreetMap files only".into(),
            )),
        }
    }
}

/// What `lod` makes of far objects for a shard's DoVs (`None`: full meshes, `--no-lod`).
fn shard_lod(lod: Option<&LodOptions>) -> Option<ShardLod> {
    lod.map(|l| ShardLod {
        ratio: l.ratio,
        min_triangles: l.min_triangles as u32,
    })
}
