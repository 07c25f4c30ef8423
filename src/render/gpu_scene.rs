//! The scene's surfaces on the GPU, uploaded once per scene (again when an object moves): every
//! object's indexed triangles (position and albedo per vertex; passes that shade take the flat
//! normal from the screen-space derivatives of the position), split into chunks no larger than
//! the device's buffer limit allows, so meshes of tens of millions of triangles upload and draw.

use glam::Vec3;
use wgpu::util::DeviceExt;

use super::{GpuContext, SurfaceVertex};
use crate::scene::Scene;

/// Albedo of casters and of receivers-only objects (the ground).
pub const CASTER_ALBEDO: f32 = 0.75;
pub const RECEIVER_ALBEDO: f32 = 0.85;

/// The largest buffer one chunk uses, at most the device's own limit: uploads go through a
/// staging copy of each buffer, so smaller chunks keep the peak memory of an upload low.
pub const CHUNK_BYTES: u64 = 128 << 20;

/// An indexed piece of the surfaces.
struct SurfaceChunk {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
}

/// Non-indexed vertices (volume triangles), in chunks of whole triangles.
pub struct VertexChunks {
    chunks: Vec<(wgpu::Buffer, u32)>,
    /// Vertices over all chunks.
    pub count: u64,
}

impl VertexChunks {
    pub fn new<T: bytemuck::Pod>(device: &wgpu::Device, label: &str, data: &[T]) -> VertexChunks {
        let size = std::mem::size_of::<T>().max(1) as u64;
        let limit = CHUNK_BYTES.min(device.limits().max_buffer_size);
        // Whole triangles per chunk.
        let per_chunk = ((limit / size) / 3 * 3).max(3) as usize;
        let chunks = data
            .chunks(per_chunk)
            .map(|piece| {
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytemuck::cast_slice(piece),
                    usage: wgpu::BufferUsages::VERTEX,
                });
                (buffer, piece.len() as u32)
            })
            .collect();
        VertexChunks {
            chunks,
            count: data.len() as u64,
        }
    }

    pub fn empty() -> VertexChunks {
        VertexChunks {
            chunks: Vec::new(),
            count: 0,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Draw every vertex, chunk by chunk, into vertex buffer slot 0.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.draw_instance(pass, 0);
    }

    /// [`VertexChunks::draw`] as instance `instance` (a shader may read its `instance_index`).
    pub fn draw_instance(&self, pass: &mut wgpu::RenderPass<'_>, instance: u32) {
        for (buffer, count) in &self.chunks {
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..*count, instance..instance + 1);
        }
    }
}

/// A volume made on the GPU, drawn with the indirect arguments its stage wrote
/// (`passes::geometry_gpu`).
#[derive(Clone)]
pub struct IndirectVolume {
    pub vertices: wgpu::Buffer,
    pub args: wgpu::Buffer,
    pub offset: u64,
}

/// Volume triangles to draw: uploaded from the CPU, or made on the GPU.
pub enum VolumeDraw {
    Chunks(VertexChunks),
    Indirect(IndirectVolume),
}

impl VolumeDraw {
    /// Draw every vertex into vertex buffer slot 0.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        match self {
            VolumeDraw::Chunks(c) => c.draw(pass),
            VolumeDraw::Indirect(v) => {
                pass.set_vertex_buffer(0, v.vertices.slice(..));
                pass.draw_indirect(&v.args, v.offset);
            }
        }
    }
}

pub struct GpuScene {
    chunks: Vec<SurfaceChunk>,
    /// Bounds `(min, max)` of every surface, taken once at upload (the camera's depth range is
    /// derived from them each frame).
    pub bounds: (Vec3, Vec3),
    pub triangles: u64,
}

