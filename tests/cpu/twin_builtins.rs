//! The CPU twin of the method against the ray-cast reference over the camera view of the built-in
//! scenes (the metrics of docs/method/metrics.md V(t) exact). Convex casters must be boundary-correct up to pixels
//! on the boundary itself; concave and overlapping casters break Assumption 1 of Jakobsen et al. 2004, and the
//! bounds there pin the D-buffer rules (nearest penumbra entry, nearest umbra exit per caster) that
//! keep them close: the paper's "farthest penumbra wins" fails them. The `fusion-*` scenes are
//! where it fails most; `dbuffer-fused` (its twin, `geometry::fused`) is held to every scene.

use dbuffer::geometry::metrics::{self, Metrics};
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{view, DBufferTwin, PreparedCasters, VolumeParams, VtVariant};
use dbuffer::scene;
use glam::Vec3;

const SIZE: u32 = 64;
const SAMPLES: usize = 256;

fn measure(name: &str) -> Metrics {
    let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    let geometry = PreparedCasters::new(&scene).build(
        scene.light.as_area().expect("a disk light"),
        &VolumeParams::for_scene(&scene),
    );
    let oracle = Oracle::from_scene(&scene, SAMPLES);
    let twin = DBufferTwin::new(&scene, &geometry.casters);
    let pixels = view::receivers(&scene, oracle.bvh(), SIZE, SIZE);
    let mask: Vec<bool> = pixels
        .iter()
        .map(|r| r.is_some_and(|r| r.faces_light))
        .collect();
    let points: Vec<Vec3> = pixels
        .iter()
        .map(|r| r.map_or(Vec3::ZERO, |r| r.position))
        .collect();
    let reference = oracle.visibility_many(&points);
    let method: Vec<f32> = pixels
        .iter()
        .map(|r| {
            r.map_or(0.0, |r| {
                twin.visibility_on(r.position, r.normal, VtVariant::Exact) as f32
            })
        })
        .collect();
    let m = metrics::compare(&reference, &method, &mask);
    println!(
        "{name:<18} mismatch {:5.2} %  MAE {:.4}  penumbra MAE {:.4} ({} px)  confusion {:?}",
        m.class_mismatch_pct, m.mae, m.penumbra_mae, m.penumbra_pixels, m.confusion
    );
    assert!(
        m.pixels > 1000 && m.penumbra_pixels > 50,
        "{name}: the view must show the shadow"
    );
    m
}

#[test]
fn convex_casters_are_boundary_correct() {
    for name in [
        "fig8a-distance",
        "fig8b-light-size",
        "table1-224",
        "table1-960",
        "table1-1440",
        "table1-5760",
        "acute-corner",
    ] {
        let m = measure(name);
        assert!(m.class_mismatch_pct <= 1.0, "{name}: {m:?}");
        assert!(m.penumbra_mae <= 0.06, "{name}: {m:?}");
    }
}

#[test]
fn concave_and_overlapping_casters_stay_close() {
    for name in ["fig7-concave", "overlap", "bunny", "fig8c-complex"] {
        let m = measure(name);
        assert!(m.class_mismatch_pct <= 2.5, "{name}: {m:?}");
        assert!(m.penumbra_mae <= 0.08, "{name}: {m:?}");
    }
}

/// The volume surfaces are closed: welded by position (a fan's end rays are the quads' own, bit
/// for bit), every edge borders two volume triangles except along the silhouette (where the
/// volume meets the caster) and at the far end of the extrusion. A dangling extrusion ray is a
/// hole a ray from the light can slip through to a far exit or entry (fig8c-complex showed them
/// as one-pixel lines in its shadow before every vertex got its fans, and chains touching at a
/// vertex were paired). The one exception: a vertex where an odd number of silhouette edges
/// meet, which happens at the open base of the bunny; one end there has no partner.
#[test]
fn volume_surfaces_are_closed() {
    use std::collections::{HashMap, HashSet};
    let key = |p: Vec3| {
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ]
    };
    for name in scene::builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        if scene.light.as_area().is_none() {
            continue; // the D-buffer's geometry is a disk light's
        }
        let prepared = PreparedCasters::new(&scene);
        let geometry = prepared.build(
            scene.light.as_area().expect("a disk light"),
            &VolumeParams::for_scene(&scene),
        );
        for (g, mesh) in geometry.casters.iter().zip(&prepared.meshes) {
            let on_caster: HashSet<[u32; 3]> = mesh.positions.iter().map(|&v| key(v)).collect();
            for umbra in [true, false] {
                // Vertices where an odd number of this volume's silhouette edges meet.
                let mut degree: HashMap<[u32; 3], usize> = HashMap::new();
                for s in g
                    .silhouettes
                    .iter()
                    .filter(|s| if umbra { s.umbra } else { s.penumbra })
                {
                    for v in s.v {
                        *degree.entry(key(v)).or_default() += 1;
                    }
                }
                let mut edges: HashMap<([u32; 3], [u32; 3]), usize> = HashMap::new();
                for i in 0..g.volumes.triangle_count() {
                    let (t, a) = g.volumes.triangle(i);
                    if a.kind.is_umbra() != umbra || a.kind.is_silhouette_face() {
                        continue;
                    }
                    for k in 0..3 {
                        let (x, y) = (key(t[k]), key(t[(k + 1) % 3]));
                        *edges
                            .entry(if x < y { (x, y) } else { (y, x) })
                            .or_default() += 1;
                    }
                }
                let mut dangling = 0;
                for ((a, b), n) in &edges {
                    let (ca, cb) = (on_caster.contains(a), on_caster.contains(b));
                    if *n != 1 || ca == cb {
                        continue; // shared, a silhouette edge, or a far edge
                    }
                    let apex = if ca { a } else { b };
                    let odd = degree.get(apex).is_some_and(|d| d % 2 == 1);
                    assert!(
                        odd,
                        "{name}/{} {}: an extrusion ray at a vertex with an even number of \
                         silhouette edges borders one triangle: a hole in the surface",
                        g.name,
                        if umbra { "umbra" } else { "penumbra" }
                    );
                    dangling += 1;
                }
                if mesh.report.is_closed_manifold() {
                    assert_eq!(
                        dangling, 0,
                        "{name}/{}: closed casters have closed volumes",
                        g.name
                    );
                }
            }
        }
    }
}

