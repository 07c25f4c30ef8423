use glam::{Vec2, Vec3};

use super::mask::wrap;
use super::*;
use crate::geometry::adjacency::CasterMesh;
use crate::geometry::bvh::Bvh;
use crate::geometry::classify::classify;
use crate::geometry::classify::FaceClass;
use crate::geometry::oracle::Oracle;
use crate::geometry::visibility::disk_segment_fraction;
use crate::geometry::PreparedCasters;
use crate::scene::{AreaLight, Scene};
use crate::scene::{Camera, Mesh, Object};

fn light() -> AreaLight {
    AreaLight {
        center: Vec3::new(0.1, 4.0, -0.2),
        normal: Vec3::new(0.05, -1.0, 0.1).normalize(),
        radius: 0.7,
        intensity: 1.0,
        outline: crate::scene::Outline::Disk,
    }
}

/// A box from its centre and half sizes, as a closed mesh.
fn slab(centre: Vec3, half: Vec3) -> Mesh {
    let mut m = crate::scene::shapes::cube();
    for p in &mut m.positions {
        *p = centre + *p * 2.0 * half;
    }
    m
}

fn scene_of(casters: Vec<Mesh>, light: AreaLight) -> Scene {
    let mut objects: Vec<Object> = casters
        .into_iter()
        .enumerate()
        .map(|(i, mesh)| Object {
            name: format!("caster {i}"),
            mesh,
            casts_shadow: true,
        })
        .collect();
    objects.push(Object {
        name: "ground".into(),
        mesh: slab(Vec3::new(0.0, -0.5, 0.0), Vec3::new(10.0, 0.5, 10.0)),
        casts_shadow: false,
    });
    Scene {
        name: "test".into(),
        camera: Camera {
            eye: Vec3::new(0.0, 3.0, 5.0),
            target: Vec3::ZERO,
            fov_y_deg: 45.0,
        },
        light: light.into(),
        objects,
    }
}

fn edges_of(scene: &Scene) -> Vec<FusedEdge> {
    let prepared = PreparedCasters::new(scene);
    prepared
        .meshes
        .iter()
        .enumerate()
        .flat_map(|(k, m)| {
            candidate_edges(m, &classify(m, &scene.light.area_or_centre()), k as u32)
        })
        .collect()
}

/// The chord is where the edge projects from x: every projected point of the edge satisfies
/// the line's equation, and the chord's negative side holds the disk centre.
#[test]
fn chord_is_the_edge_seen_from_the_receiver() {
    let l = light();
    let (e1, e2) = l.basis();
    let x = Vec3::new(0.3, 0.0, 0.4);
    for (a, b) in [
        (Vec3::new(-0.5, 1.5, 0.2), Vec3::new(0.9, 1.7, 0.5)),
        (Vec3::new(0.2, 2.0, -0.4), Vec3::new(0.25, 1.0, 0.6)),
    ] {
        let n = (b - a).cross(x - a).normalize();
        let edge = FusedEdge {
            a,
            b,
            n0: n,
            offset0: n.dot(a) + 1.0, // x behind face 0 ...
            n1: -n,
            offset1: -n.dot(a) - 1.0, // ... and in front of face 1: a silhouette from x
            fold: n,
            layers: 2,
            caster: 0,
            convex: false,
        };
        let ch = edge_chord(&edge, x, &l).expect("a silhouette from x");
        let [ca, cb, cc] = ch.chord;
        assert!(cc < 0.0);
        for t in [0.0, 0.3, 0.7, 1.0] {
            let p = a.lerp(b, t);
            let q = x + (p - x) * (l.height_of(x) / (l.height_of(x) - l.height_of(p)));
            let (u, v) = (
                (q - l.center).dot(e1) / l.radius,
                (q - l.center).dot(e2) / l.radius,
            );
            let value = ca * u + cb * v + cc;
            assert!(
                value.abs() < 1e-4 * (ca.abs() + cb.abs() + cc.abs()),
                "{value}"
            );
        }
    }
}

