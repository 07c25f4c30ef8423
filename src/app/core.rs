//! The render core as the lab holds it: a [`Session`] on eframe's own wgpu device, the targets of
//! the two views (either side of a split) that stay on the GPU and are shown as they are, and the
//! reference's worker threads (the area reference's, and the exact hard shadow's). Every pixel the lab shows is a frame of the same core `dbuffer
//! render` uses; only the probes' few hundred bytes come back per frame.

use eframe::egui;
use eframe::egui_wgpu;

use crate::render::passes::probe::ProbeResult;
use crate::render::reference::ReferenceWorker;
use crate::render::session::{FrameJob, Session};
use crate::render::{Frame, FrameTargets, GpuContext, Method, RenderError};
use crate::scene::Scene;

/// One shown view: its targets on the GPU and the egui texture that shows its display.
pub struct Slot {
    pub targets: FrameTargets,
    /// The egui texture showing the display, and the display generation it was registered for.
    pub texture: Option<(egui::TextureId, u64)>,
}

impl Slot {
    fn new() -> Slot {
        Slot {
            targets: FrameTargets::new(),
            texture: None,
        }
    }

    /// The size of what the slot's display shows, once it has one.
    pub fn display_size(&self) -> Option<(u32, u32)> {
        let d = self.targets.shown()?;
        Some((d.width, d.height))
    }
}

pub struct Core {
    pub ctx: GpuContext,
    pub session: Session,
    pub worker: ReferenceWorker,
    /// `reference-hard`'s rays, cast off the UI thread like the reference's.
    pub hard_worker: ReferenceWorker,
    /// The main view and the right-hand side of a split.
    pub slots: [Slot; 2],
    /// The reference snapshot handed to the GPU last: (done, total).
    pub reference_serial: u64,
    /// Bumped whenever an exact hard shadow is handed to the GPU.
    pub hard_serial: u64,
    /// The reference's shaded image for the FLIP view (never shown itself).
    pub flip_targets: FrameTargets,
}

impl Core {
    /// Wrap eframe's device (or the test harness's) and start a session on `scene`.
    pub fn new(ctx: GpuContext, scene: Scene) -> Core {
        let session = Session::new(&ctx, scene);
        Core {
            ctx,
            session,
            worker: ReferenceWorker::new(),
            hard_worker: ReferenceWorker::hard(),
            slots: [Slot::new(), Slot::new()],
            reference_serial: 0,
            hard_serial: 0,
            flip_targets: FrameTargets::new(),
        }
    }

    /// Look at another scene.
    pub fn replace_scene(&mut self, scene: Scene) {
        self.session = Session::new(&self.ctx, scene);
        for slot in &mut self.slots {
            slot.targets.rendered = None;
        }
    }

    pub fn scene(&self) -> &Scene {
        self.session.scene()
    }

    /// Hand the GPU the reference's newest samples, if the worker has any. Returns whether it
    /// did.
    pub fn take_reference(&mut self) -> Result<bool, RenderError> {
        let Some(s) = self.worker.take() else {
            return Ok(false);
        };
        self.session
            .set_reference(&self.ctx, s.key, &s.visibility, (s.done, s.total))?;
        self.reference_serial += 1;
        Ok(true)
    }

    /// Hand the GPU the exact hard shadow the worker finished, if any. Returns whether it did.
    pub fn take_reference_hard(&mut self) -> Result<bool, RenderError> {
        let Some(s) = self.hard_worker.take() else {
            return Ok(false);
        };
        self.session
            .set_reference_hard(&self.ctx, s.key, &s.visibility)?;
        self.hard_serial += 1;
        Ok(true)
    }

    /// Record and submit the jobs; returns the bytes they read back.
    pub fn submit(&mut self, jobs: &mut [FrameJob<'_>]) -> Result<u64, RenderError> {
        self.session.submit(&self.ctx, jobs)
    }

    /// Show each slot's display through an egui texture (registered once, again when the display
    /// was made again).
    pub fn register_textures(&mut self, render_state: &egui_wgpu::RenderState) {
        for slot in &mut self.slots {
            let Some(display) = slot.targets.shown() else {
                continue;
            };
            match slot.texture {
                Some((_, g)) if g == display.generation => {}
                Some((id, _)) => {
                    render_state
                        .renderer
                        .write()
                        .update_egui_texture_from_wgpu_texture(
                            &render_state.device,
                            display.view,
                            wgpu::FilterMode::Nearest,
                            id,
                        );
                    slot.texture = Some((id, display.generation));
                }
                None => {
                    let id = render_state.renderer.write().register_native_texture(
                        &render_state.device,
                        display.view,
                        wgpu::FilterMode::Nearest,
                    );
                    slot.texture = Some((id, display.generation));
                }
            }
        }
    }

    /// Probe answers that have arrived, per slot.
    pub fn probe_results(&mut self, wait: bool) -> [Vec<ProbeResult>; 2] {
        let ctx = &self.ctx;
        let [a, b] = &mut self.slots;
        [a, b].map(|slot| match slot.targets.probe.as_mut() {
            Some(p) if wait && p.pending() => p.wait(ctx),
            Some(p) => p.poll(ctx),
            None => Vec::new(),
        })
    }

    /// Read a slot's frame back whole, with `maps_of`'s light-space maps: for tests and
    /// exports, never per frame.
    pub fn read_slot(
        &mut self,
        slot: usize,
        maps_of: Option<Method>,
    ) -> Result<Frame, RenderError> {
        let Some(s) = self.slots.get_mut(slot) else {
            return Err(RenderError::Request(format!("no view {slot}")));
        };
        self.session.read(&self.ctx, &mut s.targets, maps_of)
    }
}
