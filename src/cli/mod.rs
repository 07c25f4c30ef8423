//! The subcommands. Each one loads through [`dbuffer::scene`] and computes through the same
//! library code the GUI uses; nothing here renders or computes on its own.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use dbuffer::geometry::fused::{FusedParams, FusedPath, FusedTwin};
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{metrics, view, DBufferTwin, PreparedCasters, VolumeParams, VtVariant};
use dbuffer::output;
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, Method, MethodParams};
use dbuffer::scene;
use glam::Vec3;
use rayon::prelude::*;

pub mod bench;
mod compare;
pub use compare::{compare, CompareArgs};

/// The knobs of the comparison methods, as flags of `render` and `compare`.
#[derive(clap::Args, Clone, Debug)]
pub struct MethodFlags {
    /// pcf: kernel radius in shadow-map texels ((2R+1)² taps), 0 to 8.
    #[arg(long, default_value_t = MethodParams::default().pcf_radius)]
    pub pcf_radius: u32,
    /// pcss: blocker-search taps (rotated Poisson disk), 1 to 64.
    #[arg(long, default_value_t = MethodParams::default().pcss_blocker_taps)]
    pub blocker_taps: u32,
    /// pcss: filter taps (rotated Poisson disk), 1 to 64.
    #[arg(long, default_value_t = MethodParams::default().pcss_filter_taps)]
    pub filter_taps: u32,
    /// sampled: shadow maps from this many stratified points on the disk, 1 to 64.
    #[arg(long, default_value_t = MethodParams::default().sampled_lights)]
    pub lights: u32,
    /// reference: rays to this many stratified disk samples per pixel (K).
    #[arg(long, default_value_t = MethodParams::default().reference_samples)]
    pub samples: u32,
}

impl MethodFlags {
    /// The knobs, each checked against its range (the message names the flag).
    pub fn params(&self) -> Result<MethodParams> {
        let checks = [
            (
                "--pcf-radius",
                self.pcf_radius,
                0,
                dbuffer::render::frame::MAX_PCF_RADIUS,
            ),
            (
                "--blocker-taps",
                self.blocker_taps,
                1,
                dbuffer::render::frame::MAX_TAPS,
            ),
            (
                "--filter-taps",
                self.filter_taps,
                1,
                dbuffer::render::frame::MAX_TAPS,
            ),
            (
                "--lights",
                self.lights,
                1,
                dbuffer::render::frame::MAX_SAMPLED_LIGHTS,
            ),
            (
                "--samples",
                self.samples,
                1,
                dbuffer::render::frame::MAX_REFERENCE_SAMPLES,
            ),
        ];
        for (flag, value, lo, hi) in checks {
            if !(lo..=hi).contains(&value) {
                bail!("{flag} expects {lo} to {hi}, found {value}");
            }
        }
        Ok(MethodParams {
            pcf_radius: self.pcf_radius,
            pcss_blocker_taps: self.blocker_taps,
            pcss_filter_taps: self.filter_taps,
            sampled_lights: self.lights,
            reference_samples: self.samples,
            ..MethodParams::default()
        })
    }
}

pub fn scenes() -> Result<()> {
    for name in scene::builtin::names() {
        println!("{name}");
    }
    Ok(())
}

/// The arguments of `dbuffer render`, as typed.
pub struct RenderArgs<'a> {
    pub scene: &'a str,
    pub out: &'a Path,
    pub size: &'a str,
    pub method: &'a str,
    pub vt: &'a str,
    pub dbuffer_size: u32,
    pub knobs: &'a MethodFlags,
    pub verbose: bool,
}

pub fn render(args: &RenderArgs) -> Result<()> {
    let (width, height) = parse_size(args.size)?;
    let method: Method = args.method.parse().map_err(anyhow::Error::msg)?;
    let vt: VtVariant = args.vt.parse().map_err(anyhow::Error::msg)?;
    check_dbuffer_size(args.dbuffer_size)?;
    let params = args.knobs.params()?;
    let scene =
        scene::load(args.scene).with_context(|| format!("cannot load scene '{}'", args.scene))?;
    let mut offline = Offline::new()?;
    if args.verbose {
        eprintln!("adapter   {}", offline.ctx.adapter_description());
    }
    let request = FrameRequest {
        width,
        height,
        dbuffer_size: args.dbuffer_size,
        method,
        vt,
        params,
        ..FrameRequest::default()
    };
    if method == Method::Reference {
        offline.progress = Some(progress_line("reference"));
    }
    let (_, outputs) = offline.render(&scene.name, &scene, &request)?;
    for w in &outputs.meta.warnings {
        eprintln!("warning   {w}");
    }
    if args.verbose {
        for (stage, ms) in &outputs.meta.cpu_ms {
            eprintln!("cpu ms    {stage:<20} {ms:8.3}");
        }
        for (pass, ms) in &outputs.meta.gpu_ms {
            eprintln!("gpu ms    {pass:<20} {ms:8.3}");
        }
    }
    let written = output::write_render(args.out, &outputs)?;
    if args.verbose {
        for path in written {
            eprintln!("wrote     {}", path.display());
        }
    }
    Ok(())
}

