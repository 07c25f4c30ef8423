use super::*;
use crate::geometry::ray::intersect_triangle;
use proptest::prelude::*;

fn brute_all(tris: &[[Vec3; 3]], o: Vec3, d: Vec3, t0: f32, t1: f32) -> Vec<(u32, u32)> {
    let mut v: Vec<(u32, u32)> = tris
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            intersect_triangle(o, d, t)
                .filter(|&t| t >= t0 && t <= t1)
                .map(|t| (i as u32, t.to_bits()))
        })
        .collect();
    v.sort_unstable();
    v
}

fn brute_closest(tris: &[[Vec3; 3]], o: Vec3, d: Vec3, t0: f32, t1: f32) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for (i, t) in tris.iter().enumerate() {
        if let Some(t) = intersect_triangle(o, d, t).filter(|&t| t >= t0 && t <= t1) {
            if best.is_none_or(|b| t < b.t) {
                best = Some(Hit {
                    t,
                    triangle: i as u32,
                });
            }
        }
    }
    best
}

fn check(tris: &[[Vec3; 3]], bvh: &Bvh, o: Vec3, d: Vec3, t0: f32, t1: f32) {
    let all = brute_all(tris, o, d, t0, t1);
    let mut got = Vec::new();
    bvh.for_each_hit(o, d, t0, t1, |h| got.push((h.triangle, h.t.to_bits())));
    got.sort_unstable();
    assert_eq!(got, all, "all hits, ray {o} {d} [{t0}, {t1}]");
    assert_eq!(bvh.any_hit(o, d, t0, t1), !all.is_empty());
    if let Some(h) = bvh.find_any_hit(o, d, t0, t1) {
        assert!(all.contains(&(h.triangle, h.t.to_bits())));
        assert!(bvh.hits_triangle(h.triangle, o, d, t0, t1));
    }
    for &(i, _) in &all {
        assert!(bvh.hits_triangle(i, o, d, t0, t1));
    }
    let tolerant_any = tris.iter().any(|t| {
        crate::geometry::ray::intersect_triangle_tolerant(o, d, t)
            .is_some_and(|t| t >= t0 && t <= t1)
    });
    let found = bvh.find_any_hit_tolerant(o, d, t0, t1);
    assert_eq!(found.is_some(), tolerant_any);
    if let Some(h) = found {
        assert!(bvh.hits_triangle_tolerant(h.triangle, o, d, t0, t1));
    }
    let c = bvh.closest_hit(o, d, t0, t1);
    let b = brute_closest(tris, o, d, t0, t1);
    assert_eq!(
        c.map(|h| (h.triangle, h.t.to_bits())),
        b.map(|h| (h.triangle, h.t.to_bits()))
    );
}

/// A small deterministic generator for the seeded tests.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn v(&mut self, s: f32) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * 2.0 * s - Vec3::splat(s)
    }
}

#[test]
fn random_soups_match_brute_force() {
    let mut rng = Rng(7);
    for soup in 0..20 {
        let n = [0usize, 1, 2, 3, 17, 100, 500, 2000][soup % 8];
        let size = [0.05f32, 0.3, 1.5][soup % 3];
        let tris: Vec<[Vec3; 3]> = (0..n)
            .map(|_| {
                let c = rng.v(5.0);
                [c + rng.v(size), c + rng.v(size), c + rng.v(size)]
            })
            .collect();
        let bvh = Bvh::build(tris.clone());
        assert_eq!(bvh.len(), n);
        for (i, t) in tris.iter().enumerate() {
            assert_eq!(bvh.triangle(i), t);
        }
        for _ in 0..300 {
            let o = rng.v(7.0);
            // Aim at a triangle half of the time, so hits are common.
            let d = if n > 0 && rng.next() < 0.5 {
                let t = &tris[(rng.next() * n as f32) as usize % n];
                (t[0] + t[1] + t[2]) / 3.0 - o
            } else {
                rng.v(1.0)
            };
            let t1 = [f32::INFINITY, 1.0, 0.5][(rng.next() * 3.0) as usize % 3];
            check(&tris, &bvh, o, d, 0.0, t1);
            check(&tris, &bvh, o, d, 0.3, t1);
        }
    }
}

