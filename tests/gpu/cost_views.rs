//! Every method's cost view: the work its camera pass counts per pixel (`count_work`,
//! `took_path` of `shaders/shared/camera.wgsl`, read back as `Frame::cost`) moves the way its
//! work does — more PCSS taps under a larger light, more listed edges where casters overlap,
//! more maps read with more sample lights — and a method that says its work is constant counts
//! the same number at every pixel. A method added to the registry fails
//! `every_method_has_a_cost_test` until it has a case here.

use dbuffer::geometry::VtVariant;
use dbuffer::render::methods::{
    dbuffer as dbuffer_method, linear_ssm, pcf, reference, sampled, smrt,
};
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, FrameRequest, Knobs, Method};
use dbuffer::scene::{self, Light, Scene};

const SIDE: u32 = 64;

fn request(method: Method, knobs: Knobs) -> FrameRequest {
    FrameRequest {
        width: SIDE,
        height: SIDE,
        dbuffer_size: 512,
        method,
        vt: VtVariant::Exact,
        knobs: knobs.with(&reference::SAMPLES, 16),
        read_cost: true,
        colour_only: false,
        ..FrameRequest::default()
    }
}

fn render(offline: &mut Offline, scene: &Scene, method: Method, knobs: Knobs) -> Frame {
    let (frame, _) = offline
        .render(scene, &request(method, knobs))
        .unwrap_or_else(|e| panic!("{method}: {e}"));
    assert_eq!(
        frame.cost.len(),
        frame.len(),
        "{method}: the cost came back"
    );
    frame
}

/// The work at the pixels that show a surface.
fn work(frame: &Frame) -> Vec<f32> {
    (0..frame.len())
        .filter(|&i| frame.hit(i))
        .map(|i| frame.cost[i][0])
        .collect()
}

fn mean(v: &[f32]) -> f64 {
    v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len().max(1) as f64
}

fn load(name: &str) -> Scene {
    scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// `scene` with its disk light's radius times `k`.
fn light_scaled(name: &str, k: f32) -> Scene {
    let mut s = load(name);
    if let Light::Area(a) = &mut s.light {
        a.radius *= k;
    }
    s
}

/// Mean work of `method` on `a` and on `b` (with their knobs): `b`'s must be larger.
fn grows(
    offline: &mut Offline,
    method: Method,
    (a, ka): (&Scene, Knobs),
    (b, kb): (&Scene, Knobs),
    why: &str,
) -> (f64, f64) {
    let lo = mean(&work(&render(offline, a, method, ka)));
    let hi = mean(&work(&render(offline, b, method, kb)));
    println!("{method}: mean {lo:.3} → {hi:.3} ({why})");
    assert!(hi > lo, "{method}: {why}: {lo} → {hi}");
    (lo, hi)
}

/// Every pixel that does work does exactly `n`, and some do.
fn constant(offline: &mut Offline, scene: &Scene, method: Method, knobs: Knobs, n: f32) {
    let w = work(&render(offline, scene, method, knobs));
    let working: Vec<f32> = w.iter().copied().filter(|&x| x > 0.0).collect();
    println!(
        "{method}: {} of {} pixels work, {n} each",
        working.len(),
        w.len()
    );
    assert!(working.len() > w.len() / 4, "{method}: too few pixels work");
    assert!(
        working.iter().all(|&x| x == n),
        "{method}: not {n} everywhere"
    );
    assert!(
        method.spec().cost.constant.is_some(),
        "{method}: constant work, and its Cost says so"
    );
}

/// The cases, by method name.
const CASES: &[&str] = &[
    "dbuffer",
    "dbuffer-center",
    "dbuffer-fused",
    "hard",
    "pcf",
    "pcss",
    "smrt",
    "vsm",
    "msm",
    "msm-soft",
    "bitmask",
    "sampled",
    "linear-ssm",
    "shadow-volume",
    "planar",
    "hybrid",
    "extended-light-map",
    "wedges",
    "raytraced",
    "reference",
    "reference-hard",
];

#[test]
fn every_method_has_a_cost_test() {
    for m in Method::all() {
        assert!(
            CASES.contains(&m.name()),
            "{m} has no case in tests/gpu/cost_views.rs: add one that its cost moves the way \
             its work does"
        );
    }
}

#[test]
fn paths_are_the_ones_each_method_names() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let disk = load("fig7-concave");
    let line = load("line-fig2");
    for &m in Method::all() {
        let scene = if m.refuses(disk.light.kind()).is_none() {
            &disk
        } else {
            &line
        };
        let f = render(&mut offline, scene, m, Knobs::default());
        let paths = m.spec().cost.paths.len();
        for i in 0..f.len() {
            let [w, p] = f.cost[i];
            assert!(w >= 0.0 && w.is_finite(), "{m}: work {w} at {i}");
            assert!(
                p == p.round() && (p as usize) < paths.max(1),
                "{m}: path {p} at {i}, it names {paths}"
            );
            if !f.hit(i) {
                assert_eq!([w, p], [0.0, 0.0], "{m}: work where there is no surface");
            }
        }
    }
}

