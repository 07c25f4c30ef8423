//! `dbuffer animate SCENE --out DIR`: the light (or the camera) once around an orbit, as PNG
//! frames and one animated PNG of the loop ([`dbuffer::animation`], which the lab's Record
//! button uses too): the command parses, shows a progress bar and reports.

use std::path::Path;

use anyhow::Result;
use dbuffer::animation::{AnimationSpec, Recording, ANIMATION_FILE};
use dbuffer::geometry::VtVariant;
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, Method};
use dbuffer::scene::orbit::Orbit;

use super::progress::Progress;
use super::{check_dbuffer_size, parse_size, MethodFlags};

/// The arguments of `dbuffer animate`, as typed.
pub struct AnimateArgs<'a> {
    pub scene: &'a str,
    /// `--scene N`: which scene of a glTF model.
    pub gltf_scene: Option<usize>,
    pub out: &'a Path,
    pub frames: usize,
    pub orbit: &'a str,
    pub fps: u32,
    pub size: &'a str,
    /// `None`: the method made for the scene's light ([`Method::made_for`]).
    pub method: Option<&'a str>,
    pub vt: &'a str,
    pub dbuffer_size: u32,
    pub knobs: &'a MethodFlags,
}

pub fn animate(args: &AnimateArgs) -> Result<()> {
    let (width, height) = parse_size(args.size)?;
    let orbit: Orbit = args.orbit.parse().map_err(anyhow::Error::msg)?;
    let named = super::parse_method(args.method, args.knobs)?;
    let vt: VtVariant = args.vt.parse().map_err(anyhow::Error::msg)?;
    check_dbuffer_size(args.dbuffer_size)?;
    let mut spec = AnimationSpec {
        frames: args.frames,
        fps: args.fps,
        orbit,
        request: FrameRequest {
            width,
            height,
            dbuffer_size: args.dbuffer_size,
            method: named.unwrap_or_default(),
            vt,
            knobs: args.knobs.knobs()?,
            read_dbuffer: false,
            read_cost: false,
            colour_only: false,
        },
    };
    spec.validate()?;
    let scene = super::load_scene(args.scene, args.gltf_scene)?;
    let method = named.unwrap_or_else(|| Method::made_for(scene.light.kind()));
    // Before the GPU starts: a disk-only method under a line light (or the reverse) says why.
    if let Some(why) = method.refuses(scene.light.kind()) {
        anyhow::bail!("{why}");
    }
    spec.request.method = method;
    let name = scene.name.clone();
    let offline = Offline::new()?;
    super::chosen(&offline.ctx);
    if let Some(why) = method.refuses_on(&offline.ctx.caps) {
        anyhow::bail!("{why}");
    }
    // One session for the whole orbit: meshes uploaded and casters prepared once, only the
    // light-dependent work redone per frame.
    let mut recording = Recording::start(&offline.ctx, scene, spec, args.out)?;
    if let Some(note) = recording.note() {
        errln!("note      {note}");
    }
    let progress = Progress::new("animate", args.frames as u64, "frames");
    progress.stage(&format!(
        "{name}, the {} orbiting, {width}x{height}, {method}",
        args.orbit
    ));
    let mut warned: Vec<String> = Vec::new();
    while !recording.is_done() {
        for w in recording.step(&offline.ctx, &mut |_, _| {})? {
            if !warned.contains(&w) {
                progress.stage(&format!("warning: {w}"));
                warned.push(w);
            }
        }
        progress.set(recording.progress().0 as u64);
    }
    progress.finish();
    let written = recording.finish()?;
    errln!(
        "wrote     {} frames and {ANIMATION_FILE} ({} KiB, {:.1} s at {} fps) into {}",
        written.files.len() - 1,
        written.animation_bytes.div_ceil(1024),
        args.frames as f64 / f64::from(args.fps),
        args.fps,
        args.out.display()
    );
    Ok(())
}
