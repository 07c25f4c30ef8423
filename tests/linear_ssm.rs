//! `linear-ssm` (seed 003): its skins on the GPU against their CPU twin, its convergence to the
//! line reference as the samples grow, and the artefacts the paper admits.

use dbuffer::geometry::light_view::LightView;
use dbuffer::geometry::ssm::{self, SKIN_TAU};
use dbuffer::render::gpu_scene::GpuScene;
use dbuffer::render::methods::linear_ssm::sample_points;
use dbuffer::render::passes::sample_maps::{lights_at, SampleMaps};
use dbuffer::render::passes::shadow_map::{BIAS_CONSTANT, BIAS_SLOPE};
use dbuffer::render::passes::ssm::{Ssm, SsmSample, MAX_SSM_SKINS};
use dbuffer::render::readback::{f32s, map_now, Readback, TextureRead};
use dbuffer::render::timer::Recorder;
use dbuffer::render::GpuContext;
use dbuffer::scene;
use glam::{Mat4, Vec3};

/// Read a whole buffer back.
fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Vec<u8> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test::staging"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue.submit([encoder.finish()]);
    staging
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.unwrap());
    map_now(&ctx.device).unwrap();
    let bytes = staging.slice(..).get_mapped_range().unwrap().to_vec();
    bytes
}

/// A skin triangle: its cell, its corners (0–3 in the cell), its first corner's world point
/// and its values.
struct Tri {
    cell: u32,
    corners: [u32; 3],
    first: Vec3,
    values: [f32; 3],
}

/// The GPU's skins of the last sample's map are the twin's, triangle for triangle.
#[test]
fn gpu_skins_are_the_twins() {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    for name in ["line-fig2", "line-fig9"] {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let line = *scene.light.as_line().unwrap();
        let view = LightView::fit(&scene);
        let size = 96;
        let n = 2;
        let points = sample_points(&line, n);
        let lights = lights_at(
            line.midpoint(),
            &points,
            &view,
            size,
            (BIAS_CONSTANT, BIAS_SLOPE),
        );
        let surfaces = GpuScene::new(&ctx.device, &scene);
        let mut maps = SampleMaps::new(&ctx);
        let mut ssm_state = Ssm::new(&ctx);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let mut rec = Recorder::new(&mut encoder, None);
        maps.record(&ctx, &mut rec, &surfaces, &lights);
        let t = maps.targets().unwrap();
        let samples: Vec<SsmSample> = (0..n as usize)
            .map(|k| {
                let l = lights.lights[k];
                SsmSample::new(
                    Mat4::from_cols_array_2d(&l.view_proj),
                    Vec3::from(l.point),
                    k as u32,
                    n,
                    size,
                    view.far,
                )
            })
            .collect();
        ssm_state
            .record(
                &ctx,
                &mut rec,
                (&t.texture, &t.array_view, t.generation),
                &samples,
            )
            .unwrap();
        ctx.queue.submit([encoder.finish()]);
        // The last map (layer n − 1), through a copy of its layer.
        let layer = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("test::layer"),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.copy_texture_to_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &t.texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: n - 1,
                },
                aspect: wgpu::TextureAspect::All,
            },
            layer.as_image_copy(),
            layer.size(),
        );
        ctx.queue.submit([encoder.finish()]);
        let mut readback = Readback::default();
        let map = f32s(
            &readback
                .read(&ctx, &[TextureRead::color(&layer, 4)])
                .unwrap()[0],
        );
        let l = lights.lights[n as usize - 1];
        let inverse = Mat4::from_cols_array_2d(&l.view_proj).inverse();
        let twin = ssm::skins(&map, size, inverse, Vec3::from(l.point), view.far, SKIN_TAU);

        let (skins, counts) = ssm_state.skin_buffers();
        let counts: Vec<u32> = bytemuck::cast_slice(&read_buffer(&ctx, counts)).to_vec();
        let verts: Vec<[u32; 8]> = bytemuck::cast_slice(&read_buffer(&ctx, skins)).to_vec();
        let found = counts[0] as usize;
        assert!(
            found < MAX_SSM_SKINS as usize,
            "{name}: {found} skins overflow"
        );
        println!(
            "{name}: {} discontinuous cells, {found} skins (twin {})",
            counts[1],
            twin.len()
        );
        assert_eq!(found, twin.len(), "{name}: skin count");
        assert!(found > 20, "{name}: the casters' edges make skins");
        // Same triangles: sorted by (cell, corners), their first corner and values compared.
        let mut gpu: Vec<Tri> = (0..found)
            .map(|i| {
                let c = |k: usize| verts[3 * i + k];
                let f = |k: usize, j: usize| f32::from_bits(c(k)[j]);
                Tri {
                    cell: c(0)[4],
                    corners: [c(0)[5], c(1)[5], c(2)[5]],
                    first: Vec3::new(f(0, 0), f(0, 1), f(0, 2)),
                    values: [f(0, 3), f(1, 3), f(2, 3)],
                }
            })
            .collect();
        let mut cpu: Vec<Tri> = twin
            .iter()
            .map(|t| {
                let x0 = t.iter().map(|c| c.texel[0]).min().unwrap_or(0);
                let y0 = t.iter().map(|c| c.texel[1]).min().unwrap_or(0);
                Tri {
                    cell: y0 * size + x0,
                    corners: t.map(|c| (c.texel[0] - x0) + 2 * (c.texel[1] - y0)),
                    first: t[0].position,
                    values: t.map(|c| c.value),
                }
            })
            .collect();
        gpu.sort_by_key(|t| (t.cell, t.corners));
        cpu.sort_by_key(|t| (t.cell, t.corners));
        for (g, c) in gpu.iter().zip(&cpu) {
            assert_eq!(
                (g.cell, g.corners),
                (c.cell, c.corners),
                "{name}: cells, corners"
            );
            assert_eq!(g.values, c.values, "{name}: values 0 near, 1 far");
            assert!(
                (g.first - c.first).length() <= 1e-3 * c.first.length().max(1.0),
                "{name}: corner {} vs twin {}",
                g.first,
                c.first
            );
        }
    }
}
