//! The render core on wgpu, headless (`dbuffer render`, `compare`, `bench`, the tests) and inside
//! the lab window alike.
//!
//! - [`frame`]: what a frame is ([`FrameRequest`], the [`FrameTargets`] it stays in on the GPU,
//!   the [`Frame`] read back from them) and the pass order, in one short function;
//! - [`methods`]: one module per shadow method and the registry of them;
//! - [`passes`]: one file per pass, each with its WGSL twin of the same name in `shaders/passes/`;
//!   below them what passes and methods share: [`light_maps`] (what a method keeps in light
//!   space) and [`frame_data`] (a frame read back); `docs/development/architecture.md` ranks
//!   the modules;
//! - [`session`]: a scene being looked at over many frames (light-space work only when the light
//!   or a caster moved); [`offline`]: one frame, read back into a render's files;
//! - [`reference`]: the ray-cast ground truth, on the CPU, in a worker thread for the lab;
//! - [`readback`], [`timer`], [`gpu_scene`], [`context`]: staging buffers, pass timings, the
//!   scene's surfaces on the GPU, the device.

pub mod adapter;
pub mod context;
pub mod frame;
pub mod frame_data;
pub mod frame_tag;
pub mod gpu_reference;
pub mod gpu_scene;
pub mod light_maps;
pub mod methods;
pub mod offline;
pub mod passes;
pub mod readback;
pub mod reference;
pub mod session;
pub mod shaders;
pub mod timer;
pub mod truth;
pub mod view_session;
pub mod watchdog;

pub use context::GpuContext;
pub use frame::{Frame, FrameRequest, FrameTargets};
pub use methods::{Knobs, Method};
pub use session::Session;

/// The expanded source of a shader, as [`shaders`] reads them now: the embedded copies, or a
/// folder's (`dbuffer gui --shaders DIR`, `DBUFFER_SHADER_DIR`) once they validated. The embedded
/// set is fixed at compile time and `tests/gpu/shaders.rs` expands and validates every file of
/// it, so a failure here is a build defect or a file missing from the folder; it still yields
/// WGSL (an empty module) rather than a panic, and pipeline creation then reports it.
pub(crate) fn shader(name: &str) -> String {
    shaders::expanded(name)
        .map(|e| e.source)
        .unwrap_or_else(|e| format!("// {e}\n"))
}

/// A shader module from an embedded shader, labelled with its name.
pub(crate) fn shader_module(device: &wgpu::Device, name: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(shader(name).into()),
    })
}

/// A storage-buffer entry of a bind group layout.
pub(crate) fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
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

/// An entry for a float texture read with `textureLoad` (not filterable: the 32-bit float
/// targets are not).
pub(crate) fn texture_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    view_dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension,
            multisampled: false,
        },
        count: None,
    }
}

/// A bind group entry for a texture view.
pub(crate) fn view_entry(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

/// A bind group entry for a whole buffer.
pub(crate) fn buffer_entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// A uniform buffer of `T`, written each frame.
pub(crate) fn uniform_buffer<T>(device: &wgpu::Device, label: &str) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: std::mem::size_of::<T>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A read-only storage buffer holding `words` (look-up tables made once on the CPU).
pub(crate) fn storage_buffer<T: bytemuck::Pod>(
    device: &wgpu::Device,
    label: &str,
    words: &[T],
) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(words),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// A 2D texture with one mip level and its default view.
pub struct Texture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
}

impl Texture {
    pub fn new(
        device: &wgpu::Device,
        label: &str,
        (width, height): (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> Texture {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Texture { texture, view }
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

/// A colour attachment cleared to `clear` and stored.
pub(crate) fn cleared(
    view: &wgpu::TextureView,
    clear: wgpu::Color,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(clear),
            store: wgpu::StoreOp::Store,
        },
    })
}

/// `(r, 0, 0, 0)`: the clear value of a distance target.
pub(crate) fn red(r: f64) -> wgpu::Color {
    wgpu::Color {
        r,
        g: 0.0,
        b: 0.0,
        a: 0.0,
    }
}

/// A depth attachment loaded with `load`; its content is kept when `store`.
pub(crate) fn depth_attachment(
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<f32>,
    store: bool,
) -> Option<wgpu::RenderPassDepthStencilAttachment<'_>> {
    Some(wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load,
            store: if store {
                wgpu::StoreOp::Store
            } else {
                wgpu::StoreOp::Discard
            },
        }),
        stencil_ops: None,
    })
}

