//! An orbit recorded as pictures: what `dbuffer animate` writes and the lab's Record button
//! makes from its current view, with one code path for both.
//!
//! **The orbit** is [`crate::scene::orbit`]'s: the light about the vertical axis through the
//! casters, or the camera about its target; frame `k` of `N` at `360° · k / N`.
//!
//! **The files.** `frame-0000.png` … (8-bit sRGB, the `image.png` of `dbuffer render` for that
//! pose) and `animation.png`, an APNG of every frame at the chosen rate, looping forever. APNG
//! rather than GIF: a GIF has 256 colours a frame, and dithering or banding of a soft shadow's
//! gradient is exactly what a viewer of this lab must not be shown; an APNG holds the frames
//! losslessly, browsers (and GitHub's README view) play it, and it is written by the `png`
//! crate `image` already uses. Frames are staged into a hidden folder as they are rendered and
//! moved into place together at the end ([`Staged`]): the folder gets the whole animation or
//! nothing, and frames of an earlier, longer run are removed. The APNG is written to its staged
//! file as the frames come, never held in memory: a run holds one frame at a time, at most
//! [`MAX_ANIMATE_PIXELS`] of them.
//!
//! A [`Recording`] renders one frame per [`Recording::step`], in its own [`Session`] (the
//! caller's view is not disturbed), so a window can record between its own frames.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::budget::MAX_ANIMATE_PIXELS;
use crate::output::{self, OutputError, Staged};
use crate::render::offline::render_in_history;
use crate::render::{FrameRequest, GpuContext, RenderError, Session};
use crate::scene::orbit::{Orbit, Poses};
use crate::scene::Scene;

/// Most frames one animation may have.
pub const MAX_FRAMES: usize = 3600;

/// Most pixels over all frames (what the frames and the APNG take on disk, and the run's time).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 31;

/// The looping animated image written beside the frames.
pub const ANIMATION_FILE: &str = "animation.png";

/// What to record.
#[derive(Clone, Copy, Debug)]
pub struct AnimationSpec {
    pub frames: usize,
    /// Frames per second of the animated image.
    pub fps: u32,
    pub orbit: Orbit,
    /// Every frame's size, method and knobs.
    pub request: FrameRequest,
}

impl AnimationSpec {
    /// Whether the spec is within the limits; the message names the flag.
    pub fn validate(&self) -> Result<(), AnimationError> {
        if !(1..=MAX_FRAMES).contains(&self.frames) {
            return Err(AnimationError::Invalid(format!(
                "--frames expects 1 to {MAX_FRAMES}, found {}",
                self.frames
            )));
        }
        if !(1..=60).contains(&self.fps) {
            return Err(AnimationError::Invalid(format!(
                "--fps expects 1 to 60 frames per second, found {}",
                self.fps
            )));
        }
        let (w, h) = (self.request.width, self.request.height);
        let pixels = u64::from(w) * u64::from(h);
        if pixels > MAX_ANIMATE_PIXELS {
            return Err(AnimationError::Invalid(format!(
                "--size {w}x{h} is {pixels} pixels: animate expects at most \
                 {MAX_ANIMATE_PIXELS} (MAX_ANIMATE_PIXELS, {} Mpixels a frame)",
                MAX_ANIMATE_PIXELS >> 20
            )));
        }
        let total = pixels * self.frames as u64;
        if total > MAX_TOTAL_PIXELS {
            return Err(AnimationError::Invalid(format!(
                "--frames {} at --size {w}x{h} is {total} pixels; the limit is \
                 {MAX_TOTAL_PIXELS} (fewer frames or a smaller size)",
                self.frames
            )));
        }
        Ok(())
    }
}

/// What can stop a recording.
#[derive(Debug, thiserror::Error)]
pub enum AnimationError {
    #[error("{0}")]
    Invalid(String),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("{what}: {message}")]
    Encode { what: &'static str, message: String },
}

