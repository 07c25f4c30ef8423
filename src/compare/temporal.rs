//! `dbuffer compare SCENE --orbit light|camera --frames N`: every method while the light (or the
//! camera) goes round the orbit `dbuffer animate` uses ([`crate::scene::orbit`]), against the
//! ray-cast reference frame by frame — how a method behaves in motion, which a still comparison
//! cannot show: sampled lights and PCSS shimmer as the light moves, class boundaries pop.
//!
//! Per method, over each step from frame `k − 1` to frame `k` and the pixels that count in both
//! frames (a surface facing the light, as `compare` counts them):
//! - the **temporal error**: the mean of `|ΔV_method − ΔV_reference|`, ΔV the change of V at the
//!   pixel since the previous frame; the method's number is its mean over the steps;
//! - **popping**: the pixels whose class (lit / penumbra / umbra, the thresholds of
//!   [`crate::geometry::metrics`]) changes in the method but not in the reference; reported as a
//!   share of the counted pixels per step (`popping`, %) and as a count over the orbit.
//!
//! **The reference** is cast here with K samples per pixel (`--samples`; [`DEFAULT_SAMPLES`]
//! unless given) that keep one pattern on the light: frame 0's stratified samples, carried with
//! the light round the orbit ([`Poses::carry`]); on a camera orbit they do not move at all. So
//! its own sampling noise is the same in every frame and does not count as motion: a still
//! scene's reference is the same image every frame, bit for bit. At K = 256 one sample is
//! 1/256 < the class threshold 0.004, so one sample more or less visible never moves a pixel
//! between umbra and penumbra.
//!
//! **What it holds.** Frame by frame, each method is drawn, measured against its own previous
//! frame and let go of before the next method: its previous V waits on disk, and so does its
//! APNG (its error beside the reference's motion, a frame per step), written as the steps come;
//! the worst method's becomes `motion.png`. Memory holds one method's frame and the reference's
//! last two, whatever the number of methods; the image is bounded as a still comparison's
//! ([`MAX_COMPARE_PIXELS`](crate::budget::MAX_COMPARE_PIXELS), checked with `--frames` before
//! the first frame).

use crate::render::truth;
use plotters::prelude::*;

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::budget::MAX_ORBIT_FRAMES;
use crate::geometry::bvh::Bvh;
use crate::geometry::metrics::ShadowClass;
use crate::geometry::oracle::Oracle;
use crate::geometry::outline::area_samples;
use crate::geometry::{oracle, view};
use crate::render::offline::Offline;
use crate::render::truth::SAMPLES;
use crate::render::{FrameRequest, Method, RenderError};
use crate::scene::orbit::{Orbit, Poses};
use crate::scene::{Light, Scene};

use super::{heatmap, CompareRequest, Plan};

/// Frames of an orbit when `--frames` is not given: a 15° step.
pub const DEFAULT_FRAMES: usize = 24;
/// The image size of an orbit when `--size` is not given (every method renders every frame).
pub const DEFAULT_SIZE: (u32, u32) = (256, 256);
/// The reference's K on an orbit when `--samples` is not given: one sample is 1/256, under the
/// class threshold (see the module documentation).
pub const DEFAULT_SAMPLES: u32 = 256;
/// Where the error images saturate (the APNG and the plots): temporal errors are a few
/// hundredths.
pub const FULL_SCALE: f32 = 0.25;
/// The APNG of the worst method's error beside the reference's own motion.
pub const MOTION_APNG: &str = "motion.png";

/// What moves, and how often it is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionRequest {
    /// Size, knobs (the reference's `samples` is its K) and V(t), as a still comparison's.
    pub compare: CompareRequest,
    /// What goes round; `None`: nothing moves (every frame the scene as it is: a still scene,
    /// whose deterministic methods must show no temporal error at all).
    pub orbit: Option<Orbit>,
    pub frames: usize,
}

