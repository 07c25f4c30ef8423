//! Files: open a scene, an OBJ or a glTF model (dialog, path field, a file dropped on the window,
//! built-ins, recent files), save the scene (temporary file, then rename), export a PNG of the
//! viewport as shown (overlays included).
//! Every failure goes to the status line; the lab keeps running on what it had.
//!
//! Dialogs come from the desktop (rfd: the XDG portal, else zenity). Where there is neither — a
//! bare X server, a container — the lab says so instead of doing nothing: files open from the
//! Scene path field, and Save as / Export write a new file in the working directory.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use eframe::egui;

use super::{LabApp, Level};

/// A viewport screenshot asked for and not yet written.
pub struct PendingExport {
    pub path: PathBuf,
    pub rect: egui::Rect,
    pub shot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
}

/// `image` as PNG bytes.
pub fn encode_png(image: &egui::ColorImage) -> Result<Vec<u8>, String> {
    let [w, h] = image.size;
    let rgba: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
    let buffer = image::RgbaImage::from_raw(w as u32, h as u32, rgba)
        .ok_or_else(|| "screenshot of an inconsistent size".to_string())?;
    let mut bytes = Vec::new();
    buffer
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| format!("encoding the PNG: {e}"))?;
    Ok(bytes)
}

/// The part of a window screenshot inside `rect` (points), at `pixels_per_point`.
pub fn crop(image: &egui::ColorImage, rect: egui::Rect, pixels_per_point: f32) -> egui::ColorImage {
    let [w, h] = image.size;
    let x0 = ((rect.left() * pixels_per_point).round().max(0.0) as usize).min(w);
    let y0 = ((rect.top() * pixels_per_point).round().max(0.0) as usize).min(h);
    let x1 = ((rect.right() * pixels_per_point).round().max(0.0) as usize).clamp(x0, w);
    let y1 = ((rect.bottom() * pixels_per_point).round().max(0.0) as usize).clamp(y0, h);
    let mut pixels = Vec::with_capacity((x1 - x0) * (y1 - y0));
    for y in y0..y1 {
        pixels.extend_from_slice(&image.pixels[y * w + x0..y * w + x1]);
    }
    egui::ColorImage::new([x1 - x0, y1 - y0], pixels)
}

/// What a file dialog gave.
enum Picked {
    Path(PathBuf),
    Cancelled,
    /// No dialog could be shown.
    NoDialog,
}

/// Whether a dialog can be shown at all: rfd needs a D-Bus session (for the XDG portal) or
/// `zenity` on the PATH.
fn dialog_possible() -> bool {
    let bus = std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some();
    let zenity = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join("zenity").is_file()));
    bus || zenity
}

/// Run a dialog. One that returns nothing faster than a person can cancel never appeared.
fn pick(run: impl FnOnce() -> Option<PathBuf>) -> Picked {
    if !dialog_possible() {
        return Picked::NoDialog;
    }
    let start = Instant::now();
    match run() {
        Some(path) => Picked::Path(path),
        None if start.elapsed() < Duration::from_millis(150) => Picked::NoDialog,
        None => Picked::Cancelled,
    }
}

/// A file from `run`'s dialog: `None` when cancelled, `Some(Err)` when no dialog could be shown.
pub(super) fn pick_file(run: impl FnOnce() -> Option<PathBuf>) -> Option<Result<PathBuf, String>> {
    match pick(run) {
        Picked::Path(path) => Some(Ok(path)),
        Picked::Cancelled => None,
        Picked::NoDialog => Some(Err(NO_DIALOG.to_owned())),
    }
}

/// `dir/name.ext`, or `dir/name-2.ext`, `-3`… — the first that does not exist, so a fallback
/// save never replaces a file the user did not choose.
pub fn unused_path(dir: &Path, name: &str, ext: &str) -> PathBuf {
    let first = dir.join(format!("{name}.{ext}"));
    if !first.exists() {
        return first;
    }
    (2..)
        .map(|i| dir.join(format!("{name}-{i}.{ext}")))
        .find(|p| !p.exists())
        .unwrap_or(first)
}

/// Where Save as / Export write when there is no dialog.
fn fallback_path(name: &str, ext: &str) -> PathBuf {
    let dir = std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."));
    unused_path(&dir, name, ext)
}

