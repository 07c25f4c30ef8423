//! The render core on wgpu: the D-buffer from the light centre, then the camera pass. Headless
//! (`dbuffer render`, the tests) and inside the lab window alike; the pass order is in
//! [`frame`], each pass is one file here with its WGSL twin of the same name in `shaders/`.

pub mod camera_pass;
pub mod context;
pub mod frame;
pub mod gpu_scene;
pub mod light_pass;
pub mod offline;
mod readback;
pub mod reference;
pub mod sample_maps;
pub mod session;

pub use context::GpuContext;
pub use frame::{Frame, FrameRenderer, FrameRequest, Method, MethodParams};

/// The expanded source of an embedded shader. The embedded set is fixed at compile time and
/// `tests/shaders.rs` expands and validates every file of it, so a failure here is a build defect;
/// it still yields WGSL (an empty module) rather than a panic, and pipeline creation then reports it.
pub(crate) fn shader(name: &str) -> String {
    crate::shader_source::load(name).unwrap_or_else(|e| format!("// {e}\n"))
}

/// A uniform-buffer entry of a bind group layout.
pub(crate) fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A fragment-stage entry for a float texture read with `textureLoad` (not filterable: the
/// 32-bit float targets are not).
pub(crate) fn texture_entry(
    binding: u32,
    view_dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension,
            multisampled: false,
        },
        count: None,
    }
}

/// A colour target written as is (no blending).
pub(crate) fn opaque(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A pipeline that draws the scene's surfaces ([`SurfaceVertex`]) with `vs_main`/`fs_main` of
/// `module`, two-sided, nearest depth (Depth32Float) wins.
pub(crate) fn surface_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(SurfaceVertex::layout())],
        },
        // Surfaces are two-sided (open meshes, the ground seen from below).
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// What can go wrong on the GPU side. Never a panic: a message for the user.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("no GPU adapter found ({0}); on a machine without a GPU install Mesa's Vulkan driver (Debian: mesa-vulkan-drivers) and set WGPU_BACKEND=vulkan")]
    NoAdapter(String),
    #[error("the GPU refused to open a device: {0}")]
    Device(String),
    #[error("the GPU reported an error: {0}")]
    Gpu(String),
    #[error("{0}")]
    Request(String),
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    #[error("{what} of {size} is not supported: expected 1 to {max}")]
    Size {
        what: &'static str,
        size: u32,
        max: u32,
    },
}

/// GPU vertex of a scene surface (both passes). Layout checked against the WGSL `SurfaceIn` by
/// `tests/render_layout.rs`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SurfaceVertex {
    pub position: [f32; 3],
    pub albedo: f32,
    pub normal: [f32; 3],
    pub _pad: f32,
}

impl SurfaceVertex {
    pub const ATTRIBUTES: [wgpu::VertexAttribute; 3] = [
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 16,
            shader_location: 1,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32,
            offset: 12,
            shader_location: 2,
        },
    ];

    pub fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

/// GPU vertex of a shadow volume: position, kind, the triangle's normal, and the silhouette edge
/// and rim point it was extruded from (for eq. 2 per fragment).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VolumeVertex {
    pub position: [f32; 3],
    pub kind: u32,
    pub normal: [f32; 3],
    pub _pad0: f32,
    pub edge_a: [f32; 3],
    pub _pad1: f32,
    pub edge_b: [f32; 3],
    pub _pad2: f32,
    pub extrusion: [f32; 3],
    pub _pad3: f32,
}

impl VolumeVertex {
    pub const ATTRIBUTES: [wgpu::VertexAttribute; 6] = [
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Uint32,
            offset: 12,
            shader_location: 1,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 16,
            shader_location: 2,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 32,
            shader_location: 3,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 48,
            shader_location: 4,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 64,
            shader_location: 5,
        },
    ];

    pub fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<VolumeVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

/// `LightUniforms` of `shaders/light_pass.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub center: [f32; 4],
    pub normal: [f32; 4],
    pub depth_scale: [f32; 4],
}

/// `CameraUniforms` of `shaders/camera_pass.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CameraUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub light_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub light_center: [f32; 4],
    pub light_normal: [f32; 4],
    pub bias: [f32; 4],
    pub mode: [u32; 4],
}

/// `MethodUniforms` of `shaders/camera_pass.wgsl`: the knobs of the comparison methods.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MethodUniforms {
    /// PCF radius (texels), PCSS blocker taps, PCSS filter taps, sampled lights.
    pub params: [f32; 4],
    /// x: the nearest caster's distance from the light centre (PCSS blocker search).
    pub pcss: [f32; 4],
    /// Light-view clip space back to world (receiver-plane depth of filter taps).
    pub inv_light_view_proj: [[f32; 4]; 4],
    /// 64 Poisson-disk points in the unit disk, two per entry (xy, zw); every prefix is spread.
    pub poisson: [[f32; 4]; 32],
}

/// One point light of the `sampled` method (`shaders/shared/sample_lights.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleLight {
    pub view_proj: [[f32; 4]; 4],
    pub point: [f32; 4],
}

/// Every point light of the `sampled` method.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleLights {
    pub lights: [SampleLight; 64],
}

const _: () = assert!(std::mem::size_of::<MethodUniforms>() == 608);
const _: () = assert!(std::mem::size_of::<SampleLights>() == 64 * 80);
const _: () = assert!(std::mem::size_of::<SurfaceVertex>() == 32);
const _: () = assert!(std::mem::size_of::<VolumeVertex>() == 80);
const _: () = assert!(std::mem::size_of::<LightUniforms>() == 112);
const _: () = assert!(std::mem::size_of::<CameraUniforms>() == 208);
