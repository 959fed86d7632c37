// Wavefront OBJ export of one region of a city, for looking at the generator's output in
// any modelling tool. Only the lots that can overlap the region are generated (objects
// are independent per id), so exporting a street corner of a million-object city is
// instant.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::config::CityConfig;
use crate::recipe::object_on;
use flaneur_scene::write_mesh_obj;
use flaneur_scene::SceneError;

/// Writes every object of `config` whose bounds overlap the x–z rectangle `region`
/// (`([x_min, z_min], [x_max, z_max])`, metres) to the OBJ file `out`, one `o object_<id>`
/// group each, with `v`, `vn` and `f v//vn` lines. Returns how many objects it wrote.
pub fn export_obj(
    config: &CityConfig,
    region: ([f32; 2], [f32; 2]),
    out: &Path,
) -> Result<u64, SceneError> {
    let layout = crate::recipe::checked_layout(config)?;
    let (min, max) = region;
    if !min.iter().chain(&max).all(|v| v.is_finite()) || min[0] > max[0] || min[1] > max[1] {
        return Err(SceneError::Config(format!(
            "region must be finite with min <= max, not x {}..{} z {}..{}",
            min[0], max[0], min[1], max[1]
        )));
    }
    let file = File::create(out).map_err(|e| SceneError::io(out, e))?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    let mut written = 0u64;
    let mut base = 1u64; // OBJ indices are 1-based and global.
    let write =
        |w: &mut BufWriter<File>, base: &mut u64, o: &crate::SceneObject| -> std::io::Result<()> {
            writeln!(w, "o object_{}", o.id)?;
            write_mesh_obj(w, &o.mesh, *base)?;
            *base += o.mesh.positions.len() as u64;
            Ok(())
        };
    writeln!(
        w,
        "# flaneur city, seed {}, {} objects; region x {}..{} z {}..{}",
        config.seed, config.objects, min[0], max[0], min[1], max[1]
    )
    .map_err(|e| SceneError::io(out, e))?;
    for id in layout.ids_overlapping(min, max, config.objects) {
        let o = object_on(config, &layout, id);
        let (lo, hi) = o.mesh.bounds();
        if hi[0] >= min[0] && lo[0] <= max[0] && hi[2] >= min[1] && lo[2] <= max[1] {
            write(&mut w, &mut base, &o).map_err(|e| SceneError::io(out, e))?;
            written += 1;
        }
    }
    w.flush().map_err(|e| SceneError::io(out, e))?;
    Ok(written)
}
