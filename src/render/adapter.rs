//! What an adapter can do, asked the way the methods state their needs
//! ([`super::methods::AdapterNeeds`]): features, which formats it renders into, blends, filters
//! or binds as storage, whether shaders may write storage, the limits. A method is checked
//! against these [`Capabilities`] before any work, so a device that cannot run it refuses it in
//! one line instead of failing in a pipeline the user never heard of.
//!
//! Also here: which backends the instance looks at (`--backend`, `WGPU_BACKEND`), every adapter
//! wgpu sees (`dbuffer adapters`), and why one was chosen (`-v`).

use std::fmt::Write as _;
use std::sync::OnceLock;

use wgpu::{DownlevelFlags, Features, TextureFormat, TextureFormatFeatureFlags, TextureUsages};

/// How a method uses a texture format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Usage {
    /// A colour target it renders into.
    Render,
    /// A colour target it blends into.
    Blend,
    /// Sampled with a filtering (linear) sampler.
    Filter,
    /// A depth or depth-stencil attachment.
    Depth,
    /// Bound as a storage texture.
    Storage,
}

impl Usage {
    /// "rendering to", to name a missing capability.
    pub fn verb(self) -> &'static str {
        match self {
            Usage::Render => "rendering to",
            Usage::Blend => "blending into",
            Usage::Filter => "filtering",
            Usage::Depth => "a depth-stencil attachment of",
            Usage::Storage => "storage textures of",
        }
    }
}

/// One format need: the first of `formats` is what the method uses; a later one is a fallback
/// it takes where the adapter lacks the first, at the cost `fallback` says (empty: none).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FormatNeed {
    pub usage: Usage,
    pub formats: &'static [TextureFormat],
    pub fallback: &'static str,
}

impl FormatNeed {
    pub const fn new(usage: Usage, format: &'static [TextureFormat]) -> FormatNeed {
        FormatNeed {
            usage,
            formats: format,
            fallback: "",
        }
    }
}

/// What a method gets on an adapter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Everything it asks for is there.
    Runs,
    /// It runs with the fallbacks named (and what they cost).
    Fallback(Vec<String>),
    /// It cannot run: what is missing, one item each.
    Cannot(Vec<String>),
}

impl Verdict {
    pub fn runs(&self) -> bool {
        !matches!(self, Verdict::Cannot(_))
    }
}

/// The formats the methods ask about (every one any method or the camera pass uses).
const FORMATS: &[TextureFormat] = &[
    TextureFormat::R8Unorm,
    TextureFormat::R16Float,
    TextureFormat::Rg16Float,
    TextureFormat::R32Float,
    TextureFormat::Rg32Float,
    TextureFormat::Rgba32Float,
    TextureFormat::Rgba8Unorm,
    TextureFormat::Rgba8UnormSrgb,
    TextureFormat::Depth32Float,
    TextureFormat::Depth24PlusStencil8,
    TextureFormat::Depth32FloatStencil8,
];

/// The major version of Mesa in a driver's description ("Mesa 22.3.6 (LLVM 15.0.6)"), if it is
/// Mesa.
pub fn mesa_major(driver_info: &str) -> Option<u32> {
    let version = driver_info.split("Mesa ").nth(1)?;
    version.split('.').next()?.trim().parse().ok()
}

/// What a device (or the device an adapter would open) can do, as far as the methods ask.
#[derive(Clone, Debug)]
pub struct Capabilities {
    /// "llvmpipe (LLVM 15.0.6, 256 bits) (Gl, Cpu)", to name it in a refusal.
    pub adapter: String,
    pub backend: wgpu::Backend,
    /// A discrete or integrated GPU, a CPU rasteriser (lavapipe, llvmpipe)…
    pub device_type: wgpu::DeviceType,
    /// The driver's own description ("Mesa 22.3.6 (LLVM 15.0.6)").
    pub driver_info: String,
    pub features: Features,
    pub limits: wgpu::Limits,
    pub downlevel: DownlevelFlags,
    formats: Vec<(TextureFormat, wgpu::TextureFormatFeatures)>,
}

