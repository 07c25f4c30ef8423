//! Which engine should cast the reference's shadow rays: the CPU oracle (BVH, rayon) or a GPU
//! compute twin? This measures both on the same points and disk samples of a built-in scene:
//! the oracle's rays/s, and a brute-force any-hit compute shader's rays/s (every ray against
//! every triangle: no BVH, the simplest GPU twin) on the wgpu adapter at hand.
//!
//! `cargo run --release --example gpu_rays -- fig8c-complex 4096 64`
//! (scene, points, samples per point).
//!
//! Known: on `fig8c-complex` under lavapipe this probe blocks 4 of 16 samples that the oracle
//! and a CPU brute-force pass over the same triangles both see (table1 scenes agree exactly);
//! the cause is not found. Its rays/s is an upper bound either way (a blocked ray stops early).

use std::time::Instant;

use dbuffer::geometry::oracle::Oracle;
use dbuffer::render::GpuContext;
use dbuffer::scene;
use glam::Vec3;
use wgpu::util::DeviceExt;

const SHADER: &str = r#"
struct Params { points: u32, samples: u32, triangles: u32, _pad: u32 };
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> tris: array<vec4<f32>>;     // 3 per triangle
@group(0) @binding(2) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> samples: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> visible: array<u32>;

// Möller–Trumbore with det-scaled barycentrics (no division), as the CPU's test: a division by
// a tiny det turns near-degenerate triangles into phantom occluders.
fn hit(o: vec3<f32>, d: vec3<f32>, i: u32) -> bool {
    let a0 = tris[3u * i].xyz;
    let e1 = tris[3u * i + 1u].xyz - a0;
    let e2 = tris[3u * i + 2u].xyz - a0;
    let p = cross(d, e2);
    let det = dot(e1, p);
    let sgn = select(-1.0, 1.0, det >= 0.0);
    let big = abs(det);
    if big == 0.0 { return false; }
    let s = o - a0;
    let a = dot(s, p) * sgn;
    if a < 0.0 || a > big { return false; }
    let q = cross(s, e1);
    let b = dot(d, q) * sgn;
    if b < 0.0 || a + b > big { return false; }
    let t = dot(e2, q) * sgn;
    return t > 1e-4 * big && t < (1.0 - 1e-4) * big;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    if p >= params.points { return; }
    let x = points[p].xyz;
    var count = 0u;
    for (var s = 0u; s < params.samples; s++) {
        let d = samples[s].xyz - x;
        var blocked = false;
        for (var i = 0u; i < params.triangles; i++) {
            if hit(x, d, i) { blocked = true; break; }
        }
        if !blocked { count += 1u; }
    }
    visible[p] = count;
}
"#;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("fig8c-complex", String::as_str);
    let n_points: usize = args.get(1).map_or(Ok(4096), |s| s.parse())?;
    let k: usize = args.get(2).map_or(Ok(64), |s| s.parse())?;
    let scene = scene::load(name)?;
    let oracle = Oracle::from_scene(&scene, k);
    // Points on the scene's surfaces under the camera: a grid of pixels' first hits.
    let side = (n_points as f64).sqrt().ceil() as u32;
    let receivers = dbuffer::geometry::view::receivers(&scene, oracle.bvh(), side, side);
    let points: Vec<Vec3> = receivers.iter().flatten().map(|r| r.position).collect();
    let tris = scene.all_triangles();

    let t = Instant::now();
    let cpu = oracle.visibility_many(&points);
    let cpu_s = t.elapsed().as_secs_f64();
    let rays = (points.len() * k) as f64;
    println!(
        "{name}: {} points × {k} samples, {} triangles",
        points.len(),
        tris.len()
    );
    println!(
        "CPU oracle (BVH, {} threads): {:.1} M rays/s",
        rayon::current_num_threads(),
        rays / cpu_s / 1e6
    );

    let ctx = GpuContext::headless()?;
    let device = &ctx.device;
    let vec4 = |v: Vec3| [v.x, v.y, v.z, 0.0f32];
    let tri_data: Vec<[f32; 4]> = tris.iter().flat_map(|t| t.map(vec4)).collect();
    let point_data: Vec<[f32; 4]> = points.iter().map(|&p| vec4(p)).collect();
    let sample_data: Vec<[f32; 4]> = oracle.sample_points().iter().map(|&p| vec4(p)).collect();
    let storage = |data: &[[f32; 4]]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let params = [points.len() as u32, k as u32, tris.len() as u32, 0];
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let out_size = (points.len() * 4) as u64;
    let visible = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: out_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: out_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let buffers = [
        &params,
        &storage(&tri_data),
        &storage(&point_data),
        &storage(&sample_data),
        &visible,
    ];
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    // Twice: the first dispatch includes the driver's shader compilation; the second is timed.
    let run = || -> anyhow::Result<(Vec<u32>, f64)> {
        let t = Instant::now();
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(points.len().div_ceil(64) as u32, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&visible, 0, &staging, 0, out_size);
        ctx.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        device.poll(wgpu::PollType::wait_indefinitely())?;
        let counts: Vec<u32> = bytemuck::cast_slice(&slice.get_mapped_range()?).to_vec();
        staging.unmap();
        Ok((counts, t.elapsed().as_secs_f64()))
    };
    run()?;
    let (counts, gpu_s) = run()?;
    let agree = counts
        .iter()
        .zip(&cpu)
        .filter(|(&c, &v)| (c as f32 / k as f32 - v).abs() <= 2.0 / k as f32)
        .count();
    println!(
        "GPU brute force ({}): {:.2} M rays/s ({:.2} G ray-triangle tests/s at most); agrees with the oracle on {:.1} % of points",
        ctx.adapter_description(),
        rays / gpu_s / 1e6,
        rays * tris.len() as f64 / gpu_s / 1e9,
        100.0 * agree as f64 / points.len() as f64
    );
    Ok(())
}
