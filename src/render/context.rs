//! The GPU device the render core draws with: headless here (no surface), or handed over by
//! eframe in the lab. Any adapter works, a CPU one (lavapipe) included.
//!
//! Besides the device and queue it keeps the objects that live as long as the device: each pass's
//! pipelines and layouts, built once on first use and shared by every [`super::Session`] on it
//! ([`GpuContext::shared`]), so a new scene never compiles a shader again.

use std::any::{Any, TypeId};
use std::collections::{BTreeSet, HashMap};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use super::adapter::Capabilities;
pub use super::adapter::{headless_features, headless_limits, wanted_features, wanted_limits};
use super::RenderError;

/// A device-lifetime object of some pass.
/// A shared object and the shader files it was made from ([`super::shaders::recording`]).
type SharedObject = (Arc<dyn Any + Send + Sync>, BTreeSet<String>);

/// A device and queue with what the render core needs to know about them.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::AdapterInfo,
    /// Timestamp queries around passes are available.
    pub timestamps: bool,
    /// What the device can do, as the methods' needs ask it ([`Method::on`](super::Method::on)).
    pub caps: Capabilities,
    /// Why this adapter (`-v`): the backends looked at and how it was picked among them.
    pub chosen: String,
    /// Validation errors no error scope caught, kept instead of panicking.
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// Why the device was lost, once it is (a driver reset, a removed GPU, `destroy`).
    lost: Arc<Mutex<Option<String>>>,
    /// Device-lifetime pass objects by type and name ([`GpuContext::shared`]).
    shared: Mutex<HashMap<(TypeId, &'static str), SharedObject>>,
    /// [`FAULT_ENV`]: the submit that reports an injected error, and the submits so far.
    fault: Option<u64>,
    submits: AtomicU64,
}

/// `DBUFFER_GPU_FAULT=N` (1 when not a number): the N-th frame submitted on a device reports a
/// validation error as wgpu words one, instead of running. A test hook: how every command
/// prints a GPU's error (docs/development/testing.md), which no valid input provokes.
pub const FAULT_ENV: &str = "DBUFFER_GPU_FAULT";

/// The message an injected fault reports: wgpu's layout (a headline, then its causes).
pub const FAULT_MESSAGE: &str = "Validation Error\n\nCaused by:\n  In a CommandEncoder, label = \
                                 'Session::encoder'\n    an error injected by DBUFFER_GPU_FAULT \
                                 (a test of how errors are printed)\n";

