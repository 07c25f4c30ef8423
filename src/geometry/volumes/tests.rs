use super::fans::MAX_FAN_TRIANGLES;
use super::*;
use crate::geometry::ray::intersect_triangle;
use crate::scene::Mesh;

fn cube(center: Vec3, half: f32) -> Mesh {
    let positions = (0..8)
        .map(|i| {
            center
                + half
                    * Vec3::new(
                        if i & 1 == 0 { -1.0 } else { 1.0 },
                        if i & 2 == 0 { -1.0 } else { 1.0 },
                        if i & 4 == 0 { -1.0 } else { 1.0 },
                    )
        })
        .collect();
    let triangles = vec![
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
    ];
    Mesh::new(positions, triangles)
}

fn light(r: f32) -> AreaLight {
    AreaLight {
        center: Vec3::new(0.0, 4.0, 0.0),
        normal: Vec3::NEG_Y,
        radius: r,
        intensity: 1.0,
        outline: Outline::Disk,
    }
}

#[test]
fn cube_volumes_are_oriented_and_closed_by_fans() {
    let mesh = CasterMesh::new("cube", &cube(Vec3::new(0.0, 1.5, 0.0), 0.5));
    let l = light(1.0);
    let g = build_caster(&mesh, &l, &VolumeParams::default());
    assert_eq!(g.stats.umbra_edges, 4);
    assert_eq!(g.stats.penumbra_edges, 4);
    assert_eq!(
        g.stats.fans, 4,
        "one penumbra fan per corner of the top rim"
    );
    assert_eq!(
        g.stats.umbra_fans, 4,
        "one umbra fan per corner of the bottom rim"
    );
    assert_eq!(g.stats.silhouette_a, 8);
    assert!(g.warnings.is_empty(), "{:?}", g.warnings);
    for i in 0..g.volumes.triangle_count() {
        let (t, attrs) = g.volumes.triangle(i);
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let facing_c = n.dot(l.center - t[0]) > 0.0;
        match attrs.kind {
            VolumeKind::UmbraQuad | VolumeKind::UmbraFan | VolumeKind::SilhouetteFaceA => {
                assert!(!facing_c)
            }
            VolumeKind::PenumbraQuad | VolumeKind::PenumbraFan => assert!(facing_c),
            VolumeKind::SilhouetteFaceB => {}
        }
    }
    // The penumbra surface is closed: every ray from c that misses the cube crosses it
    // exactly once (quads and fans neither overlap nor leave gaps). Rays (a, −1, b) with
    // |a|, |b| ≤ 0.5 all reach the penumbra; those with |a|, |b| < 0.3 hit the cube first.
    let penumbra: Vec<[Vec3; 3]> = (0..g.volumes.triangle_count())
        .map(|i| g.volumes.triangle(i))
        .filter(|(_, a)| !a.kind.is_umbra())
        .map(|(t, _)| t)
        .collect();
    let mut checked = 0;
    for i in 0..48 {
        for j in 0..48 {
            let (a, b) = (-0.5 + i as f32 / 47.0 + 1e-3, -0.5 + j as f32 / 47.0 + 2e-3);
            if a.abs() < 0.3 && b.abs() < 0.3 {
                continue;
            }
            let dir = Vec3::new(a, -1.0, b).normalize();
            let hits = penumbra
                .iter()
                .filter(|t| intersect_triangle(l.center, dir, t).is_some_and(|s| s > 0.0))
                .count();
            assert_eq!(
                hits, 1,
                "ray {dir} crosses the penumbra surface {hits} times"
            );
            checked += 1;
        }
    }
    assert!(checked > 1000);
}