/// The lab window. `DBUFFER_SMOKE_SCREENSHOT=shot.png` makes it screenshot itself once frames
/// show and exit (the scripted smoke run under Xvfb).
pub fn gui(scene: Option<String>) -> Result<()> {
    let smoke_screenshot = std::env::var_os("DBUFFER_SMOKE_SCREENSHOT").map(Into::into);
    dbuffer::app::run(dbuffer::app::LabOptions {
        scene,
        fresh_settings: smoke_screenshot.is_some(),
        smoke_screenshot,
        ..Default::default()
    })
}

fn check_dbuffer_size(size: u32) -> Result<()> {
    if !(1..=8192).contains(&size) {
        bail!("--dbuffer-size expects a texel count from 1 to 8192, found {size}");
    }
    Ok(())
}

/// A progress callback that rewrites one stderr line: "what: done/total samples".
fn progress_line(what: &'static str) -> Box<dyn FnMut(usize, usize)> {
    let start = Instant::now();
    Box::new(move |done, total| {
        eprint!(
            "\r{what}: {done}/{total} samples per pixel ({:.1} s)",
            start.elapsed().as_secs_f64()
        );
        if done >= total {
            eprintln!();
        }
    })
}

/// Whose CPU twin `inspect` compares with the reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TwinMethod {
    DBuffer,
    Fused,
}

impl TwinMethod {
    fn parse(text: &str) -> Result<TwinMethod> {
        match text {
            "dbuffer" => Ok(TwinMethod::DBuffer),
            "dbuffer-fused" => Ok(TwinMethod::Fused),
            _ => bail!(
                "--method for inspect expects dbuffer or dbuffer-fused (the methods with a CPU \
                 twin), found '{text}'"
            ),
        }
    }
}

pub fn inspect(
    name: &str,
    samples: Option<usize>,
    size: &str,
    vt: &str,
    method: &str,
    out: Option<&Path>,
) -> Result<()> {
    let method = TwinMethod::parse(method)?;
    let scene = scene::load(name).with_context(|| format!("cannot load scene '{name}'"))?;
    let t0 = Instant::now();
    let prepared = PreparedCasters::new(&scene);
    let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
    let params = VolumeParams::for_scene(&scene);
    let t1 = Instant::now();
    let geometry = prepared.build(&scene.light, &params);
    let build_ms = t1.elapsed().as_secs_f64() * 1e3;

    let l = &scene.light;
    println!("scene     {}", scene.name);
    println!(
        "light     centre {} normal {} radius {}",
        l.center, l.normal, l.radius
    );
    println!(
        "{:<16} {:>9} {:>9} {:>9} {:>6} {:>6} {:>7} {:>7} {:>5} {:>8} {:>8}",
        "caster",
        "tris",
        "all-fr",
        "none-fr",
        "sil-A",
        "sil-B",
        "umb-e",
        "pen-e",
        "fans",
        "umb-tri",
        "pen-tri"
    );
    for c in &geometry.casters {
        let s = c.stats;
        println!(
            "{:<16} {:>9} {:>9} {:>9} {:>6} {:>6} {:>7} {:>7} {:>5} {:>8} {:>8}",
            c.name,
            s.triangles,
            s.all_front,
            s.none_front,
            s.silhouette_a,
            s.silhouette_b,
            s.umbra_edges,
            s.penumbra_edges,
            s.fans,
            s.umbra_triangles,
            s.penumbra_triangles
        );
    }
    println!("geometry  prepare {prepare_ms:.3} ms (once per mesh), classes+silhouettes+volumes {build_ms:.3} ms");
    for w in &geometry.warnings {
        println!("warning   {w}");
    }

    if let Some(k) = samples {
        if k == 0 {
            bail!("--samples must be at least 1");
        }
        let (width, height) = parse_size(size)?;
        let vt: VtVariant = vt.parse().map_err(anyhow::Error::msg)?;
        let frames = compare_twin(&scene, &prepared, &geometry, k, (width, height), vt, method);
        if let Some(path) = out {
            write_comparison(path, &frames, width, height)?;
            println!("wrote {}", path.display());
        }
    } else if out.is_some() {
        bail!("--out needs --samples: the picture compares the method with the reference");
    }
    Ok(())
}

/// `WxH` with both at least 1.
pub fn parse_size(text: &str) -> Result<(u32, u32)> {
    let parsed = text
        .split_once(['x', 'X'])
        .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if w > 0 && h > 0 && u64::from(w) * u64::from(h) <= 1 << 26 => Ok((w, h)),
        _ => bail!("--size expects WxH with positive integers (at most 64 Mpixels), e.g. 512x512; found '{text}'"),
    }
}

/// Per pixel of the view: the method's V, the reference V, and whether it counts.
struct Frames {
    method: Vec<f32>,
    reference: Vec<f32>,
    mask: Vec<bool>,
}

