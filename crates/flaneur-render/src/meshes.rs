//! Object meshes resident on the GPU: uploaded when an object comes into view (or
//! into view at another level of detail), freed when it is evicted, each in a slot
//! whose number the id target shows.

use std::collections::HashMap;

use wgpu::util::DeviceExt;

use crate::Gpu;
use flaneur::error::{Error, Result};
use flaneur::scene::Mesh;
use flaneur::walk::lod_select::{Drawn, RefinedView, Refinements, REFINED};

/// One vertex as the shader reads it: position, normal, the object's slot (what the id
/// target shows) and the key its tint comes from (its id folded to 32 bits, so that an
/// object looks the same in whatever slot).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub slot: u32,
    pub key: u32,
}

/// An object id folded to the 32 bits of a tint key.
pub fn tint_key(id: u64) -> u32 {
    (id ^ (id >> 32)) as u32
}

impl Vertex {
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Uint32, 3 => Uint32],
    };
}

/// A mesh on the GPU.
pub struct GpuMesh {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
    pub slot: u32,
    pub bytes: u64,
}

/// A resident mesh's key: an object and its level of detail (0: full detail).
pub type MeshKey = (u64, usize);

/// The resident meshes, by object and level.
#[derive(Default)]
pub struct GpuMeshes {
    by_id: HashMap<MeshKey, GpuMesh>,
    /// Slot → object id; `None` for a free slot.
    slots: Vec<Option<u64>>,
    free: Vec<u32>,
    bytes: u64,
    budget: Option<u64>,
}

/// What making the GPU follow a frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Followed {
    pub uploads: usize,
    pub freed: usize,
    /// The frame's own meshes took more than the budget.
    pub over_budget: bool,
}

/// Bytes `mesh` takes on the GPU: its vertices and its indices.
pub fn gpu_bytes(mesh: &Mesh) -> u64 {
    (mesh.positions.len() * std::mem::size_of::<Vertex>() + mesh.indices.len() * 4) as u64
}

