//! The lab in a kittest window on the wgpu (lavapipe) adapter, small and quick: a 256² D-buffer,
//! half resolution, 16 reference samples. Values come back from the GPU a frame or more later
//! (a probe, the reference's samples), and the window repaints until they have: on lavapipe
//! that can take a few dozen quick test frames, hence the generous step limit. Tests that wait
//! for such values step the window on a signal (the worker's news, the GPU's queue running
//! empty), never on a timer.

use std::time::{Duration, Instant};

use dbuffer::app::{LabApp, LabOptions};
use dbuffer::render::reference::ReferenceWorker;
use eframe::egui;
use eframe::egui_wgpu;
use eframe::wgpu;
use egui_kittest::Harness;

/// The lab on `scene` (the default scene for `None`) in a `width`×`height` window.
pub fn lab_sized(scene: Option<&str>, width: f32, height: f32) -> Harness<'static, LabApp> {
    lab_with(
        LabOptions {
            scene: scene.map(str::to_string),
            ..LabOptions::default()
        },
        width,
        height,
    )
}

/// The lab as `options` say (made deterministic), in a `width`×`height` window.
pub fn lab_with(options: LabOptions, width: f32, height: f32) -> Harness<'static, LabApp> {
    build(
        Harness::builder()
            .with_size(egui::vec2(width, height))
            .with_max_steps(500)
            .with_render_cursor(false)
            .wgpu(),
        options,
    )
}

/// The lab on `scene` on a device with timestamp queries where the adapter has them (as the
/// lab's own window asks for), so the Stats panel lists GPU time per pass.
pub fn lab_timed(scene: &str, width: f32, height: f32) -> Harness<'static, LabApp> {
    lab_timed_with(
        LabOptions {
            scene: Some(scene.to_string()),
            ..LabOptions::default()
        },
        width,
        height,
    )
}

/// [`lab_timed`] as `options` say.
pub fn lab_timed_with(options: LabOptions, width: f32, height: f32) -> Harness<'static, LabApp> {
    let egui_wgpu::WgpuSetup::CreateNew(mut setup) = egui_kittest::wgpu::default_wgpu_setup()
    else {
        unreachable!("kittest creates its device")
    };
    setup.device_descriptor =
        std::sync::Arc::new(|adapter: &wgpu::Adapter| wgpu::DeviceDescriptor {
            label: Some("lab test device with timestamps"),
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            ..Default::default()
        });
    build(
        Harness::builder()
            .with_size(egui::vec2(width, height))
            .with_max_steps(500)
            .with_render_cursor(false)
            .wgpu_setup(egui_wgpu::WgpuSetup::CreateNew(setup)),
        options,
    )
}

fn build(
    builder: egui_kittest::HarnessBuilder<LabApp>,
    options: LabOptions,
) -> Harness<'static, LabApp> {
    builder.build_eframe(move |cc| {
        let mut app = LabApp::new(
            cc,
            LabOptions {
                deterministic: true,
                ..options.clone()
            },
        );
        app.settings.dbuffer_size = 256;
        app.settings.render_scale = 0.5;
        // The tests watch the CPU's reference worker (its thread, its news).
        app.settings.reference_engine = "cpu".into();
        app.settings.reference_samples = 16;
        app
    })
}

/// One of the core's two reference workers.
#[derive(Clone, Copy)]
pub enum Worker {
    /// The area reference's (`reference`, the error view).
    Area,
    /// The exact hard shadow's (`reference-hard`).
    Hard,
}

/// `worker` of the lab's render core.
pub fn worker<'h>(h: &'h Harness<'_, LabApp>, worker: Worker) -> &'h ReferenceWorker {
    let core = h.state().core().expect("the lab has a render core");
    match worker {
        Worker::Area => &core.worker,
        Worker::Hard => &core.hard_worker,
    }
}

/// Steps the window until `ready`, a step each time `of` has news (new samples handed over, or
/// it went idle): the worker casts its rays on its own thread in real time, and the window has
/// something new to show only then. At least one step a second regardless, as a window whose
/// repaint timer fires; false if `limit` passed first.
pub fn step_until_worker(
    h: &mut Harness<'_, LabApp>,
    of: Worker,
    limit: Duration,
    ready: impl Fn(&Harness<'_, LabApp>) -> bool,
) -> bool {
    let deadline = Instant::now() + limit;
    loop {
        let seen = worker(h, of).news();
        h.step();
        if ready(h) {
            return true;
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return false;
        }
        worker(h, of).wait_for_news(seen, left.min(Duration::from_secs(1)));
    }
}

/// Steps the window until `ready`, at most `steps` times, waiting after each step for the GPU
/// to finish what it submitted: values read back from the GPU (the probe under the cursor,
/// hybrid's walls) are asked for in one frame and taken in a later one, once mapped.
pub fn step_until_gpu(
    h: &mut Harness<'_, LabApp>,
    steps: usize,
    ready: impl Fn(&Harness<'_, LabApp>) -> bool,
) -> bool {
    for _ in 0..steps {
        h.step();
        // The light panel's tools are made on a worker thread: wait for it as for the GPU.
        h.state_mut().wait_for_light_panel();
        if ready(h) {
            return true;
        }
        if let Some(core) = h.state().core() {
            let _ = core.ctx.device.poll(wgpu::PollType::wait_indefinitely());
        }
    }
    false
}

/// A file dropped on the window, as egui-winit hands it over.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &std::path::Path {
        &self.0
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

/// Drop `path` on the window, and run it until it settles.
pub fn drop_file(h: &mut Harness<'_, LabApp>, path: &std::path::Path) {
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(path.to_path_buf())));
    h.run();
}
