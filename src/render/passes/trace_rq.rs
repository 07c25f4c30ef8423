//! The scene's triangles as a hardware acceleration structure, for the shadow-ray tracer's
//! ray-query path (`passes::trace::Path::RayQuery`, `shaders/passes/trace_rq.wgsl`): one bottom
//! level (BLAS) of every triangle of the CPU's BVH, in world space, as a plain list of
//! `Float32x3` vertices (three a triangle, no index buffer), all of it opaque, under a top level
//! (TLAS) of one instance with the identity transform. The driver builds both; the device needs
//! `Features::EXPERIMENTAL_RAY_QUERY` (`Capabilities::ray_queries`).

use glam::Vec3;

use crate::render::{GpuContext, RenderError};

/// The identity transform of the one instance: 3×4, row major.
const IDENTITY: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// A triangle no ray hits: Vulkan calls a triangle with a NaN vertex coordinate inactive. The
/// acceleration structure of a scene without triangles holds this one (a BLAS is never empty).
const INACTIVE: [Vec3; 3] = [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ZERO, Vec3::ZERO];

/// The scene's triangles, built into a TLAS over one BLAS.
pub struct Accel {
    pub(crate) tlas: wgpu::Tlas,
    /// Kept with the TLAS that refers to it.
    _blas: wgpu::Blas,
    _vertices: wgpu::Buffer,
}

impl Accel {
    /// Builds the acceleration structure of `triangles` (recorded and submitted; usable by any
    /// later submission); an error, before anything is made, where the device has no ray
    /// queries or takes fewer triangles in one BLAS.
    pub fn new(ctx: &GpuContext, triangles: &[[Vec3; 3]]) -> Result<Accel, RenderError> {
        if !ctx.caps.ray_queries()
            || ctx.caps.limits.max_acceleration_structures_per_shader_stage < 1
        {
            return Err(RenderError::Request(format!(
                "hardware ray queries are not available on {}",
                ctx.adapter_description()
            )));
        }
        let limits = ctx.device.limits();
        let count = triangles.len().max(1);
        let too_many = || {
            RenderError::Request(format!(
                "the scene has {count} triangles; one acceleration structure on {} holds at \
                 most {}",
                ctx.adapter_description(),
                limits.max_blas_primitive_count
            ))
        };
        let primitives = u32::try_from(count).map_err(|_| too_many())?;
        if primitives > limits.max_blas_primitive_count || limits.max_tlas_instance_count < 1 {
            return Err(too_many());
        }
        let bytes = count as u64 * 36;
        if bytes > limits.max_buffer_size {
            return Err(RenderError::Request(format!(
                "the scene's triangles need a {bytes}-byte buffer; {} takes at most {}",
                ctx.adapter_description(),
                limits.max_buffer_size
            )));
        }
        let source = if triangles.is_empty() {
            std::slice::from_ref(&INACTIVE)
        } else {
            triangles
        };
        let words: Vec<[f32; 3]> = source
            .iter()
            .flat_map(|t| t.map(|v| v.to_array()))
            .collect();
        let vertices = {
            use wgpu::util::DeviceExt;
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("Accel::vertices"),
                    contents: bytemuck::cast_slice(&words),
                    usage: wgpu::BufferUsages::BLAS_INPUT,
                })
        };
        let size = wgpu::BlasTriangleGeometrySizeDescriptor {
            vertex_format: wgpu::VertexFormat::Float32x3,
            vertex_count: primitives * 3,
            index_format: None,
            index_count: None,
            flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
        };
        let blas = ctx.device.create_blas(
            &wgpu::CreateBlasDescriptor {
                label: Some("Accel::blas"),
                flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                update_mode: wgpu::AccelerationStructureUpdateMode::Build,
            },
            wgpu::BlasGeometrySizeDescriptors::Triangles {
                descriptors: vec![size.clone()],
            },
        );
        let mut tlas = ctx.device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("Accel::tlas"),
            max_instances: 1,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        tlas[0] = Some(wgpu::TlasInstance::new(&blas, IDENTITY, 0, 0xff));
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("Accel::build"),
            });
        encoder.build_acceleration_structures(
            std::iter::once(&wgpu::BlasBuildEntry {
                blas: &blas,
                geometry: wgpu::BlasGeometries::TriangleGeometries(vec![
                    wgpu::BlasTriangleGeometry {
                        size: &size,
                        vertex_buffer: &vertices,
                        first_vertex: 0,
                        vertex_stride: 12,
                        index_buffer: None,
                        first_index: None,
                        transform_buffer: None,
                        transform_buffer_offset: None,
                    },
                ]),
            }),
            std::iter::once(&tlas),
        );
        ctx.queue.submit([encoder.finish()]);
        ctx.check_lost()?;
        Ok(Accel {
            tlas,
            _blas: blas,
            _vertices: vertices,
        })
    }
}
