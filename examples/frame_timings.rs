//! Per-pass GPU timings of the render core for a few methods, with the light-space passes made
//! again every frame (medians after two warm-up frames): the quick loop for tuning a pass, where
//! `dbuffer bench` is the whole report.
//!
//!     cargo run --release --example frame_timings -- table1-960 table1-5760 --size 1024 --frames 8 --methods dbuffer,hard

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
    let ctx = GpuContext::headless()?;
    println!(
        "adapter {}; {size}², D-buffer 1024², median of {frames} frames after 2 warm-up",
        ctx.adapter_description()
    );
    for name in names {
        let scene = scene::load(name)?;
        let mut session = Session::new(&ctx, scene);
        for &method in &methods {
            let request = FrameRequest {
                width: size,
                height: size,
                dbuffer_size: 1024,
                method,
                vt: VtVariant::Smoothstep,
                ..FrameRequest::default()
            };
            let mut passes: Vec<(String, Vec<f64>)> = Vec::new();
            for i in 0..frames + 2 {
                session.invalidate_light_maps();
                let frame = session.frame(&ctx, &request)?;
                if i < 2 {
                    continue;
                }
                for (pass, ms) in frame.gpu_ms {
                    match passes.iter_mut().find(|(p, _)| *p == pass) {
                        Some((_, v)) => v.push(ms),
                        None => passes.push((pass, vec![ms])),
                    }
                }
            }
            let cells: Vec<String> = passes
                .into_iter()
                .map(|(p, v)| format!("{p} {:.2}", median(v)))
                .collect();
            println!("{name:<14} {method:<15} {}", cells.join("  "));
        }
    }
    Ok(())
}
