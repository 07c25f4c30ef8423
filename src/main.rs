//! `dbuffer`: the lab's command line. Thin: parsing and printing; the work is in the library.

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

mod cli;

/// A lab for boundary-correct real-time soft shadows from a disk light
/// (the D-buffer of Jakobsen et al., CGI 2004).
#[derive(Parser)]
#[command(name = env!("CARGO_BIN_NAME"), version, about, long_about = None)]
struct Args {
    #[command(subcommand)]
    command: Option<Command>,
    /// The GPU backend: vulkan, gl, metal or dx12 (default: WGPU_BACKEND, else every backend
    /// wgpu has; `dbuffer adapters` lists what each sees).
    #[arg(long, global = true, value_name = "BACKEND")]
    backend: Option<String>,
    /// Say which adapter was chosen and why (and, for render, the timings and files).
    #[arg(short, long, global = true)]
    verbose: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Open the lab on a built-in name, a .toml scene file, an .obj mesh or a .gltf/.glb model.
    Gui {
        scene: Option<String>,
        /// Which scene of a glTF model to draw (default: the model's default scene, else its
        /// first).
        #[arg(long = "scene", value_name = "N")]
        gltf_scene: Option<usize>,
        /// Time the window itself and exit: N frames each of an empty viewport (egui's floor),
        /// the last image shown, a camera orbit and a moving light; prints window fps, CPU and
        /// GPU per frame (2 to 10000; under Xvfb where there is no display:
        /// scripts/window-bench.sh).
        #[arg(long, value_name = "N")]
        bench: Option<u32>,
        /// With --bench: also write the numbers to this JSON file.
        #[arg(long, value_name = "FILE", requires = "bench")]
        bench_out: Option<std::path::PathBuf>,
        /// Where the D-buffer's geometry stage runs: auto, cpu or gpu (the lab's `geometry`
        /// setting; default: the saved one).
        #[arg(long)]
        geometry: Option<String>,
        /// Show the plot of a study (a `dbuffer study --out DIR` folder) for the open scene;
        /// clicking a point shows that method and setting.
        #[arg(long, value_name = "DIR")]
        study: Option<std::path::PathBuf>,
        /// Read the shaders from this folder (a copy of shaders/, or only the files you change)
        /// and reload them whenever a file in it is saved: a broken one is shown over the
        /// viewport, and the last good shaders keep drawing.
        #[arg(long, value_name = "DIR")]
        shaders: Option<std::path::PathBuf>,
    },
    /// Render a scene headless into DIR (image.png, visibility.exr, ...).
    Render {
        /// A built-in scene name, a .toml scene file, an .obj mesh or a .gltf/.glb model.
        scene: String,
        /// Which scene of a glTF model to draw (default: the model's default scene, else its
        /// first).
        #[arg(long = "scene", value_name = "N")]
        gltf_scene: Option<usize>,
        /// Folder for image.png, visibility.exr, position.exr, dbuffer.exr, dbuffer_s.exr,
        /// classes.png and meta.json (created if missing; written all or nothing).
        #[arg(long)]
        out: std::path::PathBuf,
        /// Image size, WxH (at most 64 Mpixels, sides up to 16384).
        #[arg(long, default_value = "512x512")]
        size: String,
        /// The shadow method, as in the README's list (an unknown name prints them; default:
        /// dbuffer for a disk light, linear-ssm for a line light).
        #[arg(long)]
        method: Option<String>,
        /// V(t): smoothstep, sqrt, exact or linear.
        #[arg(long, default_value = "smoothstep")]
        vt: String,
        /// The D-buffer is N×N texels (1 to 8192).
        #[arg(long, default_value_t = 1024)]
        dbuffer_size: u32,
        #[command(flatten)]
        knobs: cli::MethodFlags,
    },
    /// Render every method and the ray-traced reference, and report their errors: each
    /// method's image, visibility EXR and error heatmap (the hard methods' mismatch against
    /// reference-hard too), montage.png (every method on one page), report.md and report.json.
    Compare {
        /// A built-in scene name, a .toml scene file, an .obj mesh or a .gltf/.glb model.
        scene: String,
        /// Which scene of a glTF model to draw (default: the model's default scene, else its
        /// first).
        #[arg(long = "scene", value_name = "N")]
        gltf_scene: Option<usize>,
        /// Folder for the images and reports (created if missing).
        #[arg(long)]
        out: std::path::PathBuf,
        /// Image size, WxH (at most 16 Mpixels, MAX_COMPARE_PIXELS; sides up to 16384); default
        /// 512x512, 256x256 with --orbit.
        #[arg(long)]
        size: Option<String>,
        /// Also every method in motion: the light (or the camera) round the orbit of
        /// `animate`, the temporal error and popping of each method against the reference
        /// (K 256 unless --samples says), a plot per method and motion.png.
        #[arg(long)]
        orbit: Option<String>,
        /// Frames of the --orbit (2 to 720).
        #[arg(long, default_value_t = 24)]
        frames: usize,
        /// Comma-separated methods to compare instead of every one, e.g. dbuffer,hard (the
        /// reference always; reference-hard too with a hard method); a user's method is
        /// file:PATH.wgsl. `--method` is the same flag.
        #[arg(long, alias = "method")]
        methods: Option<String>,
        /// Which engine traces the reference's shadow rays: cpu (the independent oracle) or
        /// gpu (the same rays on the GPU's tracer); the --orbit frames use the CPU's.
        #[arg(long, default_value = "cpu")]
        reference: String,
        /// V(t) of the D-buffer methods: smoothstep, sqrt, exact or linear.
        #[arg(long, default_value = "exact")]
        vt: String,
        /// The D-buffer and the shadow maps are N×N texels (1 to 8192).
        #[arg(long, default_value_t = 1024)]
        dbuffer_size: u32,
        #[command(flatten)]
        knobs: cli::MethodFlags,
    },
    /// Render the light (or the camera) once around an orbit: frame-0000.png, ... and
    /// animation.png (an APNG of the loop), written all or nothing.
    Animate {
        /// A built-in scene name, a .toml scene file, an .obj mesh or a .gltf/.glb model.
        scene: String,
        /// Which scene of a glTF model to draw (default: the model's default scene, else its
        /// first).
        #[arg(long = "scene", value_name = "N")]
        gltf_scene: Option<usize>,
        /// Folder for the frames and animation.png (created if missing).
        #[arg(long)]
        out: std::path::PathBuf,
        /// Frames in the loop (1 to 3600); 48 is a 7.5° step, smooth at the default 16 fps.
        #[arg(long, default_value_t = 48)]
        frames: usize,
        /// What moves: the light (about the vertical axis through the casters) or the camera
        /// (about its target).
        #[arg(long, default_value = "light")]
        orbit: String,
        /// Frames per second of animation.png (1 to 60).
        #[arg(long, default_value_t = 16)]
        fps: u32,
        /// Image size, WxH (at most 16 Mpixels, MAX_ANIMATE_PIXELS; sides up to 16384).
        #[arg(long, default_value = "480x360")]
        size: String,
        /// The shadow method (as for render; default: dbuffer for a disk light, linear-ssm for
        /// a line light).
        #[arg(long)]
        method: Option<String>,
        /// V(t): smoothstep, sqrt, exact or linear.
        #[arg(long, default_value = "smoothstep")]
        vt: String,
        /// The D-buffer is N×N texels.
        #[arg(long, default_value_t = 1024)]
        dbuffer_size: u32,
        #[command(flatten)]
        knobs: cli::MethodFlags,
    },
    /// Time every method on the D-buffer paper's Table 1 scenes, and the geometry from 1k to 1M triangles;
    /// print markdown tables and write bench.json, bench.md and geometry-scaling.png.
    Bench {
        /// Fewer frames and scaling up to 256k triangles (about 2.5 minutes on 2 CPU cores, most of
        /// it bitmask's frames).
        #[arg(long)]
        quick: bool,
        /// Folder for bench.json, bench.md and geometry-scaling.png (created if missing).
        #[arg(long, default_value = "out/bench")]
        out: std::path::PathBuf,
        /// Timed frames per scene, size and method (after the warm-up ones).
        #[arg(long)]
        frames: Option<usize>,
        /// Warm-up frames per scene, size and method (the first compiles shaders).
        #[arg(long)]
        warmup: Option<usize>,
        /// Comma-separated scenes instead of table1-224,table1-960,table1-5760,table1-1440.
        #[arg(long)]
        scenes: Option<String>,
        /// Comma-separated square image sizes instead of 300,600,1024.
        #[arg(long)]
        sizes: Option<String>,
        /// Largest caster of the geometry-scaling curve, in triangles.
        #[arg(long)]
        max_triangles: Option<u32>,
        /// Comma-separated methods to time instead of every one, e.g. dbuffer,hard (a target
        /// whose methods were not timed is reported as not measured).
        #[arg(long)]
        methods: Option<String>,
    },
    /// Error against cost for every method over its quality knobs, per scene, in one run:
    /// study.json, study.md and a plot per scene in DIR (its cache too: the same command resumes
    /// a stopped run).
    Study {
        /// A study file (TOML: scenes, size, dbuffer_size, samples, vt, warmup, frames and the
        /// settings to sweep per method; docs/guide/study.md); without one, the default study.
        file: Option<std::path::PathBuf>,
        /// Folder for study.json, study.md, plots/ and the cache (created if missing).
        #[arg(long, default_value = "out/study")]
        out: std::path::PathBuf,
        /// Four scenes (two with many casters), three settings of every method, 256², K = 256
        /// (under 10 minutes on 2 CPU cores).
        #[arg(long)]
        quick: bool,
        /// Comma-separated scenes instead of the study's.
        #[arg(long)]
        scenes: Option<String>,
        /// Comma-separated methods instead of the study's (each keeps its sweep).
        #[arg(long)]
        methods: Option<String>,
        /// Image size, WxH, instead of the study's.
        #[arg(long)]
        size: Option<String>,
        /// A knob of a user's method in --methods (file:PATH.wgsl), as its file's header
        /// declares it; repeatable.
        #[arg(long = "knob", value_name = "NAME=VALUE")]
        knobs: Vec<String>,
    },
    /// List the built-in scenes, one a line.
    Scenes,
    /// List every GPU adapter wgpu sees on every backend, and which methods each can run.
    Adapters,
    /// Print what the geometry stage makes of a scene: classes, silhouettes, volumes, warnings.
    Inspect {
        /// A built-in scene name, a .toml scene file, an .obj mesh or a .gltf/.glb model.
        scene: String,
        /// Which scene of a glTF model to draw (default: the model's default scene, else its
        /// first).
        #[arg(long = "scene", value_name = "N")]
        gltf_scene: Option<usize>,
        /// Also compare the CPU twin of the method with ray-cast ground truth over the camera's
        /// view, with this many disk samples per pixel (1 to 65536).
        #[arg(long)]
        samples: Option<usize>,
        /// View size for the comparison, WxH (at most 4 Mpixels).
        #[arg(long, default_value = "96x96")]
        size: String,
        /// V(t) variant for the comparison.
        #[arg(long, default_value = "exact")]
        vt: String,
        /// Whose CPU twin to compare: dbuffer (the paper's method) or dbuffer-fused.
        #[arg(long, default_value = dbuffer::render::Method::DBUFFER.name())]
        method: String,
        /// Also write the comparison as a PNG: method | reference | |ΔV| (0 … 0.25).
        #[arg(long)]
        out: Option<std::path::PathBuf>,
        /// Where the counts come from: the geometry stage on the CPU, on the GPU, or auto (the
        /// GPU where an adapter can run it, as `render` picks).
        #[arg(long, default_value = "auto")]
        geometry: String,
    },
}