impl GpuScene {
    pub fn new(ctx: &GpuContext, scene: &Scene) -> GpuScene {
        let device = &ctx.device;
        let limit = CHUNK_BYTES.min(device.limits().max_buffer_size);
        let vertex_size = std::mem::size_of::<SurfaceVertex>() as u64;
        // A chunk of n triangles holds at most 3n vertices and 3n indices.
        let max_triangles = (limit / (3 * vertex_size.max(4))).max(1) as usize;
        let mut builder = ChunkBuilder {
            device,
            queue: &ctx.queue,
            max_triangles,
            vertices: Vec::new(),
            indices: Vec::new(),
            chunks: Vec::new(),
        };
        let mut triangles = 0u64;
        for object in &scene.objects {
            let albedo = if object.casts_shadow {
                CASTER_ALBEDO
            } else {
                RECEIVER_ALBEDO
            };
            triangles += object.mesh.triangles.len() as u64;
            builder.add(&object.mesh.positions, &object.mesh.triangles, albedo);
        }
        builder.flush();
        GpuScene {
            chunks: builder.chunks,
            bounds: scene.bounds(),
            triangles,
        }
    }

    /// Draw every surface triangle (vertex buffer slot 0, indexed).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.draw_instances(pass, 0..1);
    }

    /// Draw every surface triangle for each of `instances` (a shader may read its
    /// `instance_index`).
    pub fn draw_instances(&self, pass: &mut wgpu::RenderPass<'_>, instances: std::ops::Range<u32>) {
        for c in &self.chunks {
            pass.set_vertex_buffer(0, c.vertices.slice(..));
            pass.set_index_buffer(c.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..c.index_count, 0, instances.clone());
        }
    }
}

/// Packs objects' triangles into chunks, remapping vertex indices per chunk.
struct ChunkBuilder<'a> {
    device: &'a wgpu::Device,
    queue: &'a wgpu::Queue,
    max_triangles: usize,
    vertices: Vec<SurfaceVertex>,
    indices: Vec<u32>,
    chunks: Vec<SurfaceChunk>,
}

impl ChunkBuilder<'_> {
    fn add(&mut self, positions: &[Vec3], triangles: &[[u32; 3]], albedo: f32) {
        let vertex = |p: Vec3| SurfaceVertex {
            position: p.to_array(),
            albedo,
        };
        let room = self.max_triangles - self.indices.len() / 3;
        let vertex_room = 3 * self.max_triangles - self.vertices.len();
        let in_range = |t: &[u32; 3]| t.iter().all(|&i| (i as usize) < positions.len());
        if triangles.len() <= room && positions.len() <= vertex_room {
            // The whole object fits: its vertices as they are.
            let base = self.vertices.len() as u32;
            self.vertices.extend(positions.iter().map(|&p| vertex(p)));
            self.indices.extend(
                triangles
                    .iter()
                    .filter(|t| in_range(t))
                    .flatten()
                    .map(|&i| base + i),
            );
            return;
        }
        // Too big: in pieces, each with only the vertices it uses.
        let mut slot = vec![u32::MAX; positions.len()];
        let mut used: Vec<u32> = Vec::new();
        for tri in triangles.iter().filter(|t| in_range(t)) {
            if self.indices.len() / 3 >= self.max_triangles
                || self.vertices.len() + 3 > 3 * self.max_triangles
            {
                self.flush();
                for &v in &used {
                    slot[v as usize] = u32::MAX;
                }
                used.clear();
            }
            for &i in tri {
                let k = i as usize;
                if slot[k] == u32::MAX {
                    slot[k] = self.vertices.len() as u32;
                    self.vertices.push(vertex(positions[k]));
                    used.push(i);
                }
                self.indices.push(slot[k]);
            }
        }
    }

    fn flush(&mut self) {
        if self.indices.is_empty() {
            return;
        }
        let vertices = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("GpuScene::vertices"),
                contents: bytemuck::cast_slice(&self.vertices),
                usage: wgpu::BufferUsages::VERTEX,
            });
        let indices = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("GpuScene::indices"),
                contents: bytemuck::cast_slice(&self.indices),
                usage: wgpu::BufferUsages::INDEX,
            });
        self.chunks.push(SurfaceChunk {
            vertices,
            indices,
            index_count: self.indices.len() as u32,
        });
        self.vertices.clear();
        self.indices.clear();
        // Each buffer was filled through a staging copy that lives until a submission has
        // carried it to the GPU: send it now, so a mesh of many chunks never holds more than one
        // chunk's staging copies (16M triangles: 2.5 GB at the peak otherwise).
        self.queue.submit(std::iter::empty());
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }
}
