//! `dbuffer compare SCENE --out DIR`: every method against the ray-cast reference; with
//! `--orbit light|camera`, also every method in motion round the orbit of `animate`.

use std::path::Path;

use anyhow::{Context, Result};
use dbuffer::compare::temporal::{self, MotionRequest};
use dbuffer::compare::{self, report, CompareRequest};
use dbuffer::geometry::VtVariant;
use dbuffer::output;
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::offline::Offline;
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
    let mut knobs = args.knobs.knobs()?;
    if orbit.is_some() && knobs.given(&SAMPLES).is_none() {
        // Every frame casts the reference: a modest K unless asked (one sample still below
        // the class threshold).
        knobs = knobs.with(&SAMPLES, temporal::DEFAULT_SAMPLES);
    }
    let motion_request = orbit.map(|orbit| MotionRequest {
        compare: CompareRequest {
            width,
            height,
            dbuffer_size: args.dbuffer_size,
            vt,
            knobs,
        },
        orbit: Some(orbit),
        frames: args.frames,
    });
    if let Some(m) = &motion_request {
        // Before any work: the budget of the whole orbit, with every method counted.
        m.validate(Method::all().len())
            .map_err(anyhow::Error::msg)?;
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
    offline.progress = Some(progress::reference_samples());
    let request = CompareRequest {
        width,
        height,
        dbuffer_size: args.dbuffer_size,
        vt,
        knobs,
    };
    let comparison = compare::run(&mut offline, &scene.name, &scene, &request, |what| {
        errln!("rendering {what}")
    })?;
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
            let motion = temporal::run(&mut offline, &scene, m, |frame, what| {
                if frame != last {
                    bar.set(frame as u64);
                    last = frame;
                }
                let _ = what;
            })?;
            bar.finish();
            if let Some(note) = &motion.note {
                errln!("note      {note}");
            }
            Some(motion)
        }
        None => None,
    };
    // The folder is made now, at the end, and taken away again if writing fails.
    let created = output::NewDirs::create(args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let written = report::write(args.out, &comparison, motion.as_ref()).map_err(|e| {
        created.remove_if_empty();
        anyhow::Error::new(e).context(format!(
            "cannot write the report into {}",
            args.out.display()
        ))
    })?;
    let r = match &motion {
        Some(m) => report::Report::with_motion(&comparison, m),
        None => report::Report::new(&comparison),
    };
    outln!(
        "{} ({}x{}, K = {}, reference {:.1} M rays/s, V(t) {})",
        r.scene,
        r.width,
        r.height,
        r.samples,
        r.reference_rays_per_s / 1e6,
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