/// What a pipeline over the scene's surfaces or volumes needs to know.
pub(crate) struct PipelineSpec<'a> {
    pub label: &'a str,
    pub module: &'a wgpu::ShaderModule,
    pub layout: &'a wgpu::PipelineLayout,
    pub vs: &'a str,
    pub fs: Option<&'a str>,
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    pub cull: Option<wgpu::Face>,
    pub depth: Option<wgpu::DepthStencilState>,
}

pub(crate) fn render_pipeline(
    device: &wgpu::Device,
    spec: &PipelineSpec<'_>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some(spec.vs),
            compilation_options: Default::default(),
            buffers: spec.buffers,
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: spec.cull,
            ..Default::default()
        },
        depth_stencil: spec.depth.clone(),
        multisample: wgpu::MultisampleState::default(),
        fragment: spec.fs.map(|fs| wgpu::FragmentState {
            module: spec.module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets: spec.targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A Depth32Float test with depth writes.
pub(crate) fn depth_test(compare: wgpu::CompareFunction) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: wgpu::TextureFormat::Depth32Float,
        depth_write_enabled: Some(true),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    })
}

/// A pipeline that draws one full-screen triangle (`vs_main`, no vertex buffers) into one
/// opaque colour target with `fs_main`: the image-space passes.
pub(crate) fn fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[opaque(format)],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// An image-space pass made whole: the bind group layout of `entries` (`NAME::layout`), and the
/// [`fullscreen_pipeline`] of the shader `shader` over it into `format` (`NAME::pipeline`).
pub(crate) fn fullscreen_pass(
    device: &wgpu::Device,
    name: &str,
    shader: &'static str,
    entries: &[wgpu::BindGroupLayoutEntry],
    format: wgpu::TextureFormat,
) -> (wgpu::RenderPipeline, wgpu::BindGroupLayout) {
    let module = shader_module(device, shader);
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(&format!("{name}::layout")),
        entries,
    });
    let pipeline = fullscreen_pipeline(
        device,
        &format!("{name}::pipeline"),
        &pipeline_layout(device, name, &[&layout]),
        &module,
        format,
    );
    (pipeline, layout)
}

/// A pipeline layout over bind group layouts.
pub(crate) fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|g| Some(*g)).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

/// The compute pipeline of `module`'s `entry` under `layout`, labelled `label`.
pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
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
    #[error(
        "the GPU device was lost ({0}); nothing more can be drawn with it: save the scene and \
         start dbuffer again"
    )]
    Lost(String),
    #[error(
        "the GPU did not finish its work within {0} s (DBUFFER_GPU_TIMEOUT_S sets the limit): a \
         shader that does not end, such as a loop whose exit is never taken, or a frame too \
         large for this device; nothing more can be drawn with it"
    )]
    Stalled(f64),
    #[error("{0}")]
    Request(String),
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    #[error("{what} of {size} is not supported by this adapter ({adapter}): expected 1 to {max}")]
    Size {
        what: &'static str,
        size: u32,
        max: u32,
        adapter: String,
    },
}

/// `value`, or the GPU error `missing` (a pass that should have made it did not).
pub fn require<T>(value: Option<T>, missing: &str) -> Result<T, RenderError> {
    value.ok_or_else(|| RenderError::Gpu(missing.into()))
}

/// GPU vertex of a scene surface (every pass that draws the scene). Layout checked against the
/// WGSL `SurfaceIn` by `tests/gpu/render_layout.rs`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SurfaceVertex {
    pub position: [f32; 3],
    pub albedo: f32,
}

impl SurfaceVertex {
    pub const ATTRIBUTES: [wgpu::VertexAttribute; 2] = [
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32,
            offset: 12,
            shader_location: 1,
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

/// The vertex layout of a shadow-volume triangle ([`VolumeVertex`], defined with the CPU code
/// that makes it in `geometry::volume_vertices`).
pub use crate::geometry::volume_vertices::VolumeVertex;

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
            format: wgpu::VertexFormat::Float32,
            offset: 16,
            shader_location: 2,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32,
            offset: 20,
            shader_location: 3,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32,
            offset: 24,
            shader_location: 4,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x2,
            offset: 28,
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

const _: () = assert!(std::mem::size_of::<SurfaceVertex>() == 16);
const _: () = assert!(std::mem::size_of::<VolumeVertex>() == 36);
