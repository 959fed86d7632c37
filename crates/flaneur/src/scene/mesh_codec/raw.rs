//! Format version 1's mesh: raw floats. Normals are quantized to signed 8-bit (as the
//! scene file does); positions are stored as they came. Written by `--codec raw` and by
//! every file of format version 1, read from both.
//!
//! ```text
//!  0  vertex count  u32
//!  4  index count   u32
//!  8  flags         u32   bit 0: indices are u16
//! 12  positions     f32 x 3 per vertex
//!  .  normals       i8 x 4 per vertex (x, y, z, 0), scaled by 127
//!  .  indices       u16 or u32 per index
//! ```

use crate::scene::Mesh;

const VERTEX_COUNT_OFFSET: usize = 0;
const INDEX_COUNT_OFFSET: usize = VERTEX_COUNT_OFFSET + 4;
const FLAGS_OFFSET: usize = INDEX_COUNT_OFFSET + 4;
const HEADER_LEN: usize = FLAGS_OFFSET + 4;
const POSITION_LEN: usize = 12;
const NORMAL_LEN: usize = 4;
const FLAG_U16: u32 = 1;

pub(crate) fn encode_mesh(mesh: &Mesh) -> Vec<u8> {
    let v = mesh.positions.len();
    let small = v <= u16::MAX as usize + 1;
    let index_len = if small { 2 } else { 4 };
    let mut out = Vec::with_capacity(
        HEADER_LEN + v * (POSITION_LEN + NORMAL_LEN) + mesh.indices.len() * index_len,
    );
    out.extend_from_slice(&(v as u32).to_le_bytes());
    out.extend_from_slice(&(mesh.indices.len() as u32).to_le_bytes());
    out.extend_from_slice(&(if small { FLAG_U16 } else { 0 }).to_le_bytes());
    for p in &mesh.positions {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for n in &mesh.normals {
        out.extend(n.map(|c| flaneur_scene::quantize_snorm8(c) as u8));
        out.push(0);
    }
    for &i in &mesh.indices {
        if small {
            out.extend_from_slice(&(i as u16).to_le_bytes());
        } else {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// Decodes and checks a mesh: sizes agree with the bytes, every index names a vertex.
pub(crate) fn decode_mesh(bytes: &[u8]) -> Result<Mesh, String> {
    if bytes.len() < HEADER_LEN {
        return Err(format!(
            "mesh of {} bytes is shorter than its header",
            bytes.len()
        ));
    }
    let word = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    let (v, n, flags) = (
        word(VERTEX_COUNT_OFFSET),
        word(INDEX_COUNT_OFFSET),
        word(FLAGS_OFFSET) as u32,
    );
    let index_len = if flags & FLAG_U16 != 0 { 2 } else { 4 };
    let need = HEADER_LEN as u64
        + v as u64 * (POSITION_LEN + NORMAL_LEN) as u64
        + n as u64 * index_len as u64;
    if need != bytes.len() as u64 {
        return Err(format!(
            "mesh header says {v} vertices and {n} indices ({need} bytes) but {} bytes are stored",
            bytes.len()
        ));
    }
    if n % 3 != 0 {
        return Err(format!("{n} indices are not whole triangles"));
    }
    let positions_at = HEADER_LEN;
    let normals_at = positions_at + v * POSITION_LEN;
    let indices_at = normals_at + v * NORMAL_LEN;
    let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    let positions: Vec<[f32; 3]> = (0..v)
        .map(|i| {
            let o = positions_at + i * POSITION_LEN;
            [f(o), f(o + 4), f(o + 8)]
        })
        .collect();
    if positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err("mesh has a position that is not finite".into());
    }
    let normals = (0..v)
        .map(|i| {
            let o = normals_at + i * NORMAL_LEN;
            flaneur_scene::dequantize_normal([
                bytes[o] as i8,
                bytes[o + 1] as i8,
                bytes[o + 2] as i8,
            ])
        })
        .collect();
    let mut indices = Vec::with_capacity(n);
    for k in 0..n {
        let o = indices_at + k * index_len;
        let i = if index_len == 2 {
            u16::from_le_bytes([bytes[o], bytes[o + 1]]) as u32
        } else {
            u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap())
        };
        if i as usize >= v {
            return Err(format!(
                "index {i} at position {k} names no vertex (the mesh has {v})"
            ));
        }
        indices.push(i);
    }
    Ok(Mesh {
        positions,
        normals,
        indices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            normals: vec![[0.0, 0.0, 1.0]; 4],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    #[test]
    fn round_trips() {
        let m = quad();
        let back = decode_mesh(&encode_mesh(&m)).unwrap();
        assert_eq!(back.positions, m.positions);
        assert_eq!(back.indices, m.indices);
        assert_eq!(back.normals, m.normals);
    }

    #[test]
    fn damage_is_named() {
        let bytes = encode_mesh(&quad());
        assert!(decode_mesh(&bytes[..bytes.len() - 1])
            .unwrap_err()
            .contains("bytes are stored"));
        let mut bad = bytes.clone();
        let last = bad.len() - 2;
        bad[last] = 9;
        assert!(decode_mesh(&bad).unwrap_err().contains("names no vertex"));
        let mut huge = bytes;
        huge[0..4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode_mesh(&huge).is_err());
    }
}