impl MotionRequest {
    /// Whether the request is within the budget (checked before any frame; the message names
    /// the flag).
    pub fn validate(&self) -> Result<(), String> {
        if !(2..=MAX_ORBIT_FRAMES).contains(&self.frames) {
            return Err(format!(
                "--frames expects 2 to {MAX_ORBIT_FRAMES} (MAX_ORBIT_FRAMES): the temporal error \
                 compares consecutive frames; found {}",
                self.frames
            ));
        }
        self.compare.validate()
    }
}

/// One method in motion.
#[derive(Debug)]
pub struct MethodMotion {
    pub method: Method,
    /// Per step, the mean `|ΔV_method − ΔV_reference|` over the pixels counted in both frames.
    pub steps: Vec<f64>,
    /// Per step, the pixels that popped (class changed in the method, not in the reference).
    pub popping: Vec<usize>,
    /// Its APNG as the run wrote it in the scratch folder: per step `|ΔV_method −
    /// ΔV_reference|` beside the reference's own `|ΔV|` ([`Motion::write_apng`] hands on the
    /// worst's).
    apng: PathBuf,
}

impl MethodMotion {
    /// The mean over the steps of the temporal error.
    pub fn temporal_error(&self) -> f64 {
        mean(&self.steps)
    }
}

/// Every method in motion.
#[derive(Debug)]
pub struct Motion {
    /// "light", "camera" or "still".
    pub orbit: String,
    pub frames: usize,
    pub width: u32,
    pub height: u32,
    /// The reference's K.
    pub samples: u32,
    /// Per step, the pixels counted in both frames.
    pub counted: Vec<usize>,
    /// Per step, the reference's own motion: the mean `|ΔV_reference|` over those pixels.
    pub reference_motion: Vec<f64>,
    /// Every method drawn, in registry order (the references left out).
    pub methods: Vec<MethodMotion>,
    /// Why the orbit is not the one asked for, if it is not (a light on the axis).
    pub note: Option<String>,
    /// Where each method's APNG and previous frame wait; removed with the `Motion`.
    scratch: Scratch,
}

impl Motion {
    /// The share of counted pixels that popped per step, in %, for `m`.
    pub fn popping_pct(&self, m: &MethodMotion) -> f64 {
        let shares: Vec<f64> = m
            .popping
            .iter()
            .zip(&self.counted)
            .map(|(&p, &n)| 100.0 * p as f64 / n.max(1) as f64)
            .collect();
        mean(&shares)
    }

    /// The method with the largest temporal error.
    pub fn worst(&self) -> Option<&MethodMotion> {
        self.methods
            .iter()
            .max_by(|a, b| a.temporal_error().total_cmp(&b.temporal_error()))
    }