/// The CPU twin of the method against the oracle over the camera's view (design.md §4 metrics).
fn compare_twin(
    scene: &scene::Scene,
    prepared: &PreparedCasters,
    geometry: &dbuffer::geometry::SceneGeometry,
    k: usize,
    (width, height): (u32, u32),
    vt: VtVariant,
    method: TwinMethod,
) -> Frames {
    let oracle = Oracle::from_scene(scene, k);
    let (paper, fused) = match method {
        TwinMethod::DBuffer => (Some(DBufferTwin::new(scene, &geometry.casters)), None),
        TwinMethod::Fused => {
            let params = FusedParams {
                vt,
                ..FusedParams::default()
            };
            (
                None,
                Some(FusedTwin::new(scene, prepared, geometry, params)),
            )
        }
    };
    let pixels = view::receivers(scene, oracle.bvh(), width, height);
    let points: Vec<Vec3> = pixels
        .iter()
        .map(|r| r.map_or(Vec3::ZERO, |r| r.position))
        .collect();
    let mask: Vec<bool> = pixels
        .iter()
        .map(|r| r.is_some_and(|r| r.faces_light))
        .collect();
    let t0 = Instant::now();
    let reference: Vec<f32> = points
        .par_iter()
        .zip(&mask)
        .map(|(&x, &on)| if on { oracle.visibility(x) } else { 0.0 })
        .collect();
    let oracle_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    // V, and for dbuffer-fused the length of the texel's list where the mask ran (None: it did
    // not) and whether it overflowed.
    let rows: Vec<(f32, Option<(usize, bool)>)> = points
        .par_iter()
        .zip(&mask)
        .map(|(&x, &on)| match (on, &paper, &fused) {
            (false, _, _) => (0.0, None),
            (true, Some(t), _) => (t.visibility(x, vt) as f32, None),
            (true, _, Some(t)) => {
                let s = t.sample(x);
                let list = match s.path {
                    FusedPath::Mask => Some((s.list_count, false)),
                    FusedPath::Overflow => Some((s.list_count, true)),
                    _ => None,
                };
                (s.v as f32, list)
            }
            (true, None, None) => (0.0, None),
        })
        .collect();
    let twin_s = t1.elapsed().as_secs_f64();
    let method_v: Vec<f32> = rows.iter().map(|r| r.0).collect();
    let m = metrics::compare(&reference, &method_v, &mask);
    let rays = mask.iter().filter(|&&m| m).count() * k;
    let name = match method {
        TwinMethod::DBuffer => "dbuffer",
        TwinMethod::Fused => "dbuffer-fused",
    };
    println!(
        "twin ({name}) vs oracle ({width}x{height}, {} px facing the light, V(t) {vt}, K = {k}):",
        m.pixels
    );
    println!(
        "  class mismatch {:.2} %   MAE {:.4}   penumbra MAE {:.4} ({} px)   p99 |dV| {:.3}",
        m.class_mismatch_pct, m.mae, m.penumbra_mae, m.penumbra_pixels, m.p99
    );
    println!("  pixels by class, reference (rows) against the twin (columns):");
    println!("  {:>10} {:>9} {:>9} {:>9}", "", "lit", "penumbra", "umbra");
    for rc in metrics::ShadowClass::ALL {
        let row = m.confusion[rc.index()];
        println!(
            "  {:>10} {:>9} {:>9} {:>9}",
            rc.name(),
            row[0],
            row[1],
            row[2]
        );
    }
    let lists: Vec<(usize, bool)> = rows.iter().filter_map(|r| r.1).collect();
    if !lists.is_empty() {
        let longest = lists.iter().map(|l| l.0).max().unwrap_or(0);
        let mean = lists.iter().map(|l| l.0).sum::<usize>() as f64 / lists.len() as f64;
        let overflow = lists.iter().filter(|l| l.1).count();
        println!(
            "  edge lists: {} px read one (mean {mean:.1} edges, longest {longest}); {overflow} px \
             overflowed and fell back to dbuffer",
            lists.len()
        );
    }
    println!(
        "  oracle {:.0} ms ({:.1} M rays/s), twin {:.0} ms",
        oracle_s * 1e3,
        rays as f64 / oracle_s / 1e6,
        twin_s * 1e3
    );
    Frames {
        method: method_v,
        reference,
        mask,
    }
}

/// Method | reference | |ΔV| side by side; pixels that do not count are dark blue.
fn write_comparison(path: &Path, f: &Frames, width: u32, height: u32) -> Result<()> {
    let mut img = image::RgbImage::new(width * 3, height);
    let gray = |v: f32| {
        let g = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
        image::Rgb([g, g, g])
    };
    for i in 0..(width * height) as usize {
        let (x, y) = (i as u32 % width, i as u32 / width);
        let panels = if f.mask[i] {
            let err = (f.method[i] - f.reference[i]).abs() / 0.25;
            [gray(f.method[i]), gray(f.reference[i]), gray(err)]
        } else {
            [image::Rgb([20, 24, 48]); 3]
        };
        for (k, px) in panels.into_iter().enumerate() {
            img.put_pixel(x + k as u32 * width, y, px);
        }
    }
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .context("encoding the PNG")?;
    dbuffer::fsutil::write_atomic(path, &bytes)
        .with_context(|| format!("cannot write {}", path.display()))
}