/// The scenes built for occluder fusion, measured here on 2026-11-30: the paper's
/// method loses most of its accuracy there (two chords, many casters, interlocked parts), and
/// these rows pin that: within 25 % of the measured figures, and clearly worse than on the convex
/// scenes. `[name, class mismatch %, penumbra MAE]`.
#[test]
fn fusion_scenes_break_the_one_chord_assumption() {
    let rows: [(&str, f64, f64); 3] = [
        ("fusion-cross", 3.13, 0.0802),
        ("fusion-links", 0.42, 0.0722),
        ("fusion-many", 7.28, 0.2168),
    ];
    for (name, mismatch, mae) in rows {
        let m = measure(name);
        assert!(m.class_mismatch_pct <= mismatch * 1.25, "{name}: {m:?}");
        assert!(
            (mae * 0.75..=mae * 1.25).contains(&m.penumbra_mae),
            "{name}: penumbra MAE {} against {mae} measured",
            m.penumbra_mae
        );
        assert!(m.penumbra_mae > 0.06, "{name} does not show the failure");
    }
}

/// `dbuffer-fused` against the same reference on every built-in, beside the paper's method:
/// penumbra MAE at most 0.012 (the reference's own noise at K = 256 is about 0.005) and p99 |ΔV|
/// at most 0.05 (0.016 and 0.07 under thin slats stacked in depth), and never more than 0.1
/// percentage point more class mismatch than the paper's.
#[test]
fn fused_twin_on_every_built_in() {
    use dbuffer::geometry::fused::{FusedParams, FusedTwin};
    for name in scene::builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        if scene.light.as_area().is_none() {
            continue; // a line light: the D-buffer family refuses it
        }
        let prepared = PreparedCasters::new(&scene);
        let geometry = prepared.build(
            &scene.light.area_or_centre(),
            &VolumeParams::for_scene(&scene),
        );
        let oracle = Oracle::from_scene(&scene, SAMPLES);
        let paper = DBufferTwin::new(&scene, &geometry.casters);
        let fused = FusedTwin::new(&scene, &prepared, &geometry, FusedParams::default());
        let pixels = view::receivers(&scene, oracle.bvh(), SIZE, SIZE);
        let mask: Vec<bool> = pixels
            .iter()
            .map(|r| r.is_some_and(|r| r.faces_light))
            .collect();
        let points: Vec<Vec3> = pixels
            .iter()
            .map(|r| r.map_or(Vec3::ZERO, |r| r.position))
            .collect();
        let reference = oracle.visibility_many(&points);
        let v_paper: Vec<f32> = pixels
            .iter()
            .map(|r| {
                r.map_or(0.0, |r| {
                    paper.visibility_on(r.position, r.normal, VtVariant::Exact) as f32
                })
            })
            .collect();
        let v_fused: Vec<f32> = points.iter().map(|&x| fused.visibility(x) as f32).collect();
        let p = metrics::compare(&reference, &v_paper, &mask);
        let f = metrics::compare(&reference, &v_fused, &mask);
        println!(
            "{name:<18} dbuffer {:5.2} % {:.4} p99 {:.3} | fused {:5.2} % {:.4} p99 {:.3}",
            p.class_mismatch_pct,
            p.penumbra_mae,
            p.p99,
            f.class_mismatch_pct,
            f.penumbra_mae,
            f.p99
        );
        assert!(
            f.penumbra_pixels > 50,
            "{name}: the view must show the shadow"
        );
        // Thin slats stacked in depth put the light several layers deep at most penumbra points,
        // where the fused walk counts its 128 mask samples (docs/method/dbuffer-fused.md).
        let (mae_bound, p99_bound) = match *name {
            "blinds" | "pergola" => (0.016, 0.07),
            _ => (0.012, 0.05),
        };
        assert!(f.penumbra_mae <= mae_bound, "{name}: {f:?}");
        assert!(f.p99 <= p99_bound, "{name}: {f:?}");
        assert!(
            f.class_mismatch_pct <= p.class_mismatch_pct + 0.1,
            "{name}: {f:?} against the paper's {p:?}"
        );
    }
}
