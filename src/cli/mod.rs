//! The subcommands. Each one loads through [`dbuffer::scene`] and computes through the same
//! library code the GUI uses; nothing here renders or computes on its own.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use dbuffer::budget::{
    MAX_DBUFFER_SIZE, MAX_IMAGE_PIXELS, MAX_INSPECT_PIXELS, MAX_ORACLE_TRIANGLES,
    MAX_REFERENCE_SAMPLES,
};
use dbuffer::geometry::fused::{FusedParams, FusedPath, FusedTwin};
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{metrics, view, DBufferTwin, PreparedCasters, VolumeParams, VtVariant};
use dbuffer::output;
use dbuffer::render::methods::{all_knobs, user, KnobKind};
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, Knobs, Method};
use dbuffer::scene;
use glam::Vec3;
use rayon::prelude::*;

/// `println!` that survives a closed standard output (see [`print`]).
macro_rules! outln {
    () => {
        crate::cli::print::out(format_args!("\n"))
    };
    ($($t:tt)*) => {
        crate::cli::print::out(format_args!("{}\n", format_args!($($t)*)))
    };
}

/// `print!` that survives a closed standard output.
macro_rules! out {
    ($($t:tt)*) => {
        crate::cli::print::out(format_args!($($t)*))
    };
}

/// `eprintln!` that never panics.
macro_rules! errln {
    () => {
        crate::cli::print::err(format_args!("\n"))
    };
    ($($t:tt)*) => {
        crate::cli::print::err(format_args!("{}\n", format_args!($($t)*)))
    };
}

pub mod adapters;
mod animate;
pub mod bench;
mod compare;
pub mod print;
mod progress;
pub mod study;
pub use adapters::{chosen, error_lines, set_verbose};
pub use animate::{animate, AnimateArgs};
pub use compare::{compare, CompareArgs};

/// The knobs of every method of the registry, as flags of `render` and `compare`
/// (`--pcf-radius`, `--lights`, …): each method's module declares its own.
#[derive(Clone, Debug, Default)]
pub struct MethodFlags {
    /// The knobs given on the command line, not yet checked against their ranges.
    pub given: Knobs,
    /// `--knob NAME=VALUE`: a user's method's knobs (`--method file:PATH.wgsl`), checked when
    /// its file is loaded.
    pub user: Vec<String>,
}

