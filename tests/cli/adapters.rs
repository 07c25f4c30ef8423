//! Every adapter a user has: each method's needs checked before any work, the GL
//! backend (Mesa's llvmpipe through EGL), the weakest device WebGPU allows, `dbuffer adapters`,
//! and errors printed as lines with nothing from a window system on stderr.
//!
//! The GL cases are small (64² images, 64² maps) and skip, loudly, where no GL adapter exists.

use std::path::PathBuf;
use std::process::{Command, Output};

use dbuffer::render::adapter::Verdict;
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, GpuContext, Method, RenderError};
use dbuffer::scene::{self, Scene};

use crate::support as cli;

fn temp_dir(name: &str) -> PathBuf {
    cli::temp_dir("adapters", name)
}

/// The binary as a user on a machine without a desktop session runs it: no `XDG_RUNTIME_DIR`,
/// no `NODEVICE_SELECT` (the binary has to keep Mesa's device-select layer quiet itself).
fn bare(args: &[&str]) -> Output {
    let mut c = cli::dbuffer();
    c.env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("DISPLAY")
        .args(args);
    c.output().expect("the binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Nothing on stderr about a window system, and no escaped newline.
fn assert_quiet(what: &str, stderr: &str) {
    let lower = stderr.to_lowercase();
    for word in ["xdg_runtime_dir", "wayland", "x11", "xcb", "display"] {
        assert!(
            !lower.contains(word),
            "{what}: '{word}' on stderr:\n{stderr}"
        );
    }
    assert!(
        !stderr.contains("\\n"),
        "{what}: a literal \\n on stderr:\n{stderr}"
    );
}

fn request(method: Method) -> FrameRequest {
    FrameRequest {
        width: 64,
        height: 64,
        dbuffer_size: 64,
        method,
        ..FrameRequest::default()
    }
}

/// The first adapter of `backends`, if there is one.
fn adapter(backends: wgpu::Backends) -> Option<wgpu::Adapter> {
    dbuffer::render::adapter::quiet_device_select();
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    let instance = wgpu::Instance::new(desc);
    pollster::block_on(instance.enumerate_adapters(backends))
        .into_iter()
        .next()
}

fn gl_adapter() -> Option<wgpu::Adapter> {
    let a = adapter(wgpu::Backends::GL);
    if a.is_none() {
        eprintln!(
            "\n*** SKIPPED: no GL adapter (install libegl1 libegl-mesa0 libgl1-mesa-dri: \
             scripts/setup-system.sh) ***\n"
        );
    }
    a
}

/// Render `method` on `scene` in `offline`, or the refusal: before any work, nothing the device
/// reported outside an error scope either way.
fn render_or_refuse(offline: &mut Offline, scene: &Scene, method: Method) -> Option<Vec<f32>> {
    let what = format!("{method} on {} ({})", scene.name, offline.ctx.caps.adapter);
    let refused = method.refuses_on(&offline.ctx.caps);
    let result = offline.render(scene, &request(method));
    let errors = offline.ctx.take_uncaptured_errors();
    assert!(errors.is_empty(), "{what}: validation errors {errors:?}");
    match (result, refused) {
        (Ok((frame, _)), None) => Some(frame.visibility),
        (Err(RenderError::Request(e)), Some(why)) => {
            assert_eq!(e, why, "{what}");
            assert!(!e.contains('\n'), "{what}: one line: {e}");
            assert!(e.contains(method.name()) && e.contains(&offline.ctx.caps.adapter));
            None
        }
        (Ok(_), Some(why)) => panic!("{what}: rendered although refused: {why}"),
        (Err(e), _) => panic!("{what}: {e}"),
    }
}

/// The scene's light takes the method (else the light refusal, tested elsewhere, comes first).
fn takes(method: Method, scene: &Scene) -> bool {
    method.refuses(scene.light.kind()).is_none()
}

#[test]
fn headless_commands_say_nothing_about_a_window_system() {
    let dir = temp_dir("quiet");
    let out = bare(&[
        "render",
        "table1-224",
        "--size",
        "64x64",
        "--dbuffer-size",
        "64",
        "--out",
        dir.to_str().unwrap_or_default(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_quiet("render", &text(&out.stderr));
    // Every backend, GL's EGL included.
    let mut c = cli::dbuffer();
    let out = c
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .env_remove("WGPU_BACKEND")
        .arg("adapters")
        .output()
        .expect("the binary runs");
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_quiet("adapters", &text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn adapters_lists_every_adapter_with_the_method_table() {
    let mut c = cli::dbuffer();
    let out = c
        .env_remove("WGPU_BACKEND")
        .arg("adapters")
        .output()
        .expect("the binary runs");
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("backend Vulkan"), "lavapipe: {stdout}");
    if gl_adapter().is_some() {
        assert!(stdout.contains("backend Gl"), "llvmpipe-GL: {stdout}");
    }
    for m in Method::all() {
        let rows = stdout
            .lines()
            .filter(|l| l.trim_start().starts_with(&format!("{} ", m.name())))
            .count();
        assert!(rows >= 1, "{m}: {stdout}");
    }
    // On lavapipe every method runs.
    let vulkan = stdout
        .split("\nadapter ")
        .find(|b| b.contains("backend Vulkan"));
    assert!(!vulkan.unwrap_or_default().contains("cannot"), "{stdout}");
    // `--backend` picks one, and `-v` says which and why.
    let out = cli::dbuffer()
        .args(["adapters", "--backend", "vulkan"])
        .output()
        .expect("the binary runs");
    assert!(
        !text(&out.stdout).contains("backend Gl"),
        "{}",
        text(&out.stdout)
    );
    let dir = temp_dir("verbose");
    let out = cli::dbuffer()
        .args([
            "render",
            "table1-224",
            "--size",
            "16x16",
            "--dbuffer-size",
            "16",
            "-v",
        ])
        .args(["--backend", "vulkan", "--out"])
        .arg(&dir)
        .output()
        .expect("the binary runs");
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("backend Vulkan") && stderr.contains("chosen by --backend vulkan"),
        "{stderr}"
    );
    let bad = cli::dbuffer()
        .args(["scenes", "--backend", "glide"])
        .output()
        .expect("the binary runs");
    assert_eq!(bad.status.code(), Some(1));
    assert!(text(&bad.stderr).contains("--backend expects vulkan, gl, metal or dx12"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The first command, as a new user on a machine with only GL types it.
#[test]
fn gl_renders_fig1_large_light() {
    if gl_adapter().is_none() {
        return;
    }
    let dir = temp_dir("gl-fig1");
    let mut c = cli::dbuffer();
    let out = c
        .env("WGPU_BACKEND", "gl")
        .env_remove("XDG_RUNTIME_DIR")
        .args([
            "render",
            "fig1-large-light",
            "--size",
            "64x64",
            "--dbuffer-size",
            "64",
        ])
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("the binary runs");
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert_quiet("render on GL", &stderr);
    assert!(dir.join("image.png").is_file());
    // A GL without float colour buffers (Mesa told to hide them, as an older driver has
    // none) refuses every method in one line naming it, what is missing and the adapter,
    // before anything is drawn or written.
    let refused = temp_dir("gl-refused");
    let out = Command::new(env!("CARGO_BIN_EXE_dbuffer"))
        .env("WGPU_BACKEND", "gl")
        .env("MESA_EXTENSION_OVERRIDE", "-GL_ARB_color_buffer_float")
        .env_remove("XDG_RUNTIME_DIR")
        .args(["render", "fig1-large-light", "--size", "64x64"])
        .arg("--out")
        .arg(&refused)
        .output()
        .expect("the binary runs");
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains("method 'dbuffer' needs rendering to Rg32Float")
            && stderr.contains("(Gl, "),
        "{stderr}"
    );
    assert!(!refused.join("image.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every built-in with every method the GL adapter can run, each within a stated tolerance of
/// lavapipe's Vulkan frame: mean |ΔV| under 0.02 and at most 3 % of pixels off by more than
/// 0.25 (both are llvmpipe underneath, but GL rasterises and rounds its own way: on 2026-12-02
/// the worst of 262 frames was 0.0095 and 0.95 %); every
/// other method refused up front.
#[test]
fn gl_renders_every_builtin_with_every_method_it_can_run() {
    let Some(gl) = gl_adapter() else {
        return;
    };
    let Some(vk) = adapter(wgpu::Backends::VULKAN) else {
        panic!("no Vulkan adapter to compare GL with");
    };
    let open = |a: &wgpu::Adapter| Offline {
        ctx: GpuContext::from_adapter(a).unwrap_or_else(|e| panic!("{e}")),
        progress: None,
        reference: Default::default(),
    };
    let (mut gl, mut vk) = (open(&gl), open(&vk));
    let mut ran = 0;
    let (mut worst_mean, mut worst_far) = (0.0f64, 0.0f64);
    for name in scene::builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        for &m in Method::all() {
            // The reference's rays are the CPU's on either backend; its drawing is tested
            // by reference-hard's (the same camera pass).
            if !takes(m, &scene) || m.is_reference() {
                continue;
            }
            let Some(v_gl) = render_or_refuse(&mut gl, &scene, m) else {
                continue;
            };
            let Some(v_vk) = render_or_refuse(&mut vk, &scene, m) else {
                continue;
            };
            let n = v_gl.len().max(1) as f64;
            let diffs: Vec<f64> = v_gl
                .iter()
                .zip(&v_vk)
                .map(|(a, b)| f64::from((a - b).abs()))
                .collect();
            let mean = diffs.iter().sum::<f64>() / n;
            let far = diffs.iter().filter(|d| **d > 0.25).count() as f64 / n;
            assert!(
                mean < 0.02 && far <= 0.03,
                "{m} on {name}: GL against Vulkan mean |dV| {mean:.4}, {:.1} % off by > 0.25",
                far * 100.0
            );
            ran += 1;
            worst_mean = worst_mean.max(mean);
            worst_far = worst_far.max(far);
        }
    }
    eprintln!(
        "GL: {ran} (scene, method) frames within tolerance of Vulkan; worst mean |dV| \
         {worst_mean:.5}, worst share off by > 0.25: {:.2} %",
        worst_far * 100.0
    );
    assert!(ran > 0, "GL ran nothing");
}

/// The weakest device WebGPU allows: WebGPU's downlevel limits (and WebGL2's) and no optional
/// features. Every method of the registry renders a small built-in or is refused up front; none
/// panics or reports a validation error.
#[test]
fn the_weakest_device_renders_or_refuses_every_method() {
    let Some(a) = adapter(wgpu::Backends::VULKAN) else {
        panic!("no Vulkan adapter");
    };
    let disk = scene::load("table1-224").unwrap_or_else(|e| panic!("{e}"));
    let line = scene::load("line-bar").unwrap_or_else(|e| panic!("{e}"));
    for (what, limits) in [
        ("downlevel", wgpu::Limits::downlevel_defaults()),
        ("webgl2", wgpu::Limits::downlevel_webgl2_defaults()),
    ] {
        let limits = limits.using_resolution(a.limits());
        let ctx = GpuContext::open(&a, wgpu::Features::empty(), limits)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let mut offline = Offline {
            ctx,
            progress: None,
            reference: Default::default(),
        };
        let mut rendered = Vec::new();
        for &m in Method::all() {
            let scene = if takes(m, &disk) { &disk } else { &line };
            if render_or_refuse(&mut offline, scene, m).is_some() {
                rendered.push(m.name());
            }
        }
        eprintln!("{what}: rendered {rendered:?}");
        if what == "downlevel" {
            assert!(rendered.contains(&"dbuffer"), "{what}: {rendered:?}");
        }
        // `compare` on it lists what the device cannot run as "n/a — needs …", with the rest.
        let request = dbuffer::compare::CompareRequest {
            width: 32,
            height: 32,
            dbuffer_size: 32,
            vt: dbuffer::geometry::VtVariant::Exact,
            knobs: dbuffer::render::Knobs::default(),
        };
        let c = dbuffer::compare::run(&mut offline, "table1-224", &disk, &request, |_| {})
            .unwrap_or_else(|e| panic!("{what}: compare: {e}"));
        let errors = offline.ctx.take_uncaptured_errors();
        assert!(errors.is_empty(), "{what}: compare: {errors:?}");
        let table = dbuffer::compare::report::Report::new(&c).table();
        for &m in Method::all() {
            if m.refuses_on(&offline.ctx.caps).is_some() {
                assert!(table.contains(&format!("| {m} | n/a — needs ")), "{table}");
            } else if takes(m, &disk) {
                assert!(
                    c.results.iter().any(|r| r.method == m),
                    "{what}: {m} not drawn"
                );
            }
        }
    }
}

/// The stencil and blending fallbacks of a device without the optional features are stated.
#[test]
fn fallbacks_are_named_with_their_cost() {
    let Some(a) = adapter(wgpu::Backends::VULKAN) else {
        panic!("no Vulkan adapter");
    };
    let caps = dbuffer::render::adapter::Capabilities::of(
        &a,
        wgpu::Features::empty(),
        wgpu::Limits::downlevel_defaults(),
    );
    match Method::all()
        .iter()
        .find(|m| m.name() == "wedges")
        .map(|m| m.on(&caps))
    {
        Some(Verdict::Fallback(f)) => {
            let all = f.join("; ");
            assert!(all.contains("Rg16Float instead of Rg32Float"), "{all}");
            assert!(
                all.contains("Depth24PlusStencil8 instead of Depth32FloatStencil8"),
                "{all}"
            );
        }
        other => panic!("wedges without FLOAT32_BLENDABLE: {other:?}"),
    }
}

/// The wedges' half-float fallback (a device whose 32-bit floats do not blend; the same device
/// otherwise) costs no accuracy a picture shows: at most 0.5 % of a built-in's pixels off the
/// 32-bit sum by more than 1/256 (an 8-bit image's step), none by more than 1/64, as
/// `needs.rs` states it.
#[test]
fn the_half_float_wedge_sum_is_within_an_8_bit_step() {
    let Some(a) = adapter(wgpu::Backends::VULKAN) else {
        panic!("no Vulkan adapter");
    };
    if !a.features().contains(wgpu::Features::FLOAT32_BLENDABLE) {
        eprintln!("\n*** SKIPPED: the adapter has no FLOAT32_BLENDABLE to compare with ***\n");
        return;
    }
    let wedges = Method::all()
        .iter()
        .copied()
        .find(|m| m.name() == "wedges")
        .unwrap_or_else(|| panic!("no wedges in the registry"));
    let features = dbuffer::render::context::wanted_features(a.features());
    let limits = dbuffer::render::context::wanted_limits(&a.limits());
    let open = |features| Offline {
        ctx: GpuContext::open(&a, features, limits.clone()).unwrap_or_else(|e| panic!("{e}")),
        progress: None,
        reference: Default::default(),
    };
    let mut full = open(features);
    let mut half = open(features - wgpu::Features::FLOAT32_BLENDABLE);
    match wedges.on(&half.ctx.caps) {
        Verdict::Fallback(f) => assert_eq!(f.len(), 1, "{f:?}"),
        other => panic!("{other:?}"),
    }
    for name in ["fig7-concave", "fig8c-complex", "table1-224", "overlap"] {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let v32 = render_or_refuse(&mut full, &scene, wedges).unwrap_or_default();
        let v16 = render_or_refuse(&mut half, &scene, wedges).unwrap_or_default();
        let d: Vec<f32> = v32.iter().zip(&v16).map(|(a, b)| (a - b).abs()).collect();
        let worst = d.iter().copied().fold(0.0f32, f32::max);
        let off = d.iter().filter(|x| **x > 1.0 / 256.0).count() as f64 / d.len().max(1) as f64;
        eprintln!(
            "{name}: half-float wedge sum, max |dV| {worst:.6}, {:.3} % over 1/256",
            off * 100.0
        );
        assert!(
            off <= 0.005 && worst <= 1.0 / 64.0,
            "{name}: max |dV| {worst}, {:.3} % over 1/256",
            off * 100.0
        );
    }
}
