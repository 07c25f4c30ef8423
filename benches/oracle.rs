//! Oracle throughput: shadow rays per second on a 5760-triangle caster over a ground plane.
//!
//! The built-in scene `fig8c-complex`: a (2,3) torus knot tube of 240×12 segments (5760
//! triangles) over a ground plane; receivers are a grid of points on the ground under it;
//! K = 1024 rays per point, rayon over all cores.
//!
//!     cargo bench --bench oracle

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use dbuffer::geometry::oracle::{Oracle, DEFAULT_SAMPLES};
use dbuffer::scene;
use glam::Vec3;

fn bench(c: &mut Criterion) {
    let scene = match scene::load("fig8c-complex") {
        Ok(s) => s,
        Err(e) => panic!("the built-in scene fig8c-complex must load: {e}"),
    };
    let oracle = Oracle::from_scene(&scene, DEFAULT_SAMPLES);
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