#[test]
fn degenerate_and_axis_aligned_inputs() {
    // Zero-area triangles, duplicates, a grid of axis-aligned triangles and axis rays.
    let mut tris = vec![
        [Vec3::ZERO; 3],
        [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        [Vec3::ONE, Vec3::ONE, Vec3::new(1.0, 2.0, 1.0)],
    ];
    for i in 0..10 {
        for j in 0..10 {
            let p = Vec3::new(i as f32, j as f32, 0.0);
            tris.push([p, p + Vec3::X, p + Vec3::Y]);
            tris.push([p + Vec3::X, p + Vec3::X + Vec3::Y, p + Vec3::Y]);
        }
    }
    // Many copies of one triangle: centroids coincide, nothing to split.
    for _ in 0..40 {
        tris.push([
            Vec3::splat(3.0),
            Vec3::new(4.0, 3.0, 3.0),
            Vec3::new(3.0, 4.0, 3.0),
        ]);
    }
    let bvh = Bvh::build(tris.clone());
    for i in 0..=20 {
        for j in 0..=20 {
            let o = Vec3::new(i as f32 * 0.5, j as f32 * 0.5, -1.0);
            check(&tris, &bvh, o, Vec3::Z, 0.0, f32::INFINITY);
            check(&tris, &bvh, o, Vec3::Z * 3.0, 0.0, 1.0);
            check(&tris, &bvh, o, Vec3::X, 0.0, f32::INFINITY);
            check(&tris, &bvh, o, Vec3::new(0.3, 0.2, 1.0), 0.0, f32::INFINITY);
        }
    }
    // Odd rays: zero direction, NaN, infinities. No panic, and the same as brute force.
    for (o, d) in [
        (Vec3::ZERO, Vec3::ZERO),
        (Vec3::NAN, Vec3::Z),
        (Vec3::ZERO, Vec3::NAN),
        (Vec3::splat(f32::INFINITY), Vec3::Z),
        (
            Vec3::new(0.5, 0.5, -1.0),
            Vec3::new(0.0, 0.0, f32::INFINITY),
        ),
    ] {
        check(&tris, &bvh, o, d, 0.0, f32::INFINITY);
    }
}

#[test]
fn nan_triangles_do_not_panic() {
    let tris = vec![
        [Vec3::NAN, Vec3::ZERO, Vec3::ONE],
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        [Vec3::splat(f32::INFINITY), Vec3::ZERO, Vec3::Y],
    ];
    let bvh = Bvh::build(tris);
    let _ = bvh.closest_hit(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 0.0, f32::INFINITY);
    let _ = bvh.any_hit(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 0.0, f32::INFINITY);
}

/// A traversal of the flat arrays alone (as the GPU's), with the tolerant test on the
/// stored corner and edges: the same answer as the BVH's own for every ray.
fn flat_any_hit(f: &FlatBvh, o: Vec3, d: Vec3, t0: f32, t1: f32) -> bool {
    let node = |i: usize| (f.nodes[2 * i], f.nodes[2 * i + 1]);
    let enters = |i: usize| {
        let (a, b) = node(i);
        let ray = Ray::new(o, d);
        let n = PackedNode {
            min: Vec4::from_array(a),
            max: Vec4::from_array(b),
        };
        ray.enter(&n, t0, t1).is_some()
    };
    if f.triangle_count() == 0 || !enters(0) {
        return false;
    }
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        if !enters(i) {
            continue;
        }
        let (a, b) = node(i);
        let (first, count) = (a[3].to_bits() as usize, b[3].to_bits() as usize);
        if count == 0 {
            stack.extend([first, first + 1]);
            continue;
        }
        for k in first..first + count {
            let v = |j: usize| {
                Vec3A::from_array([
                    f.triangles[3 * k + j][0],
                    f.triangles[3 * k + j][1],
                    f.triangles[3 * k + j][2],
                ])
            };
            let hit = intersect_edges_tolerant(o.into(), d.into(), v(0), v(1), v(2));
            if hit.is_some_and(|t| t >= t0 && t <= t1) {
                return true;
            }
        }
    }
    false
}

#[test]
fn the_flat_arrays_hold_the_same_tree() {
    let mut rng = Rng(11);
    for n in [0usize, 1, 5, 300] {
        let tris: Vec<[Vec3; 3]> = (0..n)
            .map(|_| {
                let c = rng.v(4.0);
                [c + rng.v(0.5), c + rng.v(0.5), c + rng.v(0.5)]
            })
            .collect();
        let bvh = Bvh::build(tris.clone());
        let f = bvh.flatten();
        assert_eq!(f.node_count(), bvh.node_count());
        assert_eq!(f.triangle_count(), n);
        let mut seen: Vec<u32> = (0..n).map(|k| f.triangles[3 * k][3].to_bits()).collect();
        seen.sort_unstable();
        assert_eq!(
            seen,
            (0..n as u32).collect::<Vec<_>>(),
            "each triangle once"
        );
        for k in 0..n {
            let t = &tris[f.triangles[3 * k][3].to_bits() as usize];
            assert_eq!(f.triangles[3 * k][..3], t[0].to_array()[..]);
        }
        for _ in 0..500 {
            let o = rng.v(6.0);
            let d = if n > 0 && rng.next() < 0.5 {
                let t = &tris[(rng.next() * n as f32) as usize % n];
                (t[0] + t[1] + t[2]) / 3.0 - o
            } else {
                rng.v(1.0)
            };
            assert_eq!(
                flat_any_hit(&f, o, d, 1e-4, 1.0 - 1e-4),
                bvh.find_any_hit_tolerant(o, d, 1e-4, 1.0 - 1e-4).is_some(),
                "ray {o} {d}"
            );
        }
    }
}

#[test]
fn empty_bvh_has_no_hits() {
    let bvh = Bvh::build(Vec::new());
    assert!(bvh.is_empty());
    assert!(!bvh.any_hit(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY));
    assert!(bvh
        .closest_hit(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY)
        .is_none());
}

fn vec3() -> impl Strategy<Value = Vec3> {
    (-4.0f32..4.0, -4.0f32..4.0, -4.0f32..4.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn proptest_matches_brute_force(
        tris in prop::collection::vec((vec3(), vec3(), vec3()).prop_map(|(a, b, c)| [a, b, c]), 0..64),
        rays in prop::collection::vec((vec3(), vec3(), 0.0f32..2.0), 1..16),
    ) {
        let bvh = Bvh::build(tris.clone());
        for (o, d, t1) in rays {
            check(&tris, &bvh, o, d, 0.0, t1);
        }
    }
}
