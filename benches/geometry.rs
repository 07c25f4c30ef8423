//! Geometry stage cost per light move: classification + silhouettes + volumes, for casters of
//! 224 to 1M triangles (Jakobsen et al. 2004, Table 1 sizes, then scaling). Adjacency (welding, edges) is built
//! once per mesh and timed separately.
//!
//!     cargo bench --bench geometry

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use dbuffer::geometry::volumes::build_caster;
use dbuffer::geometry::{CasterMesh, VolumeParams};
use dbuffer::scene::{self, shapes, AreaLight, Mesh, Outline};
use glam::{Affine3A, Vec3};

fn light() -> AreaLight {
    AreaLight {
        center: Vec3::new(0.3, 4.0, -0.2),
        normal: Vec3::new(0.1, -1.0, 0.05).normalize(),
        radius: 0.6,
        intensity: 1.0,
        outline: Outline::Disk,
    }
}

fn placed(mesh: Mesh) -> Mesh {
    mesh.transformed(&Affine3A::from_translation(Vec3::new(0.0, 1.5, 0.0)))
}

fn casters() -> Vec<(String, Mesh)> {
    let mut list = vec![
        ("sphere-224".to_string(), placed(shapes::sphere(16, 8))),
        ("sphere-960".to_string(), placed(shapes::sphere(32, 16))),
        (
            "rounded-box-1440".to_string(),
            placed(shapes::rounded_box(48, 16)),
        ),
        (
            "rounded-box-5760".to_string(),
            placed(shapes::rounded_box(96, 31)),
        ),
    ];
    if let Ok(s) = scene::load("fig8c-complex") {
        if let Some(o) = s.casters().next() {
            list.push(("knot-5760".to_string(), o.mesh.clone()));
        }
    }
    list.push(("sphere-100k".to_string(), placed(shapes::sphere(250, 201))));
    list.push(("sphere-1M".to_string(), placed(shapes::sphere(1000, 501))));
    list
}

fn geometry(c: &mut Criterion) {
    let light = light();
    let params = VolumeParams::default();
    let mut group = c.benchmark_group("volumes");
    group.sample_size(20);
    for (name, mesh) in casters() {
        let caster = CasterMesh::new(&name, &mesh);
        group.throughput(Throughput::Elements(mesh.triangles.len() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(&name), &caster, |b, m| {
            b.iter(|| build_caster(m, &light, &params))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("prepare");
    group.sample_size(10);
    for (name, mesh) in casters()
        .into_iter()
        .filter(|(n, _)| n.contains("5760") || n.contains("1M"))
    {
        group.throughput(Throughput::Elements(mesh.triangles.len() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(&name), &mesh, |b, m| {
            b.iter(|| CasterMesh::new("caster", m))
        });
    }
    group.finish();
}

criterion_group!(benches, geometry);
criterion_main!(benches);