impl Capabilities {
    /// The capabilities of a device with `features` and `limits` on `adapter` (its format
    /// support is the adapter's where wgpu uses it — a downlevel adapter or one asked for its
    /// own format features — and WebGPU's guaranteed one otherwise, as wgpu validates).
    pub fn of(adapter: &wgpu::Adapter, features: Features, limits: wgpu::Limits) -> Capabilities {
        let info = adapter.get_info();
        let downlevel = adapter.get_downlevel_capabilities().flags;
        let own = features.contains(Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
            || !downlevel.contains(DownlevelFlags::WEBGPU_TEXTURE_FORMAT_SUPPORT);
        let formats = FORMATS
            .iter()
            .map(|&f| {
                let ff = if !features.contains(f.required_features()) {
                    wgpu::TextureFormatFeatures {
                        allowed_usages: TextureUsages::empty(),
                        flags: TextureFormatFeatureFlags::empty(),
                    }
                } else if own {
                    adapter.get_texture_format_features(f)
                } else {
                    f.guaranteed_format_features(features)
                };
                (f, ff)
            })
            .collect();
        Capabilities {
            adapter: describe(&info),
            device_type: info.device_type,
            driver_info: info.driver_info.clone(),
            backend: info.backend,
            features,
            limits,
            downlevel,
            formats,
        }
    }

    /// A device wgpu validates as WebGPU does (`features`, `limits`, the guaranteed formats):
    /// for a device someone else opened without handing over its adapter.
    pub fn webgpu(info: &wgpu::AdapterInfo, features: Features, limits: wgpu::Limits) -> Self {
        let formats = FORMATS
            .iter()
            .map(|&f| (f, f.guaranteed_format_features(features)))
            .collect();
        Capabilities {
            adapter: describe(info),
            device_type: info.device_type,
            driver_info: info.driver_info.clone(),
            backend: info.backend,
            features,
            limits,
            downlevel: DownlevelFlags::all(),
            formats,
        }
    }

    /// The major version of Mesa, where the driver is Mesa's.
    pub fn mesa_major(&self) -> Option<u32> {
        mesa_major(&self.driver_info)
    }

    /// Whether shaders may trace rays through acceleration structures (hardware ray queries,
    /// `Features::EXPERIMENTAL_RAY_QUERY`): the shadow-ray tracer's first path
    /// (`passes::trace::Path::RayQuery`).
    pub fn ray_queries(&self) -> bool {
        self.features.contains(Features::EXPERIMENTAL_RAY_QUERY)
    }

    /// Whether `format` can be used as `usage`.
    pub fn supports(&self, format: TextureFormat, usage: Usage) -> bool {
        let Some((_, ff)) = self.formats.iter().find(|(f, _)| *f == format) else {
            return false;
        };
        let render = ff.allowed_usages.contains(TextureUsages::RENDER_ATTACHMENT);
        match usage {
            Usage::Render | Usage::Depth => render,
            Usage::Blend => render && ff.flags.contains(TextureFormatFeatureFlags::BLENDABLE),
            Usage::Filter => {
                ff.allowed_usages.contains(TextureUsages::TEXTURE_BINDING)
                    && ff.flags.contains(TextureFormatFeatureFlags::FILTERABLE)
            }
            Usage::Storage => ff.allowed_usages.contains(TextureUsages::STORAGE_BINDING),
        }
    }

    /// The first of `need.formats` the device takes, if any.
    pub fn pick(&self, need: &FormatNeed) -> Option<TextureFormat> {
        need.formats
            .iter()
            .copied()
            .find(|&f| self.supports(f, need.usage))
    }
}

/// "llvmpipe (LLVM 15.0.6, 256 bits) (Gl, Cpu)".
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}

/// The `--backend` the command line gave, for every instance this process makes.
static BACKEND: OnceLock<wgpu::Backends> = OnceLock::new();

/// The backends `--backend` names (`vulkan`, `gl`, `metal`, `dx12`), or why not.
pub fn parse_backend(text: &str) -> Result<wgpu::Backends, String> {
    match text.to_ascii_lowercase().as_str() {
        "vulkan" | "vk" => Ok(wgpu::Backends::VULKAN),
        "gl" | "gles" | "opengl" => Ok(wgpu::Backends::GL),
        "metal" | "mtl" => Ok(wgpu::Backends::METAL),
        "dx12" | "d3d12" => Ok(wgpu::Backends::DX12),
        _ => Err(format!(
            "--backend expects vulkan, gl, metal or dx12, found '{text}'"
        )),
    }
}

/// Use `backends` for every instance from now on (`--backend`; it wins over `WGPU_BACKEND`).
pub fn set_backend(backends: wgpu::Backends) {
    let _ = BACKEND.set(backends);
}

/// The backends `--backend` chose, if it was given.
pub fn backend() -> Option<wgpu::Backends> {
    BACKEND.get().copied()
}

/// The instance every headless device and `dbuffer adapters` start from, and why it looks at
/// the backends it does.
pub fn instance() -> (wgpu::Instance, String) {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    let why = if let Some(&b) = BACKEND.get() {
        desc.backends = b;
        format!("--backend {}", backend_name(b))
    } else if let Ok(v) = std::env::var("WGPU_BACKEND") {
        format!("WGPU_BACKEND={v}")
    } else {
        "every backend (no --backend, no WGPU_BACKEND)".into()
    };
    (wgpu::Instance::new(desc), why)
}

fn backend_name(b: wgpu::Backends) -> &'static str {
    if b == wgpu::Backends::VULKAN {
        "vulkan"
    } else if b == wgpu::Backends::GL {
        "gl"
    } else if b == wgpu::Backends::METAL {
        "metal"
    } else if b == wgpu::Backends::DX12 {
        "dx12"
    } else {
        "several"
    }
}