impl GpuMeshes {
    /// Uploads level `level` of object `id` unless it is resident; whether it
    /// uploaded. A mesh whose normals do not match its positions, or whose indices are
    /// not whole triangles of live vertices, is an error naming the object.
    pub fn upload(&mut self, gpu: &Gpu, (id, level): MeshKey, mesh: &Mesh) -> Result<bool> {
        if self.by_id.contains_key(&(id, level)) {
            return Ok(false);
        }
        let (positions, normals, indices) = (&mesh.positions, &mesh.normals, &mesh.indices);
        if positions.len() != normals.len() || indices.len() % 3 != 0 {
            return Err(Error::Render(format!(
                "object {id}: {} positions, {} normals, {} indices",
                positions.len(),
                normals.len(),
                indices.len()
            )));
        }
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(Error::Render(format!(
                "object {id}: index {i} with {} positions",
                positions.len()
            )));
        }
        let slot = self.take_slot();
        let vertices = vertices_of(positions, normals, slot, id);
        let vb = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("object vertices"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
            });
        let ib = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("object indices"),
                contents: bytemuck::cast_slice(indices.as_slice()),
                usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_SRC,
            });
        let bytes = vb.size() + ib.size();
        self.bytes += bytes;
        self.slots[slot as usize] = Some(id);
        self.by_id.insert(
            (id, level),
            GpuMesh {
                vertices: vb,
                indices: ib,
                index_count: indices.len() as u32,
                slot,
                bytes,
            },
        );
        Ok(true)
    }

    /// What the GPU holds of a resident mesh, read back: its vertices, and the indices
    /// it draws. For checking that incremental uploads kept it whole.
    pub fn read_back(&self, gpu: &Gpu, key: MeshKey) -> Result<(Vec<Vertex>, Vec<u32>)> {
        let m = self.by_id.get(&key).ok_or_else(|| {
            Error::Invalid(format!(
                "object {} at level {} is not on the GPU",
                key.0, key.1
            ))
        })?;
        let read = |buffer: &wgpu::Buffer, bytes: u64| -> Result<Vec<u8>> {
            let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("mesh readback"),
                size: bytes.max(4),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes.max(4));
            gpu.queue.submit([encoder.finish()]);
            gpu.read_mapped(&staging, "a mesh", |data| data[..bytes as usize].to_vec())
        };
        let vertices = read(&m.vertices, m.vertices.size())?;
        let indices = read(&m.indices, m.index_count as u64 * 4)?;
        Ok((
            bytemuck::pod_collect_to_vec(&vertices),
            bytemuck::pod_collect_to_vec(&indices),
        ))
    }

    /// A free slot, or a new one.
    fn take_slot(&mut self) -> u32 {
        match self.free.pop() {
            Some(s) => s,
            None => {
                self.slots.push(None);
                (self.slots.len() - 1) as u32
            }
        }
    }

    /// Brings object `id`'s refined mesh up to date on the GPU: the first time, buffers
    /// sized for the full mesh (so that refinement never reallocates them) filled with
    /// the selective mesh; after that, only the ranges that changed. Whether it
    /// allocated.
    pub fn upload_refined(&mut self, gpu: &Gpu, id: u64, r: RefinedView<'_>) -> Result<bool> {
        let key = (id, REFINED);
        let (pending, mesh) = (r.pending, r.mesh);
        let (positions, normals, indices) = (mesh.positions(), mesh.normals(), mesh.indices());
        let (vertex_cap, triangle_cap) = r.capacity;
        if positions.len() > vertex_cap || indices.len() > 3 * triangle_cap {
            return Err(Error::Render(format!(
                "object {id}: a selective mesh of {} vertices and {} triangles outgrows its \
                 full mesh's {vertex_cap} and {triangle_cap}",
                positions.len(),
                indices.len() / 3
            )));
        }
        let created = !self.by_id.contains_key(&key);
        if created {
            let slot = self.take_slot();
            let buffer = |label, size: usize, usage| {
                gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size.max(4) as u64,
                    usage: usage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            };
            let vb = buffer(
                "refined vertices",
                vertex_cap * std::mem::size_of::<Vertex>(),
                wgpu::BufferUsages::VERTEX,
            );
            let ib = buffer(
                "refined indices",
                triangle_cap * 12,
                wgpu::BufferUsages::INDEX,
            );
            let bytes = vb.size() + ib.size();
            self.bytes += bytes;
            self.slots[slot as usize] = Some(id);
            self.by_id.insert(
                key,
                GpuMesh {
                    vertices: vb,
                    indices: ib,
                    index_count: 0,
                    slot,
                    bytes,
                },
            );
        }
        let m = self.by_id.get_mut(&key).expect("inserted above");
        // All of it the first time; after that, what changed.
        for (a, b) in spans(created, &pending.vertices, positions.len()) {
            let v = vertices_of(&positions[a..b], &normals[a..b], m.slot, id);
            let offset = (a * std::mem::size_of::<Vertex>()) as u64;
            gpu.queue
                .write_buffer(&m.vertices, offset, bytemuck::cast_slice(&v));
        }
        for (a, b) in spans(created, &pending.indices, indices.len()) {
            gpu.queue.write_buffer(
                &m.indices,
                (a * 4) as u64,
                bytemuck::cast_slice(&indices[a..b]),
            );
        }
        m.index_count = indices.len() as u32;
        Ok(created)
    }

    /// Makes the GPU hold what a frame draws: frees what `holds` (the walk's buffer)
    /// no longer holds and the other levels of an object drawn at a new one; under a
    /// budget, frees meshes this frame does not draw (largest first) to make room;
    /// then uploads what `selected` draws for the first time at its level.
    pub fn follow(
        &mut self,
        gpu: &Gpu,
        holds: impl Fn(u64) -> bool,
        selected: &[Drawn],
        mut lods: Option<&mut dyn Refinements>,
    ) -> Result<Followed> {
        let level: HashMap<u64, usize> = selected.iter().map(|d| (d.id, d.level)).collect();
        let mut freed =
            self.retain(|(id, l)| holds(id) && level.get(&id).is_none_or(|&now| now == l));
        if let Some(budget) = self.budget {
            let needed: u64 = selected
                .iter()
                .filter(|d| !self.by_id.contains_key(&(d.id, d.level)))
                .map(|d| gpu_bytes(&d.mesh))
                .sum();
            if self.bytes + needed > budget {
                let mut idle: Vec<(u64, MeshKey)> = self
                    .by_id
                    .iter()
                    .filter(|(k, _)| level.get(&k.0) != Some(&k.1))
                    .map(|(&k, m)| (m.bytes, k))
                    .collect();
                idle.sort_unstable_by(|a, b| b.cmp(a));
                for (_, k) in idle {
                    if self.bytes + needed <= budget {
                        break;
                    }
                    self.evict(k);
                    freed += 1;
                }
            }
        }
        let mut uploads = 0;
        for d in selected {
            uploads += match (d.level, lods.as_deref_mut().and_then(|l| l.refined(d.id))) {
                (REFINED, Some(r)) => self.upload_refined(gpu, d.id, r)?,
                (REFINED, None) => {
                    return Err(Error::Render(format!(
                        "object {} is drawn refined, but no refinement was given",
                        d.id
                    )))
                }
                _ => self.upload(gpu, (d.id, d.level), &d.mesh)?,
            } as usize;
        }
        Ok(Followed {
            uploads,
            freed,
            over_budget: self.budget.is_some_and(|b| self.bytes > b),
        })
    }

    /// Sets the GPU memory the meshes may take, bytes (`None`: no limit). A frame
    /// whose own meshes do not fit is drawn anyway, and [`Followed::over_budget`]
    /// says so.
    pub fn set_budget(&mut self, bytes: Option<u64>) {
        self.budget = bytes;
    }

    pub fn budget(&self) -> Option<u64> {
        self.budget
    }

    /// Frees every resident mesh `keep` says no to; how many.
    pub fn retain(&mut self, keep: impl Fn(MeshKey) -> bool) -> usize {
        let gone: Vec<MeshKey> = self.keys().filter(|&k| !keep(k)).collect();
        for &k in &gone {
            self.evict(k);
        }
        gone.len()
    }

    /// Frees a mesh's buffers; whether it was resident.
    pub fn evict(&mut self, key: MeshKey) -> bool {
        match self.by_id.remove(&key) {
            Some(m) => {
                self.bytes -= m.bytes;
                self.slots[m.slot as usize] = None;
                self.free.push(m.slot);
                m.vertices.destroy();
                m.indices.destroy();
                true
            }
            None => false,
        }
    }

    /// The resident meshes' keys, in no order.
    pub fn keys(&self) -> impl Iterator<Item = MeshKey> + '_ {
        self.by_id.keys().copied()
    }

    pub fn get(&self, key: MeshKey) -> Option<&GpuMesh> {
        self.by_id.get(&key)
    }

    /// The object in `slot`, if any.
    pub fn object_in(&self, slot: u32) -> Option<u64> {
        self.slots.get(slot as usize).copied().flatten()
    }

    pub fn len(&self) -> usize {
        self.by_id.len()
    }

    pub fn is_empty(&self) -> bool {
        self.by_id.is_empty()
    }

    /// GPU memory the resident meshes take, bytes.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

/// The vertices the shader reads for `positions` and `normals` of object `id` in `slot`.
fn vertices_of(positions: &[[f32; 3]], normals: &[[f32; 3]], slot: u32, id: u64) -> Vec<Vertex> {
    positions
        .iter()
        .zip(normals)
        .map(|(&position, &normal)| Vertex {
            position,
            normal,
            slot,
            key: tint_key(id),
        })
        .collect()
}

/// The non-empty spans of an array of `len` to upload: all of it when `whole`, else
/// `changed` cut to the array's length (changes gathered over frames may reach past an
/// array that has since shrunk).
fn spans(whole: bool, changed: &[std::ops::Range<u32>], len: usize) -> Vec<(usize, usize)> {
    if whole {
        return if len > 0 { vec![(0, len)] } else { Vec::new() };
    }
    changed
        .iter()
        .map(|r| (r.start as usize, (r.end as usize).min(len)))
        .filter(|(a, b)| a < b)
        .collect()
}
