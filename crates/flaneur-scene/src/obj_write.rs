// Wavefront OBJ output of one mesh: how the generator exports a region of a city and the
// LOD core writes its levels, so both produce files any modelling tool opens.

use std::io::Write;

use crate::mesh::Mesh;

/// Writes `mesh` as OBJ `v`, `vn` and `f v//vn` lines, its vertex 0 numbered `first` (OBJ
/// indices are 1-based and count every vertex before them in the file).
pub fn write_mesh_obj(w: &mut impl Write, mesh: &Mesh, first: u64) -> std::io::Result<()> {
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
    }
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as u64 + first);
        writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
    }
    Ok(())
}
