//! How long the lab's reference takes to converge with each engine: a [`ViewSession`] showing
//! the reference of a built-in at the lab's default viewport size, advanced as a window advances
//! it (one advance a frame; between frames a wait of at most 16 ms that ends as soon as the
//! engine has new samples), timed from the first advance to the first frame shown with every
//! sample. Also the slowest advance (what the window's thread spent in one frame, shading the
//! new samples included) and how many snapshots were shown on the way; then, for scale, the same
//! reference traced in one go on each engine (as `compare --reference gpu|cpu` does).
//!
//! `cargo run --release --example lab_reference -- fig7-concave 695x750 256`
//! (scene, size, K; these are the defaults: 695×750 is the viewport of the lab's 1280×800
//! window).

use std::time::{Duration, Instant};

use dbuffer::geometry::VtVariant;
use dbuffer::render::passes::view::{Mapping, View, ViewParams};
use dbuffer::render::truth::{self, Engine};
use dbuffer::render::view_session::{Intent, ViewSession};
use dbuffer::render::{gpu_reference, reference, FrameRequest, GpuContext, Knobs};
use dbuffer::scene::{self, Scene};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("fig7-concave", String::as_str);
    let (width, height) = match args.get(1) {
        Some(s) => dbuffer::budget::parse_wxh(s)
            .ok_or_else(|| anyhow::anyhow!("the size is WxH, found {s}"))?,
        None => (695, 750),
    };
    let samples: u32 = args.get(2).map_or(Ok(256), |s| s.parse())?;
    let scene = scene::load(name)?;
    let ctx = GpuContext::headless()?;
    println!(
        "{name} {width}x{height}, K = {samples}, on {} ({} CPU threads)",
        ctx.adapter_description(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    let mut v = ViewSession::new(ctx, scene);
    // Pipelines made and shaders compiled before anything is timed: a small reference each.
    for engine in [Engine::Gpu, Engine::Cpu] {
        converge(&mut v, engine, &intent(64, 64, 4))?;
    }
    for engine in [Engine::Gpu, Engine::Cpu] {
        let ask = intent(width, height, samples);
        let Some(r) = converge(&mut v, engine, &ask)? else {
            println!("{engine}: this adapter cannot trace the reference");
            continue;
        };
        println!(
            "{engine}: K = {samples} in {:.1} s ({} advances, {} snapshots shown, the slowest \
             advance {:.0} ms)",
            r.seconds, r.frames, r.snapshots, r.slowest_ms
        );
    }
    // For scale: the same rays traced in one go on each engine, the window's thread waiting
    // (`compare --reference gpu|cpu`).
    let scene = v.scene().clone();
    let t = Instant::now();
    match gpu_reference::compute(&v.ctx, &scene, width, height, samples, &mut |_, _| {}) {
        Ok((c, cost)) => println!(
            "gpu in one go: {:.1} s ({:.1} s of shadow rays, {:.1} M rays/s)",
            t.elapsed().as_secs_f64(),
            c.rays_ms / 1e3,
            cost.rays as f64 / c.rays_ms / 1e3
        ),
        Err(e) => println!("gpu in one go: {e}"),
    }
    let t = Instant::now();
    let c = reference::compute(&scene, width, height, samples, &mut |_, _| {});
    let rays = c.hit_pixels as f64 * f64::from(samples);
    println!(
        "cpu in one go: {:.1} s ({:.1} s of shadow rays, about {:.1} M rays/s)",
        t.elapsed().as_secs_f64(),
        c.rays_ms / 1e3,
        rays / c.rays_ms / 1e3
    );
    Ok(())
}

/// One run to convergence.
struct Run {
    seconds: f64,
    frames: u32,
    snapshots: u32,
    slowest_ms: f64,
}

/// Converge `ask`'s reference with `engine` from nothing; `None` where the adapter cannot.
fn converge(v: &mut ViewSession, engine: Engine, ask: &Intent) -> anyhow::Result<Option<Run>> {
    {
        v.set_reference_engine(Some(engine));
        if v.reference_engine() != engine {
            return Ok(None);
        }
        // A light nudged for each run: a reference of its own, nothing kept from the last.
        let light = v.scene().light;
        v.set_light(light.with_center(light.center() + glam::Vec3::new(1e-3, 0.0, 0.0)));
        let start = Instant::now();
        let (mut frames, mut snapshots, mut slowest, mut last) = (0u32, 0u32, 0.0f64, None);
        loop {
            let seen = v.reference_news();
            let t = Instant::now();
            let update = v.advance(ask, &mut |_: &Scene, _, _| 0);
            slowest = slowest.max(t.elapsed().as_secs_f64() * 1e3);
            frames += 1;
            anyhow::ensure!(update.errors.is_empty(), "{:?}", update.errors);
            // A frame of this reference (not one kept from before while its first samples
            // come).
            let shown = v
                .shown(0)
                .filter(|s| s.note.is_none() && s.light == v.scene().light)
                .and_then(|s| s.reference);
            if shown != last {
                snapshots += 1;
                last = shown;
            }
            if shown.is_some_and(|(d, t)| d == t) {
                break;
            }
            anyhow::ensure!(
                start.elapsed() < Duration::from_secs(3600),
                "not done in an hour"
            );
            v.wait_for_reference(seen, Duration::from_millis(16));
        }
        Ok(Some(Run {
            seconds: start.elapsed().as_secs_f64(),
            frames,
            snapshots,
            slowest_ms: slowest,
        }))
    }
}

fn intent(width: u32, height: u32, samples: u32) -> Intent {
    Intent {
        request: FrameRequest {
            width,
            height,
            dbuffer_size: 1024,
            method: truth::SOFT,
            vt: VtVariant::Smoothstep,
            knobs: truth::with_samples(Knobs::default(), samples),
            ..FrameRequest::default()
        },
        split: None,
        params: ViewParams {
            view: View::Final,
            channels: [true, false, false, false],
            mapping: Mapping::unit(),
        },
        probe: None,
        moving: false,
        wait: false,
    }
}