#[test]
fn volumes_over_the_budget_are_not_built() {
    let mesh = CasterMesh::new("cube", &cube(Vec3::new(0.0, 1.0, 0.0), 0.5));
    let l = light(0.5);
    let params = VolumeParams::default();
    let full = build_caster(&mesh, &l, &params);
    let needed = full.volumes.triangle_count();
    assert!(
        needed > 0 && full.warnings.is_empty(),
        "{:?}",
        full.warnings
    );
    // Exactly enough, give or take a fan (the fans are checked conservatively).
    let roomy = build_caster_within(&mesh, &l, &params, needed + MAX_FAN_TRIANGLES);
    assert_eq!(roomy.volumes.triangle_count(), needed);
    // Too little: no volumes at all (never half of them), and a warning naming the budget.
    for limit in [0, needed / 2, needed - 1] {
        let g = build_caster_within(&mesh, &l, &params, limit);
        assert_eq!(g.volumes.triangle_count(), 0, "limit {limit}");
        assert_eq!(g.classes, full.classes);
        let w = g.warnings.join("\n");
        assert!(
            w.contains("MAX_VOLUME_TRIANGLES") && w.contains("casts no shadow"),
            "{w}"
        );
    }
}

#[test]
fn fan_rim_points_follow_the_shorter_arc() {
    let mesh = CasterMesh::new("cube", &cube(Vec3::new(0.0, 1.5, 0.0), 0.5));
    let l = light(1.0);
    let g = build_caster(&mesh, &l, &VolumeParams::default());
    for v in g
        .volumes
        .vertices
        .iter()
        .filter(|v| v.kind == VolumeKind::PenumbraFan)
    {
        assert!(
            ((v.extrusion - l.center).length() - 1.0).abs() < 1e-4,
            "on the rim"
        );
        // Rim points of the fan at a corner lie on the opposite side of c from the corner.
        let corner = v.edge[0];
        let radial = (v.extrusion - l.center).normalize();
        assert!(
            radial.x * corner.x <= 1e-4 && radial.z * corner.z <= 1e-4,
            "{v:?}"
        );
    }
}

#[test]
fn edge_plane_distance_matches_eq2_in_words() {
    let l = light(1.0);
    // A quad extruded from an edge at height 1.5 (2.5 below the light): any ray from c meets
    // the plane through the edge parallel to the disk at 2.5 / cos(angle to the normal).
    let v = VolumeVertex {
        position: Vec3::ZERO,
        kind: VolumeKind::PenumbraQuad,
        edge: [Vec3::new(-0.5, 1.5, 0.5), Vec3::new(0.5, 1.5, 0.5)],
        extrusion: Vec3::new(0.0, 4.0, -1.0),
    };
    let hit = Vec3::new(0.2, 1.5, 0.5) + 3.0 * (Vec3::new(0.2, 1.5, 0.5) - v.extrusion);
    let dir = (hit - l.center).normalize();
    let expected = 2.5 / dir.dot(l.normal);
    assert!((v.edge_plane_distance(hit, dir, &l) - expected).abs() < 1e-4);
    // A tilted edge: the edge point is the one on the line from the extrusion point.
    let tilted = VolumeVertex {
        edge: [Vec3::new(-0.5, 1.0, 0.5), Vec3::new(0.5, 2.0, 0.5)],
        ..v
    };
    let e = Vec3::new(0.25, 1.75, 0.5);
    let hit = e + 2.0 * (e - v.extrusion);
    let dir = (hit - l.center).normalize();
    let expected = (4.0 - 1.75) / dir.dot(l.normal);
    assert!((tilted.edge_plane_distance(hit, dir, &l) - expected).abs() < 1e-4);
    // A silhouette face is its own edge.
    let face = VolumeVertex {
        kind: VolumeKind::SilhouetteFaceA,
        ..v
    };
    assert!((face.edge_plane_distance(hit, dir, &l) - (hit - l.center).length()).abs() < 1e-5);
}

#[test]
fn caster_through_the_light_plane_warns_without_panicking() {
    let mesh = CasterMesh::new("tall", &cube(Vec3::new(0.3, 4.0, 0.0), 0.5));
    let g = build_caster(&mesh, &light(0.5), &VolumeParams::default());
    assert!(
        g.warnings
            .iter()
            .any(|w| w.contains("reaches the light plane")),
        "{:?}",
        g.warnings
    );
    for v in &g.volumes.vertices {
        assert!(v.position.is_finite());
    }
}
