//! `dbuffer animate SCENE --out DIR`: the light (or the camera) once around an orbit, as PNG
//! frames and one animated PNG of the loop.
//!
//! **The orbit.** `light`: the disk's centre turns about the vertical axis through the centre of
//! the casters' bounding box, at its own height and distance from that axis, and its normal turns
//! with it (a light tilted toward the casters stays tilted toward them). A light (nearly)
//! straight above that axis would hardly move its shadow, so one closer to the axis than a
//! quarter of its height above the casters' centre orbits at half that height from the axis
//! instead (said on stderr). `camera`: the eye turns about the vertical axis through its target. Frame
//! `k` of `N` is at `360° · k / N`, so the last frame leads back into the first.
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
use dbuffer::scene::{self, Camera, DiskLight, Scene};
use glam::{Quat, Vec3};

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

/// What moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orbit {
    Light,
    Camera,
}

impl std::str::FromStr for Orbit {
    type Err = String;
    fn from_str(s: &str) -> Result<Orbit, String> {
        match s {
            "light" => Ok(Orbit::Light),
            "camera" => Ok(Orbit::Camera),
            other => Err(format!("--orbit expects light or camera, found '{other}'")),
        }
    }
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
        poses.apply(&mut session, k, args.frames);
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

/// The orbit: the pose at frame 0 and the axis everything turns about.
pub struct Poses {
    orbit: Orbit,
    light: DiskLight,
    camera: Camera,
    /// A point on the vertical axis of the orbit.
    axis: Vec3,
    /// Said once on stderr (a light moved off the axis to orbit at all).
    pub note: Option<String>,
}

impl Poses {
    pub fn new(scene: &Scene, orbit: Orbit) -> Poses {
        let mut light = scene.light;
        let mut note = None;
        let axis = match orbit {
            Orbit::Camera => scene.camera.target,
            Orbit::Light => {
                let centre = casters_centre(scene).unwrap_or(Vec3::ZERO);
                let offset = light.center - centre;
                let flat = Vec3::new(offset.x, 0.0, offset.z);
                let horizontal = flat.length();
                let radius = 0.5 * offset.y.abs().max(light.radius);
                if horizontal < 0.5 * radius {
                    let out = flat.try_normalize().unwrap_or(Vec3::X);
                    light.center = Vec3::new(
                        centre.x + out.x * radius,
                        light.center.y,
                        centre.z + out.z * radius,
                    );
                    note = Some(format!(
                        "the light is (nearly) straight above the casters: it orbits {radius:.2} m \
                         off their vertical axis, half its height above their centre"
                    ));
                }
                centre
            }
        };
        Poses {
            orbit,
            light,
            camera: scene.camera,
            axis,
            note,
        }
    }

    /// Put frame `k` of `n`'s light or camera into `session`.
    pub fn apply(&self, session: &mut Session, k: usize, n: usize) {
        let (light, camera) = self.at(k, n);
        match self.orbit {
            Orbit::Light => session.set_light(light),
            Orbit::Camera => session.set_camera(camera),
        }
    }

    /// Frame `k` of `n`'s light and camera (the one that does not orbit stays as it was).
    pub fn at(&self, k: usize, n: usize) -> (DiskLight, Camera) {
        let angle = std::f32::consts::TAU * k as f32 / n.max(1) as f32;
        let turn = Quat::from_rotation_y(angle);
        let about = |p: Vec3| {
            let axis = Vec3::new(self.axis.x, p.y, self.axis.z);
            axis + turn * (p - axis)
        };
        match self.orbit {
            Orbit::Light => (
                DiskLight {
                    center: about(self.light.center),
                    normal: (turn * self.light.normal).normalize_or(self.light.normal),
                    ..self.light
                },
                self.camera,
            ),
            Orbit::Camera => (
                self.light,
                Camera {
                    eye: about(self.camera.eye),
                    ..self.camera
                },
            ),
        }
    }
}

/// The centre of the casters' bounding box (every object's if none casts).
fn casters_centre(scene: &Scene) -> Option<Vec3> {
    let any_caster = scene.objects.iter().any(|o| o.casts_shadow);
    let mut bounds: Option<(Vec3, Vec3)> = None;
    for o in scene
        .objects
        .iter()
        .filter(|o| o.casts_shadow || !any_caster)
    {
        if let Some((a, b)) = o.mesh.bounds() {
            bounds = Some(match bounds {
                Some((lo, hi)) => (lo.min(a), hi.max(b)),
                None => (a, b),
            });
        }
    }
    bounds.map(|(lo, hi)| (lo + hi) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_light_keeps_its_height_distance_and_relative_tilt() {
        let scene = scene::load("fig7-concave").unwrap();
        let poses = Poses::new(&scene, Orbit::Light);
        let start = scene.light;
        let centre = casters_centre(&scene).unwrap();
        let axis_dist = |p: Vec3| Vec3::new(p.x - centre.x, 0.0, p.z - centre.z).length();
        let mut last = start.center;
        for k in 0..8 {
            let (l, _) = poses.at(k, 8);
            assert!((l.center.y - poses.light.center.y).abs() < 1e-5);
            assert!((axis_dist(l.center) - axis_dist(poses.light.center)).abs() < 1e-4);
            // The normal keeps its angle to the direction toward the axis.
            let inward =
                |c: Vec3| Vec3::new(centre.x - c.x, 0.0, centre.z - c.z).normalize_or_zero();
            let a0 = poses.light.normal.dot(inward(poses.light.center));
            assert!((l.normal.dot(inward(l.center)) - a0).abs() < 1e-4);
            assert!((l.normal.y - poses.light.normal.y).abs() < 1e-5);
            if k > 0 {
                assert!((l.center - last).length() > 1e-3, "frame {k} moved");
            }
            last = l.center;
        }
        assert!((poses.at(0, 8).0.center - poses.light.center).length() < 1e-6);
    }

    #[test]
    fn a_light_on_the_axis_is_moved_off_it_and_the_camera_orbits_its_target() {
        let mut scene = scene::load("fig7-concave").unwrap();
        let centre = casters_centre(&scene).unwrap();
        scene.light.center = Vec3::new(centre.x, centre.y + 4.0, centre.z);
        let poses = Poses::new(&scene, Orbit::Light);
        assert!(poses.note.is_some());
        assert!((poses.light.center.x - centre.x - 2.0).abs() < 1e-4);

        let poses = Poses::new(&scene, Orbit::Camera);
        let target = scene.camera.target;
        let d0 = (scene.camera.eye - target).length();
        let (_, camera) = poses.at(3, 12);
        assert_eq!(camera.target, target);
        assert!(((camera.eye - target).length() - d0).abs() < 1e-4);
        assert!((camera.eye - scene.camera.eye).length() > 1e-3);
    }

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