/// One adapter as `dbuffer adapters` lists it.
pub struct AdapterReport {
    pub info: wgpu::AdapterInfo,
    pub caps: Capabilities,
}

/// Every adapter the instance sees, on every backend it looks at.
pub fn every_adapter() -> (Vec<AdapterReport>, String) {
    let (instance, why) = instance();
    let backends = BACKEND
        .get()
        .copied()
        .unwrap_or_else(|| wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all()));
    let adapters = pollster::block_on(instance.enumerate_adapters(backends));
    let reports = adapters
        .iter()
        .map(|a| {
            let features = headless_features(a.features());
            AdapterReport {
                info: a.get_info(),
                caps: Capabilities::of(a, features, headless_limits(features, &a.limits())),
            }
        })
        .collect();
    (reports, why)
}

/// The lines of `info` for `-v` and `dbuffer adapters`: name, backend, type, driver.
pub fn info_line(info: &wgpu::AdapterInfo) -> String {
    let mut s = format!(
        "{} — backend {:?}, {:?}",
        info.name, info.backend, info.device_type
    );
    if !info.driver.is_empty() || !info.driver_info.is_empty() {
        let _ = write!(s, ", driver {} {}", info.driver, info.driver_info);
    }
    s.trim_end().to_string()
}

/// Mesa's Vulkan device-select layer asks the window system (Wayland, X11) which GPU drives the
/// display and complains on stderr, twice, where there is none (ssh, CI, a container): a
/// headless command has no display to match, so the layer is switched off unless the user set
/// `NODEVICE_SELECT`. Call it first thing in `main`, before any thread reads the environment.
///
/// Also: wgpu's GL backend looks for float colour buffers only as an extension, and Mesa's
/// desktop GL core context (where they are core since GL 3.0) does not list one, so wgpu calls
/// `R32Float` and `Rg32Float` unrenderable there; naming the extension for Mesa
/// (`MESA_EXTENSION_OVERRIDE`, read by Mesa alone, unless the user set it) tells wgpu what the
/// context already does.
pub fn quiet_device_select() {
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
    if std::env::var_os("MESA_EXTENSION_OVERRIDE").is_none() {
        std::env::set_var("MESA_EXTENSION_OVERRIDE", "+GL_ARB_color_buffer_float");
    }
}

/// The machine the adapter runs on, "AMD EPYC 7B13, 2 cores" from /proc/cpuinfo where there is
/// one (a CPU rasteriser's times are this machine's), else the architecture.
pub fn host_description() -> String {
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{model}, {cores} cores")
}

/// The limits the render core asks of an adapter: everything the adapter supports where it
/// matters for size (buffers, textures), so every image, D-buffer and mesh inside the budget that
/// the adapter can hold works, not only what wgpu's portable defaults allow.
pub fn wanted_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
    wgpu::Limits {
        max_texture_dimension_2d: adapter.max_texture_dimension_2d,
        max_texture_array_layers: adapter.max_texture_array_layers,
        max_buffer_size: adapter.max_buffer_size,
        max_storage_buffer_binding_size: adapter.max_storage_buffer_binding_size,
        max_uniform_buffer_binding_size: adapter.max_uniform_buffer_binding_size,
        ..wgpu::Limits::default().using_resolution(adapter.clone())
    }
}

/// The features the render core uses when the adapter has them: timestamps (pass timings), a
/// float depth-stencil format (the stencil shadow methods' precision; they fall back on
/// `Depth24PlusStencil8` without it) and blending into 32-bit float targets (the penumbra
/// wedges' coverage sum; `R16Float` without it).
pub fn wanted_features(adapter: wgpu::Features) -> wgpu::Features {
    adapter
        & (wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::DEPTH32FLOAT_STENCIL8
            | wgpu::Features::FLOAT32_BLENDABLE)
}

/// The features a headless device asks for ([`super::GpuContext::from_adapter`], and what
/// `dbuffer adapters` reports): [`wanted_features`], and ray queries where the adapter has them
/// (the shadow-ray tracer's hardware path). Ray queries are an experimental wgpu feature, so a
/// device that gets them is opened with wgpu's experimental features allowed; the lab's window
/// asks for [`wanted_features`] alone.
pub fn headless_features(adapter: wgpu::Features) -> wgpu::Features {
    wanted_features(adapter) | (adapter & wgpu::Features::EXPERIMENTAL_RAY_QUERY)
}

/// The limits a device with `features` asks of an adapter with `adapter`: [`wanted_limits`],
/// with the adapter's acceleration-structure limits where `features` has ray queries (WebGPU's
/// defaults allow none).
pub fn headless_limits(features: wgpu::Features, adapter: &wgpu::Limits) -> wgpu::Limits {
    let limits = wanted_limits(adapter);
    if features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) {
        limits.using_acceleration_structure_values(adapter.clone())
    } else {
        limits
    }
}