/// One straight edge parallel to the disk: the exact path gives the disk segment beyond the
/// chord, found by similar triangles.
#[test]
fn one_straight_edge_is_exact() {
    let l = AreaLight {
        center: Vec3::new(0.0, 4.0, 0.0),
        normal: Vec3::NEG_Y,
        radius: 0.5,
        intensity: 1.0,
        outline: crate::scene::Outline::Disk,
    };
    // A wide plate 2 below the light, its edge along z at x = 0, the plate toward −x.
    let plate = slab(Vec3::new(-3.0, 2.0, 0.0), Vec3::new(3.0, 0.01, 3.0));
    let scene = scene_of(vec![plate], l);
    let edges = edges_of(&scene);
    let mask = DiskMask::new(128, MaskEval::Exact);
    for s in [-0.45f32, -0.2, -0.05, 0.1, 0.3, 0.45] {
        let x = Vec3::new(s, 0.0, 0.0);
        // The ray from x through the silhouette edge (the top one, y = 2.01, for s > 0; the
        // bottom one, y = 1.99, for s < 0) meets the light plane at q = s − s·4/(4 − y); the
        // plate hides the disk at x < q.
        let (hx, he) = (4.0f64, if s < 0.0 { 4.0 - 1.99 } else { 4.0 - 2.01 });
        let q = f64::from(s) + (0.0 - f64::from(s)) * hx / (hx - he);
        // The plate hides the part of the disk at x < q (toward −x).
        let expected = 1.0 - disk_segment_fraction(-q / f64::from(l.radius));
        // The ray from x to the centre passes under the plate (two layers) when s < 0.
        let lc = if s < 0.0 { 2 } else { 0 };
        let m = mask_visibility(&edges, x, CentreLayers::Known(lc), &l, &mask);
        let exact = m.exact.expect("one layer deep");
        assert!(
            (exact - expected).abs() < 2e-3,
            "s = {s}: {exact} against {expected}"
        );
        assert!((m.v_samples() - expected).abs() < 0.04, "s = {s}: {m:?}");
    }
}

/// Two bars at different heights crossing in the light's view: the method with the oracle's
/// own samples sees the same samples hidden, where each bar alone would hide a strip.
#[test]
fn two_crossing_bars_hide_the_union_of_their_strips() {
    let l = light();
    let scene = scene_of(
        vec![
            slab(Vec3::new(0.0, 2.4, 0.0), Vec3::new(1.5, 0.05, 0.12)),
            slab(Vec3::new(0.1, 1.2, 0.0), Vec3::new(0.1, 0.05, 1.5)),
        ],
        l,
    );
    let edges = edges_of(&scene);
    let oracle = Oracle::from_scene(&scene, 256);
    let mask = DiskMask::new(256, MaskEval::Exact);
    let casters = Bvh::build(
        scene
            .casters()
            .flat_map(|o| o.mesh.triangle_corners())
            .collect(),
    );
    let mut fused_points = 0;
    for i in 0..21 {
        for j in 0..21 {
            let x = Vec3::new(-1.0 + 0.1 * i as f32, 0.0, -1.0 + 0.1 * j as f32);
            let d = l.center - x;
            let mut lc = 0;
            casters.for_each_hit(x, d, 1e-4, 1.0 - 1e-4, |_| lc += 1);
            let m = mask_visibility(&edges, x, CentreLayers::Known(lc), &l, &mask);
            let v = f64::from(oracle.visibility(x));
            assert!(
                (m.v_samples() - v).abs() <= 2.0 / 256.0,
                "{x}: {} samples visible, the oracle {v}",
                m.visible
            );
            fused_points += usize::from(m.exact.is_none() && v > 0.0 && v < 1.0);
        }
    }
    assert!(
        fused_points > 10,
        "points where both bars hide the disk: {fused_points}"
    );
}

/// `region_area` against a grid count of the same region.
#[test]
fn region_area_matches_a_grid_count() {
    let n = 600;
    for (p, q) in [
        (Vec2::new(-1.5, 0.4), Vec2::new(1.5, 0.3)),
        (Vec2::new(0.2, 0.1), Vec2::new(0.9, -0.6)),
        (Vec2::new(-0.3, 0.5), Vec2::new(0.6, 2.0)),
        (Vec2::new(0.5, 0.5), Vec2::new(0.5, -0.5)),
        (Vec2::new(2.0, 2.0), Vec2::new(3.0, 1.0)),
    ] {
        let (a, b, c) = {
            let n = (q - p).perp();
            let n = if n.dot(-p) > 0.0 { -n } else { n };
            (n.x, n.y, -n.dot(p))
        };
        let ch = EdgeChord {
            chord: [a, b, c],
            end_a: [p.y, -p.x],
            end_b: [q.y, -q.x],
            delta: 2,
            area: 0.0,
            ends: [p, q],
        };
        let mut inside = 0usize;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new(
                    -1.0 + 2.0 * (i as f32 + 0.5) / n as f32,
                    -1.0 + 2.0 * (j as f32 + 0.5) / n as f32,
                );
                inside += usize::from(u.length() <= 1.0 && ch.contains(u));
            }
        }
        let grid = inside as f64 * 4.0 / (n * n) as f64 / std::f64::consts::PI;
        let exact = region_area(p, q);
        assert!(
            (grid - exact).abs() < 2e-3,
            "{p} {q}: {exact} against {grid}"
        );
    }
}

