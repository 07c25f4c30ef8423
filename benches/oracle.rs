//! Oracle throughput: shadow rays per second on a 5760-triangle caster over a ground plane.
//!
//! The caster is a (2,3) torus knot tube of 240×12 segments (5760 triangles, the shape of the
//! built-in scene `fig8c-complex`), generated here; receivers are a grid of points on the
//! ground under it; K = 1024 rays per point, rayon over all cores.

use std::f32::consts::TAU;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use dbuffer::geometry::oracle::{Oracle, DEFAULT_SAMPLES};
use dbuffer::scene::DiskLight;
use glam::Vec3;

/// A (2,3) torus knot tube, about `1.9` across in XZ, centred at `centre`.
fn torus_knot(tubular: u32, radial: u32, centre: Vec3) -> Vec<[Vec3; 3]> {
    const SCALE: f32 = 0.5;
    let (big, small, tube) = (SCALE, 0.5 * SCALE, 0.3 * SCALE);
    let curve = |t: f32| {
        let w = big + small * (3.0 * t).cos();
        Vec3::new(
            w * (2.0 * t).cos(),
            small * (3.0 * t).sin(),
            w * (2.0 * t).sin(),
        )
    };
    let point = |i: u32, j: u32| {
        let u = TAU * (i % tubular) as f32 / tubular as f32;
        let v = TAU * (j % radial) as f32 / radial as f32;
        let c = curve(u);
        let t = (curve(u + 1e-3) - curve(u - 1e-3)).normalize();
        let b = t.cross(c).normalize();
        let n = b.cross(t);
        centre + c + tube * (v.cos() * n + v.sin() * b)
    };
    let mut tris = Vec::new();
    for i in 0..tubular {
        for j in 0..radial {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    tris
}

fn scene() -> (Vec<[Vec3; 3]>, DiskLight) {
    let mut tris = torus_knot(240, 12, Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(tris.len(), 5760);
    let g = 5.0;
    tris.push([
        Vec3::new(-g, 0.0, -g),
        Vec3::new(g, 0.0, -g),
        Vec3::new(g, 0.0, g),
    ]);
    tris.push([
        Vec3::new(-g, 0.0, -g),
        Vec3::new(g, 0.0, g),
        Vec3::new(-g, 0.0, g),
    ]);
    let light = DiskLight {
        center: Vec3::new(0.0, 4.0, 0.0),
        normal: Vec3::NEG_Y,
        radius: 0.5,
        intensity: 1.0,
    };
    (tris, light)
}

fn bench(c: &mut Criterion) {
    let (tris, light) = scene();
    let oracle = Oracle::new(tris, light, DEFAULT_SAMPLES);
    // Receivers: a 16×16 grid on the ground under the knot (umbra, penumbra and lit).
    let n = 16;
    let xs: Vec<Vec3> = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            let s = |i: usize| -1.4 + 2.8 * (i as f32 + 0.5) / n as f32;
            Vec3::new(s(i), 0.0, s(j))
        })
        .collect();
    let v = oracle.visibility_many(&xs);
    let shadowed = v.iter().filter(|&&v| v < 1.0).count();
    let umbra = v.iter().filter(|&&v| v == 0.0).count();
    eprintln!(
        "oracle bench: {} receivers, {} in shadow ({} umbra), {} BVH nodes",
        xs.len(),
        shadowed,
        umbra,
        oracle.bvh().node_count()
    );
    let rays = (xs.len() * oracle.sample_count()) as u64;
    let mut g = c.benchmark_group("oracle");
    g.throughput(Throughput::Elements(rays));
    g.sample_size(20);
    g.bench_function("knot5760_k1024_par", |b| {
        b.iter(|| oracle.visibility_many(std::hint::black_box(&xs)))
    });
    g.bench_function("knot5760_k1024_1thread", |b| {
        b.iter(|| {
            std::hint::black_box(&xs)
                .iter()
                .map(|&x| oracle.visibility(x))
                .sum::<f32>()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
