//! How a mesh lies in a database extent. Format version 1 stores raw floats (`raw`);
//! version 2 stores meshoptimizer's buffers over quantised vertices, levels of detail
//! sharing one vertex buffer (`geometry`, `quantize`), each buffer optionally a zstd
//! frame (`squeeze`), with a dictionary trained on the city (`dictionary`). A version-2 mesh starts with a magic no version-1 mesh can start
//! with, so a reader tells them apart by their bytes: one file never mixes them, but
//! every reader reads both.

mod dictionary;
mod faces;
mod geometry;
mod quantize;
mod raw;
mod squeeze;

pub use dictionary::Dictionaries;
pub(crate) use dictionary::Use as DictionaryUse;
use dictionary::Use;
#[cfg(test)]
use geometry::grid_of;
pub(crate) use geometry::{
    decode_level as decode_level_v2, encode_levels as encode_levels_v2, is_geometry,
};
pub(crate) use quantize::{dequantize_normal, quantize_normal, Grid};
pub(crate) use raw::encode_mesh;
pub(crate) use squeeze::Framing;
pub(crate) use squeeze::{expand_frame, is_frame, squeeze};

use crate::scene::Mesh;

/// How a database stores its meshes: chosen at build, recorded in the header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum MeshCodec {
    /// Format version 1: f32 positions, i8 normals, u16/u32 indices, every level of
    /// detail a mesh of its own.
    Raw,
    /// Format version 2: meshoptimizer's codecs over 16-bit positions and 8-bit normals,
    /// levels sharing one vertex buffer, and zstd at this level around each buffer when
    /// `Some`.
    Meshopt {
        /// zstd's level (1..=22), or none.
        zstd: Option<i32>,
    },
}

/// The zstd level a build uses unless told. With the dictionaries, level 9 finds what
/// level 3 misses: the 3,000-object city falls from 6.06 to 5.81 bytes a triangle, its
/// build no slower within the noise (11.5 against 11.6 s); reading is as fast.
pub const DEFAULT_ZSTD_LEVEL: i32 = 9;

/// Format version 2 with zstd at [`DEFAULT_ZSTD_LEVEL`]: now that the levels of detail
/// share one vertex buffer, a coarse level costs less than the full mesh it stands for,
/// and the 3,000-object city is 11.2 MiB against version 1's 137.2. Version 1 stays
/// readable and writable (`MeshCodec::Raw`).
impl Default for MeshCodec {
    fn default() -> MeshCodec {
        MeshCodec::meshopt()
    }
}

impl MeshCodec {
    /// Whether a file in this codec packs small blobs (meshes, LOD chains) several to a
    /// page, as format version 2 does; version 1's raw floats take whole pages.
    pub fn packs(&self) -> bool {
        *self != MeshCodec::Raw
    }

    /// meshoptimizer's codecs with zstd at its default level.
    pub fn meshopt() -> MeshCodec {
        MeshCodec::Meshopt {
            zstd: Some(DEFAULT_ZSTD_LEVEL),
        }
    }

    /// `mesh` as a database's mesh extent holds it in this codec. meshoptimizer's reads
    /// each position back within half a step of its box's 65,535 per axis, plus two
    /// ulps (`quantize.rs`).
    ///
    /// ```
    /// use flaneur::scene::{bunny, MeshCodec};
    /// let mesh = bunny();
    /// let bytes = MeshCodec::meshopt().to_bytes(&mesh)?;
    /// assert!(bytes.len() * 2 < MeshCodec::Raw.to_bytes(&mesh)?.len());
    /// assert_eq!(MeshCodec::from_bytes(&bytes)?.triangle_count(), mesh.triangle_count());
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn to_bytes(&self, mesh: &Mesh) -> crate::Result<Vec<u8>> {
        self.encode(mesh).map_err(crate::Error::Invalid)
    }

    /// The mesh a mesh extent of either codec holds, checked (an `Error::Invalid`
    /// naming what is wrong with bytes that are not one).
    pub fn from_bytes(bytes: &[u8]) -> crate::Result<Mesh> {
        decode_mesh(bytes, None).map_err(crate::Error::Invalid)
    }

    /// [`MeshCodec::from_bytes`] for a mesh extent compressed with its database's
    /// dictionaries ([`Store::dictionaries`](crate::store::Store::dictionaries)).
    pub fn from_bytes_with(bytes: &[u8], dict: Option<&Dictionaries>) -> crate::Result<Mesh> {
        decode_mesh(bytes, dict).map_err(crate::Error::Invalid)
    }
}

impl MeshCodec {
    /// Encodes a mesh that has no coarse levels of its own.
    pub(crate) fn encode(&self, mesh: &Mesh) -> Result<Vec<u8>, String> {
        self.encode_with(mesh, None)
    }

    /// [`MeshCodec::encode`], its zstd frames compressed with `dict`'s dictionary for
    /// full meshes when there is one.
    pub(crate) fn encode_with(
        &self,
        mesh: &Mesh,
        dict: Option<&Dictionaries>,
    ) -> Result<Vec<u8>, String> {
        match self {
            MeshCodec::Raw => Ok(encode_mesh(mesh)),
            MeshCodec::Meshopt { zstd } => {
                geometry::encode(mesh, Framing::of(*zstd, dict, Use::Meshes))
            }
        }
    }
}

/// Decodes and checks a mesh extent of either version: sizes agree with the bytes,
/// every index names a vertex, every position is finite. A version-2 mesh compressed
/// with its database's dictionary needs `dict`.
pub(crate) fn decode_mesh(bytes: &[u8], dict: Option<&Dictionaries>) -> Result<Mesh, String> {
    if is_geometry(bytes) {
        geometry::decode(bytes, dict)
    } else {
        raw::decode_mesh(bytes)
    }
}

#[cfg(test)]
mod tests;
