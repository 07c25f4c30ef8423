//! `dbuffer compare SCENE --out DIR`: every method against the ray-cast reference.

use std::path::Path;

use anyhow::{Context, Result};
use dbuffer::compare::{self, report, CompareRequest};
use dbuffer::geometry::VtVariant;
use dbuffer::render::offline::Offline;
use dbuffer::scene;

use super::{check_dbuffer_size, parse_size, progress, MethodFlags};

/// The arguments of `dbuffer compare`, as typed.
pub struct CompareArgs<'a> {
    pub scene: &'a str,
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
    let scene =
        scene::load(args.scene).with_context(|| format!("cannot load scene '{}'", args.scene))?;
    let mut offline = Offline::new()?;
    eprintln!("adapter   {}", offline.ctx.adapter_description());
    offline.progress = Some(progress::reference_samples());
    let request = CompareRequest {
        width,
        height,
        dbuffer_size: args.dbuffer_size,
        vt,
        knobs,
    };
    let comparison = compare::run(&mut offline, &scene.name, &scene, &request, |what| {
        eprintln!("rendering {what}")
    })?;
    let written = report::write(args.out, &comparison)
        .with_context(|| format!("cannot write the report into {}", args.out.display()))?;
    let r = report::Report::new(&comparison);
    println!(
        "{} ({}x{}, K = {}, reference {:.1} M rays/s, V(t) {})",
        r.scene,
        r.width,
        r.height,
        r.samples,
        r.reference_rays_per_s / 1e6,
        r.vt
    );
    print!("{}", r.table());
    let hard = r.hard_table();
    if !hard.is_empty() {
        println!("against reference-hard (lit iff V >= 0.5):");
        print!("{hard}");
    }
    eprintln!(
        "wrote     {} files into {}",
        written.len(),
        args.out.display()
    );
    Ok(())
}