fn encode_err(what: &'static str) -> impl FnOnce(png::EncodingError) -> AnimationError {
    move |e| AnimationError::Encode {
        what,
        message: e.to_string(),
    }
}

/// The APNG's staged file, shared with the encoder that writes it (the encoder keeps its
/// writer to the end; the recording flushes and syncs the file after it).
#[derive(Clone)]
struct Sink(Arc<Mutex<BufWriter<File>>>);

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0
            .lock()
            .map_err(|_| std::io::Error::other("APNG file poisoned"))?
            .write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0
            .lock()
            .map_err(|_| std::io::Error::other("APNG file poisoned"))?
            .flush()
    }
}

/// What a finished recording wrote.
#[derive(Debug)]
pub struct Written {
    /// The frames and the animated image, in that order.
    pub files: Vec<PathBuf>,
    pub animation_bytes: usize,
}

/// An orbit being recorded into a folder, one frame per [`step`](Recording::step).
pub struct Recording {
    spec: AnimationSpec,
    poses: Poses,
    session: Session,
    staged: Staged,
    apng: png::Writer<Sink>,
    bytes: Sink,
    out: PathBuf,
    next: usize,
}

impl Recording {
    /// Start recording `scene` into `out` (checked and prepared now: a bad folder fails before
    /// any frame is rendered).
    pub fn start(
        ctx: &GpuContext,
        scene: Scene,
        spec: AnimationSpec,
        out: &Path,
    ) -> Result<Recording, AnimationError> {
        spec.validate()?;
        spec.request
            .validate(ctx)
            .map_err(|e| AnimationError::Invalid(e.to_string()))?;
        let poses = Poses::new(&scene, spec.orbit);
        let mut staged = Staged::new(out)?;
        let (file, _) = staged.open(ANIMATION_FILE)?;
        let bytes = Sink(Arc::new(Mutex::new(BufWriter::with_capacity(
            1 << 20,
            file,
        ))));
        let (w, h) = (spec.request.width, spec.request.height);
        let mut encoder = png::Encoder::new(bytes.clone(), w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::High);
        encoder
            .set_animated(spec.frames as u32, 0)
            .and_then(|()| encoder.set_frame_delay(1, spec.fps as u16))
            .map_err(encode_err("setting up the APNG encoder"))?;
        let apng = encoder
            .write_header()
            .map_err(encode_err("writing the APNG header"))?;
        Ok(Recording {
            spec,
            poses,
            session: Session::new(ctx, scene),
            staged,
            apng,
            bytes,
            out: out.to_path_buf(),
            next: 0,
        })
    }

    /// Why the orbit differs from the one asked for, if it does (a light on the axis).
    pub fn note(&self) -> Option<&str> {
        self.poses.note.as_deref()
    }

    /// Frames rendered so far, and the total.
    pub fn progress(&self) -> (usize, usize) {
        (self.next, self.spec.frames)
    }

    pub fn is_done(&self) -> bool {
        self.next >= self.spec.frames
    }

    /// Where it writes.
    pub fn out(&self) -> &Path {
        &self.out
    }

