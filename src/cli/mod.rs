//! The subcommands. Each one loads through [`dbuffer::scene`] and computes through the same
//! library code the GUI uses; nothing here renders or computes on its own.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{metrics, view, DBufferTwin, PreparedCasters, VolumeParams, VtVariant};
use dbuffer::output;
use dbuffer::render::methods::all_knobs;
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, Knobs, Method};
use dbuffer::scene;
use glam::Vec3;
use rayon::prelude::*;

mod animate;
pub mod bench;
mod compare;
mod progress;
pub use animate::{animate, AnimateArgs};
pub use compare::{compare, CompareArgs};

/// The knobs of every method of the registry, as flags of `render` and `compare`
/// (`--pcf-radius`, `--lights`, …): each method's module declares its own.
#[derive(Clone, Debug, Default)]
pub struct MethodFlags {
    /// The knobs given on the command line.
    pub given: Vec<(&'static str, u32)>,
}

impl clap::FromArgMatches for MethodFlags {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        Ok(MethodFlags {
            given: all_knobs()
                .into_iter()
                .filter_map(|k| m.get_one::<u32>(k.name).map(|v| (k.name, *v)))
                .collect(),
        })
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for MethodFlags {
    fn augment_args(mut cmd: clap::Command) -> clap::Command {
        for k in all_knobs() {
            cmd = cmd.arg(
                clap::Arg::new(k.name)
                    .long(k.name)
                    .value_name("N")
                    .value_parser(clap::value_parser!(u32))
                    .help(format!(
                        "{}, {} to {} (default {})",
                        k.help, k.min, k.max, k.default
                    )),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl MethodFlags {
    /// The knobs, each checked against its range (the message names the flag).
    pub fn knobs(&self) -> Result<Knobs> {
        let mut knobs = Knobs::default();
        for &(name, value) in &self.given {
            knobs.set(name, value).map_err(anyhow::Error::msg)?;
        }
        knobs.validate().map_err(anyhow::Error::msg)?;
        Ok(knobs)
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
    let knobs = args.knobs.knobs()?;
    let scene =
        scene::load(args.scene).with_context(|| format!("cannot load scene '{}'", args.scene))?;
    // Before the GPU starts: a disk-only method under a line light (or the reverse) says why.
    if let Some(why) = method.refuses(scene.light.kind()) {
        bail!("{why}");
    }
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
        knobs,
        read_dbuffer: true,
    };
    if method.is_reference() {
        offline.progress = Some(progress::reference_samples());
    }
    let name = scene.name.clone();
    let mut session = offline.session(scene);
    let (frame, report) = offline.render_in(&mut session, &request)?;
    let meta = output::render_meta(
        &name,
        session.scene(),
        &request,
        &offline.ctx,
        &frame,
        &report,
    );
    for w in &meta.warnings {
        eprintln!("warning   {w}");
    }
    if args.verbose {
        for (stage, ms) in &meta.cpu_ms {
            eprintln!("cpu ms    {stage:<20} {ms:8.3}");
        }
        for (pass, ms) in &meta.gpu_ms {
            eprintln!("gpu ms    {pass:<20} {ms:8.3}");
        }
    }
    let outputs = output::RenderOutputs::from_frame(&frame, meta);
    drop(frame);
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

pub fn inspect(
    name: &str,
    samples: Option<usize>,
    size: &str,
    vt: &str,
    out: Option<&Path>,
) -> Result<()> {
    let scene = scene::load(name).with_context(|| format!("cannot load scene '{name}'"))?;
    let Some(&l) = scene.light.as_disk() else {
        bail!(
            "inspect shows the D-buffer's geometry stage, which needs a disk light, and the \
             light of '{name}' is a line (kind = \"line\"); use `dbuffer render` or `dbuffer \
             compare` for a line light"
        );
    };
    let t0 = Instant::now();
    let prepared = PreparedCasters::new(&scene);
    let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
    let params = VolumeParams::for_scene(&scene);
    let t1 = Instant::now();
    let geometry = prepared.build(&l, &params);
    let build_ms = t1.elapsed().as_secs_f64() * 1e3;

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
        let frames = compare_twin(&scene, &geometry, k, width, height, vt);
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
    geometry: &dbuffer::geometry::SceneGeometry,
    k: usize,
    width: u32,
    height: u32,
    vt: VtVariant,
) -> Frames {
    let oracle = Oracle::from_scene(scene, k);
    let twin = DBufferTwin::new(scene, &geometry.casters);
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
    let method: Vec<f32> = points
        .par_iter()
        .zip(&mask)
        .map(|(&x, &on)| {
            if on {
                twin.visibility(x, vt) as f32
            } else {
                0.0
            }
        })
        .collect();
    let twin_s = t1.elapsed().as_secs_f64();
    let m = metrics::compare(&reference, &method, &mask);
    let rays = mask.iter().filter(|&&m| m).count() * k;
    println!(
        "twin vs oracle ({width}x{height}, {} px facing the light, V(t) {vt}, K = {k}):",
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
    println!(
        "  oracle {:.0} ms ({:.1} M rays/s), twin {:.0} ms",
        oracle_s * 1e3,
        rays as f64 / oracle_s / 1e6,
        twin_s * 1e3
    );
    Frames {
        method,
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
