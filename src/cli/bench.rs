//! `dbuffer bench`: runs [`dbuffer::bench`], prints the markdown tables and writes `bench.json`,
//! `bench.md` and `geometry-scaling.png` into the output folder.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use dbuffer::bench::{self, Config};
use dbuffer::fsutil::write_atomic;
use dbuffer::render::GpuContext;

/// The arguments of `dbuffer bench`, as typed.
pub struct BenchArgs<'a> {
    pub quick: bool,
    pub out: &'a Path,
    pub frames: Option<usize>,
    pub warmup: Option<usize>,
    pub scenes: Option<&'a str>,
    pub sizes: Option<&'a str>,
    pub max_triangles: Option<u32>,
    pub methods: Option<&'a str>,
}

/// The names of a comma-separated list, trimmed, empty ones left out.
fn items(list: &str) -> impl Iterator<Item = &str> {
    list.split(',').map(str::trim).filter(|s| !s.is_empty())
}

/// The run the flags ask for: `--quick` or the full one, then the overrides.
pub fn config(args: &BenchArgs) -> Result<Config> {
    let mut config = if args.quick {
        Config::quick()
    } else {
        Config::full()
    };
    if let Some(n) = args.frames {
        if n == 0 {
            bail!("--frames expects at least 1 timed frame");
        }
        config.frames = n;
    }
    if let Some(n) = args.warmup {
        config.warmup = n;
    }
    if let Some(list) = args.scenes {
        config.scenes = items(list).map(str::to_string).collect();
        if config.scenes.is_empty() {
            bail!("--scenes expects a comma-separated list of scene names, e.g. table1-224,table1-960");
        }
    }
    if let Some(list) = args.sizes {
        config.sizes = list
            .split(',')
            .map(|s| {
                s.trim().parse::<u32>().map_err(|_| {
                    anyhow::anyhow!(
                        "--sizes expects comma-separated square image sizes in pixels, e.g. 300,600,1024; found '{s}'"
                    )
                })
            })
            .collect::<Result<_>>()?;
    }
    if let Some(max) = args.max_triangles {
        config.scaling.retain(|&t| t <= max);
        if config.scaling.is_empty() {
            config.scaling.push(max);
        }
    }
    if let Some(list) = args.methods {
        let wanted = items(list)
            .map(|s| {
                s.parse::<dbuffer::render::Method>()
                    .map_err(anyhow::Error::msg)
            })
            .collect::<Result<Vec<_>>>()
            .context("--methods")?;
        if wanted.is_empty() {
            bail!("--methods expects a comma-separated list of methods, e.g. dbuffer,hard");
        }
        config.cases.retain(|c| wanted.contains(&c.method));
        // A user's method (`file:PATH.wgsl`) is on no list of cases: timed at its defaults.
        for &m in &wanted {
            if !config.cases.iter().any(|c| c.method == m) {
                config.cases.push(dbuffer::bench::Case::for_method(m));
            }
        }
    }
    config.validate()?;
    Ok(config)
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let config = config(args)?;
    let loaded = bench::load_scenes(&config)?;
    let ctx = GpuContext::headless()?;
    super::chosen(&ctx);
    errln!(
        "bench on {}: {} scenes × {} sizes × {} cases (every method, and the D-buffer under a \
         16-gon), {} + {} frames each; about {:.0} s",
        ctx.adapter_description(),
        config.scenes.len(),
        config.sizes.len(),
        config.cases.len(),
        config.warmup,
        config.frames,
        config.estimate_s()
    );
    for case in &config.cases {
        if let Some(why) = case.method.refuses_on(&ctx.caps) {
            errln!("skipped   {why}");
        }
    }
    // One step per report of bench::run: each scene's geometry, each (scene, size), the
    // coherence run, each point of the scaling curve.
    let steps = config.scenes.len() * (1 + config.sizes.len())
        + usize::from(config.coherence)
        + config.scaling.len();
    let bar = super::progress::Progress::new("bench", steps as u64, "steps");
    let mut done = 0u64;
    let mut progress = |line: &str| {
        bar.set(done);
        bar.stage(line);
        done += 1;
    };
    let report = bench::run(&ctx, &config, loaded, &mut progress)?;
    bar.set(steps as u64);
    bar.finish();
    // A case that failed is "n/a (error)" in the tables: its error here, as lines (the
    // refusals were said above, as "skipped").
    let refusals: Vec<String> = config
        .cases
        .iter()
        .filter_map(|c| c.method.refuses_on(&ctx.caps))
        .collect();
    let mut said: Vec<&str> = Vec::new();
    for run in &report.runs {
        let Some(e) = run.error.as_deref() else {
            continue;
        };
        if refusals.iter().any(|r| r == e) || said.contains(&e) {
            continue;
        }
        said.push(e);
        errln!(
            "error     {} on {} at {}²: {}",
            run.label,
            run.scene,
            run.size,
            super::adapters::gpu_lines(e).trim_end()
        );
    }
    let markdown = bench::table::markdown(&report);

    std::fs::create_dir_all(args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let json = serde_json::to_vec_pretty(&report).context("encoding bench.json")?;
    let mut written: Vec<PathBuf> = Vec::new();
    let mut write = |name: &str, bytes: &[u8]| -> Result<()> {
        let path = args.out.join(name);
        write_atomic(&path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
        written.push(path);
        Ok(())
    };
    write("bench.json", &json)?;
    write("bench.md", markdown.as_bytes())?;
    if !report.scaling.is_empty() {
        let png = bench::plot::scaling_png(&report.scaling, 900, 600)?;
        write("geometry-scaling.png", &png)?;
    }
    outln!("{markdown}");
    for path in written {
        errln!("wrote  {}", path.display());
    }
    Ok(())
}