/// The look-up tables differ from the exact test only on samples next to a line.
#[test]
fn lut_masks_agree_with_the_exact_test() {
    let (exact, lut) = (
        DiskMask::new(128, MaskEval::Exact),
        DiskMask::new(128, MaskEval::Lut),
    );
    let mut worst = 0;
    for k in 0..200 {
        let f = k as f32;
        let phi = f * 2.399;
        let rho = (f * 0.618).fract() * 0.95 + 0.02;
        let (s, c) = phi.sin_cos();
        let ch = EdgeChord {
            chord: [c, s, -rho],
            end_a: [(phi + 0.7).sin(), -(phi + 0.7).cos()],
            end_b: [(phi - 1.1).sin(), -(phi - 1.1).cos()],
            delta: 2,
            area: 0.0,
            ends: [Vec2::ZERO; 2],
        };
        let (mut a, mut b) = (vec![0; 128], vec![0; 128]);
        exact.add_region(&ch, &mut a);
        lut.add_region(&ch, &mut b);
        worst = worst.max(a.iter().zip(&b).filter(|(x, y)| x != y).count());
    }
    assert!(worst <= 3, "{worst} samples differ");
}

/// A sphere under a light wider than itself: the edges between two silhouette faces are
/// candidates (they are silhouettes from some disk points) though neither the umbra nor the
/// penumbra silhouette; edges between two all-frontfacing faces are not.
#[test]
fn candidates_include_edges_between_silhouette_faces() {
    let l = AreaLight {
        radius: 1.5,
        ..light()
    };
    let mut sphere = crate::scene::shapes::sphere(24, 12);
    for p in &mut sphere.positions {
        *p = *p * 0.6 + Vec3::new(0.0, 2.0, 0.0);
    }
    let mesh = CasterMesh::new("sphere", &sphere);
    let classes = classify(&mesh, &l);
    let edges = candidate_edges(&mesh, &classes, 0);
    let (mut between_silhouette_faces, mut all_front) = (0, 0);
    for e in &mesh.edges {
        let (c0, c1) = (classes[e.faces[0] as usize], classes[e.faces[1] as usize]);
        let a = mesh.position(e.v[0]);
        let listed = edges
            .iter()
            .any(|f| f.a == a && f.b == mesh.position(e.v[1]));
        if c0.is_silhouette_face() && c1.is_silhouette_face() {
            between_silhouette_faces += 1;
            assert!(listed);
        }
        if c0 == FaceClass::AllFront && c1 == FaceClass::AllFront {
            all_front += 1;
            assert!(!listed);
        }
    }
    assert!(between_silhouette_faces > 20 && all_front > 20);
}

