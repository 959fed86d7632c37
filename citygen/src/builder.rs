// Flat-shaded solid building blocks: quads, triangles and boxes, each given with the
// direction it must face. Archetypes describe facades by where surfaces are and which way
// is out; the builder works out the winding, so no archetype has to get CCW order right
// by hand, and every face gets its own vertices (flat normals, shared within a quad).

use glam::Vec3;

use flaneur_scene::Mesh;

/// Accumulates flat-shaded faces into a [`Mesh`].
#[derive(Default)]
pub(crate) struct MeshBuilder {
    mesh: Mesh,
}

impl MeshBuilder {
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// A planar quad through `p` (in order around its edge, either direction), wound so
    /// that it faces `outward`. Degenerate (zero-area) quads are skipped.
    pub(crate) fn quad(&mut self, p: [Vec3; 4], outward: Vec3) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]) + (p[2] - p[0]).cross(p[3] - p[0]);
        if n.length_squared() < 1e-12 {
            return;
        }
        let p = if n.dot(outward) < 0.0 {
            [p[0], p[3], p[2], p[1]]
        } else {
            p
        };
        let normal = if n.dot(outward) < 0.0 { -n } else { n }.normalize();
        let base = self.mesh.positions.len() as u32;
        for v in p {
            self.mesh.positions.push(v.to_array());
            self.mesh.normals.push(normal.to_array());
        }
        self.mesh
            .indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// The flat ring between the quad `outer` and the quad `inner` inside it (both in the
    /// same order around), facing `outward`: 8 triangles on 8 shared vertices — a window
    /// frame at half the vertices of four separate quads.
    pub(crate) fn frame(&mut self, outer: [Vec3; 4], inner: [Vec3; 4], outward: Vec3) {
        let n = (outer[1] - outer[0]).cross(outer[2] - outer[0])
            + (outer[2] - outer[0]).cross(outer[3] - outer[0]);
        let (o, i, normal) = if n.dot(outward) < 0.0 {
            let r = |q: [Vec3; 4]| [q[0], q[3], q[2], q[1]];
            (r(outer), r(inner), -n.normalize())
        } else {
            (outer, inner, n.normalize())
        };
        let base = self.mesh.positions.len() as u32;
        for v in o.iter().chain(&i) {
            self.mesh.positions.push(v.to_array());
            self.mesh.normals.push(normal.to_array());
        }
        for k in 0..4 {
            let (o0, o1, i0, i1) = (
                base + k,
                base + (k + 1) % 4,
                base + 4 + k,
                base + 4 + (k + 1) % 4,
            );
            self.mesh
                .indices
                .extend_from_slice(&[o0, o1, i1, o0, i1, i0]);
        }
    }

    /// A triangle, wound so that it faces `outward`. Degenerate triangles are skipped.
    pub(crate) fn tri(&mut self, p: [Vec3; 3], outward: Vec3) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        if n.length_squared() < 1e-12 {
            return;
        }
        let (p, normal) = if n.dot(outward) < 0.0 {
            ([p[0], p[2], p[1]], -n.normalize())
        } else {
            (p, n.normalize())
        };
        let base = self.mesh.positions.len() as u32;
        for v in p {
            self.mesh.positions.push(v.to_array());
            self.mesh.normals.push(normal.to_array());
        }
        self.mesh
            .indices
            .extend_from_slice(&[base, base + 1, base + 2]);
    }

    /// A closed axis-aligned box between two opposite corners (in any order): 12 triangles.
    pub(crate) fn cuboid(&mut self, a: Vec3, b: Vec3) {
        let (lo, hi) = (a.min(b), a.max(b));
        let c = |x: bool, y: bool, z: bool| {
            Vec3::new(
                if x { hi.x } else { lo.x },
                if y { hi.y } else { lo.y },
                if z { hi.z } else { lo.z },
            )
        };
        let (f, t) = (false, true);
        self.quad([c(f, f, f), c(f, t, f), c(f, t, t), c(f, f, t)], -Vec3::X);
        self.quad([c(t, f, f), c(t, t, f), c(t, t, t), c(t, f, t)], Vec3::X);
        self.quad([c(f, f, f), c(t, f, f), c(t, f, t), c(f, f, t)], -Vec3::Y);
        self.quad([c(f, t, f), c(t, t, f), c(t, t, t), c(f, t, t)], Vec3::Y);
        self.quad([c(f, f, f), c(t, f, f), c(t, t, f), c(f, t, f)], -Vec3::Z);
        self.quad([c(f, f, t), c(t, f, t), c(t, t, t), c(f, t, t)], Vec3::Z);
    }

    /// The mesh built so far.
    pub(crate) fn finish(self) -> Mesh {
        self.mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuboid_is_closed_and_outward() {
        let mut b = MeshBuilder::new();
        b.cuboid(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO);
        let m = b.finish();
        assert_eq!(m.triangle_count(), 12);
        assert!((m.signed_volume() - 6.0).abs() < 1e-6);
        assert!(m.validate().is_ok());
    }

    #[test]
    fn winding_follows_outward() {
        let mut b = MeshBuilder::new();
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z];
        b.quad(p, Vec3::Y);
        b.quad(p, -Vec3::Y);
        b.tri([Vec3::ZERO, Vec3::X, Vec3::Z], Vec3::Y);
        let inner = p.map(|v| v * 0.5 + Vec3::new(0.25, 0.0, 0.25));
        b.frame(p, inner, -Vec3::Y);
        let m = b.finish();
        assert_eq!(m.triangle_count(), 2 + 2 + 1 + 8);
        assert_eq!(m.normals[11], [0.0, -1.0, 0.0]);
        assert_eq!(m.normals[0], [0.0, 1.0, 0.0]);
        assert_eq!(m.normals[4], [0.0, -1.0, 0.0]);
        assert_eq!(m.normals[8], [0.0, 1.0, 0.0]);
        // The geometric normal of each triangle agrees with its stored normal.
        for t in m.indices.chunks_exact(3) {
            let [a, b2, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(m.positions[i as usize]));
            let g = (b2 - a).cross(c - a);
            assert!(g.dot(Vec3::from(m.normals[t[0] as usize])) > 0.0);
        }
    }
}
