//! The oracle against closed-form soft shadows: a straight edge (parallel and tilted) and a disk
//! under the disk light.

use std::f32::consts::PI;

use dbuffer::geometry::oracle::{Oracle, DEFAULT_SAMPLES};
use dbuffer::scene::{AreaLight, Outline};
use glam::Vec3;

fn light() -> AreaLight {
    AreaLight {
        center: Vec3::new(0.0, 4.0, 0.0),
        normal: Vec3::NEG_Y,
        radius: 0.5,
        intensity: 1.0,
        outline: Outline::Disk,
    }
}

/// Fraction of the unit disk beyond the chord at signed distance `d` (in radii) from the centre.
fn segment_fraction(d: f32) -> f32 {
    let d = d.clamp(-1.0, 1.0);
    (d.acos() - d * (1.0 - d * d).sqrt()) / PI
}

/// A half-plane occluder as a quad: bounded by the line through `e` along unit `dir`, extending
/// `reach` along unit `w` (perpendicular to `dir`) and `half` both ways along `dir`.
fn half_plane(e: Vec3, dir: Vec3, w: Vec3, half: f32, reach: f32) -> Vec<[Vec3; 3]> {
    let a = e - dir * half;
    let b = e + dir * half;
    let c = b + w * reach;
    let d = a + w * reach;
    vec![[a, b, c], [a, c, d]]
}

/// Exact visible fraction of the light from `p` behind a half-plane occluder bounded by the line
/// through `e` along `dir`, with `q` any point of the occluder. Valid when every segment from `p`
/// to the disk crosses the occluder's plane within the modelled quad: the plane through `p` and
/// the edge line then cuts the disk along a chord and hides exactly one side of it.
fn exact_edge(l: &AreaLight, p: Vec3, e: Vec3, dir: Vec3, q: Vec3) -> f32 {
    let m = dir.cross(e - p);
    let sigma = (m.dot(q - p)).signum();
    let m_par = m - m.dot(l.normal) * l.normal;
    let d = sigma * m.dot(l.center - p) / (m_par.length() * l.radius);
    segment_fraction(d)
}

#[test]
fn straight_edge_parallel_to_the_light() {
    let l = light();
    // Occluder at y = 2 covering x < 0; receivers on y = 0 across the penumbra (|x| < 0.5).
    let e = Vec3::new(0.0, 2.0, 0.0);
    let (dir, w) = (Vec3::Z, Vec3::NEG_X);
    let oracle = Oracle::new(half_plane(e, dir, w, 50.0, 100.0), l, DEFAULT_SAMPLES);
    let mut worst = 0.0f32;
    for i in 0..=200 {
        let p = Vec3::new(-0.8 + 1.6 * i as f32 / 200.0, 0.0, 0.37);
        let exact = exact_edge(&l, p, e, dir, e + w);
        // The hand formula for this setup: the edge projects to the chord x = −p.x.
        let hand = segment_fraction(-p.x / l.radius);
        assert!((exact - hand).abs() < 1e-5, "{exact} vs {hand}");
        let v = oracle.visibility(p);
        worst = worst.max((v - exact).abs());
    }
    eprintln!("max |V - exact| = {worst}");
    assert!(worst < 0.015, "max |V - exact| = {worst}");
}

#[test]
fn straight_edge_tilted_against_the_light() {
    let l = light();
    // An edge rising along z, the occluder's plane tilted too.
    let e = Vec3::new(0.1, 2.0, 0.0);
    let dir = Vec3::new(0.3, 0.25, 1.0).normalize();
    let w0 = Vec3::new(-1.0, 0.15, 0.0);
    let w = (w0 - w0.dot(dir) * dir).normalize();
    let oracle = Oracle::new(half_plane(e, dir, w, 50.0, 100.0), l, DEFAULT_SAMPLES);
    let mut worst = 0.0f32;
    let mut penumbra = 0;
    for i in 0..=200 {
        let p = Vec3::new(-1.0 + 2.0 * i as f32 / 200.0, 0.0, 0.2);
        let exact = exact_edge(&l, p, e, dir, e + w);
        if exact > 0.0 && exact < 1.0 {
            penumbra += 1;
        }
        let v = oracle.visibility(p);
        worst = worst.max((v - exact).abs());
    }
    assert!(penumbra > 50, "the line crosses the penumbra ({penumbra})");
    eprintln!("max |V - exact| = {worst}");
    assert!(worst < 0.015, "max |V - exact| = {worst}");
}

