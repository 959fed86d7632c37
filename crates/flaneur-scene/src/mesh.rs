// The triangle mesh every object is made of, and the few whole-mesh operations the
// generator needs (bounds, validation, merging, moving, smooth normals, subdivision).
// Everything downstream — the scene codec, the LOD builder, the renderer — takes this
// one plain form, so it is kept as three flat arrays rather than a half-edge structure.

use std::collections::HashMap;

use glam::Vec3;

/// An indexed triangle mesh: metres, y up, counter-clockwise triangles seen from outside.
///
/// `normals[i]` is the unit normal of `positions[i]`; `indices` holds three vertex
/// indices per triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in metres.
    pub positions: Vec<[f32; 3]>,
    /// One unit normal per vertex.
    pub normals: Vec<[f32; 3]>,
    /// Three indices into `positions` per triangle, counter-clockwise from outside.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// The number of triangles (`indices.len() / 3`).
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The axis-aligned bounds of the positions, as `(min, max)`.
    ///
    /// An empty mesh gives the empty box `([+inf; 3], [-inf; 3])`, which overlaps nothing.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        (min, max)
    }

    /// Checks the structural contract: one normal per position, whole triangles, every
    /// index in range, every number finite. The error says what is wrong and where.
    pub fn validate(&self) -> Result<(), String> {
        if self.normals.len() != self.positions.len() {
            return Err(format!(
                "{} normals for {} positions",
                self.normals.len(),
                self.positions.len()
            ));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(format!(
                "{} indices is not a whole number of triangles",
                self.indices.len()
            ));
        }
        let n = self.positions.len();
        if let Some((i, &bad)) = self
            .indices
            .iter()
            .enumerate()
            .find(|(_, &ix)| ix as usize >= n)
        {
            return Err(format!("index {i} is {bad}, but there are {n} vertices"));
        }
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(format!(
                "position {i} is not finite: {:?}",
                self.positions[i]
            ));
        }
        if let Some(i) = self
            .normals
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(format!("normal {i} is not finite: {:?}", self.normals[i]));
        }
        Ok(())
    }

    /// Appends `other`, re-basing its indices.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Scales uniformly by `scale` about the origin, then translates by `offset`.
    /// Normals are unchanged (a uniform scale keeps them).
    pub fn scale_translate(&mut self, scale: f32, offset: [f32; 3]) {
        let o = Vec3::from(offset);
        for p in &mut self.positions {
            *p = (Vec3::from(*p) * scale + o).to_array();
        }
    }

    /// Rotates about the y axis by `quarter_turns` × 90° (counter-clockwise seen from
    /// above), positions and normals alike. Exact: no trigonometry is involved.
    pub fn rotate_y_quarter(&mut self, quarter_turns: u32) {
        let rot = |v: [f32; 3]| -> [f32; 3] {
            match quarter_turns % 4 {
                0 => v,
                1 => [v[2], v[1], -v[0]],
                2 => [-v[0], v[1], -v[2]],
                _ => [-v[2], v[1], v[0]],
            }
        };
        for p in &mut self.positions {
            *p = rot(*p);
        }
        for n in &mut self.normals {
            *n = rot(*n);
        }
    }

    /// Reverses the winding of every triangle and negates the normals.
    pub fn flip(&mut self) {
        for t in self.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        for n in &mut self.normals {
            *n = (-Vec3::from(*n)).to_array();
        }
    }

    /// The signed volume enclosed by the triangles (divergence theorem). Positive when
    /// a closed mesh is wound counter-clockwise seen from outside.
    pub fn signed_volume(&self) -> f64 {
        self.indices
            .chunks_exact(3)
            .map(|t| {
                let p = |i: u32| {
                    let v = self.positions[i as usize];
                    [v[0] as f64, v[1] as f64, v[2] as f64]
                };
                let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
                let cross = [
                    b[1] * c[2] - b[2] * c[1],
                    b[2] * c[0] - b[0] * c[2],
                    b[0] * c[1] - b[1] * c[0],
                ];
                (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0
            })
            .sum()
    }

    /// Recomputes smooth vertex normals as the area-weighted mean of the adjacent face
    /// normals. A vertex with no area around it gets +y.
    pub fn compute_smooth_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(self.positions[i as usize]));
            let n = (b - a).cross(c - a); // length = 2 × area: area weighting for free
            for &i in t {
                acc[i as usize] += n;
            }
        }
        self.normals = acc
            .into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Y).to_array())
            .collect();
    }

    /// Midpoint subdivision, 1 to 4: every edge gets one new vertex at its midpoint
    /// (shared between the two triangles on that edge), every triangle becomes four.
    /// The shape does not change; normals are recomputed smooth.
    pub fn subdivide(&self) -> Mesh {
        let mut positions = self.positions.clone();
        let mut indices = Vec::with_capacity(self.indices.len() * 4);
        // Lookup only: insertion order follows the triangles, so the output is
        // deterministic whatever the map's iteration order would be.
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::with_capacity(self.indices.len());
        let mut mid = |a: u32, b: u32, positions: &mut Vec<[f32; 3]>| -> u32 {
            let key = (a.min(b), a.max(b));
            *midpoints.entry(key).or_insert_with(|| {
                let m =
                    (Vec3::from(positions[a as usize]) + Vec3::from(positions[b as usize])) * 0.5;
                positions.push(m.to_array());
                positions.len() as u32 - 1
            })
        };
        for t in self.indices.chunks_exact(3) {
            let (a, b, c) = (t[0], t[1], t[2]);
            let ab = mid(a, b, &mut positions);
            let bc = mid(b, c, &mut positions);
            let ca = mid(c, a, &mut positions);
            indices.extend_from_slice(&[a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
        }
        let mut out = Mesh {
            positions,
            normals: Vec::new(),
            indices,
        };
        out.compute_smooth_normals();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            normals: vec![],
            indices: vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
        };
        m.compute_smooth_normals();
        m
    }

    #[test]
    fn validate_catches_each_fault() {
        let good = tetra();
        assert!(good.validate().is_ok());
        let mut m = good.clone();
        m.normals.pop();
        assert!(m.validate().unwrap_err().contains("normals"));
        let mut m = good.clone();
        m.indices.push(0);
        assert!(m.validate().is_err());
        let mut m = good.clone();
        m.indices[4] = 4;
        assert!(m.validate().unwrap_err().contains("index 4"));
        let mut m = good.clone();
        m.positions[1][2] = f32::NAN;
        assert!(m.validate().unwrap_err().contains("position 1"));
    }

    #[test]
    fn subdivide_quadruples_and_keeps_volume() {
        let t = tetra();
        assert!((t.signed_volume() - 1.0 / 6.0).abs() < 1e-9);
        let s = t.subdivide().subdivide();
        assert_eq!(s.triangle_count(), 4 * 4 * 4);
        // 4 + 6 edges' midpoints, then the 24 edges of the 16 triangles.
        assert_eq!(s.positions.len(), 4 + 6 + 24);
        assert!((s.signed_volume() - t.signed_volume()).abs() < 1e-6);
        assert!(s.validate().is_ok());
    }

    #[test]
    fn rotation_and_flip_keep_validity() {
        let mut m = tetra();
        let v = m.signed_volume();
        m.rotate_y_quarter(1);
        assert!((m.signed_volume() - v).abs() < 1e-9);
        m.flip();
        assert!((m.signed_volume() + v).abs() < 1e-9);
        assert_eq!(m.bounds(), ([0.0, 0.0, -1.0], [1.0, 1.0, 0.0]));
    }
}