    /// Render and stage the next frame; returns the render's warnings. `reference_progress`
    /// hears (samples done, total) when the method is the ray-cast reference.
    pub fn step(
        &mut self,
        ctx: &GpuContext,
        reference_progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Vec<String>, AnimationError> {
        if self.is_done() {
            return Ok(Vec::new());
        }
        let k = self.next;
        let (light, camera) = self.poses.at(k, self.spec.frames);
        self.session.set_light(light);
        self.session.set_camera(camera);
        // A temporal method's history is filled at the first pose, as a still view's is, then
        // carried from frame to frame as the light or camera moves.
        let (frame, report) = render_in_history(
            ctx,
            &mut self.session,
            &self.spec.request,
            reference_progress,
            k == 0,
        )?;
        let (w, h) = (self.spec.request.width, self.spec.request.height);
        let width = w as usize;
        let color = &frame.color;
        self.staged.write_with(&frame_name(k), |out, target| {
            output::png_file(out, target, w, h, |y, row| {
                for (px, c) in row.chunks_exact_mut(3).zip(&color[y * width..]) {
                    px.copy_from_slice(&c[..3]);
                }
            })
        })?;
        let rgb: Vec<u8> = color.iter().flat_map(|c| [c[0], c[1], c[2]]).collect();
        drop(frame);
        self.apng
            .write_image_data(&rgb)
            .map_err(encode_err("adding a frame to the APNG"))?;
        self.next += 1;
        Ok(report.warnings)
    }

    /// Write the animated image and move every file into place (all or nothing). Before every
    /// frame is rendered it is an error and the folder is left as it was.
    pub fn finish(self) -> Result<Written, AnimationError> {
        let Recording {
            spec,
            mut staged,
            apng,
            bytes,
            out,
            next,
            ..
        } = self;
        if next < spec.frames {
            return Err(AnimationError::Invalid(format!(
                "the recording stopped after {next} of {} frames; {} was left as it was",
                spec.frames,
                out.display()
            )));
        }
        apng.finish().map_err(encode_err("finishing the APNG"))?;
        let animation_bytes = {
            let mut file = bytes
                .0
                .lock()
                .map_err(|_| AnimationError::Invalid("APNG file poisoned".into()))?;
            let written = (|| {
                file.flush()?;
                file.get_ref().sync_all()?;
                file.get_ref().metadata()
            })();
            written
                .map_err(|e| AnimationError::Encode {
                    what: "writing the APNG",
                    message: e.to_string(),
                })?
                .len() as usize
        };
        for stale in stale_frames(&out, spec.frames) {
            staged.remove_on_commit(&stale);
        }
        let mut files = staged.commit()?;
        // The frames, then the animated image (staged first, to be written as they came).
        if !files.is_empty() {
            files.rotate_left(1);
        }
        Ok(Written {
            files,
            animation_bytes,
        })
    }
}

/// `frame-0007.png`.
pub fn frame_name(k: usize) -> String {
    format!("frame-{k:04}.png")
}

/// Frame files in `dir` from an earlier run that a run of `frames` frames does not replace.
fn stale_frames(dir: &Path, frames: usize) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|name| {
            name.strip_prefix("frame-")
                .and_then(|n| n.strip_suffix(".png"))
                .filter(|n| n.len() >= 4 && n.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|n| n.parse::<usize>().ok())
                .is_some_and(|k| k >= frames)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_frames_are_those_past_the_new_count() {
        let dir = std::env::temp_dir().join(format!("dbuffer-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for name in [
            "frame-0000.png",
            "frame-0003.png",
            "frame-0012.png",
            "frame-x.png",
            "keep.png",
        ] {
            std::fs::write(dir.join(name), b"x").unwrap();
        }
        let mut stale = stale_frames(&dir, 4);
        stale.sort();
        assert_eq!(stale, ["frame-0012.png"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn limits_name_their_flags() {
        let spec = |frames, fps, w| AnimationSpec {
            frames,
            fps,
            orbit: Orbit::Light,
            request: FrameRequest {
                width: w,
                height: w,
                ..FrameRequest::default()
            },
        };
        assert!(spec(24, 12, 64).validate().is_ok());
        let e = spec(0, 12, 64).validate().unwrap_err().to_string();
        assert!(e.contains("--frames") && e.contains("found 0"), "{e}");
        let e = spec(24, 0, 64).validate().unwrap_err().to_string();
        assert!(e.contains("--fps"), "{e}");
        let e = spec(3600, 12, 8192).validate().unwrap_err().to_string();
        assert!(
            e.contains("pixels") && e.contains("--size 8192x8192"),
            "{e}"
        );
    }
}