/// A disk of radius `r` centred at `c` in the plane y = c.y, as a fan of `n` triangles.
fn disk(c: Vec3, r: f32, n: usize) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|i| {
            let a0 = 2.0 * PI * i as f32 / n as f32;
            let a1 = 2.0 * PI * (i + 1) as f32 / n as f32;
            [
                c,
                c + r * Vec3::new(a0.cos(), 0.0, a0.sin()),
                c + r * Vec3::new(a1.cos(), 0.0, a1.sin()),
            ]
        })
        .collect()
}

#[test]
fn disk_under_disk_umbra_and_penumbra_radii() {
    let l = light();
    let (big_h, h, r_o) = (4.0f32, 1.5f32, 0.4f32);
    let r = l.radius;
    let occ = disk(l.center - Vec3::Y * h, r_o, 256);
    let oracle = Oracle::new(occ, l, DEFAULT_SAMPLES);
    let umbra = r_o * big_h / h - r * (big_h - h) / h;
    let penumbra = r_o * big_h / h + r * (big_h - h) / h;
    assert!(umbra > 0.1 && penumbra > umbra + 1.0);
    let (edge_margin, inner_margin) = (0.01f32, 0.05f32);
    let mut points = Vec::new();
    for i in 0..=120 {
        let rho = 2.4 * i as f32 / 120.0;
        for k in 0..3 {
            let a = 0.3 + 2.1 * k as f32;
            points.push((rho, Vec3::new(rho * a.cos(), 0.0, rho * a.sin())));
        }
    }
    let xs: Vec<Vec3> = points.iter().map(|p| p.1).collect();
    let vs = oracle.visibility_many(&xs);
    for (&(rho, p), &v) in points.iter().zip(&vs) {
        if rho < umbra - edge_margin {
            assert_eq!(v, 0.0, "umbra at {p} (rho {rho})");
        } else if rho > penumbra + edge_margin {
            assert_eq!(v, 1.0, "lit at {p} (rho {rho})");
        } else if rho > umbra + inner_margin && rho < penumbra - inner_margin {
            assert!(v > 0.0 && v < 1.0, "penumbra at {p} (rho {rho}): {v}");
        }
    }
    // Monotone in the radius (up to sampling noise).
    for w in vs.chunks(3).collect::<Vec<_>>().windows(2) {
        assert!(w[1][0] >= w[0][0] - 0.01);
    }
    assert_eq!(
        oracle.rays_cast(),
        (points.len() * DEFAULT_SAMPLES) as u64,
        "one ray per sample and point"
    );
}

#[test]
fn behind_the_light_is_dark_and_an_empty_scene_is_lit() {
    let l = light();
    let occ = disk(Vec3::new(0.0, 2.0, 0.0), 0.4, 64);
    let oracle = Oracle::new(occ, l, DEFAULT_SAMPLES);
    for p in [
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::new(0.0, 4.5, 0.0),
        Vec3::new(3.0, 10.0, -2.0),
    ] {
        assert_eq!(oracle.visibility(p), 0.0, "{p}");
    }
    let empty = Oracle::new(Vec::new(), l, DEFAULT_SAMPLES);
    for i in 0..20 {
        let p = Vec3::new(i as f32 - 10.0, 3.9 - i as f32, 0.5 * i as f32);
        assert_eq!(empty.visibility(p), 1.0, "{p}");
    }
}

