//! Built-in shapes (closed, 2-manifold, welded, outward) and built-in scenes (load, exact caster
//! triangle counts, convexity, placement under the light, the property each scene is for).

use dbuffer::geometry::ray::intersect_triangle;
use dbuffer::scene::{builtin, load, shapes, AreaLight, Light, Mesh, Scene};
use glam::Vec3;
use std::collections::{HashMap, HashSet};

/// Every closed shape with a few parameter choices (defaults, small, odd).
const CLOSED: &[&str] = &[
    "cube",
    "sphere",
    "sphere:3x2",
    "sphere:16x8",
    "sphere:7x5",
    "icosphere:0",
    "icosphere",
    "icosphere:3",
    "torus",
    "torus:3x3",
    "torus:24x20",
    "cylinder",
    "cylinder:3",
    "cone",
    "cone:5",
    "l-prism",
    "wedge",
    "rounded-box",
    "rounded-box:48x16",
    "rounded-box:96x31",
    "rounded-box:5x3",
    "torus-knot",
    "torus-knot:64x5",
    "links",
    "links:3x3",
];

/// Shapes that must be convex polyhedra.
const CONVEX: &[&str] = &[
    "cube",
    "sphere",
    "sphere:16x8",
    "sphere:32x16",
    "sphere:7x5",
    "icosphere:0",
    "icosphere:2",
    "cylinder",
    "cone:5",
    "rounded-box",
    "rounded-box:48x16",
    "rounded-box:96x31",
];

fn shape(name: &str) -> Mesh {
    shapes::build(name).unwrap_or_else(|e| panic!("{name}: {e:?}"))
}

fn signed_volume(m: &Mesh) -> f64 {
    m.triangle_corners()
        .map(|[a, b, c]| a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())))
        .sum::<f64>()
        / 6.0
}