    /// Copy `m`'s APNG into `out`: its error beside the reference's own motion, a frame per
    /// step at [`APNG_FPS`] ([`MOTION_APNG`] of the worst method).
    pub fn write_apng(&self, m: &MethodMotion, out: &mut impl Write) -> Result<(), String> {
        let _ = &self.scratch;
        let mut file =
            std::fs::File::open(&m.apng).map_err(|e| format!("{}: {e}", m.apng.display()))?;
        std::io::copy(&mut file, out).map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// Frames per second of the motion APNG.
pub const APNG_FPS: u16 = 8;

/// White columns between the two halves of the APNG.
const GAP: u32 = 4;

fn byte_rgb(e: u8) -> [u8; 3] {
    if e == 0 {
        heatmap::colormap(0.0)
    } else {
        heatmap::colormap(f32::from(e) / 255.0)
    }
}

fn to_byte(v: f32) -> u8 {
    ((v / FULL_SCALE).clamp(0.0, 1.0) * 255.0).round() as u8
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// A folder of work kept on disk rather than in memory, removed when dropped.
#[derive(Debug)]
struct Scratch {
    dir: PathBuf,
}

impl Scratch {
    fn new(parent: &Path) -> Result<Scratch, RenderError> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let dir = parent.join(format!(
            ".dbuffer-motion-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).map_err(|e| scratch_error(&dir, e))?;
        Ok(Scratch { dir })
    }

    fn file(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn scratch_error(path: &Path, e: impl std::fmt::Display) -> RenderError {
    RenderError::Request(format!(
        "{}: cannot keep the orbit's work there: {e}",
        path.display()
    ))
}

/// A method's state between frames: its APNG being written, and where its previous frame's V
/// waits (on disk: an orbit holds one method's frame in memory, not every method's).
struct Track {
    apng: png::Writer<BufWriter<File>>,
    apng_path: PathBuf,
    previous: PathBuf,
}

impl Track {
    fn new(
        scratch: &Scratch,
        method: Method,
        (w, h): (u32, u32),
        steps: u32,
    ) -> Result<Track, RenderError> {
        let path = scratch.file(&format!("{}.png", method.name()));
        let file = File::create(&path).map_err(|e| scratch_error(&path, e))?;
        let mut encoder = png::Encoder::new(BufWriter::new(file), 2 * w + GAP, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::High);
        let encode = |e: png::EncodingError| scratch_error(&path, e);
        encoder
            .set_animated(steps.max(1), 0)
            .and_then(|()| encoder.set_frame_delay(1, APNG_FPS))
            .map_err(encode)?;
        let apng = encoder.write_header().map_err(encode)?;
        Ok(Track {
            apng,
            apng_path: path,
            previous: scratch.file(&format!("{}.v", method.name())),
        })
    }

    /// The V this method drew at the previous frame, into `into`.
    fn load(&self, into: &mut [f32]) -> Result<(), RenderError> {
        let mut f = File::open(&self.previous).map_err(|e| scratch_error(&self.previous, e))?;
        f.read_exact(bytemuck::cast_slice_mut(into))
            .map_err(|e| scratch_error(&self.previous, e))
    }

    fn store(&self, v: &[f32]) -> Result<(), RenderError> {
        std::fs::write(&self.previous, bytemuck::cast_slice::<f32, u8>(v))
            .map_err(|e| scratch_error(&self.previous, e))
    }
}

/// The reference's samples on the light of frame `k`: frame 0's, carried with the light.
fn samples_at(poses: &Poses, frame0: &Light, k: usize, n: usize, count: u32) -> Vec<glam::Vec3> {
    let base = match frame0 {
        Light::Area(a) => area_samples(a, count as usize),
        Light::Line(l) => oracle::line_samples(l, count as usize),
    };
    base.into_iter().map(|p| poses.carry(k, n, p)).collect()
}

/// Render every method at every frame of the orbit and measure each step against the reference;
/// `progress` hears (frame, what). Its work on disk (each method's previous frame and APNG)
/// goes into a folder in the system's temporary folder ([`run_in`] names another).
pub fn run(
    offline: &mut Offline,
    scene: &Scene,
    request: &MotionRequest,
    progress: impl FnMut(usize, &str),
) -> Result<Motion, RenderError> {
    let plan = Plan::new(scene.light.kind(), &offline.ctx.caps);
    run_in(
        offline,
        scene,
        request,
        &plan,
        &std::env::temp_dir(),
        progress,
    )
}

/// [`run`] for the methods of `plan` (the references left out: motion is measured against
/// them), with its work on disk in a folder made in `scratch` (removed with the [`Motion`]).
/// Frame by frame, each method is drawn, measured against its own previous frame (read back
/// from disk) and let go of before the next: memory holds one method's frame and the
/// reference's two, whatever the number of methods.
pub fn run_in(
    offline: &mut Offline,
    scene: &Scene,
    request: &MotionRequest,
    plan: &Plan,
    scratch: &Path,
    mut progress: impl FnMut(usize, &str),
) -> Result<Motion, RenderError> {
    let c = &request.compare;
    c.knobs.validate().map_err(RenderError::Request)?;
    let methods: Vec<Method> = plan
        .drawn
        .iter()
        .copied()
        .filter(|m| !truth::is_truth(*m))
        .collect();
    request.validate().map_err(RenderError::Request)?;
    let (w, h) = (c.width, c.height);
    let n = w as usize * h as usize;
    let k_samples = c.knobs.get(&SAMPLES);
    let orbit = request.orbit.unwrap_or(Orbit::Light);
    let poses = Poses::new(scene, orbit);
    let frames = request.frames;
    let pose = |k: usize| {
        if request.orbit.is_some() {
            poses.at(k, frames)
        } else {
            (scene.light, scene.camera)
        }
    };
    let frame0_light = pose(0).0;
    let triangles = scene.all_triangles();
    let surfaces = Bvh::build(triangles.clone());
    let mut session = offline.session(scene.clone());
    let scratch = Scratch::new(scratch)?;
    let steps = (frames - 1) as u32;
    let mut tracks = methods
        .iter()
        .map(|&m| Track::new(&scratch, m, (w, h), steps))
        .collect::<Result<Vec<_>, _>>()?;
    let mut out: Vec<MethodMotion> = methods
        .iter()
        .zip(&tracks)
        .map(|(&method, t)| MethodMotion {
            method,
            steps: Vec::with_capacity(frames - 1),
            popping: Vec::with_capacity(frames - 1),
            apng: t.apng_path.clone(),
        })
        .collect();
    let mut counted = Vec::with_capacity(frames - 1);
    let mut reference_motion = Vec::with_capacity(frames - 1);
    // The previous frame: the reference's V and the counted pixels.
    let mut previous: Option<(Vec<f32>, Vec<bool>)> = None;
    let mut before = vec![0.0f32; if frames > 1 { n } else { 0 }];
    for k in 0..frames {
        let (light, camera) = pose(k);
        session.set_light(light);
        session.set_camera(camera);
        let posed = session.scene().clone();
        progress(k, truth::SOFT.name());
        let samples = if request.orbit.is_some() {
            samples_at(&poses, &frame0_light, k, frames, k_samples)
        } else {
            samples_at(&poses, &frame0_light, 0, frames, k_samples)
        };
        let oracle = Oracle::with_samples(triangles.clone(), light, samples);
        let (reference, facing): (Vec<f32>, Vec<bool>) = {
            use rayon::prelude::*;
            (0..n as u32)
                .into_par_iter()
                .with_min_len(64)
                .map(|i| match view::receiver_at(&posed, &surfaces, i, w, h) {
                    Some(r) => (oracle.visibility(r.position), r.faces_light),
                    None => (0.0, false),
                })
                .unzip()
        };
        drop(oracle);
        // The pixels counted at this frame (from the first method's depth), and in both.
        let mut mask: Vec<bool> = Vec::new();
        let mut both: Vec<bool> = Vec::new();
        let mut moved: Vec<u8> = Vec::new();
        let mut count = 0;
        for (i, &method) in methods.iter().enumerate() {
            progress(k, method.name());
            let req = FrameRequest {
                width: w,
                height: h,
                dbuffer_size: c.dbuffer_size,
                method,
                vt: c.vt,
                knobs: c.knobs,
                read_dbuffer: false,
                read_cost: false,
                colour_only: false,
            };
            // A temporal method keeps its state from frame to frame (its history, as a user
            // moving the light or camera has it), filled at the first pose as a still view's is;
            // every other method is let go of after its frame.
            let frame = if method.spec().history.is_some() {
                if k == 0 {
                    session.fill_history(&offline.ctx, &req)?;
                }
                session.frame(&offline.ctx, &req)?
            } else {
                session.frame_releasing(&offline.ctx, &req)?
            };
            if i == 0 {
                mask = facing
                    .iter()
                    .enumerate()
                    .map(|(j, &f)| f && frame.hit(j))
                    .collect();
                if let Some((ref_prev, mask_prev)) = &previous {
                    both = mask.iter().zip(mask_prev).map(|(a, b)| *a && *b).collect();
                    count = both.iter().filter(|b| **b).count();
                    moved = vec![0u8; n];
                    let mut motion = 0.0f64;
                    for j in (0..n).filter(|&j| both[j]) {
                        let d = (reference[j] - ref_prev[j]).abs();
                        motion += f64::from(d);
                        moved[j] = to_byte(d);
                    }
                    counted.push(count);
                    reference_motion.push(motion / count.max(1) as f64);
                }
            }
            let now = frame.visibility;
            let track = &mut tracks[i];
            if let Some((ref_prev, _)) = &previous {
                track.load(&mut before)?;
                let m = &mut out[i];
                let mut sum = 0.0f64;
                let mut popped = 0usize;
                let mut err = vec![0u8; n];
                for j in (0..n).filter(|&j| both[j]) {
                    let dm = now[j] - before[j];
                    let dr = reference[j] - ref_prev[j];
                    let e = if dm.is_finite() { (dm - dr).abs() } else { 1.0 };
                    sum += f64::from(e);
                    err[j] = to_byte(e);
                    let class = |v: f32| ShadowClass::of(f64::from(v));
                    let method_changed = class(now[j]) != class(before[j]);
                    let reference_changed = class(reference[j]) != class(ref_prev[j]);
                    popped += usize::from(method_changed && !reference_changed);
                }
                m.steps.push(sum / count.max(1) as f64);
                m.popping.push(popped);
                let rgb = apng_frame(&err, &moved, w, h);
                track
                    .apng
                    .write_image_data(&rgb)
                    .map_err(|e| scratch_error(&m.apng, e))?;
            }
            if k + 1 < frames {
                track.store(&now)?;
            }
        }
        previous = Some((reference, mask));
    }
    for (track, m) in tracks.into_iter().zip(&out) {
        track.apng.finish().map_err(|e| scratch_error(&m.apng, e))?;
    }
    Ok(Motion {
        orbit: match request.orbit {
            Some(Orbit::Light) => "light",
            Some(Orbit::Camera) => "camera",
            None => "still",
        }
        .to_string(),
        frames,
        width: w,
        height: h,
        samples: k_samples,
        counted,
        reference_motion,
        methods: out,
        note: request.orbit.and(poses.note.clone()),
        scratch,
    })
}

/// One frame of a method's APNG: its `err` bytes beside the reference's `moved`, row by row.
fn apng_frame(err: &[u8], moved: &[u8], w: u32, h: u32) -> Vec<u8> {
    let mut rgb = Vec::with_capacity(((2 * w + GAP) * h * 3) as usize);
    for y in 0..h as usize {
        let row = y * w as usize..(y + 1) * w as usize;
        for &e in &err[row.clone()] {
            rgb.extend(byte_rgb(e));
        }
        for _ in 0..GAP {
            rgb.extend([255, 255, 255]);
        }
        for &e in &moved[row] {
            rgb.extend(byte_rgb(e));
        }
    }
    rgb
}

/// The plot of one method's temporal error per step, with the reference's own motion for
/// scale, as PNG bytes (`width`×`height`).
pub fn plot_png(
    motion: &Motion,
    m: &MethodMotion,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, String> {
    if !crate::bench::plot::register_fonts() {
        return Err("the embedded font does not parse".into());
    }
    let family = crate::bench::plot::FAMILY;
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let steps = m.steps.len().max(1);
    let top = m
        .steps
        .iter()
        .chain(&motion.reference_motion)
        .fold(1e-4f64, |a, &b| a.max(b))
        * 1.15;
    let mut buffer = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let caption = format!(
            "{}: temporal error {:.4}, popping {:.2} % a step ({} orbit, K = {})",
            m.method,
            m.temporal_error(),
            motion.popping_pct(m),
            motion.orbit,
            motion.samples
        );
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, (family, 16))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(1f64..steps as f64, 0f64..top)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("frame (step from the one before)")
            .y_desc("mean |ΔV − ΔV_ref|")
            .axis_desc_style((family, 14))
            .label_style((family, 12))
            .x_label_formatter(&|x| format!("{x:.0}"))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| err(&e))?;
        let blue = RGBColor(31, 100, 180);
        let grey = RGBColor(150, 150, 150);
        let series: Vec<(f64, f64)> = m
            .steps
            .iter()
            .enumerate()
            .map(|(i, &e)| ((i + 1) as f64, e))
            .collect();
        let reference: Vec<(f64, f64)> = motion
            .reference_motion
            .iter()
            .enumerate()
            .map(|(i, &e)| ((i + 1) as f64, e))
            .collect();
        chart
            .draw_series(LineSeries::new(reference, grey.stroke_width(1)))
            .map_err(|e| err(&e))?
            .label("the reference's own motion, mean |ΔV_ref|")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
        chart
            .draw_series(LineSeries::new(series.clone(), blue.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label("temporal error")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(2))
            });
        chart
            .draw_series(series.iter().map(|&p| Circle::new(p, 3, blue.filled())))
            .map_err(|e| err(&e))?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((family, 12))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK.mix(0.3))
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    let img = image::RgbImage::from_raw(width, height, buffer)
        .ok_or_else(|| "plot buffer has the wrong size".to_string())?;
    crate::output::png_rgb8(width, height, img.as_raw()).map_err(|e| e.to_string())
}

/// A method's temporal plot.
pub fn plot_file(method: Method) -> String {
    format!("{}-temporal.png", method.name())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::VtVariant;
    use crate::render::Knobs;

    #[test]
    fn limits_name_their_flags() {
        let request = |frames, side| MotionRequest {
            compare: CompareRequest {
                width: side,
                height: side,
                dbuffer_size: 256,
                vt: VtVariant::Exact,
                knobs: Knobs::default(),
            },
            orbit: Some(Orbit::Light),
            frames,
        };
        assert!(request(24, 256).validate().is_ok());
        assert!(request(MAX_ORBIT_FRAMES, 4096).validate().is_ok());
        let e = request(1, 64).validate().unwrap_err();
        assert!(e.contains("--frames") && e.contains("found 1"), "{e}");
        let e = request(MAX_ORBIT_FRAMES + 1, 64).validate().unwrap_err();
        assert!(e.contains("MAX_ORBIT_FRAMES"), "{e}");
        let e = request(24, 4097).validate().unwrap_err();
        assert!(
            e.contains("MAX_COMPARE_PIXELS") && e.contains("--size 4097x4097"),
            "{e}"
        );
    }

    #[test]
    fn the_reference_samples_ride_with_the_light() {
        let scene = crate::scene::load("fig7-concave").unwrap();
        let poses = Poses::new(&scene, Orbit::Light);
        let light = poses.at(0, 8).0;
        let s0 = samples_at(&poses, &light, 0, 8, 64);
        let s3 = samples_at(&poses, &light, 3, 8, 64);
        let l3 = poses.at(3, 8).0;
        // The same pattern on the light: every sample keeps its distance from the centre, and
        // the set has moved with the light.
        for (a, b) in s0.iter().zip(&s3) {
            let da = (*a - light.center()).length();
            let db = (*b - l3.center()).length();
            assert!((da - db).abs() < 1e-4, "{da} {db}");
        }
        assert!((s0[0] - s3[0]).length() > 1e-2);
        // On a camera orbit nothing on the light moves.
        let still = Poses::new(&scene, Orbit::Camera);
        assert_eq!(
            samples_at(&still, &light, 5, 8, 16),
            samples_at(&still, &light, 0, 8, 16)
        );
    }
}