/// What the lab opens, by extension (a dialog's filter, files dropped on the window).
pub const OPENABLE: [&str; 4] = ["toml", "obj", "glb", "gltf"];

fn is_openable(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| OPENABLE.iter().any(|o| o.eq_ignore_ascii_case(e)))
}

const NO_DIALOG: &str = "no file dialog here (it needs xdg-desktop-portal or zenity)";

fn with_extension(path: PathBuf, ext: &str) -> PathBuf {
    if path.extension().is_some() {
        path
    } else {
        path.with_extension(ext)
    }
}

impl LabApp {
    pub(super) fn open_dialog(&mut self) {
        let mut dialog = rfd::FileDialog::new()
            .set_title("Open a scene or a mesh")
            .add_filter("scene or model", &OPENABLE);
        if let Some(dir) = self.doc.path.as_deref().and_then(Path::parent) {
            dialog = dialog.set_directory(dir);
        }
        match pick(|| dialog.pick_file()) {
            Picked::Path(path) => self.open_scene(&path.display().to_string()),
            Picked::Cancelled => {}
            Picked::NoDialog => self.set_status(
                format!("{NO_DIALOG}: type a scene or OBJ path in Scene path"),
                Level::Warning,
            ),
        }
    }

    /// Open a file dropped on the window this frame (the first one the lab can open; errors go
    /// to the status line and the current scene stays).
    pub(super) fn open_dropped(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        if dropped.is_empty() {
            return;
        }
        // A `.wgsl` file is a method of the user's own (File ▸ Open method…).
        let (methods, dropped): (Vec<PathBuf>, Vec<PathBuf>) = dropped.into_iter().partition(|p| {
            p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("wgsl"))
        });
        for path in &methods {
            self.open_method(path);
        }
        if dropped.is_empty() {
            return;
        }
        match dropped.iter().find(|p| is_openable(p)) {
            Some(path) => {
                self.open_scene(&path.display().to_string());
                let ignored = dropped.len() - 1;
                if ignored > 0 && self.status.1 != Level::Error {
                    let (text, level) = self.status.clone();
                    self.set_status(
                        format!(
                            "{text} ({ignored} more dropped files ignored: one scene at a time)"
                        ),
                        level,
                    );
                }
            }
            None => self.set_status(
                format!(
                    "cannot open {}: the lab opens .{} files",
                    dropped[0].display(),
                    OPENABLE.join(", .")
                ),
                Level::Error,
            ),
        }
    }

    /// While files hover over the window: say what dropping them will do.
    pub(super) fn drop_hint(&self, ctx: &egui::Context) {
        let hovered: Vec<Option<PathBuf>> =
            ctx.input(|i| i.raw.hovered_files.iter().map(|f| f.path.clone()).collect());
        let Some(first) = hovered.first() else {
            return;
        };
        let text = match first {
            Some(p) if is_openable(p) => format!("drop to open {}", p.display()),
            Some(p) => format!("{} is not a scene, OBJ or glTF", p.display()),
            None => "drop a scene, OBJ or glTF to open it".to_string(),
        };
        let rect = ctx.content_rect();
        let painter = ctx.layer_painter(egui::LayerId::new(
            egui::Order::Foreground,
            egui::Id::unique("drop_hint"),
        ));
        painter.rect_filled(rect, 0.0, egui::Color32::from_black_alpha(160));
        painter.text(
            rect.center(),
            egui::Align2::CENTER_CENTER,
            text,
            egui::FontId::proportional(20.0),
            egui::Color32::WHITE,
        );
    }

    pub(super) fn save(&mut self) {
        match self.doc.toml_path().map(Path::to_path_buf) {
            Some(path) => self.save_to(&path),
            None => self.save_as_dialog(),
        }
    }

    pub(super) fn save_as_dialog(&mut self) {
        let name = format!("{}.toml", self.doc.name);
        let picked = pick(|| {
            rfd::FileDialog::new()
                .set_title("Save the scene")
                .add_filter("scene", &["toml"])
                .set_file_name(name)
                .save_file()
        });
        match picked {
            Picked::Path(path) => self.save_to(&with_extension(path, "toml")),
            Picked::Cancelled => {}
            Picked::NoDialog => self.save_to(&fallback_path(&self.doc.name, "toml")),
        }
    }

    pub fn save_to(&mut self, path: &Path) {
        let camera = self.camera;
        match self.doc.save(path, &camera) {
            Ok(()) => {
                self.settings.push_recent(&path.display().to_string());
                self.set_status(format!("saved {}", path.display()), Level::Info);
            }
            Err(e) => self.set_status(format!("not saved: {e}"), Level::Error),
        }
    }

    pub(super) fn export_dialog(&mut self, ctx: &egui::Context) {
        let Some(rect) = self.viewport.rect else {
            return;
        };
        let name = format!("{}-{}", self.doc.name, self.settings.method);
        let picked = pick(|| {
            rfd::FileDialog::new()
                .set_title("Export the viewport as PNG")
                .add_filter("PNG image", &["png"])
                .set_file_name(format!("{name}.png"))
                .save_file()
        });
        match picked {
            Picked::Path(path) => self.export_to(ctx, with_extension(path, "png"), rect),
            Picked::Cancelled => {}
            Picked::NoDialog => self.export_to(ctx, fallback_path(&name, "png"), rect),
        }
    }

    /// Screenshot the window on the next frame and write the viewport's part to `path`.
    pub fn export_to(&mut self, ctx: &egui::Context, path: PathBuf, rect: egui::Rect) {
        let shot = Arc::new(Mutex::new(None));
        let slot = Arc::clone(&shot);
        ctx.request_screenshot(move |image| {
            if let Ok(mut s) = slot.lock() {
                *s = Some(image);
            }
        });
        self.export = Some(PendingExport { path, rect, shot });
    }

    /// Write a screenshot that has arrived.
    pub(super) fn finish_export(&mut self, ctx: &egui::Context) {
        let Some(pending) = self.export.as_ref() else {
            return;
        };
        let image = pending.shot.lock().ok().and_then(|mut s| s.take());
        let Some(image) = image else {
            ctx.request_repaint();
            return;
        };
        let path = pending.path.clone();
        let cropped = crop(&image, pending.rect, ctx.pixels_per_point());
        self.export = None;
        let result = encode_png(&cropped).and_then(|png| {
            crate::fsutil::write_atomic(&path, &png)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))
        });
        match result {
            Ok(()) => self.set_status(format!("exported {}", path.display()), Level::Info),
            Err(e) => self.set_status(format!("not exported: {e}"), Level::Error),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_takes_the_rect_in_pixels() {
        let mut image = egui::ColorImage::filled([4, 4], egui::Color32::BLACK);
        image.pixels[2 * 4 + 3] = egui::Color32::RED;
        let rect = egui::Rect::from_min_max(egui::pos2(1.0, 1.0), egui::pos2(2.0, 1.5));
        let c = crop(&image, rect, 2.0);
        assert_eq!(c.size, [2, 1]);
        assert_eq!(c.pixels[1], egui::Color32::RED);
        let outside = egui::Rect::from_min_max(egui::pos2(10.0, 10.0), egui::pos2(20.0, 20.0));
        assert_eq!(crop(&image, outside, 1.0).size, [0, 0]);
    }

    #[test]
    fn fallback_paths_never_name_an_existing_file() {
        let dir = std::env::temp_dir().join(format!("dbuffer-unused-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let first = unused_path(&dir, "scene", "toml");
        assert_eq!(first, dir.join("scene.toml"));
        std::fs::write(&first, "x").unwrap();
        let second = unused_path(&dir, "scene", "toml");
        assert_eq!(second, dir.join("scene-2.toml"));
        std::fs::write(&second, "x").unwrap();
        assert_eq!(unused_path(&dir, "scene", "toml"), dir.join("scene-3.toml"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn png_round_trip() {
        let image = egui::ColorImage::filled([3, 2], egui::Color32::from_rgb(1, 2, 3));
        let png = encode_png(&image).unwrap();
        let back = image::load_from_memory(&png).unwrap().to_rgba8();
        assert_eq!(back.dimensions(), (3, 2));
        assert_eq!(back.get_pixel(2, 1).0, [1, 2, 3, 255]);
    }
}
