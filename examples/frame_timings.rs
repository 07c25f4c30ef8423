//! Per-pass GPU timings of the render core for a few methods, with the light-space passes made
//! again every frame (medians after two warm-up frames): the quick loop for tuning a pass, where
//! `dbuffer bench` is the whole report.
//!
//!     cargo run --release --example frame_timings -- table1-960 table1-5760 --size 1024 --frames 8 --methods dbuffer,hard
//!
//! `--knob name=value` sets a method's knob (`--knob list-size=128`), as `dbuffer render` does.
//! `--stats` adds, per scene and method, one more frame read back with its cost view: the share
//! of the pixels on each of the method's paths, its work per pixel (mean over the pixels that
//! show a surface, over those that work, the largest), the share of 4×2 pixel blocks (a SIMD
//! group of lavapipe's 8 lanes) where some pixel works; and the volume fragments per texel of a
//! method that counts them.

use dbuffer::geometry::VtVariant;
use dbuffer::render::{FrameRequest, GpuContext, Method, Session};
use dbuffer::scene;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
    };
    let size: u32 = value("--size").map_or(Ok(600), |v| v.parse())?;
    let frames: usize = value("--frames").map_or(Ok(8), |v| v.parse())?;
    let methods: Vec<Method> = value("--methods")
        .map_or("dbuffer,hard", |v| v.as_str())
        .split(',')
        .map(|m| m.parse().map_err(anyhow::Error::msg))
        .collect::<anyhow::Result<_>>()?;
    let names: Vec<&String> = args
        .iter()
        .enumerate()
        .filter(|(i, a)| !a.starts_with("--") && (*i == 0 || !args[i - 1].starts_with("--")))
        .map(|(_, a)| a)
        .collect();
    let stats = args.iter().any(|a| a == "--stats");
    // `--knob name=value` (again for more): a method's knob, as `dbuffer render --name value`.
    let mut knobs = dbuffer::render::Knobs::default();
    for (i, a) in args.iter().enumerate() {
        if a == "--knob" {
            let (name, value) = args
                .get(i + 1)
                .and_then(|v| v.split_once('='))
                .ok_or_else(|| anyhow::anyhow!("--knob takes name=value"))?;
            knobs
                .set(name, value.parse()?)
                .map_err(anyhow::Error::msg)?;
        }
    }
    let ctx = GpuContext::headless()?;
    println!(
        "adapter {}; {size}², D-buffer 1024², median of {frames} frames after 2 warm-up",
        ctx.adapter_description()
    );
    for name in names {
        let scene = scene::load(name)?;
        // One session per method, frames interleaved method by method so a machine whose speed
        // drifts slows every method alike.
        let mut sessions: Vec<Session> = methods
            .iter()
            .map(|_| Session::new(&ctx, scene.clone()))
            .collect();
        let mut passes: Vec<Vec<(String, Vec<f64>)>> = vec![Vec::new(); methods.len()];
        for i in 0..frames + 2 {
            for (k, &method) in methods.iter().enumerate() {
                let request = FrameRequest {
                    width: size,
                    height: size,
                    dbuffer_size: std::env::var("DS")
                        .ok()
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(1024),
                    method,
                    vt: VtVariant::Smoothstep,
                    knobs,
                    ..FrameRequest::default()
                };
                sessions[k].invalidate_light_maps();
                let frame = sessions[k].frame(&ctx, &request)?;
                if i < 2 {
                    continue;
                }
                for (pass, ms) in frame.gpu_ms {
                    match passes[k].iter_mut().find(|(p, _)| *p == pass) {
                        Some((_, v)) => v.push(ms),
                        None => passes[k].push((pass, vec![ms])),
                    }
                }
            }
        }
        for (k, method) in methods.iter().enumerate() {
            let cells: Vec<String> = passes[k]
                .iter()
                .map(|(p, v)| format!("{p} {:.2}", median(v.clone())))
                .collect();
            println!("{name:<14} {method:<15} {}", cells.join("  "));
        }
        if stats {
            for (k, &method) in methods.iter().enumerate() {
                let request = FrameRequest {
                    width: size,
                    height: size,
                    method,
                    vt: VtVariant::Smoothstep,
                    knobs,
                    read_cost: true,
                    ..FrameRequest::default()
                };
                let frame = sessions[k].frame(&ctx, &request)?;
                println!("{name:<14} {method:<15} {}", cost_stats(method, &frame));
                if let Some(Ok(fill)) = sessions[k].stencil_fill(&ctx, method) {
                    println!("{name:<14} {method:<15} volume fragments per texel {fill:.3}");
                }
            }
        }
    }
    Ok(())
}

/// The cost view of a frame in a line (see the module docs, `--stats`).
fn cost_stats(method: Method, frame: &dbuffer::render::Frame) -> String {
    let spec = method.spec().cost;
    let hit: Vec<usize> = (0..frame.len()).filter(|&i| frame.hit(i)).collect();
    if frame.cost.len() != frame.len() || hit.is_empty() {
        return "no cost view".into();
    }
    let n = hit.len() as f64;
    let work: Vec<f64> = hit.iter().map(|&i| f64::from(frame.cost[i][0])).collect();
    let working: Vec<f64> = work.iter().copied().filter(|w| *w > 0.0).collect();
    let mean = work.iter().sum::<f64>() / n;
    let mean_working = working.iter().sum::<f64>() / working.len().max(1) as f64;
    let max = working.iter().copied().fold(0.0, f64::max);
    let paths: Vec<String> = (0..spec.paths.len().max(1))
        .map(|p| {
            let on = hit
                .iter()
                .filter(|&&i| frame.cost[i][1].round() as usize == p)
                .count();
            format!(
                "{} {:.1} %",
                spec.path_name(p as f32),
                100.0 * on as f64 / n
            )
        })
        .collect();
    // 4×2 blocks with a surface, and those where some pixel works.
    let (w, h) = (frame.width as usize, frame.height as usize);
    let (mut blocks, mut busy) = (0usize, 0usize);
    for by in (0..h).step_by(2) {
        for bx in (0..w).step_by(4) {
            let px =
                (by..(by + 2).min(h)).flat_map(|y| (bx..(bx + 4).min(w)).map(move |x| y * w + x));
            let (mut any_hit, mut any_work) = (false, false);
            for i in px {
                any_hit |= frame.hit(i);
                any_work |= frame.hit(i) && frame.cost[i][0] > 0.0;
            }
            blocks += usize::from(any_hit);
            busy += usize::from(any_work);
        }
    }
    format!(
        "{}: mean {mean:.2} (over the {:.1} % of pixels that work {mean_working:.2}), max {max:.0}; \
         4x2 blocks working {:.1} %; paths: {}",
        spec.unit,
        100.0 * working.len() as f64 / n,
        100.0 * busy as f64 / blocks.max(1) as f64,
        paths.join(", ")
    )
}
