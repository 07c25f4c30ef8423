//! The scripted smoke run (`DBUFFER_SMOKE_SCREENSHOT=shot.png dbuffer gui SCENE`): once the
//! viewport has shown rendered frames, screenshot the whole window into the PNG and close.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use eframe::egui;

use super::LabApp;

/// Window frames to wait after the first rendered frame, so panels and textures settle.
const SETTLE_FRAMES: u32 = 5;
/// Give up (and exit non-zero) after this long without a screenshot.
const TIMEOUT: Duration = Duration::from_secs(120);

/// Fails on an image of (nearly) one colour: a window that shows nothing.
fn not_blank(image: &egui::ColorImage, what: &str) -> Result<(), String> {
    let n = image.pixels.len().max(1) as f64;
    let luma: Vec<f64> = image
        .pixels
        .iter()
        .map(|c| 0.299 * f64::from(c.r()) + 0.587 * f64::from(c.g()) + 0.114 * f64::from(c.b()))
        .collect();
    let mean = luma.iter().sum::<f64>() / n;
    let sd = (luma.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n).sqrt();
    let mut colours: Vec<[u8; 4]> = image.pixels.iter().map(|c| c.to_array()).collect();
    colours.sort_unstable();
    colours.dedup();
    eprintln!(
        "smoke: {what} {}x{}: luma mean {mean:.1}, sd {sd:.1}, {} colours",
        image.size[0],
        image.size[1],
        colours.len()
    );
    if sd < 8.0 || colours.len() < 32 {
        return Err(format!(
            "the {what} looks blank (luma sd {sd:.1}, {} colours)",
            colours.len()
        ));
    }
    Ok(())
}

/// Where a smoke run leaves its result: written once, read after the window closed.
pub type Outcome = Arc<Mutex<Option<Result<(), String>>>>;

pub struct Smoke {
    path: PathBuf,
    started: Instant,
    settled: u32,
    requested: bool,
    shot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    /// Where the result goes for [`super::run`] to report.
    pub outcome: Option<Outcome>,
}

impl Smoke {
    pub fn new(path: PathBuf) -> Smoke {
        Smoke {
            path,
            started: Instant::now(),
            settled: 0,
            requested: false,
            shot: Arc::new(Mutex::new(None)),
            outcome: None,
        }
    }

    fn finish(&mut self, ctx: &egui::Context, result: Result<(), String>) {
        if let Some(o) = &self.outcome {
            if let Ok(mut o) = o.lock() {
                *o = Some(result);
            }
        }
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}

impl LabApp {
    pub(super) fn smoke_step(&mut self, ctx: &egui::Context) {
        let rendered = self.frames_rendered();
        let adapter = self.adapter();
        let Some(smoke) = self.smoke.as_mut() else {
            return;
        };
        ctx.request_repaint();
        if smoke.started.elapsed() > TIMEOUT {
            smoke.finish(ctx, Err(format!("no screenshot after {TIMEOUT:?}")));
            return;
        }
        if rendered == 0 {
            return;
        }
        if smoke.settled < SETTLE_FRAMES {
            smoke.settled += 1;
            return;
        }
        if !smoke.requested {
            smoke.requested = true;
            let slot = Arc::clone(&smoke.shot);
            ctx.request_screenshot(move |image| {
                if let Ok(mut s) = slot.lock() {
                    *s = Some(image);
                }
            });
            return;
        }
        let image = smoke.shot.lock().ok().and_then(|mut s| s.take());
        if let Some(image) = image {
            let viewport = self
                .viewport
                .rect
                .map(|r| super::files::crop(&image, r, ctx.pixels_per_point()));
            let Some(smoke) = self.smoke.as_mut() else {
                return;
            };
            let result = not_blank(&image, "window")
                .and_then(|()| match &viewport {
                    Some(v) => not_blank(v, "viewport"),
                    None => Err("no viewport was drawn".into()),
                })
                .and_then(|()| super::files::encode_png(&image))
                .and_then(|png| {
                    crate::fsutil::write_atomic(&smoke.path, &png)
                        .map_err(|e| format!("cannot write {}: {e}", smoke.path.display()))
                })
                .map(|()| {
                    eprintln!(
                        "smoke: {} frames rendered on {}, screenshot {}x{} written to {}",
                        rendered,
                        adapter.unwrap_or_else(|| "no adapter".into()),
                        image.size[0],
                        image.size[1],
                        smoke.path.display()
                    );
                });
            smoke.finish(ctx, result);
        }
    }
}
