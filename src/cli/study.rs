//! `dbuffer study [STUDY.toml] --out DIR`: runs [`dbuffer::study`] with a progress bar and an
//! ETA, then writes `study.json`, `study.md` and the plots into DIR (its cache too, so the same
//! command resumes a stopped run).

use std::path::Path;

use anyhow::{Context, Result};
use dbuffer::render::GpuContext;
use dbuffer::study::{self, Flow, Progress, StudySpec};

/// The arguments of `dbuffer study`, as typed.
pub struct StudyArgs<'a> {
    pub file: Option<&'a Path>,
    pub out: &'a Path,
    pub quick: bool,
    pub scenes: Option<&'a str>,
    pub methods: Option<&'a str>,
    pub size: Option<&'a str>,
    /// `--knob NAME=VALUE`: the knobs of a user's method among `methods`.
    pub knobs: &'a [String],
}

fn items(list: &str) -> Vec<String> {
    list.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect()
}

/// The study the file and flags ask for, checked (keys, ranges, budget, scenes) before any work.
pub fn spec(args: &StudyArgs) -> Result<(StudySpec, Vec<dbuffer::scene::Scene>)> {
    let base = if args.quick {
        StudySpec::quick()
    } else {
        StudySpec::full()
    };
    let mut spec = match args.file {
        Some(path) => StudySpec::from_file(path, base)?,
        None => base,
    };
    // A user's method (file:PATH.wgsl) is loaded with the --knob settings, as render takes it.
    let flags = super::MethodFlags {
        user: args.knobs.to_vec(),
        ..super::MethodFlags::default()
    };
    let methods = match args.methods {
        Some(list) => Some(
            flags
                .methods(items(list).iter().map(String::as_str))
                .context("--methods")?,
        ),
        None => {
            if let Some(k) = args.knobs.first() {
                anyhow::bail!(
                    "--knob {k}: --knob sets the knobs of a user's method, and --methods names \
                     no file:PATH.wgsl"
                );
            }
            None
        }
    };
    let size = args.size.map(super::parse_size).transpose()?;
    spec.narrow(args.scenes.map(items), methods, size)?;
    spec.check_budget()?;
    super::check_dbuffer_size(spec.dbuffer_size)?;
    let scenes = spec
        .scenes
        .iter()
        .enumerate()
        .map(|(i, name)| {
            super::load_scene(name, None).with_context(|| format!("scene {} of the study", i + 1))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((spec, scenes))
}

pub fn run(args: &StudyArgs) -> Result<()> {
    let (spec, scenes) = spec(args)?;
    let ctx = GpuContext::headless()?;
    super::chosen(&ctx);
    errln!(
        "study on {}: {} scenes × {} cells, {}×{}, K = {}, {} + {} frames a cell",
        ctx.adapter_description(),
        scenes.len(),
        spec.cell_count() / scenes.len().max(1) as u64,
        spec.width,
        spec.height,
        spec.samples,
        spec.warmup,
        spec.frames
    );
    std::fs::create_dir_all(args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let per_scene: u64 = spec.methods.iter().map(|m| m.settings.len() as u64).sum();
    let total = scenes.len() as u64 * (1 + 2 * per_scene);
    let bar = super::progress::Progress::new("study", total, "measurements");
    let mut report = |p: Progress<'_>| {
        match p {
            Progress::Stage { scene, stage } => bar.stage(&format!("{scene}: {stage}")),
            Progress::Done { done, .. } => bar.set(done as u64),
        }
        Flow::Go
    };
    let study = study::run(&ctx, &spec, &scenes, args.out, &mut report)?;
    bar.set(total);
    bar.finish();
    let written = study::report::write(&study, args.out).map_err(anyhow::Error::msg)?;
    errln!(
        "{} cells measured, {} from the cache, in {:.0} s",
        study.measured,
        study.cached,
        study.seconds
    );
    for path in written {
        errln!("wrote  {}", path.display());
    }
    Ok(())
}