/// Every list texel whose test accepts an edge lies inside the projection of the edge's
/// proxy (what the GPU rasterises), padded by three list texels' footprint: the proxy loses
/// no list entry. Checked on every texel of a coarse grid over three built-ins.
#[test]
fn wedge_proxies_hold_every_accepted_texel() {
    for name in ["fig8c-complex", "overlap", "fusion-many"] {
        let Ok(scene) = crate::scene::load(name) else {
            panic!("{name} loads");
        };
        let prepared = PreparedCasters::new(&scene);
        let geometry = prepared.build(
            &scene.light.area_or_centre(),
            &crate::geometry::VolumeParams::for_scene(&scene),
        );
        let params = FusedParams {
            list_size: 96,
            ..FusedParams::default()
        };
        let twin = FusedTwin::new(&scene, &prepared, &geometry, params);
        let l = scene.light.area_or_centre();
        let h_max = max_receiver_height(&scene, &l);
        let half_slope = 0.5 * twin.view_slope.length() / 96.0;
        let vp = twin.vp;
        let project = |p: Vec3| {
            let c = vp * p.extend(1.0);
            Vec2::new(c.x, c.y) / c.w
        };
        let mut accepted = 0;
        for ty in 0..96u32 {
            for tx in 0..96u32 {
                let Some(ray) = twin.texel_ray_of([tx, ty]) else {
                    continue;
                };
                let ndc = project(l.center + ray.dir);
                for (k, e) in twin.edges().iter().enumerate() {
                    if !edge_in_texel(e, &ray, &l) {
                        continue;
                    }
                    accepted += 1;
                    let pad = proxy_pad(e, &l, half_slope);
                    let [o0, o1] = wedge_proxy(e, &l, h_max, pad);
                    let pts: Vec<Vec2> = o0.iter().chain(&o1).map(|&p| project(p)).collect();
                    assert!(
                        inside_hull(ndc, &pts),
                        "{name}: texel {tx},{ty} accepts edge {k} outside its proxy"
                    );
                    // The polygon the GPU draws (counter-clockwise) holds it too.
                    let poly = proxy_hull(e, &l, h_max, pad, &vp);
                    let inside_polygon = (0..poly.len()).all(|i| {
                        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                        (b - a).perp_dot(ndc - a) >= -1e-6
                    });
                    assert!(
                        poly.len() <= 16 && inside_polygon,
                        "{name}: texel {tx},{ty} accepts edge {k} outside its drawn proxy"
                    );
                }
            }
        }
        assert!(accepted > 1000, "{name}: {accepted}");
    }
}

fn inside_hull(p: Vec2, pts: &[Vec2]) -> bool {
    // Inside the convex hull iff no line through two of the points has all of them on one
    // side and p strictly on the other.
    for (i, &a) in pts.iter().enumerate() {
        for &b in &pts[i + 1..] {
            let side = |q: Vec2| (b - a).perp_dot(q - a);
            let (lo, hi) = pts.iter().fold((0.0f32, 0.0f32), |(lo, hi), &q| {
                (lo.min(side(q)), hi.max(side(q)))
            });
            let s = side(p);
            if (lo >= -1e-7 && s < -1e-6) || (hi <= 1e-7 && s > 1e-6) {
                return false;
            }
        }
    }
    true
}

/// The light as seen from a point, on the knot's ground where two loops fuse: its layers
/// give the method's visible samples, each chord's line passes through its projected ends,
/// and the path says where the mask did not run.
#[test]
fn the_light_from_a_point_is_what_the_mask_saw() {
    let Ok(scene) = crate::scene::load("fig8c-complex") else {
        panic!("fig8c-complex loads");
    };
    let prepared = PreparedCasters::new(&scene);
    let geometry = prepared.build(
        &scene.light.area_or_centre(),
        &crate::geometry::VolumeParams::for_scene(&scene),
    );
    let twin = FusedTwin::new(&scene, &prepared, &geometry, FusedParams::default());
    let (mut masked, mut fused) = (0, 0);
    for i in 0..40 {
        for j in 0..40 {
            let x = Vec3::new(-1.2 + 0.06 * i as f32, 0.0, -1.2 + 0.06 * j as f32);
            let l = twin.light_from(x);
            let s = twin.sample(x);
            assert_eq!((l.v, l.path), (s.v, s.path));
            if l.path != FusedPath::Mask {
                assert!(l.chords.is_empty() && l.layers.is_empty());
                continue;
            }
            masked += 1;
            let m = s.mask.expect("the mask ran");
            assert_eq!(l.layers.len(), l.samples.len());
            let lit = l.layers.iter().filter(|&&k| k <= 0).count() as u32;
            assert_eq!(lit, m.visible, "{x}");
            fused += usize::from(l.layers.iter().any(|&k| k > 2));
            for c in &l.chords {
                let [a, b, cc] = c.chord.chord;
                let scale = a.abs() + b.abs() + cc.abs();
                for p in c.chord.ends {
                    let on = a * p.x + b * p.y + cc;
                    assert!(on.abs() <= 1e-3 * scale * (1.0 + p.length()), "{x}: {on}");
                }
                assert!(twin.edges()[c.edge as usize].caster == c.caster);
            }
        }
    }
    assert!(masked > 100 && fused > 0, "{masked} masked, {fused} fused");
}

#[test]
fn counters_wrap_like_the_gpus() {
    assert_eq!(wrap(15), 15);
    assert_eq!(wrap(16), -16);
    assert_eq!(wrap(-17), 15);
    assert_eq!(wrap(3 - 4), -1);
}