/// The watchdog's end of a command whose GPU work does not finish.
fn stalled(message: &str) -> ! {
    cli::print::err(format_args!("dbuffer: {message}\n"));
    std::process::exit(1)
}

fn main() -> ExitCode {
    // Before any thread starts: no window system is asked anything by a headless command.
    dbuffer::render::adapter::quiet_device_select();
    // `dbuffer --help` ends with the resource budget.
    let matches = Args::command()
        .after_help(dbuffer::budget::summary())
        .get_matches();
    let args = match Args::from_arg_matches(&matches) {
        Ok(args) => args,
        Err(e) => e.exit(),
    };
    if let Some(b) = &args.backend {
        match dbuffer::render::adapter::parse_backend(b) {
            Ok(b) => dbuffer::render::adapter::set_backend(b),
            Err(e) => {
                cli::print::err(format_args!("dbuffer: {e}\n"));
                return ExitCode::FAILURE;
            }
        }
    }
    cli::set_verbose(args.verbose);
    let verbose = args.verbose;
    // A command line stops, naming the work, where the GPU never finishes it (a user's shader
    // that does not end); the lab starts no watchdog.
    if !matches!(args.command, Some(Command::Gui { .. }) | None) {
        dbuffer::render::watchdog::start(stalled);
    }
    // `DBUFFER_SHADER_DIR`'s files, checked before any GPU work: a broken one is reported as its
    // file, line and the line itself, not as a pipeline's error.
    if let Err(e) = dbuffer::render::shaders::check_env() {
        cli::print::err(format_args!("{}", cli::error_lines(&anyhow::Error::new(e))));
        return ExitCode::FAILURE;
    }
    let result = match args.command {
        Some(Command::Study {
            file,
            out,
            quick,
            scenes,
            methods,
            size,
            knobs,
        }) => cli::study::run(&cli::study::StudyArgs {
            file: file.as_deref(),
            out: &out,
            quick,
            scenes: scenes.as_deref(),
            methods: methods.as_deref(),
            size: size.as_deref(),
            knobs: &knobs,
        }),
        Some(Command::Scenes) => cli::scenes(),
        Some(Command::Adapters) => cli::adapters::list(),
        Some(Command::Inspect {
            scene,
            gltf_scene,
            samples,
            size,
            vt,
            method,
            out,
            geometry,
        }) => cli::inspect(
            &scene,
            gltf_scene,
            samples,
            (&size, &vt, &method),
            out.as_deref(),
            &geometry,
        ),
        None => cli::gui(
            None,
            cli::GuiArgs {
                gltf_scene: None,
                bench: None,
                bench_out: None,
                study: None,
                shaders: None,
                geometry: None,
            },
            verbose,
        ),
        Some(Command::Gui {
            scene,
            gltf_scene,
            bench,
            bench_out,
            study,
            shaders,
            geometry,
        }) => cli::gui(
            scene,
            cli::GuiArgs {
                gltf_scene,
                bench,
                bench_out,
                study,
                shaders,
                geometry,
            },
            verbose,
        ),
        Some(Command::Render {
            scene,
            gltf_scene,
            out,
            size,
            method,
            vt,
            dbuffer_size,
            knobs,
        }) => cli::render(&cli::RenderArgs {
            scene: &scene,
            gltf_scene,
            out: &out,
            size: &size,
            method: method.as_deref(),
            vt: &vt,
            dbuffer_size,
            knobs: &knobs,
            verbose,
        }),
        Some(Command::Compare {
            scene,
            gltf_scene,
            out,
            size,
            orbit,
            frames,
            methods,
            reference,
            vt,
            dbuffer_size,
            knobs,
        }) => cli::compare(&cli::CompareArgs {
            scene: &scene,
            gltf_scene,
            out: &out,
            size: size.as_deref(),
            orbit: orbit.as_deref(),
            frames,
            methods: methods.as_deref(),
            reference: &reference,
            vt: &vt,
            dbuffer_size,
            knobs: &knobs,
        }),
        Some(Command::Animate {
            scene,
            gltf_scene,
            out,
            frames,
            orbit,
            fps,
            size,
            method,
            vt,
            dbuffer_size,
            knobs,
        }) => cli::animate(&cli::AnimateArgs {
            scene: &scene,
            gltf_scene,
            out: &out,
            frames,
            orbit: &orbit,
            fps,
            size: &size,
            method: method.as_deref(),
            vt: &vt,
            dbuffer_size,
            knobs: &knobs,
        }),
        Some(Command::Bench {
            quick,
            out,
            frames,
            warmup,
            scenes,
            sizes,
            max_triangles,
            methods,
        }) => cli::bench::run(&cli::bench::BenchArgs {
            quick,
            out: &out,
            frames,
            warmup,
            scenes: scenes.as_deref(),
            sizes: sizes.as_deref(),
            max_triangles,
            methods: methods.as_deref(),
        }),
    };
    // Output that could not be written (other than to a reader that went away) fails the run.
    let result = result.and_then(|()| {
        cli::print::finish().map_err(|e| anyhow::anyhow!("cannot write to standard output: {e}"))
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            cli::print::err(format_args!("{}", cli::error_lines(&e)));
            ExitCode::FAILURE
        }
    }
}
