//! Writing a scene file: the header, one checked record per object, the trailer that
//! chains their checksums.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::{
    header_bytes, SceneSummary, FLAG_U16_INDICES, HEADER_LEN, MAX_INDICES, MAX_VERTICES,
    TRAILER_CHAIN_OFFSET, TRAILER_COUNT_OFFSET, TRAILER_CRC_OFFSET, TRAILER_LEN, TRAILER_MAGIC,
    TRAILER_MAGIC_OFFSET,
};
use crate::error::SceneError;
use crate::object::SceneObject;

/// Writes a scene file, one object at a time.
///
/// Call [`finish`](Self::finish) at the end: without it the file has no trailer, and a
/// reader rejects it as cut short.
pub struct SceneWriter {
    path: PathBuf,
    out: BufWriter<File>,
    summary: SceneSummary,
    chain: crc32fast::Hasher,
    last_id: Option<u64>,
    buf: Vec<u8>,
}

impl SceneWriter {
    /// Creates (or truncates) the file at `path` and writes its header.
    pub fn create(path: &Path) -> Result<Self, SceneError> {
        let file = File::create(path).map_err(|e| SceneError::io(path, e))?;
        let mut out = BufWriter::with_capacity(1 << 20, file);
        let header = header_bytes();
        out.write_all(&header)
            .map_err(|e| SceneError::io(path, e))?;
        let mut chain = crc32fast::Hasher::new();
        chain.update(&header);
        Ok(SceneWriter {
            path: path.to_path_buf(),
            out,
            summary: SceneSummary {
                bytes: HEADER_LEN as u64,
                ..Default::default()
            },
            chain,
            last_id: None,
            buf: Vec::new(),
        })
    }

    /// Appends one object. Ids must be strictly increasing and the mesh must pass
    /// [`Mesh::validate`](crate::Mesh::validate); anything else is refused and nothing is written.
    pub fn write(&mut self, obj: &SceneObject) -> Result<(), SceneError> {
        let refuse = |what: String| SceneError::Corrupt {
            path: self.path.clone(),
            object: self.summary.objects,
            what: format!("refusing to write object id {}: {what}", obj.id),
        };
        if let Some(last) = self.last_id {
            if obj.id <= last {
                return Err(refuse(format!(
                    "ids must increase, and the last was {last}"
                )));
            }
        }
        let m = &obj.mesh;
        m.validate().map_err(refuse)?;
        if m.positions.len() > MAX_VERTICES as usize || m.indices.len() > MAX_INDICES as usize {
            return Err(refuse(format!(
                "{} vertices and {} indices are over the limits",
                m.positions.len(),
                m.indices.len()
            )));
        }
        let small = m.positions.len() <= 1 << 16;
        let b = &mut self.buf;
        b.clear();
        b.extend_from_slice(&obj.id.to_le_bytes());
        b.push(obj.kind.as_u8());
        b.push(if small { FLAG_U16_INDICES } else { 0 });
        b.extend_from_slice(&(m.positions.len() as u32).to_le_bytes());
        b.extend_from_slice(&(m.indices.len() as u32).to_le_bytes());
        for p in &m.positions {
            for c in p {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        for n in &m.normals {
            b.extend(n.map(|c| quantize_snorm8(c) as u8));
        }
        if small {
            for &i in &m.indices {
                b.extend_from_slice(&(i as u16).to_le_bytes());
            }
        } else {
            for &i in &m.indices {
                b.extend_from_slice(&i.to_le_bytes());
            }
        }
        let crc = crc32fast::hash(b).to_le_bytes();
        b.extend_from_slice(&crc);
        self.out
            .write_all(b)
            .map_err(|e| SceneError::io(&self.path, e))?;
        self.chain.update(&crc);
        self.last_id = Some(obj.id);
        self.summary.objects += 1;
        self.summary.triangles += m.triangle_count() as u64;
        self.summary.bytes += b.len() as u64;
        Ok(())
    }

    /// Writes the trailer and flushes. Returns what the file holds.
    pub fn finish(mut self) -> Result<SceneSummary, SceneError> {
        let mut t = [0u8; TRAILER_LEN];
        t[TRAILER_MAGIC_OFFSET..TRAILER_COUNT_OFFSET].copy_from_slice(&TRAILER_MAGIC);
        t[TRAILER_COUNT_OFFSET..TRAILER_CHAIN_OFFSET]
            .copy_from_slice(&self.summary.objects.to_le_bytes());
        t[TRAILER_CHAIN_OFFSET..TRAILER_CRC_OFFSET]
            .copy_from_slice(&self.chain.finalize().to_le_bytes());
        let crc = crc32fast::hash(&t[..TRAILER_CRC_OFFSET]);
        t[TRAILER_CRC_OFFSET..].copy_from_slice(&crc.to_le_bytes());
        self.out
            .write_all(&t)
            .map_err(|e| SceneError::io(&self.path, e))?;
        self.out
            .flush()
            .map_err(|e| SceneError::io(&self.path, e))?;
        self.summary.bytes += TRAILER_LEN as u64;
        Ok(self.summary)
    }
}

/// A unit-range float as snorm8 (the normals' codec of the scene file and the database).
pub fn quantize_snorm8(c: f32) -> i8 {
    (c.clamp(-1.0, 1.0) * 127.0).round() as i8
}