impl GpuContext {
    /// Request an adapter and device without a window: `--backend` ([`super::adapter::set_backend`]),
    /// else `WGPU_BACKEND`, chooses the backends; `WGPU_ADAPTER_NAME` one adapter among several.
    pub fn headless() -> Result<GpuContext, RenderError> {
        let (instance, backends) = super::adapter::instance();
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        };
        let adapter = pollster::block_on(instance.request_adapter(&options))
            .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let mut ctx = Self::from_adapter(&adapter)?;
        ctx.chosen = match std::env::var("WGPU_ADAPTER_NAME") {
            Ok(name) => format!("{backends}; WGPU_ADAPTER_NAME={name}"),
            Err(_) => format!("{backends}; wgpu's pick for high performance"),
        };
        Ok(ctx)
    }

    /// Open a device on `adapter` with the features and limits the render core uses, ray
    /// queries included where the adapter has them ([`headless_features`]).
    pub fn from_adapter(adapter: &wgpu::Adapter) -> Result<GpuContext, RenderError> {
        let features = headless_features(adapter.features());
        Self::open(
            adapter,
            features,
            headless_limits(features, &adapter.limits()),
        )
    }

    /// Open a device on `adapter` with exactly `features` and `limits` (the weakest-device
    /// test opens one with WebGPU's downlevel limits and no optional features). wgpu's
    /// experimental features are allowed only where `features` asks for one (ray queries).
    pub fn open(
        adapter: &wgpu::Adapter,
        features: wgpu::Features,
        limits: wgpu::Limits,
    ) -> Result<GpuContext, RenderError> {
        let experimental = if features.intersects(wgpu::Features::all_experimental_mask()) {
            // SAFETY: wgpu's token that its experimental features may have bugs it will fix;
            // only ray queries are asked for, and only the shadow-ray tracer uses them
            // (`passes::trace`, held to the BVH traversed in WGSL by tests/gpu/trace.rs).
            unsafe { wgpu::ExperimentalFeatures::enabled() }
        } else {
            wgpu::ExperimentalFeatures::disabled()
        };
        let desc = wgpu::DeviceDescriptor {
            label: Some("dbuffer::device"),
            required_features: features,
            required_limits: limits,
            experimental_features: experimental,
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|e| RenderError::Device(e.to_string()))?;
        Ok(Self::with_adapter(device, queue, adapter))
    }

    /// Wrap a device someone else opened on `adapter` (eframe's): its capabilities are asked of
    /// the adapter, as wgpu validates them.
    pub fn with_adapter(device: wgpu::Device, queue: wgpu::Queue, adapter: &wgpu::Adapter) -> Self {
        let caps = Capabilities::of(adapter, device.features(), device.limits());
        let mut ctx = Self::new(device, queue, adapter.get_info());
        ctx.caps = caps;
        ctx
    }

    /// Wrap a device someone else opened, its adapter unknown: its formats are taken to be
    /// WebGPU's guaranteed ones (prefer [`GpuContext::with_adapter`]).
    pub fn new(device: wgpu::Device, queue: wgpu::Queue, adapter: wgpu::AdapterInfo) -> GpuContext {
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut errors) = sink.lock() {
                errors.push(e.to_string());
            }
        }));
        let lost = Arc::new(Mutex::new(None));
        let why = Arc::clone(&lost);
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut lost) = why.lock() {
                *lost = Some(if message.is_empty() {
                    format!("{reason:?}")
                } else {
                    format!("{reason:?}: {message}")
                });
            }
        });
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let caps = Capabilities::webgpu(&adapter, device.features(), device.limits());
        GpuContext {
            caps,
            chosen: "handed over by its caller".into(),
            device,
            queue,
            adapter,
            timestamps,
            uncaptured,
            lost,
            shared: Mutex::new(HashMap::new()),
            fault: std::env::var(FAULT_ENV)
                .ok()
                .map(|n| n.trim().parse().unwrap_or(1)),
            submits: AtomicU64::new(0),
        }
    }

    /// Count a frame's submit; `Err` for the one [`FAULT_ENV`] names.
    pub fn injected_fault(&self) -> Result<(), RenderError> {
        let n = self.submits.fetch_add(1, Ordering::Relaxed) + 1;
        match self.fault {
            Some(k) if k == n => Err(RenderError::Gpu(FAULT_MESSAGE.into())),
            _ => Ok(()),
        }
    }

    /// "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)".
    pub fn adapter_description(&self) -> String {
        super::adapter::describe(&self.adapter)
    }

    /// `Err(RenderError::Lost)` once the device is lost: nothing recorded on it will run again.
    pub fn check_lost(&self) -> Result<(), RenderError> {
        match self.lost.lock().ok().and_then(|l| l.clone()) {
            Some(why) => Err(RenderError::Lost(why)),
            None => Ok(()),
        }
    }

    /// [`GpuContext::check_lost`] after the work in flight finished (at most a quarter of a
    /// second): wgpu reports a loss from a poll, a destroyed device once its queue is empty.
    /// Only on an error path: it waits.
    pub fn check_lost_after_poll(&self) -> Result<(), RenderError> {
        let _ = self.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(std::time::Duration::from_millis(250)),
        });
        self.check_lost()
    }

    /// Errors the device reported outside any error scope since the last call.
    pub fn take_uncaptured_errors(&self) -> Vec<String> {
        self.uncaptured
            .lock()
            .map(|mut e| std::mem::take(&mut *e))
            .unwrap_or_default()
    }

    /// The device-lifetime object of type `T` (a pass's pipelines and layouts), made by `make`
    /// on first use.
    pub fn shared<T: Any + Send + Sync>(&self, make: impl FnOnce(&wgpu::Device) -> T) -> Arc<T> {
        self.shared_named("", make)
    }

    /// [`GpuContext::shared`] for several objects of one type, told apart by `name`.
    pub fn shared_named<T: Any + Send + Sync>(
        &self,
        name: &'static str,
        make: impl FnOnce(&wgpu::Device) -> T,
    ) -> Arc<T> {
        let key = (TypeId::of::<T>(), name);
        let cached = self.shared.lock().ok().and_then(|m| m.get(&key).cloned());
        if let Some((found, files)) = cached {
            if let Ok(found) = found.downcast::<T>() {
                // What is made from it depends on its files too.
                super::shaders::note(files.iter().map(String::as_str));
                return found;
            }
        }
        // Built outside the lock: making a pipeline may itself ask for another shared object.
        let (made, files) = super::shaders::recording(|| Arc::new(make(&self.device)));
        if let Ok(mut m) = self.shared.lock() {
            m.insert(key, (made.clone(), files));
        }
        made
    }

    /// Let go of every shared object made from one of `changed` (shader files, named as
    /// [`super::shaders`] names them), and of those made with one of them: the next `get`
    /// builds them from the shaders as they are now. How many were let go of.
    pub fn forget_shaders(&self, changed: &BTreeSet<String>) -> usize {
        let Ok(mut m) = self.shared.lock() else {
            return 0;
        };
        let before = m.len();
        m.retain(|_, (_, files)| files.is_disjoint(changed));
        before - m.len()
    }

    /// The largest 2D texture side the device takes.
    pub fn max_texture_side(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// The largest buffer the device takes.
    pub fn max_buffer_size(&self) -> u64 {
        self.device.limits().max_buffer_size
    }
}

/// Run `work` (recording and submitting GPU work on `device`) inside a capture of the attached
/// graphics debugger (RenderDoc's `StartFrameCapture`/`EndFrameCapture`, Xcode's capture
/// manager), waiting for the GPU before the capture ends; without a debugger attached wgpu does
/// nothing. The passes appear under the debug groups the frame's timer names.
pub fn capture<T>(device: &wgpu::Device, work: impl FnOnce() -> T) -> T {
    // SAFETY: wgpu's conditions: no other capture is active (this is the only place dbuffer
    // starts one, and `work` records and submits frames, never starting one) and one is active
    // when it is stopped (started just above, on the same device).
    unsafe { device.start_graphics_debugger_capture() };
    let out = work();
    let _ = device.poll(wgpu::PollType::Wait {
        submission_index: None,
        timeout: Some(super::watchdog::gpu_timeout()),
    });
    // SAFETY: the capture started above is the one active.
    unsafe { device.stop_graphics_debugger_capture() };
    out
}

/// Whether RenderDoc's library is loaded in this process (Linux: `/proc/self/maps`), which is
/// how wgpu finds it; `None` where that cannot be told.
pub fn renderdoc_attached() -> Option<bool> {
    std::fs::read_to_string("/proc/self/maps")
        .ok()
        .map(|maps| maps.contains("librenderdoc"))
}
