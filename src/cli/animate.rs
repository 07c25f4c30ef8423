//! `dbuffer animate SCENE --out DIR`: the light (or the camera) once around an orbit, as PNG
//! frames and one animated PNG of the loop.
//!
//! **The orbit** is [`dbuffer::scene::orbit`]'s: the light about the vertical axis through the
//! casters, or the camera about its target; frame `k` of `N` at `360° · k / N`.
//!
//! **The files.** `frame-0000.png` … (8-bit sRGB, the `image.png` of `dbuffer render` for that
//! pose) and `animation.png`, an APNG of every frame at `--fps`, looping forever. APNG rather
//! than GIF: a GIF has 256 colours a frame, and dithering or banding of a soft shadow's gradient
//! is exactly what a viewer of this lab must not be shown; an APNG holds the frames losslessly,
//! browsers (and GitHub's README view) play it, and it is written by the `png` crate `image`
//! already uses. Frames are staged into a hidden folder as they are rendered and moved into
//! place together at the end (`output::Staged`): the folder gets the whole animation or nothing,
//! and frames of an earlier, longer run are removed.

use std::path::Path;

use anyhow::{bail, Context, Result};
use dbuffer::geometry::VtVariant;
use dbuffer::output::{self, Staged};
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, Method, Session};
use dbuffer::scene;
use dbuffer::scene::orbit::{Orbit, Poses};

use super::progress::Progress;
use super::{check_dbuffer_size, parse_size, MethodFlags};

/// Most frames one animation may have.
pub const MAX_FRAMES: usize = 3600;

/// Most pixels over all frames (the APNG is built in memory, compressed).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 31;

/// The looping animated image written beside the frames.
pub const ANIMATION_FILE: &str = "animation.png";

/// The arguments of `dbuffer animate`, as typed.
pub struct AnimateArgs<'a> {
    pub scene: &'a str,
    pub out: &'a Path,
    pub frames: usize,
    pub orbit: &'a str,
    pub fps: u32,
    pub size: &'a str,
    pub method: &'a str,
    pub vt: &'a str,
    pub dbuffer_size: u32,
    pub knobs: &'a MethodFlags,
}

pub fn animate(args: &AnimateArgs) -> Result<()> {
    let (width, height) = parse_size(args.size)?;
    if !(1..=MAX_FRAMES).contains(&args.frames) {
        bail!("--frames expects 1 to {MAX_FRAMES}, found {}", args.frames);
    }
    if !(1..=60).contains(&args.fps) {
        bail!(
            "--fps expects 1 to 60 frames per second, found {}",
            args.fps
        );
    }
    let total = u64::from(width) * u64::from(height) * args.frames as u64;
    if total > MAX_TOTAL_PIXELS {
        bail!(
            "--frames {} at --size {width}x{height} is {total} pixels; the limit is \
             {MAX_TOTAL_PIXELS} (fewer frames or a smaller size)",
            args.frames
        );
    }
    let orbit: Orbit = args.orbit.parse().map_err(anyhow::Error::msg)?;
    let method: Method = args.method.parse().map_err(anyhow::Error::msg)?;
    let vt: VtVariant = args.vt.parse().map_err(anyhow::Error::msg)?;
    check_dbuffer_size(args.dbuffer_size)?;
    let knobs = args.knobs.knobs()?;
    let scene =
        scene::load(args.scene).with_context(|| format!("cannot load scene '{}'", args.scene))?;
    let request = FrameRequest {
        width,
        height,
        dbuffer_size: args.dbuffer_size,
        method,
        vt,
        knobs,
        read_dbuffer: false,
    };
    let poses = Poses::new(&scene, orbit);
    if let Some(note) = &poses.note {
        eprintln!("note      {note}");
    }

    let mut staged = Staged::new(args.out)?;
    let mut apng = Vec::new();
    let mut encoder = png::Encoder::new(&mut apng, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::High);
    encoder
        .set_animated(args.frames as u32, 0)
        .and_then(|()| encoder.set_frame_delay(1, args.fps as u16))
        .context("setting up the APNG encoder")?;
    let mut writer = encoder.write_header().context("writing the APNG header")?;

    let mut offline = Offline::new()?;
    // One session for the whole orbit: meshes uploaded and casters prepared once, only the
    // light-dependent work redone per frame.
    let name = scene.name.clone();
    let mut session = offline.session(scene);
    let progress = Progress::new("animate", args.frames as u64, "frames");
    progress.stage(&format!(
        "{name}, the {} orbiting, {width}x{height}, {method}",
        args.orbit
    ));
    let mut warned: Vec<String> = Vec::new();
    for k in 0..args.frames {
        let (light, camera) = poses.at(k, args.frames);
        session.set_light(light);
        session.set_camera(camera);
        let (rgb, warnings) = render_rgb8(&mut offline, &mut session, &request)?;
        for w in warnings {
            if !warned.contains(&w) {
                progress.stage(&format!("warning: {w}"));
                warned.push(w);
            }
        }
        let png = output::png_rgb8(width, height, &rgb).context("encoding a frame")?;
        staged.add(&frame_name(k), &png)?;
        writer
            .write_image_data(&rgb)
            .context("adding a frame to the APNG")?;
        progress.set(k as u64 + 1);
    }
    writer.finish().context("finishing the APNG")?;
    progress.finish();
    staged.add(ANIMATION_FILE, &apng)?;
    for stale in stale_frames(args.out, args.frames) {
        staged.remove_on_commit(&stale);
    }
    let written = staged.commit()?;
    eprintln!(
        "wrote     {} frames and {ANIMATION_FILE} ({} KiB, {:.1} s at {} fps) into {}",
        written.len() - 1,
        apng.len().div_ceil(1024),
        args.frames as f64 / f64::from(args.fps),
        args.fps,
        args.out.display()
    );
    Ok(())
}

/// One frame through the render core, exactly as `dbuffer render` makes its `image.png`:
/// 8-bit sRGB bytes and the render's warnings.
fn render_rgb8(
    offline: &mut Offline,
    session: &mut Session,
    request: &FrameRequest,
) -> Result<(Vec<u8>, Vec<String>)> {
    let (frame, report) = offline.render_in(session, request)?;
    let rgb = frame
        .color
        .iter()
        .flat_map(|c| [c[0], c[1], c[2]])
        .collect();
    Ok((rgb, report.warnings))
}

/// `frame-0007.png`.
pub fn frame_name(k: usize) -> String {
    format!("frame-{k:04}.png")
}

/// Frame files in `dir` from an earlier run that this run of `frames` frames does not replace.
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
}
