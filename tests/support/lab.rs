//! The lab in a kittest window on the wgpu (lavapipe) adapter, small and quick: a 256² D-buffer,
//! half resolution, 16 reference samples. Values come back from the GPU a frame or more later
//! (a probe, the reference's samples), and the window repaints until they have: on lavapipe
//! that can take a few dozen quick test frames, hence the generous step limit.

use dbuffer::app::{LabApp, LabOptions};
use eframe::egui;
use egui_kittest::Harness;

/// The lab on `scene` (the default scene for `None`) in a `width`×`height` window.
pub fn lab_sized(scene: Option<&str>, width: f32, height: f32) -> Harness<'static, LabApp> {
    let scene = scene.map(str::to_string);
    Harness::builder()
        .with_size(egui::vec2(width, height))
        .with_max_steps(500)
        .with_render_cursor(false)
        .wgpu()
        .build_eframe(move |cc| {
            let mut app = LabApp::new(
                cc,
                LabOptions {
                    scene,
                    deterministic: true,
                    ..LabOptions::default()
                },
            );
            app.settings.dbuffer_size = 256;
            app.settings.render_scale = 0.5;
            app.settings.reference_samples = 16;
            app
        })
}