/// Each undirected edge used by exactly two triangles, once in each direction; every vertex used
/// and its triangles forming one fan (a disk neighbourhood); no degenerate triangles; no two
/// vertices at the same position. Returns the Euler characteristic V − E + F.
fn assert_closed_manifold(name: &str, m: &Mesh) -> i64 {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for (i, &[a, b, c]) in m.triangles.iter().enumerate() {
        assert!(
            a != b && b != c && a != c,
            "{name}: triangle {i} repeats a vertex"
        );
        let [p, q, r] = m.corners(i);
        assert!(
            (q - p).cross(r - p).length() > 1e-9,
            "{name}: triangle {i} is degenerate"
        );
        for e in [(a, b), (b, c), (c, a)] {
            *directed.entry(e).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(
            n, 1,
            "{name}: directed edge {a}->{b} used {n} times (inconsistent winding)"
        );
        assert!(
            directed.contains_key(&(b, a)),
            "{name}: edge {a}-{b} has no opposite (open boundary or inconsistent winding)"
        );
    }
    // Vertex links: the edges opposite each vertex must form a single cycle.
    let mut link: HashMap<u32, HashMap<u32, u32>> = HashMap::new();
    for &[a, b, c] in &m.triangles {
        for (v, x, y) in [(a, b, c), (b, c, a), (c, a, b)] {
            link.entry(v).or_default().insert(x, y);
        }
    }
    assert_eq!(link.len(), m.positions.len(), "{name}: unused vertices");
    for (v, next) in &link {
        let start = *next.keys().next().unwrap();
        let (mut at, mut steps) = (start, 0);
        loop {
            at = next[&at];
            steps += 1;
            if at == start {
                break;
            }
        }
        assert_eq!(
            steps,
            next.len(),
            "{name}: vertex {v} is not a manifold vertex"
        );
    }
    // Welded: no duplicated positions.
    let unique: HashSet<[u32; 3]> = m
        .positions
        .iter()
        .map(|p| {
            [
                (p.x + 0.0).to_bits(),
                (p.y + 0.0).to_bits(),
                (p.z + 0.0).to_bits(),
            ]
        })
        .collect();
    assert_eq!(
        unique.len(),
        m.positions.len(),
        "{name}: duplicated positions"
    );
    let v = signed_volume(m);
    assert!(v > 0.0, "{name}: signed volume {v} (should face outward)");
    m.positions.len() as i64 - (directed.len() / 2) as i64 + m.triangles.len() as i64
}

/// Every vertex on or behind every face plane (within a tolerance relative to the size).
fn assert_convex(name: &str, m: &Mesh) {
    let (lo, hi) = m.bounds().unwrap();
    let eps = 1e-4 * (hi - lo).length();
    for (i, [a, b, c]) in m.triangle_corners().enumerate() {
        let n = (b - a).cross(c - a).normalize();
        for (k, &p) in m.positions.iter().enumerate() {
            let d = n.dot(p - a);
            assert!(d <= eps, "{name}: vertex {k} is {d} in front of face {i}");
        }
    }
}

#[test]
fn closed_shapes_are_closed_welded_outward_manifolds() {
    for name in CLOSED {
        let m = shape(name);
        let chi = assert_closed_manifold(name, &m);
        let expected = if name.starts_with("torus") || name.starts_with("links") {
            0 // one torus, or two (links)
        } else {
            2
        };
        assert_eq!(chi, expected, "{name}: Euler characteristic");
    }
}

#[test]
fn convex_shapes_are_convex() {
    for name in CONVEX {
        assert_convex(name, &shape(name));
    }
}

#[test]
fn concave_shapes_are_not_convex() {
    for name in ["l-prism", "torus", "torus-knot", "links"] {
        let r = std::panic::catch_unwind(|| assert_convex(name, &shape(name)));
        assert!(r.is_err(), "{name} should be concave");
    }
}

#[test]
fn triangle_counts_follow_the_documented_formulas() {
    let count = |n: &str| shape(n).triangles.len();
    assert_eq!(count("plane"), 2);
    assert_eq!(count("cube"), 12);
    for (s, k) in [(3, 2), (16, 8), (32, 16), (7, 5)] {
        assert_eq!(count(&format!("sphere:{s}x{k}")), 2 * s * (k - 1));
        assert_eq!(count(&format!("rounded-box:{s}x{k}")), 2 * s * (k - 1));
    }
    assert_eq!(count("sphere:16x8"), 224);
    assert_eq!(count("sphere:32x16"), 960);
    assert_eq!(count("rounded-box:48x16"), 1440);
    assert_eq!(count("rounded-box:96x31"), 5760);
    assert_eq!(count("torus-knot:240x12"), 5760);
    assert_eq!(count("torus-knot"), 5760);
    assert_eq!(count("torus:24x20"), 960);
    assert_eq!(count("links"), 1024);
    assert_eq!(count("links:16x6"), 384);
    assert_eq!(count("icosphere:3"), 1280);
    assert_eq!(count("cylinder:10"), 40);
    assert_eq!(count("cone:10"), 20);
    assert_eq!(count("l-prism"), 20);
    assert_eq!(count("wedge"), 8);
    assert_eq!(count("bunny"), 3674);
}

#[test]
fn sphere_has_single_pole_vertices() {
    let m = shape("sphere:16x8");
    assert_eq!(m.positions.len(), 16 * 7 + 2);
    let top = m.positions.iter().filter(|p| p.y == 0.5).count();
    assert_eq!(top, 1);
}

#[test]
fn plane_is_open_and_faces_up() {
    let m = shape("plane");
    assert_eq!(m.positions.len(), 4);
    for [a, b, c] in m.triangle_corners() {
        assert!((b - a).cross(c - a).y > 0.0);
    }
}

/// The npm bunny is the decimated scan with its holes already filled: it is closed. Pin that
/// down so nobody relies on it for open-boundary coverage by mistake (assets/README.md).
#[test]
fn bunny_is_welded_and_closed() {
    let m = shape("bunny");
    assert_eq!(m.positions.len(), 1839);
    assert_eq!(assert_closed_manifold("bunny", &m), 2);
}

const EXPECTED_NAMES: &[&str] = &[
    "fig1-large-light",
    "fig7-concave",
    "fig8a-distance",
    "fig8b-light-size",
    "fig8c-complex",
    "table1-224",
    "table1-960",
    "table1-1440",
    "table1-5760",
    "bunny",
    "overlap",
    "leak-test",
    "no-umbra",
    "acute-corner",
    "fusion-cross",
    "fusion-links",
    "fusion-many",
    "cluster",
    "blinds",
    "line-fig2",
    "line-fig3-tilted",
    "line-fig6-gap",
    "line-fig8-overlap",
    "line-fig9",
    "line-bar",
    "rect-strip",
    "rect-fig7",
    "polygon-triangle",
    "rect-fusion",
    "pergola",
];

fn scene(name: &str) -> Scene {
    load(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The disk light of a built-in that has one.
fn disk(s: &Scene) -> AreaLight {
    *s.light
        .as_area()
        .unwrap_or_else(|| panic!("{}: a disk light", s.name))
}

#[test]
fn builtin_names_in_order() {
    assert_eq!(builtin::names(), EXPECTED_NAMES);
    assert!(builtin::get("nope").is_none());
}

#[test]
fn every_builtin_scene_loads_and_is_well_formed() {
    for &name in builtin::names() {
        let s = scene(name);
        let again = builtin::get(name).unwrap().unwrap();
        assert_eq!(s.name, name);
        assert_eq!(again.caster_triangle_count(), s.caster_triangle_count());
        assert!(
            builtin::source(name).unwrap().starts_with('#'),
            "{name}: comment on top"
        );

        let ground: Vec<_> = s.objects.iter().filter(|o| !o.casts_shadow).collect();
        assert_eq!(ground.len(), 1, "{name}: one non-casting ground");
        assert_eq!(
            ground[0].mesh.triangles.len(),
            2,
            "{name}: the ground is a plane"
        );
        let (lo, hi) = ground[0].mesh.bounds().unwrap();
        assert!(
            hi.x - lo.x >= 9.0 && hi.z - lo.z >= 9.0,
            "{name}: ground ~10 wide"
        );

        assert!(s.casters().count() >= 1);
        // Every caster between the light and the ground: below a disk's plane (which points
        // down), below both ends of a line light.
        let height = |p: Vec3| match s.light {
            Light::Area(d) => {
                assert!(d.normal.is_normalized());
                assert!(d.normal.y < -0.9, "{name}: light points down");
                d.height_of(p)
            }
            Light::Line(l) => {
                assert!(
                    l.length() >= 1.0,
                    "{name}: a line light a metre or more long"
                );
                l.a.y.min(l.b.y) - p.y
            }
        };
        for o in s.casters() {
            for &p in &o.mesh.positions {
                let h = height(p);
                assert!(
                    h > 0.05,
                    "{name}/{}: vertex {p} at {h} below the light",
                    o.name
                );
                assert!(p.y > lo.y, "{name}/{}: caster above the ground", o.name);
            }
        }
        // The camera looks at the shadowed region: target within the ground, eye above it.
        assert!(
            s.camera.eye.y > 0.5 && s.camera.target.length() < 3.0,
            "{name}: camera"
        );
    }
}

#[test]
fn caster_triangle_counts() {
    let expected = [
        ("table1-224", 224),
        ("table1-960", 960),
        ("table1-1440", 1440),
        ("table1-5760", 5760),
        ("fig8c-complex", 5760),
        ("fig8a-distance", 3 * 224),
        // `bunny-open`: the 3674-triangle npm bunny without the triangles of its bottom 3 %.
        ("bunny", 3389),
        ("fig7-concave", 20),
        ("acute-corner", 8),
    ];
    for (name, n) in expected {
        assert_eq!(scene(name).caster_triangle_count(), n, "{name}");
    }
}

#[test]
fn convex_casters_are_convex() {
    for name in [
        "table1-224",
        "table1-960",
        "table1-1440",
        "table1-5760",
        "fig8a-distance",
        "fig8b-light-size",
        "overlap",
        "no-umbra",
        "fig1-large-light",
    ] {
        for o in scene(name).casters() {
            assert_convex(&format!("{name}/{}", o.name), &o.mesh);
        }
    }
}

#[test]
fn concave_scenes_are_concave() {
    let s = scene("fig7-concave");
    let o = s.casters().next().unwrap();
    assert!(std::panic::catch_unwind(|| assert_convex("fig7", &o.mesh)).is_err());
}

/// Bounds (in XZ) of a convex caster's penumbra on the ground plane y = 0 under a horizontal
/// disk light: each vertex q projects from light point p to p + (q − p)·t, t = p.y/(p.y − q.y),
/// which over the disk is a disk of centre c + (q − c)·t and radius r·|1 − t|. Under a line
/// light, the projections of every vertex from both ends (the shadow from any point between).
fn penumbra_bounds(s: &Scene, m: &Mesh) -> (glam::Vec2, glam::Vec2) {
    if let Light::Line(l) = s.light {
        let mut lo = glam::Vec2::splat(f32::INFINITY);
        let mut hi = -lo;
        for &q in &m.positions {
            for p in [l.a, l.b] {
                let g = p + (q - p) * (p.y / (p.y - q.y));
                lo = lo.min(glam::Vec2::new(g.x, g.z));
                hi = hi.max(glam::Vec2::new(g.x, g.z));
            }
        }
        return (lo, hi);
    }
    let c = disk(s).center;
    let r = disk(s).radius;
    let mut lo = glam::Vec2::splat(f32::INFINITY);
    let mut hi = -lo;
    for &q in &m.positions {
        let t = c.y / (c.y - q.y);
        let centre = c + (q - c) * t;
        let rad = r * (1.0 - t).abs();
        lo = lo.min(glam::Vec2::new(centre.x, centre.z) - rad);
        hi = hi.max(glam::Vec2::new(centre.x, centre.z) + rad);
    }
    (lo, hi)
}

fn boxes_overlap(a: (glam::Vec2, glam::Vec2), b: (glam::Vec2, glam::Vec2)) -> bool {
    a.0.x < b.1.x && b.0.x < a.1.x && a.0.y < b.1.y && b.0.y < a.1.y
}

#[test]
fn fig8a_spheres_at_three_heights_with_separate_penumbrae() {
    let s = scene("fig8a-distance");
    assert_eq!(disk(&s).normal, Vec3::NEG_Y);
    let casters: Vec<_> = s.casters().collect();
    assert_eq!(casters.len(), 3);
    let heights: Vec<f32> = casters
        .iter()
        .map(|o| o.mesh.bounds().unwrap().0.y)
        .collect();
    assert!(
        heights[0] < heights[1] && heights[1] < heights[2],
        "{heights:?}"
    );
    let boxes: Vec<_> = casters
        .iter()
        .map(|o| penumbra_bounds(&s, &o.mesh))
        .collect();
    for i in 0..3 {
        for j in i + 1..3 {
            assert!(
                !boxes_overlap(boxes[i], boxes[j]),
                "penumbrae {i} and {j} overlap"
            );
        }
    }
}

/// Whether `x` sees light point `p` past every object.
fn sees(s: &Scene, x: Vec3, p: Vec3) -> bool {
    let origin = x + Vec3::Y * 1e-4;
    let dir = p - origin;
    !s.casters().any(|o| {
        o.mesh
            .triangle_corners()
            .any(|t| intersect_triangle(origin, dir, &t).is_some_and(|t| t > 1e-6 && t < 1.0))
    })
}

fn rim(s: &Scene, n: usize) -> Vec<Vec3> {
    let (u, v) = disk(s).basis();
    (0..n)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / n as f32;
            disk(s).center + disk(s).radius * (a.cos() * u + a.sin() * v)
        })
        .collect()
}

#[test]
fn overlap_penumbrae_overlap() {
    let s = scene("overlap");
    let casters: Vec<_> = s.casters().collect();
    assert_eq!(casters.len(), 2);
    let (a, b) = (
        casters[0].mesh.bounds().unwrap(),
        casters[1].mesh.bounds().unwrap(),
    );
    assert!(a.1.y < b.0.y || b.1.y < a.0.y, "different heights");
    // A ground point that each caster alone partly shadows: both hide some rim points from it.
    let x = Vec3::new(0.1, 0.0, 0.05);
    let only = |k: usize| Scene {
        objects: s
            .objects
            .iter()
            .filter(|o| !o.casts_shadow || o.name == casters[k].name)
            .cloned()
            .collect(),
        ..s.clone()
    };
    for k in 0..2 {
        let sk = only(k);
        let hidden = rim(&sk, 64).iter().filter(|&&p| !sees(&sk, x, p)).count();
        assert!(
            hidden > 0 && hidden < 64,
            "caster {k} hides {hidden}/64 rim points"
        );
    }
}

#[test]
fn no_umbra_reaches_the_ground() {
    let s = scene("no-umbra");
    let (lo, hi) = s.casters().next().unwrap().mesh.bounds().unwrap();
    // Over the whole region below the caster, some part of the light's rim stays visible.
    let rim = rim(&s, 64);
    let mut partly = 0;
    for i in -10..=10 {
        for j in -10..=10 {
            let x = Vec3::new(i as f32 * 0.1, 0.0, j as f32 * 0.1);
            let visible = rim.iter().filter(|&&p| sees(&s, x, p)).count();
            assert!(visible > 0, "ground point {x} is in umbra");
            partly += usize::from(visible < rim.len());
        }
    }
    assert!(partly > 0, "the caster shadows something");
    assert!(
        hi.x - lo.x < disk(&s).radius,
        "caster smaller than the light"
    );
}

#[test]
fn fig1_caster_is_much_smaller_than_the_light() {
    let s = scene("fig1-large-light");
    let (lo, hi) = s.casters().next().unwrap().mesh.bounds().unwrap();
    // Light diameter at least three times the caster's largest extent.
    assert!(3.0 * (hi - lo).max_element() < 2.0 * disk(&s).radius);
}

#[test]
fn acute_corner_has_a_15_degree_corner_and_tilted_light() {
    let s = scene("acute-corner");
    assert!(
        disk(&s).normal.x.abs() > 0.05,
        "the one scene with a tilted light"
    );
    assert_eq!(s.casters().count(), 1);
    assert!((shapes::WEDGE_ANGLE_DEG - 15.0).abs() < 1e-6);
}

/// The camera frames the shadow: the casters and the extent of their penumbrae on the ground
/// project inside a square viewport (the narrowest the GUI or `render` uses by default).
#[test]
fn cameras_frame_casters_and_shadows() {
    for &name in builtin::names() {
        let s = scene(name);
        let view = glam::Mat4::look_at_rh(s.camera.eye, s.camera.target, Vec3::Y);
        let proj = glam::Mat4::perspective_rh(s.camera.fov_y_deg.to_radians(), 1.0, 0.05, 100.0);
        let m = proj * view;
        let inside = |p: Vec3, what: &str| {
            let c = m * p.extend(1.0);
            assert!(c.w > 0.0, "{name}: {what} {p} behind the camera");
            let ndc = c.truncate() / c.w;
            assert!(
                ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0,
                "{name}: {what} {p} outside the view ({ndc})"
            );
        };
        for o in s.casters() {
            let (lo, hi) = o.mesh.bounds().unwrap();
            for k in 0..8 {
                let pick = |bit: usize, a: f32, b: f32| if k & bit != 0 { b } else { a };
                let p = Vec3::new(
                    pick(1, lo.x, hi.x),
                    pick(2, lo.y, hi.y),
                    pick(4, lo.z, hi.z),
                );
                inside(p, "caster corner");
            }
            // The extreme points of the (round or box-like) penumbra: its bounds' edge midpoints.
            let (a, b) = penumbra_bounds(&s, &o.mesh);
            let mid = (a + b) / 2.0;
            for p in [
                glam::Vec2::new(a.x, mid.y),
                glam::Vec2::new(b.x, mid.y),
                glam::Vec2::new(mid.x, a.y),
                glam::Vec2::new(mid.x, b.y),
            ] {
                inside(Vec3::new(p.x, 0.0, p.y), "penumbra corner");
            }
        }
    }
}

/// The bunny scene is there to exercise open boundaries: its caster must have some, and the
/// geometry stage must say so once.
#[test]
fn bunny_scene_caster_is_open() {
    let s = scene("bunny");
    let caster = s.casters().next().expect("the bunny scene has a caster");
    let prepared = dbuffer::geometry::CasterMesh::new(&caster.name, &caster.mesh);
    assert!(prepared.report.boundary_edges > 20, "{:?}", prepared.report);
    assert_eq!(prepared.report.non_manifold_edges, 0);
    let geometry = dbuffer::geometry::PreparedCasters::new(&s).build(
        s.light.as_area().expect("a disk light"),
        &dbuffer::geometry::VolumeParams::for_scene(&s),
    );
    let open: Vec<_> = geometry
        .warnings
        .iter()
        .filter(|w| w.contains("open boundary edges"))
        .collect();
    assert_eq!(open.len(), 1, "{:?}", geometry.warnings);
}
