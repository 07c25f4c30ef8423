//! Steady-state frame timings of the render core (the first frames include the driver's shader
//! compilation): geometry rebuilt, and GPU ms per pass from timestamp queries, medians over
//! frames. The seed for `dbuffer bench`.
//!
//!     cargo run --release --example frame_timings -- table1-224 table1-960 table1-5760 --size 600 --frames 12

use std::time::Instant;

use dbuffer::geometry::{PreparedCasters, VolumeParams, VtVariant};
use dbuffer::render::session::Session;
use dbuffer::render::{FrameRequest, GpuContext, Method};
use dbuffer::scene;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str, default: u32| -> anyhow::Result<u32> {
        match args.iter().position(|a| a == flag) {
            Some(i) => Ok(args
                .get(i + 1)
                .ok_or_else(|| anyhow::anyhow!("{flag} needs a value"))?
                .parse()?),
            None => Ok(default),
        }
    };
    let size = value("--size", 600)?;
    let frames = value("--frames", 12)?.max(3);
    let names: Vec<&String> = args
        .iter()
        .enumerate()
        .filter(|(i, a)| !a.starts_with("--") && (*i == 0 || !args[i - 1].starts_with("--")))
        .map(|(_, a)| a)
        .collect();
    let ctx = GpuContext::headless()?;
    println!(
        "adapter {}; {size}x{size}, D-buffer 1024², median of {frames} frames after 2 warm-up",
        ctx.adapter_description()
    );
    println!("| scene | caster tris | geometry ms (CPU) | light pass ms (GPU) | camera pass ms (GPU) | frame ms (wall, with readback) |");
    println!("|---|---|---|---|---|---|");
    for name in names {
        let scene = scene::load(name)?;
        let prepared = PreparedCasters::new(&scene);
        let params = VolumeParams::for_scene(&scene);
        let geometry_ms = median(
            (0..frames)
                .map(|_| {
                    let t = Instant::now();
                    let g = prepared.build(&scene.light, &params);
                    std::hint::black_box(g);
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect(),
        );
        let tris = scene.caster_triangle_count();
        let mut session = Session::new(&ctx, scene);
        let request = FrameRequest {
            width: size,
            height: size,
            dbuffer_size: 1024,
            method: Method::DBuffer,
            vt: VtVariant::Smoothstep,
            ..FrameRequest::default()
        };
        let (mut light, mut camera, mut wall) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..frames + 2 {
            let t = Instant::now();
            let frame = session.frame(&ctx, &request)?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            if i >= 2 {
                wall.push(ms);
                for (pass, ms) in frame.gpu_ms {
                    match pass.as_str() {
                        "light_pass" => light.push(ms),
                        "camera_pass" => camera.push(ms),
                        _ => {}
                    }
                }
            }
        }
        println!(
            "| `{name}` | {tris} | {geometry_ms:.3} | {:.1} | {:.1} | {:.1} |",
            median(light),
            median(camera),
            median(wall)
        );
    }
    Ok(())
}
