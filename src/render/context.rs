//! The GPU device the render core draws with: headless here (no surface), or handed over by
//! eframe in the lab. Any adapter works, a CPU one (lavapipe) included.

use std::sync::{Arc, Mutex};

use super::RenderError;

/// A device and queue with what the render core needs to know about them.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::AdapterInfo,
    /// Timestamp queries around passes are available.
    pub timestamps: bool,
    /// Validation errors no error scope caught, kept instead of panicking.
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl GpuContext {
    /// Request an adapter and device without a window. `WGPU_BACKEND` and `WGPU_ADAPTER_NAME`
    /// choose among several.
    pub fn headless() -> Result<GpuContext, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        };
        let adapter = pollster::block_on(instance.request_adapter(&options))
            .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        Self::from_adapter(&adapter)
    }

    /// Open a device on `adapter` with the features the render core uses when present.
    pub fn from_adapter(adapter: &wgpu::Adapter) -> Result<GpuContext, RenderError> {
        let info = adapter.get_info();
        let wanted = wgpu::Features::TIMESTAMP_QUERY;
        let features = adapter.features() & wanted;
        let desc = wgpu::DeviceDescriptor {
            label: Some("dbuffer::device"),
            required_features: features,
            required_limits: wgpu::Limits::default().using_resolution(adapter.limits()),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|e| RenderError::Device(e.to_string()))?;
        Ok(Self::new(device, queue, info))
    }

    /// Wrap a device someone else opened (eframe's).
    pub fn new(device: wgpu::Device, queue: wgpu::Queue, adapter: wgpu::AdapterInfo) -> GpuContext {
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut errors) = sink.lock() {
                errors.push(e.to_string());
            }
        }));
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        GpuContext {
            device,
            queue,
            adapter,
            timestamps,
            uncaptured,
        }
    }

    /// "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)".
    pub fn adapter_description(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.adapter.name, self.adapter.backend, self.adapter.device_type
        )
    }

    /// Errors the device reported outside any error scope since the last call.
    pub fn take_uncaptured_errors(&self) -> Vec<String> {
        self.uncaptured
            .lock()
            .map(|mut e| std::mem::take(&mut *e))
            .unwrap_or_default()
    }
}