impl clap::FromArgMatches for MethodFlags {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Knobs::default();
        for &k in all_knobs() {
            if let Some(&v) = m.get_one::<u32>(k.name) {
                given = given.with(k, v);
            }
        }
        let user = m
            .get_many::<String>(USER_KNOB)
            .map(|v| v.cloned().collect())
            .unwrap_or_default();
        Ok(MethodFlags { given, user })
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for MethodFlags {
    fn augment_args(mut cmd: clap::Command) -> clap::Command {
        cmd = cmd.arg(
            clap::Arg::new(USER_KNOB)
                .long(USER_KNOB)
                .value_name("NAME=VALUE")
                .action(clap::ArgAction::Append)
                .help(
                    "A knob of a user's method (--method file:PATH.wgsl), as its file's header \
                     declares it (`// knob: NAME MIN..MAX = DEFAULT`); repeatable",
                ),
        );
        for k in all_knobs() {
            let (min, max) = k.range();
            // Every kind takes the whole number it is kept as; a switch also takes true/false,
            // a choice its options' names.
            let parser = match k.kind {
                KnobKind::Switch => clap::builder::ValueParser::new(parse_switch),
                KnobKind::Choice { choices } => {
                    clap::builder::ValueParser::new(move |text: &str| parse_choice(choices, text))
                }
                _ => clap::value_parser!(u32).into(),
            };
            cmd = cmd.arg(
                clap::Arg::new(k.name)
                    .long(k.name)
                    .value_name("N")
                    .value_parser(parser)
                    .help(format!(
                        "{}, {min} to {max} (default {})",
                        k.help, k.default
                    )),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

/// The flag of a user's method's knobs.
const USER_KNOB: &str = "knob";

/// An on/off knob's value: a whole number (checked against 0 to 1 with the others), `true` or
/// `false`.
/// A choice's value: its number, or the name of one of its options.
fn parse_choice(choices: &[&str], text: &str) -> Result<u32, String> {
    match choices.iter().position(|c| *c == text) {
        Some(i) => Ok(i as u32),
        None => text.parse().map_err(|_| {
            format!(
                "expected {} (or its number from 0), found '{text}'",
                choices.join(", ")
            )
        }),
    }
}

fn parse_switch(text: &str) -> Result<u32, std::num::ParseIntError> {
    match text {
        "true" => Ok(1),
        "false" => Ok(0),
        _ => text.parse(),
    }
}

impl MethodFlags {
    /// The methods `--method` or `--methods` named, `names`: a user's file loaded with the
    /// `--knob` settings; `--knob` without a user's method among them is refused.
    pub fn methods<'a>(&self, names: impl IntoIterator<Item = &'a str>) -> Result<Vec<Method>> {
        let methods = names
            .into_iter()
            .map(|n| match user::path_of(n) {
                // A shader's error whole: the command line prints its offending line too.
                Some(path) => user::load_checked(path, &self.user).map_err(|e| match e {
                    user::LoadError::Shader(e) => anyhow::Error::new(e),
                    user::LoadError::Other(e) => anyhow::Error::msg(e),
                }),
                None => Method::parse_with(n, &self.user).map_err(anyhow::Error::msg),
            })
            .collect::<Result<Vec<_>>>()?;
        if let (Some(k), false) = (self.user.first(), methods.iter().any(|m| m.is_user())) {
            bail!(
                "--knob {k}: --knob sets the knobs of a user's method, and no --method \
                 file:PATH.wgsl is named"
            );
        }
        Ok(methods)
    }

    /// The knobs, each checked against its range (the message names the flag).
    pub fn knobs(&self) -> Result<Knobs> {
        self.given.validate().map_err(anyhow::Error::msg)?;
        Ok(self.given)
    }
}

pub fn scenes() -> Result<()> {
    for name in scene::builtin::names() {
        outln!("{name}");
    }
    Ok(())
}

/// The arguments of `dbuffer render`, as typed.
pub struct RenderArgs<'a> {
    pub scene: &'a str,
    /// `--scene N`: which scene of a glTF model.
    pub gltf_scene: Option<usize>,
    pub out: &'a Path,
    pub size: &'a str,
    /// `None`: the method made for the scene's light ([`Method::made_for`]).
    pub method: Option<&'a str>,
    pub vt: &'a str,
    pub dbuffer_size: u32,
    pub knobs: &'a MethodFlags,
    pub verbose: bool,
}

/// The scene SCENE names (with `--scene N` for a glTF model); the model's notes (an extension
/// ignored, a skin in its bind pose) go to stderr as warnings, one line each.
pub(crate) fn load_scene(name: &str, gltf_scene: Option<usize>) -> Result<scene::Scene> {
    let loaded = scene::load_with(name, scene::LoadOptions { gltf_scene })
        .with_context(|| format!("cannot load scene '{name}'"))?;
    for note in &loaded.notes {
        errln!("warning   {note}");
    }
    Ok(loaded.scene)
}

/// `--method` if given (an unknown name lists the methods; a user's file is loaded with the
/// `--knob` settings of `flags`).
pub(crate) fn parse_method(name: Option<&str>, flags: &MethodFlags) -> Result<Option<Method>> {
    Ok(flags.methods(name)?.first().copied())
}

pub fn render(args: &RenderArgs) -> Result<()> {
    let (width, height) = parse_size(args.size)?;
    let named = parse_method(args.method, args.knobs)?;
    let vt: VtVariant = args.vt.parse().map_err(anyhow::Error::msg)?;
    check_dbuffer_size(args.dbuffer_size)?;
    let knobs = args.knobs.knobs()?;
    // Before any work: a render that cannot be written is not started.
    output::check_out_dir(args.out, &output::FILE_NAMES).context("--out")?;
    let scene = load_scene(args.scene, args.gltf_scene)?;
    let method = named.unwrap_or_else(|| Method::made_for(scene.light.kind()));
    // Before the GPU starts: a disk-only method under a line light (or the reverse) says why.
    if let Some(why) = method.refuses(scene.light.kind()) {
        bail!("{why}");
    }
    let offline = Offline::new()?;
    chosen(&offline.ctx);
    // Before any work: a device that lacks what the method needs says what, in one line.
    if let Some(why) = method.refuses_on(&offline.ctx.caps) {
        bail!("{why}");
    }
    let request = FrameRequest {
        width,
        height,
        dbuffer_size: args.dbuffer_size,
        method,
        vt,
        knobs,
        read_dbuffer: true,
        read_cost: false,
        colour_only: false,
    };
    let name = scene.name.clone();
    let mut session = offline.session(scene);
    // The frame without its light-space maps: the D-buffer goes to its files a band of rows
    // at a time, straight from the GPU (an 8192² D-buffer is 1.3 GB of floats).
    let mut reference_progress = progress::reference_samples();
    let (frame, report) = dbuffer::render::offline::render_in(
        &offline.ctx,
        &mut session,
        &FrameRequest {
            read_dbuffer: false,
            ..request
        },
        &mut *reference_progress,
    )?;
    let maps_of = session.prepare_maps(&offline.ctx, &request)?;
    let maps_size = session.light_maps(maps_of).map_or(0, |m| m.size);
    let mut meta = output::render_meta(
        &name,
        session.scene(),
        &request,
        &offline.ctx,
        &frame,
        &report,
    );
    meta.dbuffer_size = maps_size;
    for w in &meta.warnings {
        errln!("warning   {w}");
    }
    if args.verbose {
        for (stage, ms) in &meta.cpu_ms {
            errln!("cpu ms    {stage:<20} {ms:8.3}");
        }
        for (pass, ms) in &meta.gpu_ms {
            errln!("gpu ms    {pass:<20} {ms:8.3}");
        }
    }
    let ctx = &offline.ctx;
    // Bands of about 16 MB of texels.
    let band = ((16 << 20) / (20 * maps_size.max(1))).max(1);
    let mut dbuffer = output::BandedRows::new(maps_size, band, |first, n| {
        session
            .read_map_rows(ctx, maps_of, first..first + n)
            .map(|band| output::dbuffer_texels(&band))
            .map_err(|e| e.to_string())
    });
    let written =
        output::write_render_parts(args.out, &meta, &output::FramePixels(&frame), &mut dbuffer)?;
    if args.verbose {
        for path in written {
            errln!("wrote     {}", path.display());
        }
    }
    Ok(())
}

/// The lab window. `DBUFFER_SMOKE_SCREENSHOT=shot.png` makes it screenshot itself once frames
/// show and exit (the scripted smoke run under Xvfb).
/// `dbuffer gui`'s flags.
pub struct GuiArgs {
    pub gltf_scene: Option<usize>,
    pub bench: Option<u32>,
    pub bench_out: Option<std::path::PathBuf>,
    pub study: Option<std::path::PathBuf>,
    pub shaders: Option<std::path::PathBuf>,
    pub geometry: Option<String>,
}

pub fn gui(scene: Option<String>, args: GuiArgs, verbose: bool) -> Result<()> {
    let GuiArgs {
        gltf_scene,
        bench,
        bench_out,
        study,
        shaders,
        geometry,
    } = args;
    let shaders = shaders
        .as_deref()
        .map(dbuffer::app::check_shader_dir)
        .transpose()
        .map_err(anyhow::Error::msg)?;
    let geometry = match geometry.as_deref() {
        None => None,
        Some(text) => {
            let choices = match dbuffer::render::methods::dbuffer::GEOMETRY.0.kind {
                KnobKind::Choice { choices } => choices,
                _ => &[],
            };
            Some(parse_choice(choices, text).map_err(|e| anyhow::anyhow!("--geometry: {e}"))?)
        }
    };
    if let Some(dir) = &study {
        let json = dir.join("study.json");
        if !json.is_file() {
            bail!(
                "--study {}: no study.json there (write one with `dbuffer study --out {}`)",
                dir.display(),
                dir.display()
            );
        }
    }
    if let Some(n) = bench {
        if !(2..=10_000).contains(&n) {
            bail!("--bench expects a frame count from 2 to 10000, found {n}");
        }
    }
    let smoke_screenshot = std::env::var_os("DBUFFER_SMOKE_SCREENSHOT").map(Into::into);
    dbuffer::app::run(dbuffer::app::LabOptions {
        scene,
        gltf_scene,
        fresh_settings: smoke_screenshot.is_some() || bench.is_some(),
        window_bench: bench,
        window_bench_out: bench_out,
        smoke_screenshot,
        verbose,
        study,
        shaders,
        geometry,
        ..Default::default()
    })
}

fn check_dbuffer_size(size: u32) -> Result<()> {
    if !(1..=MAX_DBUFFER_SIZE).contains(&size) {
        bail!(
            "--dbuffer-size expects a texel count from 1 to {MAX_DBUFFER_SIZE} \
             (MAX_DBUFFER_SIZE), found {size}"
        );
    }
    Ok(())
}

/// Whose CPU twin `inspect` compares with the reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TwinMethod {
    DBuffer,
    Fused,
}

impl TwinMethod {
    /// Every one, with the registry's method it is the twin of.
    const ALL: [(TwinMethod, Method); 2] = [
        (TwinMethod::DBuffer, Method::DBUFFER),
        (TwinMethod::Fused, Method::DBUFFER_FUSED),
    ];

    fn parse(text: &str) -> Result<TwinMethod> {
        match TwinMethod::ALL.iter().find(|(_, m)| m.name() == text) {
            Some(&(twin, _)) => Ok(twin),
            None => bail!(
                "--method for inspect expects {} or {} (the methods with a CPU twin), found \
                 '{text}'",
                Method::DBUFFER,
                Method::DBUFFER_FUSED
            ),
        }
    }

    fn method(self) -> Method {
        match self {
            TwinMethod::DBuffer => Method::DBUFFER,
            TwinMethod::Fused => Method::DBUFFER_FUSED,
        }
    }
}

pub fn inspect(
    name: &str,
    gltf_scene: Option<usize>,
    samples: Option<usize>,
    (size, vt, method): (&str, &str, &str),
    out: Option<&Path>,
    geometry_path: &str,
) -> Result<()> {
    let method = TwinMethod::parse(method)?;
    let on_gpu = match geometry_path {
        "cpu" => None,
        "gpu" => Some(true),
        "auto" => Some(false),
        other => bail!("--geometry expects auto, cpu or gpu, found '{other}'"),
    };
    // Every flag is checked before the scene is loaded: nothing is computed for a run that
    // would be refused at the end.
    let comparison = match samples {
        Some(k) => {
            if !(1..=MAX_REFERENCE_SAMPLES as usize).contains(&k) {
                bail!(
                    "--samples expects 1 to {MAX_REFERENCE_SAMPLES} disk samples per pixel \
                     (MAX_REFERENCE_SAMPLES), found {k}"
                );
            }
            let (width, height) = parse_view_size(size, MAX_INSPECT_PIXELS, "MAX_INSPECT_PIXELS")?;
            let vt: VtVariant = vt.parse().map_err(anyhow::Error::msg)?;
            if let Some(path) = out {
                output::check_out_file(path).context("--out")?;
            }
            Some((k, width, height, vt))
        }
        None if out.is_some() => {
            bail!("--out needs --samples: the picture compares the method with the reference")
        }
        None => None,
    };
    let scene = load_scene(name, gltf_scene)?;
    let triangles: usize = scene.objects.iter().map(|o| o.mesh.triangles.len()).sum();
    if comparison.is_some() && triangles as u64 > MAX_ORACLE_TRIANGLES {
        bail!(
            "--samples: the scene has {triangles} triangles, more than the CPU reference \
             ray-casts ({MAX_ORACLE_TRIANGLES}, MAX_ORACLE_TRIANGLES); inspect it without \
             --samples, or compare it on the GPU with `dbuffer compare`"
        );
    }
    let Some(&l) = scene.light.as_area() else {
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
    // The counts from the GPU stage where it runs (the fill and the twin read the CPU's).
    let gpu_counts = match on_gpu {
        None => None,
        Some(required) => gpu_stage_counts(&scene, &prepared, &l, &params, required)?,
    };
    // The paper's twin needs the geometry, not the prepared casters (welding and adjacency):
    // give their memory back before the oracle builds its BVH. dbuffer-fused's twin reads the
    // caster edges from them.
    let prepared = (method == TwinMethod::Fused).then_some(prepared);

    outln!("scene     {}", scene.name);
    outln!(
        "light     centre {} normal {} radius {}",
        l.center,
        l.normal,
        l.radius
    );
    outln!(
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
    let counted = gpu_counts.as_ref().map_or(&geometry, |(g, _, _)| g);
    for c in &counted.casters {
        let s = c.stats;
        outln!(
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
    outln!("geometry  prepare {prepare_ms:.3} ms (once per mesh), classes+silhouettes+volumes {build_ms:.3} ms");
    if let Some((g, adapter, ms)) = &gpu_counts {
        outln!(
            "geometry  counts above from the GPU stage on {adapter} ({ms:.3} ms with its readback)"
        );
        for w in g.warnings.iter().filter(|w| !geometry.warnings.contains(w)) {
            outln!("warning   {w}");
        }
    }
    print_volume_fill(&scene, &geometry, &l);
    for w in &geometry.warnings {
        outln!("warning   {w}");
    }

    if let Some((k, width, height, vt)) = comparison {
        let frames = compare_twin(
            &scene,
            prepared.as_ref(),
            &geometry,
            k,
            (width, height),
            vt,
            method,
        );
        if let Some(path) = out {
            write_comparison(path, &frames, width, height)?;
            outln!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// The GPU geometry stage's counts for `inspect`, its adapter and its milliseconds: `None` where
/// no adapter can run it and it was not `required` (`--geometry auto`), an error where it was.
fn gpu_stage_counts(
    scene: &scene::Scene,
    prepared: &PreparedCasters,
    light: &scene::AreaLight,
    params: &VolumeParams,
    required: bool,
) -> Result<Option<(dbuffer::geometry::SceneGeometry, String, f64)>> {
    use dbuffer::render::methods::dbuffer::{gpu_geometry_by_default, gpu_geometry_runs};
    use dbuffer::render::passes::geometry_gpu::GpuGeometry;
    let ctx = match dbuffer::render::GpuContext::headless() {
        Ok(ctx) => ctx,
        Err(e) if required => bail!("--geometry gpu: {e}"),
        Err(_) => return Ok(None),
    };
    let runs = if required {
        gpu_geometry_runs(&ctx.caps)
    } else {
        gpu_geometry_by_default(&ctx.caps, scene.caster_triangle_count())
    };
    if !runs {
        if required {
            bail!(
                "--geometry gpu: {} has no compute shaders, indirect draws or storage buffers \
                 enough for the GPU geometry stage",
                ctx.caps.adapter
            );
        }
        return Ok(None);
    }
    let reach = dbuffer::geometry::volume_vertices::reach_below(light, scene.bounds());
    let t = Instant::now();
    let g = GpuGeometry::run_once(&ctx, prepared, light, params, Some(reach))
        .map_err(|e| anyhow::anyhow!("--geometry gpu: {e}"))?;
    Ok(Some((
        g,
        ctx.caps.adapter.clone(),
        t.elapsed().as_secs_f64() * 1e3,
    )))
}

/// What the D-buffer's volumes cost the rasteriser of a light map: fragments per texel, every
/// triangle over its whole footprint before the depth test, as the light pass draws them (ended
/// where no receiver lies beyond) and whole (to the extrusion's far end).
fn print_volume_fill(
    scene: &scene::Scene,
    geometry: &dbuffer::geometry::SceneGeometry,
    l: &scene::AreaLight,
) {
    use dbuffer::geometry::light_view::LightView;
    use dbuffer::geometry::volume_vertices::{drawn_volumes, footprint_texels, reach_below};
    let view = LightView::fit(scene);
    // The light map the D-buffer is drawn at by default (`--dbuffer-size`).
    let size = FrameRequest::default().dbuffer_size;
    let texels = f64::from(size) * f64::from(size);
    let fill = |reach| {
        let d = drawn_volumes(geometry, l, &view, reach);
        let umbra: f64 = d
            .umbrae
            .iter()
            .map(|(u, _)| footprint_texels(u, &view, size))
            .sum();
        (
            umbra / texels,
            footprint_texels(&d.penumbra, &view, size) / texels,
        )
    };
    let (umbra, penumbra) = fill(Some(reach_below(l, scene.bounds())));
    let (umbra_whole, penumbra_whole) = fill(None);
    outln!(
        "fill      volume fragments per texel of a {size}² light map (footprints, before the \
         depth test): umbra {umbra:.3}, penumbra {penumbra:.3} as drawn (ended below the \
         lowest receiver); {umbra_whole:.3} and {penumbra_whole:.3} whole"
    );
}

/// `WxH` of a rendered image: both from 1 to `MAX_IMAGE_SIDE`, at most `MAX_IMAGE_PIXELS`.
pub fn parse_size(text: &str) -> Result<(u32, u32)> {
    parse_view_size(text, MAX_IMAGE_PIXELS, "MAX_IMAGE_PIXELS")
}

/// `WxH` with both from 1 to `MAX_IMAGE_SIDE` and at most `max_pixels` (called `name`).
fn parse_view_size(text: &str, max_pixels: u64, name: &str) -> Result<(u32, u32)> {
    let Some((w, h)) = dbuffer::budget::parse_wxh(text) else {
        bail!("--size expects WxH with positive integers, e.g. 512x512; found '{text}'");
    };
    if let Err(why) = dbuffer::budget::check_image_size(w, h, max_pixels, name) {
        bail!("--size {why}");
    }
    Ok((w, h))
}

/// Per pixel of the view: the method's V, the reference V, and whether it counts.
struct Frames {
    method: Vec<f32>,
    reference: Vec<f32>,
    mask: Vec<bool>,
}

/// The CPU twin of the method against the oracle over the camera's view (the metrics of docs/method/metrics.md.
fn compare_twin(
    scene: &scene::Scene,
    prepared: Option<&PreparedCasters>,
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
            let fused = prepared.map(|p| FusedTwin::new(scene, p, geometry, params));
            (None, fused)
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
        .zip(&pixels)
        .map(|((&x, &on), r)| match (on, &paper, &fused) {
            (false, _, _) => (0.0, None),
            (true, Some(t), _) => (
                r.map_or(0.0, |r| t.visibility_on(x, r.normal, vt) as f32),
                None,
            ),
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
    let name = method.method();
    outln!(
        "twin ({name}) vs oracle ({width}x{height}, {} px facing the light, V(t) {vt}, K = {k}):",
        m.pixels
    );
    outln!(
        "  class mismatch {:.2} %   MAE {:.4}   penumbra MAE {:.4} ({} px)   p99 |dV| {:.3}",
        m.class_mismatch_pct,
        m.mae,
        m.penumbra_mae,
        m.penumbra_pixels,
        m.p99
    );
    outln!("  pixels by class, reference (rows) against the twin (columns):");
    outln!("  {:>10} {:>9} {:>9} {:>9}", "", "lit", "penumbra", "umbra");
    for rc in metrics::ShadowClass::ALL {
        let row = m.confusion[rc.index()];
        outln!(
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
        outln!(
            "  edge lists: {} px read one (mean {mean:.1} edges, longest {longest}); {overflow} px \
             overflowed theirs and walked every candidate edge (dbuffer's V past {} candidates)",
            lists.len(),
            dbuffer::geometry::fused::WHOLE_WALK_EDGES
        );
    }
    outln!(
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
