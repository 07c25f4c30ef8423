//! The scene on the GPU: every surface triangle (flat-shaded, both passes) and each caster's
//! umbra and penumbra volumes (the light pass). Surfaces are uploaded once per scene; volumes again
//! whenever the geometry stage ran (the light or a caster moved).

use glam::Vec3;
use wgpu::util::DeviceExt;

use super::{SurfaceVertex, VolumeVertex};
use crate::geometry::{CasterGeometry, SceneGeometry};
use crate::scene::Scene;

/// Albedo of casters and of receivers-only objects (the ground).
const CASTER_ALBEDO: f32 = 0.75;
const RECEIVER_ALBEDO: f32 = 0.85;

/// A vertex buffer and how many vertices it holds (`None` when empty: wgpu has no empty buffers).
pub struct VertexBuffer {
    pub buffer: Option<wgpu::Buffer>,
    pub count: u32,
}

impl VertexBuffer {
    fn new<T: bytemuck::Pod>(device: &wgpu::Device, label: &str, data: &[T]) -> VertexBuffer {
        let buffer = (!data.is_empty()).then(|| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(data),
                usage: wgpu::BufferUsages::VERTEX,
            })
        });
        VertexBuffer {
            buffer,
            count: data.len() as u32,
        }
    }

    /// Draw all vertices, if any.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.draw_instances(pass, 0..1);
    }

    /// Draw all vertices for each of `instances` (a shader may read its `instance_index`).
    pub fn draw_instances(&self, pass: &mut wgpu::RenderPass<'_>, instances: std::ops::Range<u32>) {
        if let Some(b) = &self.buffer {
            pass.set_vertex_buffer(0, b.slice(..));
            pass.draw(0..self.count, instances);
        }
    }
}

/// One caster's volumes on the GPU.
pub struct CasterVolumes {
    pub umbra: VertexBuffer,
}

pub struct GpuScene {
    pub surfaces: VertexBuffer,
    pub casters: Vec<CasterVolumes>,
    /// Every caster's penumbra triangles: one rule (nearest entry) over all of them.
    pub penumbra: VertexBuffer,
    /// Bounds `(min, max)` of every surface, taken once at upload (the camera's depth range is
    /// derived from them each frame).
    pub bounds: (Vec3, Vec3),
}

impl GpuScene {
    pub fn new(device: &wgpu::Device, scene: &Scene, geometry: &SceneGeometry) -> GpuScene {
        let mut surfaces = Vec::new();
        let mut bounds = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for object in &scene.objects {
            if let Some((lo, hi)) = object.mesh.bounds() {
                bounds = (bounds.0.min(lo), bounds.1.max(hi));
            }
            let albedo = if object.casts_shadow {
                CASTER_ALBEDO
            } else {
                RECEIVER_ALBEDO
            };
            for tri in object.mesh.triangle_corners() {
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
                surfaces.extend(tri.map(|p| SurfaceVertex {
                    position: p.to_array(),
                    albedo,
                    normal: n.to_array(),
                    _pad: 0.0,
                }));
            }
        }
        let mut gpu = GpuScene {
            surfaces: VertexBuffer::new(device, "GpuScene::surfaces", &surfaces),
            casters: Vec::new(),
            penumbra: VertexBuffer::new::<VolumeVertex>(device, "GpuScene::penumbra", &[]),
            bounds,
        };
        gpu.set_volumes(device, geometry);
        gpu
    }

    /// Replace the volumes after the geometry stage ran again.
    pub fn set_volumes(&mut self, device: &wgpu::Device, geometry: &SceneGeometry) {
        let mut penumbra = Vec::new();
        self.casters = geometry
            .casters
            .iter()
            .map(|g| {
                let (umbra, pen) = volume_vertices(g);
                penumbra.extend(pen);
                CasterVolumes {
                    umbra: VertexBuffer::new(device, "GpuScene::umbra", &umbra),
                }
            })
            .collect();
        self.penumbra = VertexBuffer::new(device, "GpuScene::penumbra", &penumbra);
    }
}

/// The caster's volume triangles as GPU vertices, umbra and penumbra apart, each vertex carrying
/// its triangle's normal (the winding says which way a ray crosses it).
pub fn volume_vertices(g: &CasterGeometry) -> (Vec<VolumeVertex>, Vec<VolumeVertex>) {
    let (mut umbra, mut penumbra) = (Vec::new(), Vec::new());
    for i in 0..g.volumes.triangle_count() {
        let (corners, attrs) = g.volumes.triangle(i);
        let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let n = n.normalize_or_zero();
        let out = if attrs.kind.is_umbra() {
            &mut umbra
        } else {
            &mut penumbra
        };
        out.extend(corners.map(|p| VolumeVertex {
            position: p.to_array(),
            kind: attrs.kind.code(),
            normal: n.to_array(),
            edge_a: attrs.edge[0].to_array(),
            edge_b: attrs.edge[1].to_array(),
            extrusion: attrs.extrusion.to_array(),
            ..VolumeVertex::default()
        }));
    }
    (umbra, penumbra)
}