/// A line light over one straight edge: the oracle's stratified segment samples against the
/// closed form of `geometry::line_light` (an infinite edge, modelled by a 200 m quad). One
/// interval of the segment is hidden, so the K-sample estimate is within 2/K of the truth (one
/// straddling stratum at each end).
#[test]
fn line_light_over_an_edge_matches_the_closed_form() {
    use dbuffer::geometry::line_light::{half_plane_visibility, HalfPlane};
    use dbuffer::scene::LineLight;
    let lights = [
        // Parallel to the ground, along x.
        LineLight {
            a: Vec3::new(-1.0, 4.0, 0.0),
            b: Vec3::new(1.0, 4.0, 0.0),
            intensity: 1.0,
        },
        // Tilted (not parallel to the receiver) and skew to the axes.
        LineLight {
            a: Vec3::new(-0.8, 3.2, -0.4),
            b: Vec3::new(1.1, 4.6, 0.5),
            intensity: 1.0,
        },
    ];
    let edges = [
        // Perpendicular to the first light, then oblique, then parallel to it (a hard edge).
        HalfPlane {
            origin: Vec3::new(0.0, 2.0, 0.0),
            along: Vec3::Z,
            into: Vec3::NEG_X,
        },
        HalfPlane {
            origin: Vec3::new(0.1, 2.0, 0.2),
            along: Vec3::new(0.6, 0.0, 0.8),
            into: Vec3::new(0.8, 0.0, -0.6),
        },
        HalfPlane {
            origin: Vec3::new(0.0, 1.5, 0.0),
            along: Vec3::X,
            into: Vec3::NEG_Z,
        },
    ];
    for (li, light) in lights.iter().enumerate() {
        for (ei, edge) in edges.iter().enumerate() {
            let tris = edge.quad(100.0, 100.0).to_vec();
            for k in [64usize, 1024] {
                let oracle = Oracle::new(tris.clone(), *light, k);
                let mut worst = 0.0f64;
                let mut penumbra = 0;
                for i in 0..300 {
                    // A grid over the ground around the shadow's edge (off the grazing
                    // plane of the parallel edge, where a ray exactly touches it).
                    let p = Vec3::new(
                        -2.0 + 4.0 * ((i % 20) as f32 + 0.37) / 20.0,
                        0.0,
                        -2.0 + 4.0 * ((i / 20) as f32 + 0.37) / 15.0,
                    );
                    let exact = half_plane_visibility(light, edge, p);
                    let v = f64::from(oracle.visibility(p));
                    worst = worst.max((v - exact).abs());
                    penumbra += usize::from(exact > 0.01 && exact < 0.99);
                }
                let bound = 2.0 / k as f64 + 1e-4;
                assert!(
                    worst <= bound,
                    "light {li}, edge {ei}, K = {k}: worst |V_K − V| {worst} > {bound}"
                );
                if ei < 2 {
                    assert!(
                        penumbra > 20,
                        "light {li}, edge {ei}: {penumbra} penumbra points"
                    );
                }
            }
        }
    }
}

/// A line light emits all around: a point below, beside or above the segment is lit with no
/// occluder, unlike a one-sided disk.
#[test]
fn a_line_light_lights_every_side() {
    use dbuffer::scene::LineLight;
    let light = LineLight {
        a: Vec3::new(-1.0, 4.0, 0.0),
        b: Vec3::new(1.0, 4.0, 0.0),
        intensity: 1.0,
    };
    let o = Oracle::new(Vec::new(), light, 32);
    for p in [
        Vec3::ZERO,
        Vec3::new(0.0, 8.0, 0.0),
        Vec3::new(3.0, 4.0, 0.0),
    ] {
        assert_eq!(o.visibility(p), 1.0, "{p}");
    }
    assert_eq!(o.visibility(Vec3::new(f32::NAN, 0.0, 0.0)), 0.0);
}
