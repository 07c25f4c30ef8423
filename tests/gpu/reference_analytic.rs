//! The `reference` method, end to end through the render core (the pixels' points, the oracle, the
//! camera pass shading its V), against closed-form soft shadows: a straight edge parallel to the
//! light, and a disk under the disk light.

use std::f32::consts::PI;

use dbuffer::geometry::VtVariant;
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, FrameRequest, Knobs, Method};
use dbuffer::scene::{AreaLight, Camera, Mesh, Object, Outline, Scene};
use glam::Vec3;

const H: f32 = 4.0; // light height
const R: f32 = 1.0; // light radius

fn light() -> AreaLight {
    AreaLight {
        center: Vec3::new(0.0, H, 0.0),
        normal: Vec3::NEG_Y,
        radius: R,
        intensity: 1.0,
        outline: Outline::Disk,
    }
}

/// A horizontal quad at height `y` over `[x0, x1] × [z0, z1]`.
fn quad(y: f32, x0: f32, x1: f32, z0: f32, z1: f32) -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(x0, y, z0),
            Vec3::new(x1, y, z0),
            Vec3::new(x1, y, z1),
            Vec3::new(x0, y, z1),
        ],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
    }
}

/// A horizontal disk of radius `a` at height `y`, centred on the axis, as a 256-gon.
fn disk(y: f32, a: f32) -> Mesh {
    let n = 256;
    let mut positions = vec![Vec3::new(0.0, y, 0.0)];
    positions.extend((0..n).map(|k| {
        let t = k as f32 / n as f32 * 2.0 * PI;
        // Circumscribed polygon: the same area as the circle to first order.
        let a = a / (PI / n as f32).cos().sqrt();
        Vec3::new(a * t.cos(), y, a * t.sin())
    }));
    let triangles = (0..n as u32)
        .map(|k| [0, 1 + (k + 1) % n as u32, 1 + k])
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

/// The ground, seen from a low camera below the caster (which stays out of view).
fn scene(name: &str, caster: Mesh) -> Scene {
    Scene {
        name: name.into(),
        camera: Camera {
            eye: Vec3::new(0.0, 1.2, 5.0),
            target: Vec3::new(0.0, 0.0, 0.0),
            fov_y_deg: 50.0,
        },
        light: light().into(),
        objects: vec![
            Object {
                name: "ground".into(),
                mesh: quad(0.0, -20.0, 20.0, -20.0, 20.0),
                casts_shadow: false,
            },
            Object {
                name: "caster".into(),
                mesh: caster,
                casts_shadow: true,
            },
        ],
    }
}

fn reference(scene: &Scene) -> Frame {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let request = FrameRequest {
        width: 64,
        height: 64,
        dbuffer_size: 256,
        method: Method::REFERENCE,
        vt: VtVariant::Exact,
        knobs: Knobs::default().with(&SAMPLES, 1024),
        read_dbuffer: false,
        read_cost: false,
        colour_only: false,
    };
    offline
        .render(scene, &request)
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// Fraction of the unit disk on the far side of the chord at signed distance `u` (in radii).
fn segment_fraction(u: f32) -> f32 {
    let u = u.clamp(-1.0, 1.0);
    (u.acos() - u * (1.0 - u * u).sqrt()) / PI
}

/// Area of the intersection of two disks of radii `r1`, `r2` whose centres are `d` apart.
fn lens_area(r1: f32, r2: f32, d: f32) -> f32 {
    let (r1, r2, d) = (f64::from(r1), f64::from(r2), f64::from(d));
    if d >= r1 + r2 {
        return 0.0;
    }
    if d <= (r1 - r2).abs() {
        return (std::f64::consts::PI * r1.min(r2).powi(2)) as f32;
    }
    let a1 = ((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1)).acos();
    let a2 = ((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2)).acos();
    let k = 0.5 * ((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)).sqrt();
    (r1 * r1 * a1 + r2 * r2 * a2 - k) as f32
}

/// Compare the frame's V with `exact(x)` over every pixel on the ground; returns (max, mean)
/// error and how many pixels were in the penumbra.
fn errors(frame: &Frame, exact: impl Fn(Vec3) -> f32) -> (f32, f32, usize) {
    let (mut worst, mut sum, mut n, mut penumbra) = (0.0f32, 0.0f32, 0usize, 0usize);
    for (i, &v) in frame.visibility.iter().enumerate() {
        let Some(p) = frame.position(i).filter(|p| p.y.abs() <= 1e-3) else {
            continue;
        };
        let e = exact(p);
        worst = worst.max((v - e).abs());
        sum += (v - e).abs();
        n += 1;
        penumbra += usize::from(e > 0.01 && e < 0.99);
    }
    assert!(n > 2000, "the view must show the ground ({n} pixels)");
    (worst, sum / n as f32, penumbra)
}

#[test]
fn straight_edge_parallel_to_the_light() {
    // The occluder at height h = 2 covers x > 0: a ground point at x sees disk points with
    // q.x ≤ x·(1 − H/h) = −x, a chord at −x/R; umbra for x ≥ R, lit for x ≤ −R.
    let h = 2.0;
    let frame = reference(&scene("edge", quad(h, 0.0, 40.0, -40.0, 40.0)));
    let (worst, mean, penumbra) = errors(&frame, |x| {
        let chord = x.x * (1.0 - H / h) / R;
        1.0 - segment_fraction(chord)
    });
    println!("straight edge: max |ΔV| {worst:.4}, mean {mean:.5}, {penumbra} penumbra px");
    assert!(
        penumbra > 300,
        "the view must cross the penumbra ({penumbra} px)"
    );
    // K = 1024 stratified samples: a chord crosses about √K cells, each off by at most 1/K.
    assert!(worst <= 0.02, "max error {worst}");
    assert!(mean <= 0.004, "mean error {mean}");
}

#[test]
fn disk_under_the_disk_light() {
    // An occluding disk of radius a at height h, seen from a ground point at distance ρ from the
    // axis, covers a disk of radius a·H/h centred ρ·(H/h − 1) from the light's centre on the
    // light's plane: V = 1 − lens area / πR².
    let (h, a) = (2.0, 0.8);
    let frame = reference(&scene("disk", disk(h, a)));
    let (worst, mean, penumbra) = errors(&frame, |x| {
        let rho = (x.x * x.x + x.z * x.z).sqrt();
        let covered = lens_area(R, a * H / h, rho * (H / h - 1.0));
        1.0 - covered / (PI * R * R)
    });
    println!("disk under disk: max |ΔV| {worst:.4}, mean {mean:.5}, {penumbra} penumbra px");
    assert!(
        penumbra > 300,
        "the view must cross the penumbra ({penumbra} px)"
    );
    assert!(worst <= 0.02, "max error {worst}");
    assert!(mean <= 0.004, "mean error {mean}");
    // The umbra: radius a·H/h − R projected back, ρ(H/h − 1) ≤ aH/h − R → ρ ≤ 0.6 here.
    let centre = (0..frame.len())
        .filter(|&i| {
            frame
                .position(i)
                .is_some_and(|p| p.y.abs() < 1e-3 && p.x.hypot(p.z) < 0.5)
        })
        .map(|i| frame.visibility[i])
        .fold(0.0f32, f32::max);
    assert!(
        centre == 0.0,
        "inside the umbra V must be 0, found {centre}"
    );
}

/// A line light over one straight edge (Heidrich et al. 2000, Fig. 2): the light from (−1, 4, 0) to
/// (1, 4, 0), the occluder at height 2 covering x > 0 (edge across the light), receivers on the
/// ground. The closed form of `geometry::line_light` (here V = clamp(½ − x/2, 0, 1), linear
/// across the penumbra) against the reference end to end, and against `sampled` with N points
/// on the segment (N + 1 levels: within 1/N of the truth, where its maps resolve it) and
/// `linear-ssm` with two.
#[test]
fn line_light_over_an_edge_end_to_end() {
    use dbuffer::geometry::line_light::{half_plane_visibility, HalfPlane};
    use dbuffer::render::methods::sampled::LIGHTS;
    use dbuffer::scene::LineLight;
    let line = LineLight {
        a: Vec3::new(-1.0, H, 0.0),
        b: Vec3::new(1.0, H, 0.0),
        intensity: 1.0,
    };
    let edge = HalfPlane {
        origin: Vec3::new(0.0, 2.0, 0.0),
        along: Vec3::Z,
        into: Vec3::X,
    };
    // A 3 × 6 m occluder (a light view can frame it, which a 40 m one it cannot), seen from
    // above; only ground points whose every shadow ray crosses the occluder's plane inside it
    // count (|z| ≤ 2: rays cross at z/2; x ≤ 2: at (x + s)/2 ≤ 1.5), where it is a half-plane.
    let mut s = scene("line-edge", quad(2.0, 0.0, 3.0, -3.0, 3.0));
    s.light = line.into();
    s.camera = Camera {
        eye: Vec3::new(0.0, 3.5, 3.5),
        target: Vec3::new(0.0, 0.0, 0.0),
        fov_y_deg: 50.0,
    };
    let exact = |x: Vec3| half_plane_visibility(&line, &edge, x) as f32;
    let errors = |frame: &Frame, exact: &dyn Fn(Vec3) -> f32| {
        let (mut worst, mut sum, mut n, mut penumbra) = (0.0f32, 0.0f32, 0usize, 0usize);
        for (i, &v) in frame.visibility.iter().enumerate() {
            let Some(x) = frame.position(i) else {
                continue;
            };
            if x.y.abs() > 1e-3 || x.z.abs() > 2.0 || x.x.abs() > 2.0 {
                continue;
            }
            let e = exact(x);
            worst = worst.max((v - e).abs());
            sum += (v - e).abs();
            n += 1;
            penumbra += usize::from(e > 0.01 && e < 0.99);
        }
        assert!(n > 1000, "the view must show the ground ({n} pixels)");
        (worst, sum / n as f32, penumbra)
    };
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let mut frame = |method: Method, knobs: Knobs| {
        let request = FrameRequest {
            width: 64,
            height: 64,
            dbuffer_size: 1024,
            method,
            vt: VtVariant::Exact,
            knobs: knobs.with(&SAMPLES, 1024),
            read_dbuffer: false,
            read_cost: false,
            colour_only: false,
        };
        offline
            .render(&s, &request)
            .unwrap_or_else(|e| panic!("{method}: {e}"))
            .0
    };
    let (worst, mean, penumbra) = errors(&frame(Method::REFERENCE, Knobs::default()), &exact);
    println!("line over an edge: reference max |ΔV| {worst:.4}, mean {mean:.5}, {penumbra} px");
    assert!(
        penumbra > 300,
        "the view must cross the penumbra ({penumbra} px)"
    );
    // One interval of the segment is hidden: K = 1024 stratified samples are within 2/K.
    assert!(worst <= 2.0 / 1024.0 + 1e-4, "max error {worst}");
    for n in [4u32, 16] {
        let f = frame(
            "sampled".parse().unwrap(),
            Knobs::default().with(&LIGHTS, n),
        );
        let (worst, mean, _) = errors(&f, &exact);
        println!("line over an edge: sampled {n}: max |ΔV| {worst:.4}, mean {mean:.5}");
        // Half a level either way, plus a texel of the maps at the hard steps.
        assert!(
            worst <= 1.0 / n as f32 + 0.02,
            "sampled {n}: max error {worst}"
        );
    }
    let f = frame("linear-ssm".parse().unwrap(), Knobs::default());
    let (worst, mean, _) = errors(&f, &exact);
    println!("line over an edge: linear-ssm 2: max |ΔV| {worst:.4}, mean {mean:.5}");
    // The receiver is parallel to the light: the truth is linear in x. The skins interpolate
    // linearly in the sample's image (the paper's Gouraud shading), whose plane is tilted toward
    // the occluder here, so not quite linearly on the ground (perspective-correct interpolation,
    // linear along the skin, is further off still: mean 0.067 on this scene).
    assert!(
        mean <= 0.03 && worst <= 0.1,
        "linear-ssm: max {worst}, mean {mean}"
    );
}
