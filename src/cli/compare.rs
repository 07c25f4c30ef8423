//! `dbuffer compare SCENE --out DIR`: every method against the ray-cast reference; with
//! `--orbit light|camera`, also every method in motion round the orbit of `animate`.

use std::path::Path;

use anyhow::{Context, Result};
use dbuffer::compare::temporal::{self, MotionRequest};
use dbuffer::compare::{self, report, CompareRequest};
use dbuffer::geometry::VtVariant;
use dbuffer::output;
use dbuffer::render::gpu_reference;
use dbuffer::render::offline::Offline;
use dbuffer::render::truth::{self, SAMPLES};
use dbuffer::render::Method;
use dbuffer::scene::orbit::Orbit;

use super::progress::Progress;
use super::{check_dbuffer_size, parse_size, progress, MethodFlags};

/// The arguments of `dbuffer compare`, as typed.
pub struct CompareArgs<'a> {
    pub scene: &'a str,
    /// `--scene N`: which scene of a glTF model.
    pub gltf_scene: Option<usize>,
    pub out: &'a Path,
    /// `None`: 512x512, or [`temporal::DEFAULT_SIZE`] with an orbit.
    pub size: Option<&'a str>,
    pub orbit: Option<&'a str>,
    pub frames: usize,
    /// `--methods a,b`: only these (and the references).
    pub methods: Option<&'a str>,
    /// `--reference cpu|gpu`: which engine traces the reference's rays.
    pub reference: &'a str,
    pub vt: &'a str,
    pub dbuffer_size: u32,
    pub knobs: &'a MethodFlags,
}

pub fn compare(args: &CompareArgs) -> Result<()> {
    let orbit: Option<Orbit> = args
        .orbit
        .map(|o| o.parse().map_err(anyhow::Error::msg))
        .transpose()?;
    let (width, height) = match (args.size, orbit) {
        (Some(size), _) => parse_size(size)?,
        (None, Some(_)) => temporal::DEFAULT_SIZE,
        (None, None) => (512, 512),
    };
    let vt: VtVariant = args.vt.parse().map_err(anyhow::Error::msg)?;
    check_dbuffer_size(args.dbuffer_size)?;
    let only = args
        .methods
        .map(|list| parse_methods(list, args.knobs))
        .transpose()?;
    let engine: truth::Engine = args.reference.parse().map_err(anyhow::Error::msg)?;
    let mut knobs = args.knobs.knobs()?;
    if orbit.is_some() && knobs.given(&SAMPLES).is_none() {
        // Every frame casts the reference: a modest K unless asked (one sample still below
        // the class threshold).
        knobs = knobs.with(&SAMPLES, temporal::DEFAULT_SAMPLES);
    }
    let request = CompareRequest {
        width,
        height,
        dbuffer_size: args.dbuffer_size,
        vt,
        knobs,
    };
    // Before any work: the image a comparison may hold, and the orbit's frames.
    request.validate().map_err(anyhow::Error::msg)?;
    let motion_request = orbit.map(|orbit| MotionRequest {
        compare: request,
        orbit: Some(orbit),
        frames: args.frames,
    });
    if let Some(m) = &motion_request {
        m.validate().map_err(anyhow::Error::msg)?;
    }
    // Before any work: a comparison that cannot be written is not started.
    output::check_out_dir(args.out, &[]).context("--out")?;
    let scene = super::load_scene(args.scene, args.gltf_scene)?;
    for w in scene.warnings() {
        errln!("warning   {w}");
    }
    let mut offline = Offline::new()?;
    errln!("adapter   {}", offline.ctx.adapter_description());
    super::chosen(&offline.ctx);
    if engine == truth::Engine::Gpu {
        // Before any work: an adapter the GPU reference cannot run on is refused in one line.
        if let Some(why) = gpu_reference::refuses_on(&offline.ctx.caps) {
            anyhow::bail!("--reference gpu: {why}");
        }
    }
    offline.reference = engine;
    offline.progress = Some(progress::reference_samples());
    let cannot_write = || format!("cannot write the report into {}", args.out.display());
    // Each method's files are written (into the folder's hidden staging folder) as it finishes,
    // and its frame let go of; everything is moved into place at the end, all or nothing.
    let named = only.as_deref().unwrap_or_default();
    let mut plan = compare::Plan::with(scene.light.kind(), &offline.ctx.caps, named);
    if let Some(only) = &only {
        plan = plan.only(only);
    }
    let mut writer =
        report::Writer::new(args.out, (width, height), &plan.drawn).with_context(cannot_write)?;
    let drawn = plan.clone();
    let (outline, baseline) = compare::run_each(
        &mut offline,
        &scene.name,
        &scene,
        &request,
        plan,
        |what| errln!("rendering {what}"),
        |tile, against, r| writer.method(tile, against, &r).with_context(cannot_write),
    )?;
    drop(baseline);
    let motion = match &motion_request {
        Some(m) => {
            let bar = Progress::new("orbit", m.frames as u64, "frames");
            bar.stage(&format!(
                "{}, the {} orbiting, {width}x{height}, reference K = {}",
                scene.name,
                args.orbit.unwrap_or_default(),
                request.samples()
            ));
            let mut last = 0;
            let scratch = writer
                .scratch()
                .map(Path::to_path_buf)
                .unwrap_or_else(std::env::temp_dir);
            let motion =
                temporal::run_in(&mut offline, &scene, m, &drawn, &scratch, |frame, _| {
                    if frame != last {
                        bar.set(frame as u64);
                        last = frame;
                    }
                })?;
            bar.finish();
            if let Some(note) = &motion.note {
                errln!("note      {note}");
            }
            Some(motion)
        }
        None => None,
    };
    let (r, written) = writer
        .finish(&outline, motion.as_ref())
        .with_context(cannot_write)?;
    outln!(
        "{} ({}x{}, K = {}, reference {:.1} M rays/s on the {}, V(t) {})",
        r.scene,
        r.width,
        r.height,
        r.samples,
        r.reference_rays_per_s / 1e6,
        r.reference.to_uppercase(),
        r.vt
    );
    out!("{}", r.table());
    let temporal = r.temporal_table();
    if let (false, Some(m)) = (temporal.is_empty(), &r.motion) {
        outln!(
            "in motion ({} orbit, {} frames, reference K = {}):",
            m.orbit,
            m.frames,
            m.samples
        );
        out!("{temporal}");
    }
    let hard = r.hard_table();
    if !hard.is_empty() {
        outln!("against reference-hard (lit iff V >= 0.5):");
        out!("{hard}");
    }
    errln!(
        "wrote     {} files into {}",
        written.len(),
        args.out.display()
    );
    Ok(())
}

/// `--methods a,b,c`: each a method of the registry (an unknown name lists them) or a user's
/// file (`file:PATH.wgsl`, with the `--knob` settings of `flags`).
fn parse_methods(list: &str, flags: &MethodFlags) -> Result<Vec<Method>> {
    let methods = flags
        .methods(list.split(',').map(str::trim).filter(|m| !m.is_empty()))
        .context("--methods")?;
    if methods.is_empty() {
        anyhow::bail!("--methods expects a comma-separated list of methods, e.g. dbuffer,hard");
    }
    Ok(methods)
}
