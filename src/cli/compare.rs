//! `dbuffer compare SCENE --out DIR`: every method against the ray-cast reference.

use std::path::Path;

use anyhow::{Context, Result};
use dbuffer::compare::{self, report, CompareRequest};
use dbuffer::geometry::VtVariant;
use dbuffer::output;
use dbuffer::render::offline::Offline;

use super::{check_dbuffer_size, parse_size, progress, MethodFlags};

/// The arguments of `dbuffer compare`, as typed.
pub struct CompareArgs<'a> {
    pub scene: &'a str,
    /// `--scene N`: which scene of a glTF model.
    pub gltf_scene: Option<usize>,
    pub out: &'a Path,
    pub size: &'a str,
    pub vt: &'a str,
    pub dbuffer_size: u32,
    pub knobs: &'a MethodFlags,
}

pub fn compare(args: &CompareArgs) -> Result<()> {
    let (width, height) = parse_size(args.size)?;
    let vt: VtVariant = args.vt.parse().map_err(anyhow::Error::msg)?;
    check_dbuffer_size(args.dbuffer_size)?;
    let knobs = args.knobs.knobs()?;
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
    // The folder is made now, at the end, and taken away again if writing fails.
    let created = output::NewDirs::create(args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let written = report::write(args.out, &comparison).map_err(|e| {
        created.remove_if_empty();
        anyhow::Error::new(e).context(format!(
            "cannot write the report into {}",
            args.out.display()
        ))
    })?;
    let r = report::Report::new(&comparison);
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