#[test]
fn shadow_map_methods_count_their_taps() {
    let mut o = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let s = load("fig7-concave");
    constant(&mut o, &s, Method::HARD, Knobs::default(), 1.0);
    let m = |name: &str| name.parse::<Method>().unwrap();
    constant(
        &mut o,
        &s,
        m("pcf"),
        Knobs::default().with(&pcf::RADIUS, 1),
        9.0,
    );
    constant(
        &mut o,
        &s,
        m("pcf"),
        Knobs::default().with(&pcf::RADIUS, 2),
        25.0,
    );
    constant(&mut o, &s, m("vsm"), Knobs::default(), 1.0);
    // Two boxes of the summed-area table, four corners each.
    constant(&mut o, &s, m("msm"), Knobs::default(), 8.0);
    constant(&mut o, &s, m("extended-light-map"), Knobs::default(), 1.0);
    for name in ["shadow-volume", "planar", "hybrid"] {
        constant(&mut o, &s, m(name), Knobs::default(), 1.0);
    }
    constant(&mut o, &s, Method::REFERENCE_HARD, Knobs::default(), 1.0);
}

#[test]
fn larger_lights_cost_the_searching_methods_more() {
    let mut o = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let (small, large) = (
        light_scaled("fig7-concave", 0.5),
        light_scaled("fig7-concave", 2.0),
    );
    let d = Knobs::default();
    for name in ["pcss", "msm-soft", "bitmask", "wedges"] {
        let m: Method = name.parse().unwrap();
        grows(
            &mut o,
            m,
            (&small, d),
            (&large, d),
            "a larger light: wider searches and penumbrae",
        );
    }
}

#[test]
fn more_samples_cost_more() {
    let mut o = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let s = load("fig7-concave");
    let d = Knobs::default();
    let (lo, hi) = grows(
        &mut o,
        "sampled".parse().unwrap(),
        (&s, d.with(&sampled::LIGHTS, 4)),
        (&s, d.with(&sampled::LIGHTS, 16)),
        "16 sample maps against 4",
    );
    // A lit point in front of every sample reads each map once.
    assert!(hi <= 16.0 && lo <= 4.0 && hi > 3.0 * lo, "{lo} {hi}");
    grows(
        &mut o,
        "smrt".parse().unwrap(),
        (&s, d.with(&smrt::STEPS, 4)),
        (&s, d.with(&smrt::STEPS, 12)),
        "12 steps a ray against 4",
    );
    let line = load("line-fig2");
    grows(
        &mut o,
        "linear-ssm".parse().unwrap(),
        (&line, d.with(&linear_ssm::SAMPLES, 2)),
        (&line, d.with(&linear_ssm::SAMPLES, 8)),
        "8 samples on the segment against 2",
    );
}

#[test]
fn the_dbuffers_count_their_reads_and_fused_its_listed_edges() {
    let mut o = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let d = Knobs::default();
    // The closing fans' corners are read only with --dbuffer-corners (V exact).
    let s = load("fig8c-complex");
    for m in [Method::DBUFFER, Method::DBUFFER_CENTER] {
        grows(
            &mut o,
            m,
            (&s, d.with(&dbuffer_method::CORNERS, 0)),
            (&s, d.with(&dbuffer_method::CORNERS, 1)),
            "the fans' corners read",
        );
    }
    // More listed edges where two casters overlap than under either alone.
    let both = load("overlap");
    let mut one = both.clone();
    let casters: Vec<usize> = (0..one.objects.len())
        .filter(|&i| one.objects[i].casts_shadow)
        .collect();
    assert!(casters.len() >= 2, "overlap has two casters");
    one.objects.remove(casters[1]);
    let fused = Method::DBUFFER_FUSED;
    let max = |f: &Frame| work(f).into_iter().fold(0.0f32, f32::max);
    let single = max(&render(&mut o, &one, fused, d));
    let overlapping = max(&render(&mut o, &both, fused, d));
    println!("dbuffer-fused: most listed edges {single} alone, {overlapping} overlapping");
    assert!(overlapping > single, "{single} {overlapping}");
    grows(
        &mut o,
        fused,
        (&one, d),
        (&both, d),
        "a second caster's edges listed",
    );
}

/// `raytraced` counts the BVH nodes its rays visit: four rays a pixel visit about four times
/// the nodes of one, and a caster of more triangles (a deeper tree) more than a simple one.
#[test]
fn the_traced_rays_count_the_nodes_they_visit() {
    use dbuffer::render::methods::raytraced::RAYS;
    let mut o = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let rt: Method = "raytraced".parse().unwrap();
    let s = load("fig7-concave");
    let d = Knobs::default();
    let (lo, hi) = grows(
        &mut o,
        rt,
        (&s, d.with(&RAYS, 1)),
        (&s, d.with(&RAYS, 4)),
        "4 rays a pixel against 1",
    );
    assert!(hi > 3.0 * lo && hi < 5.0 * lo, "{lo} {hi}");
    grows(
        &mut o,
        rt,
        (&load("table1-224"), d),
        (&load("table1-5760"), d),
        "a caster of 5,760 triangles against 224",
    );
}

#[test]
fn the_reference_counts_its_rays_so_far() {
    let offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let scene = load("fig7-concave");
    let mut session = offline.session(scene);
    let req = request(
        Method::REFERENCE,
        Knobs::default().with(&reference::SAMPLES, 64),
    );
    let mut last = 0.0;
    for step in [4, 12] {
        let (done, _) = session
            .advance_reference(&offline.ctx, &req, step)
            .unwrap_or_else(|e| panic!("{e}"));
        let f = session
            .frame(&offline.ctx, &req)
            .unwrap_or_else(|e| panic!("{e}"));
        let w = work(&f);
        let most = w.iter().copied().fold(0.0f32, f32::max);
        println!("reference: {done} samples done, {most} rays a pixel");
        assert_eq!(most, done as f32);
        assert!(most > last);
        last = most;
    }
}
