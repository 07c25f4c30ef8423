//! What engines ship today, against the ray-cast reference: shadow-map ray tracing (`smrt`).
//! Numbers are printed (`cargo test --release --test gpu engine_methods -- --nocapture`).

use dbuffer::render::methods::smrt;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, Knobs, Method};
use dbuffer::scene;

use crate::support::scored::{self, Scored};

const SIZE: u32 = 96;

fn render(
    offline: &mut Offline,
    scene: &dbuffer::scene::Scene,
    method: Method,
    knobs: Knobs,
) -> Frame {
    scored::render(offline, scene, method, knobs, SIZE)
}

/// The penumbra MAE 32 uncapped rays stay under where they beat PCSS: below the 0.08–0.11 of a
/// world-space march (rect-strip, whose rectangle takes the disk's concentric ray pattern, is the
/// highest: 0.063 on lavapipe, 2026-12-07).
const MARCHED: f64 = 0.065;

fn smrt_method() -> Method {
    Method::of(&smrt::SMRT).expect("smrt is on the registry")
}

/// More rays, less error: with UE's cap on the ray's angle lifted (`smrt-max-angle 1570`) and
/// every ray traced, the penumbra's error falls with the ray count on every scene, and at 32 rays
/// it is below PCSS's on the scenes whose casters stand high under a large light — where a ray
/// marched in world-space steps with a tolerance in distances read the one depth layer as a
/// height field with skirts (penumbra MAE 0.08–0.11 at 32 rays, a near-hard shadow under
/// `fig1-large-light`'s cube) and UE's march in the map's projected space does not. At the
/// defaults (UE's 30 mrad cap, adaptive count) no pixel the reference has fully lit reads
/// shadowed (the normal offset, the screen ray's start and the slope bias keep the receiver out
/// of its own map), and the adaptive count is never better than tracing every ray.
#[test]
fn smrt_converges_with_its_rays() {
    let smrt = smrt_method();
    let pcss = Method::of(&dbuffer::render::methods::pcss::PCSS).expect("pcss");
    println!("| scene | method | class mismatch % | MAE | penumbra MAE | p99 |");
    for (name, beats_pcss) in [
        ("table1-960", true),
        ("fig1-large-light", true),
        ("fig7-concave", false),
        ("acute-corner", true),
        ("rect-strip", true),
    ] {
        let mut s = Scored::new(name, SIZE);
        // The cap lifted and every ray traced.
        let rays = |n: u32| {
            Knobs::default()
                .with(&smrt::RAYS, n)
                .with(&smrt::ADAPTIVE.0, 0)
                .with(&smrt::MAX_ANGLE.0, 1570)
        };
        let (_, two) = s.measure_as(smrt, rays(2), "smrt 2 rays, uncapped");
        let (_, eight) = s.measure_as(smrt, rays(8), "smrt 8 rays, uncapped");
        let (_, many) = s.measure_as(smrt, rays(32), "smrt 32 rays, uncapped");
        let (_, p) = s.measure_as(pcss, Knobs::default(), "pcss");
        assert!(
            many.penumbra_mae < eight.penumbra_mae && eight.penumbra_mae < two.penumbra_mae,
            "{name}: penumbra MAE 2 / 8 / 32 rays {:.4} / {:.4} / {:.4}",
            two.penumbra_mae,
            eight.penumbra_mae,
            many.penumbra_mae
        );
        if beats_pcss {
            assert!(
                many.penumbra_mae < p.penumbra_mae && many.penumbra_mae < MARCHED,
                "{name}: 32 rays uncapped {:.4} against PCSS's {:.4}",
                many.penumbra_mae,
                p.penumbra_mae
            );
        }
        let (d, defaults) = s.measure_as(smrt, Knobs::default(), "smrt defaults (UE's)");
        let every = Knobs::default().with(&smrt::ADAPTIVE.0, 0);
        let (_, seven) = s.measure_as(smrt, every, "smrt defaults, every ray");
        assert!(
            defaults.penumbra_mae >= seven.penumbra_mae - 1e-3,
            "{name}: adaptive {defaults:?} vs every ray {seven:?}"
        );
        let false_shadow = s
            .reference
            .iter()
            .zip(&d.visibility)
            .zip(&s.mask)
            .filter(|((r, v), m)| **m && **r >= 0.999 && **v < 0.5)
            .count();
        let counted = s.mask.iter().filter(|m| **m).count();
        assert!(
            false_shadow * 500 <= counted,
            "{name}: {false_shadow} of {counted} fully lit pixels read shadowed"
        );
    }
}

/// The light points and step offsets come from the pixel alone: two renders of the same frame
/// are the same picture (no flicker with the camera and light still); and UE's cap on the angle
/// a ray spans seen from the light narrows the penumbra under a large light: at its 30 mrad the
/// shadow of `fig1-large-light`'s cube has far fewer penumbra pixels than with the cap lifted,
/// and fewer still at 5 mrad.
#[test]
fn smrt_is_deterministic_and_its_ray_angle_caps_the_penumbra() {
    let smrt = smrt_method();
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let concave = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let a = render(&mut offline, &concave, smrt, Knobs::default());
    let b = render(&mut offline, &concave, smrt, Knobs::default());
    assert_eq!(
        a.visibility, b.visibility,
        "two renders of one frame differ"
    );
    let large = scene::load("fig1-large-light").unwrap_or_else(|e| panic!("{e}"));
    let penumbra = |f: &Frame| {
        f.visibility
            .iter()
            .filter(|&&v| v > 0.004 && v < 0.996)
            .count()
    };
    let every = |angle: u32| {
        Knobs::default()
            .with(&smrt::ADAPTIVE.0, 0)
            .with(&smrt::MAX_ANGLE.0, angle)
    };
    let uncapped = penumbra(&render(&mut offline, &large, smrt, every(1570)));
    let ue = penumbra(&render(&mut offline, &large, smrt, every(30)));
    let tight = penumbra(&render(&mut offline, &large, smrt, every(5)));
    println!("penumbra pixels: uncapped {uncapped}, 30 mrad {ue}, 5 mrad {tight}");
    assert!(
        tight < ue && 2 * ue < uncapped,
        "penumbra pixels at 5 / 30 mrad / uncapped: {tight} / {ue} / {uncapped}"
    );
}

/// Variance shadow maps bleed light where the filter sees two occluders at different depths:
/// on `leak-test`, ground in the low plate's umbra under the high plate's edge reads lit where
/// the reference (and the plain hard shadow of the same map) reads dark, over a band as wide as
/// the filter; a stronger bleeding reduction hides it. The four-moment map with the same filter
/// (`msm`) leaks nothing there and `msm-soft` at its defaults less than vsm; `msm-soft`'s own
/// failure shows beside it (printed, docs/method/README.md): its penumbra filter, widened by the
/// high plate, sees three depths and leaks over a wider part of the low plate's umbra.
#[test]
fn vsm_bleeds_light_on_leak_test() {
    use dbuffer::render::methods::{msm, msm_soft, vsm};
    const FILTER: u32 = 12;
    let mut s = Scored::new("leak-test", 160);
    // Deep umbra: the reference dark over the whole (2·2+1)² neighbourhood, so a soft method's
    // wider penumbra at an umbra's rim does not count as a leak.
    let n = s.size as usize;
    let dark = |i: usize| s.mask[i] && s.reference[i] <= 0.02;
    let deep: Vec<bool> = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            (x >= 2 && y >= 2 && x + 2 < n && y + 2 < n)
                && (y - 2..=y + 2).all(|yy| (x - 2..=x + 2).all(|xx| dark(yy * n + xx)))
        })
        .collect();
    let run = |s: &mut Scored,
               spec: &'static dbuffer::render::methods::MethodSpec,
               knobs: Knobs,
               label: &str| {
        let method = Method::of(spec).expect("on the registry");
        s.measure_as(method, knobs, label).0.visibility
    };
    let lit_in = |v: &[f32], region: &[bool]| {
        v.iter()
            .zip(region)
            .filter(|(v, r)| **r && **v >= 0.25)
            .count()
    };
    let mean_in = |v: &[f32], region: &[bool]| {
        let (sum, n) = v
            .iter()
            .zip(region)
            .filter(|(_, r)| **r)
            .fold((0.0, 0), |(s, n), (v, _)| (s + v, n + 1));
        sum / n.max(1) as f32
    };
    let wide = |k: &'static dbuffer::render::methods::Knob| Knobs::default().with(k, FILTER);
    let hard = run(
        &mut s,
        &dbuffer::render::methods::hard::HARD,
        Knobs::default(),
        "hard",
    );
    let vsm = run(&mut s, &vsm::VSM, wide(&vsm::RADIUS), "vsm, radius 12");
    let vsm_reduced = run(
        &mut s,
        &vsm::VSM,
        wide(&vsm::RADIUS).with(&vsm::BLEED, 60),
        "vsm, radius 12, bleed reduction 0.6",
    );
    let msm = run(&mut s, &msm::MSM, wide(&msm::RADIUS), "msm, radius 12");
    let msm_soft = run(
        &mut s,
        &msm_soft::MSM_SOFT,
        Knobs::default(),
        "msm-soft (defaults)",
    );
    let pcss = run(
        &mut s,
        &dbuffer::render::methods::pcss::PCSS,
        Knobs::default(),
        "pcss (defaults)",
    );
    // The bled band: deep umbra that vsm reads lit.
    let band: Vec<bool> = deep
        .iter()
        .zip(&vsm)
        .map(|(d, v)| *d && *v >= 0.25)
        .collect();
    println!(
        "deep umbra ({} pixels) read V >= 0.25: hard {}, vsm {}, vsm at 0.6 {}, msm {}, msm-soft {}, pcss {}",
        deep.iter().filter(|d| **d).count(),
        lit_in(&hard, &deep),
        lit_in(&vsm, &deep),
        lit_in(&vsm_reduced, &deep),
        lit_in(&msm, &deep),
        lit_in(&msm_soft, &deep),
        lit_in(&pcss, &deep),
    );
    let band_pixels = band.iter().filter(|b| **b).count();
    println!(
        "mean V over vsm's bled band ({band_pixels} pixels; the reference reads <= 0.02): vsm {:.3}, \
         vsm at 0.6 {:.3}, msm {:.3}, msm-soft {:.3}, pcss {:.3}",
        mean_in(&vsm, &band),
        mean_in(&vsm_reduced, &band),
        mean_in(&msm, &band),
        mean_in(&msm_soft, &band),
        mean_in(&pcss, &band),
    );
    assert!(
        band_pixels >= 30 && lit_in(&hard, &deep) * 4 <= band_pixels,
        "vsm should bleed on leak-test: {band_pixels} deep-umbra pixels lit (hard: {})",
        lit_in(&hard, &deep)
    );
    let vsm_band = mean_in(&vsm, &band);
    assert!(
        vsm_band >= 0.25,
        "vsm's band reads V {vsm_band}: well above the reference's"
    );
    assert!(
        mean_in(&vsm_reduced, &band) < 0.5 * vsm_band,
        "the bleeding reduction should hide most of it"
    );
    for (name, v) in [("msm", &msm), ("msm-soft", &msm_soft)] {
        let leak = mean_in(v, &band);
        assert!(
            leak < 0.75 * vsm_band,
            "{name} should leak less than vsm in vsm's bled band: V {leak:.3} vs {vsm_band:.3}"
        );
    }
}

/// Moment soft shadows against PCSS, the method they replace in an engine: with the filter
/// sized by the light's image projected into the map, the table's depths heights above the
/// light's plane (a receiver parallel to the light is one depth over any box) and boxes wider
/// than the table's room summed in pieces, `msm-soft`'s exact box filter beats PCSS's 32 noisy
/// taps on convex casters — spheres at several heights, a caster smaller than the light, the
/// strip and triangle lights — and on the concave, overlapping and fusing ones scored here. The
/// filtered hard shadows (`vsm`, `msm`) stand between the hard shadow and the soft methods.
#[test]
fn msm_soft_against_pcss_and_the_filtered_hard_shadows() {
    use dbuffer::render::methods::{hard, msm, msm_soft, pcss, vsm};
    let of = |spec| Method::of(spec).expect("on the registry");
    println!("| scene | method | class mismatch % | MAE | penumbra MAE | p99 |");
    for name in [
        "fig1-large-light",
        "fig8a-distance",
        "fig8b-light-size",
        "no-umbra",
        "table1-224",
        "table1-960",
        "rect-strip",
        "polygon-triangle",
        "fig7-concave",
        "overlap",
        "fusion-cross",
        "fusion-many",
    ] {
        let mut s = Scored::new(name, SIZE);
        let d = Knobs::default();
        let (_, h) = s.measure_as(of(&hard::HARD), d, "hard");
        let (_, v) = s.measure_as(of(&vsm::VSM), d, "vsm");
        let (_, m) = s.measure_as(of(&msm::MSM), d, "msm");
        let (_, ms) = s.measure_as(of(&msm_soft::MSM_SOFT), d, "msm-soft");
        let (_, p) = s.measure_as(of(&pcss::PCSS), d, "pcss");
        assert!(
            ms.penumbra_mae <= p.penumbra_mae,
            "{name}: msm-soft's penumbra MAE {:.4} against PCSS's {:.4}",
            ms.penumbra_mae,
            p.penumbra_mae
        );
        for (label, f) in [("vsm", &v), ("msm", &m)] {
            assert!(
                f.penumbra_mae < h.penumbra_mae && f.penumbra_mae > ms.penumbra_mae,
                "{name}: {label} {:.4} should lie between msm-soft {:.4} and hard {:.4}",
                f.penumbra_mae,
                ms.penumbra_mae,
                h.penumbra_mae
            );
        }
    }
}

fn bitmask_method() -> Method {
    Method::of(&dbuffer::render::methods::bitmask::BITMASK).expect("bitmask is on the registry")
}

/// Bitmask soft shadows against PCSS: back-projecting every texel in front of the receiver onto
/// the light's samples leaves only the one depth layer and the samples' own noise, so its
/// penumbra error is at most PCSS's on every scene — concave, overlapping and fusing casters and
/// rectangle and polygon lights included — and on convex casters, where the one layer the map
/// holds is all there is, within 0.03 of the reference.
#[test]
fn bitmask_beats_pcss_on_every_scene() {
    let bitmask = bitmask_method();
    let pcss = Method::of(&dbuffer::render::methods::pcss::PCSS).expect("pcss");
    println!("| scene | method | class mismatch % | MAE | penumbra MAE | p99 |");
    for (name, convex) in [
        ("fig1-large-light", true),
        ("fig8a-distance", true),
        ("fig8b-light-size", true),
        ("no-umbra", true),
        ("table1-224", true),
        ("rect-strip", true),
        ("polygon-triangle", true),
        ("fig7-concave", false),
        ("overlap", false),
        ("acute-corner", true),
        ("fusion-cross", false),
        ("fusion-many", false),
        ("rect-fusion", false),
        ("leak-test", false),
    ] {
        let mut s = Scored::new(name, SIZE);
        let (_, b) = s.measure_as(bitmask, Knobs::default(), "bitmask");
        let (_, p) = s.measure_as(pcss, Knobs::default(), "pcss");
        assert!(
            b.penumbra_mae <= p.penumbra_mae,
            "{name}: bitmask's penumbra MAE {:.4} against PCSS's {:.4}",
            b.penumbra_mae,
            p.penumbra_mae
        );
        if convex {
            assert!(
                b.penumbra_mae <= 0.03,
                "{name}: bitmask's penumbra MAE {:.4} on a convex caster",
                b.penumbra_mae
            );
        }
    }
}

/// The gap filling and the pyramid: on a curved caster seen at a slant (the sphere of
/// `table1-960`, whose texels step in distance toward its rim) micro-patches flat at their own
/// texel's distance leave gaps between them that light leaks through, and the shared corners
/// close them. Back-projecting a pyramid node that is one surface wholly in front of the receiver
/// as one patch gives the shadow of its texels one by one; reading a node too small to matter
/// on the light at its middle texel (the level of detail) moves V by a fraction of a sample.
#[test]
fn bitmask_gap_filling_closes_the_gaps_and_the_pyramid_changes_little() {
    use dbuffer::render::methods::bitmask::{COARSE, DETAIL, GAP_FILL};
    let bitmask = bitmask_method();
    let mut s = Scored::new("table1-960", SIZE);
    let (default_frame, filled) = s.measure_as(bitmask, Knobs::default(), "bitmask");
    let (_, gaps) = s.measure_as(
        bitmask,
        Knobs::default().with(&GAP_FILL.0, 0),
        "bitmask, no gap filling",
    );
    assert!(
        filled.mae < gaps.mae,
        "gap filling should lower the error: {:.4} with, {:.4} without",
        filled.mae,
        gaps.mae
    );
    // On a 512² map, where every texel of the sphere fits in the 65 535 iterations Mesa's
    // llvmpipe gives a shader's loops (render::methods::bitmask).
    let mut on_512 = |knobs: Knobs| {
        let request = dbuffer::render::FrameRequest {
            width: SIZE,
            height: SIZE,
            dbuffer_size: 512,
            method: bitmask,
            vt: dbuffer::geometry::VtVariant::Exact,
            knobs,
            read_dbuffer: false,
            read_cost: false,
            colour_only: false,
        };
        s.offline
            .render(&s.scene, &request)
            .unwrap_or_else(|e| panic!("{e}"))
            .0
    };
    let every_node = Knobs::default().with(&DETAIL.0, 0);
    let nodes_frame = on_512(every_node);
    let texels_frame = on_512(every_node.with(&COARSE.0, 0));
    let differ = |a: &Frame, b: &Frame| {
        let d: Vec<f32> = a
            .visibility
            .iter()
            .zip(&b.visibility)
            .map(|(a, b)| (a - b).abs())
            .collect();
        let mean = d.iter().sum::<f32>() / d.len().max(1) as f32;
        (mean, d.into_iter().fold(0.0f32, f32::max))
    };
    let (mean, worst) = differ(&nodes_frame, &texels_frame);
    println!("coarse nodes: mean {mean:.4}, worst {worst:.3}");
    assert!(
        mean < 0.002 && worst < 0.1,
        "coarse nodes moved V by {mean:.4} on average, {worst:.3} at worst"
    );
    let (detailed_frame, _) = s.measure_as(bitmask, every_node, "bitmask, no level of detail");
    let (mean, worst) = differ(&default_frame, &detailed_frame);
    println!("level of detail: mean {mean:.4}, worst {worst:.3}");
    assert!(
        mean < 0.004 && worst < 0.2,
        "the level of detail moved V by {mean:.4} on average, {worst:.3} at worst"
    );
}

/// Occluders combine as bits, not as areas: where the two bars of `fusion-cross` cross, each
/// hides a strip of the light and the two strips overlap, and a sum of the two would hide more
/// light than either. Bitmask's V under the crossing stays within the reference's noise, like
/// `dbuffer-fused`'s, where the paper's D-buffer (one chord a pixel) is off.
#[test]
fn bitmask_fuses_occluders_in_image_space() {
    let bitmask = bitmask_method();
    let mut s = Scored::new("fusion-cross", SIZE);
    let (_, b) = s.measure_as(bitmask, Knobs::default(), "bitmask");
    let (_, d) = s.measure_as(Method::DBUFFER, Knobs::default(), "dbuffer");
    assert!(
        b.penumbra_mae < d.penumbra_mae,
        "bitmask {:.4} against the one-chord D-buffer {:.4}",
        b.penumbra_mae,
        d.penumbra_mae
    );
}

/// The camera pass against its CPU twin on the map it read: the frame's shadow map read back,
/// every texel in front of a ground pixel made a micro-patch with the gap-filled corners of
/// `geometry::bitmask::corner_distance`, and `geometry::bitmask::visibility` over all of them
/// (no pyramid, no search region) gives the GPU's V within the look-up tables' rounding — with
/// the pyramid's coarse nodes and without.
#[test]
fn bitmask_matches_its_cpu_twin_on_the_map_it_reads() {
    use dbuffer::geometry::bitmask::{corner_distance, visibility, LightPlane};
    use dbuffer::geometry::fused::{DiskMask, MaskEval};
    use dbuffer::geometry::light_view::LightView;
    use dbuffer::render::methods::bitmask::COARSE;
    use dbuffer::render::FrameRequest;
    use glam::{Vec3, Vec4};
    const MAP: u32 = 256;
    let scene = scene::load("fig8a-distance").unwrap_or_else(|e| panic!("{e}"));
    let light = *scene.light.as_area().expect("a disk light");
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let view = LightView::fit(&scene).view_projection();
    let inverse = view.inverse();
    let plane = LightPlane::of(&light);
    let mask = DiskMask::for_light(&light, 256, MaskEval::Lut);
    for coarse in [1, 0] {
        let request = FrameRequest {
            width: 48,
            height: 48,
            dbuffer_size: MAP,
            method: bitmask_method(),
            vt: dbuffer::geometry::VtVariant::Exact,
            knobs: Knobs::default().with(&COARSE.0, coarse),
            read_dbuffer: true,
            read_cost: false,
            colour_only: false,
        };
        let (frame, _) = offline
            .render(&scene, &request)
            .unwrap_or_else(|e| panic!("{e}"));
        let maps = frame.maps.as_ref().expect("the shadow map read back");
        let o = |x: i64, y: i64| -> f32 {
            if x < 0 || y < 0 || x >= MAP as i64 || y >= MAP as i64 {
                return 3.0e38;
            }
            maps.texel(x as u32, y as u32).map_or(3.0e38, |t| t[0][0])
        };
        let direction = |s: f32, t: f32| -> Vec3 {
            let ndc = Vec4::new(
                s / MAP as f32 * 2.0 - 1.0,
                1.0 - t / MAP as f32 * 2.0,
                0.5,
                1.0,
            );
            let p = inverse * ndc;
            (p.truncate() / p.w - light.center).normalize()
        };
        // Every caster texel (the ground is never in front of a ground pixel) as a patch.
        let mut patches = Vec::new();
        for y in 0..MAP as i64 {
            for x in 0..MAP as i64 {
                let own = o(x, y);
                if own >= 1.0e30 || own.is_nan() {
                    continue;
                }
                let corner = |cx: i64, cy: i64| {
                    let around = [o(cx - 1, cy - 1), o(cx, cy - 1), o(cx - 1, cy), o(cx, cy)];
                    let d = corner_distance(own, &around);
                    light.center + direction(cx as f32, cy as f32) * d
                };
                let quad = [
                    corner(x, y),
                    corner(x + 1, y),
                    corner(x + 1, y + 1),
                    corner(x, y + 1),
                ];
                // Off the ground: casters only.
                if quad.iter().all(|p| p.y > 0.01) {
                    patches.push(quad);
                }
            }
        }
        let (mut worst, mut sum, mut n) = (0.0f32, 0.0f32, 0);
        for i in 0..frame.len() {
            let Some(x) = frame.position(i) else { continue };
            if x.y.abs() > 1e-3 {
                continue;
            }
            let twin = visibility(&plane, &mask, x, &patches);
            let gpu = frame.visibility[i];
            worst = worst.max((twin - gpu).abs());
            sum += (twin - gpu).abs();
            n += 1;
        }
        let mean = sum / n.max(1) as f32;
        println!("coarse {coarse}: {n} ground pixels, mean |ΔV| {mean:.4}, worst {worst:.3}");
        assert!(n > 500, "{n} ground pixels");
        // Texel by texel the GPU reads the twin's tables: the same bits but for rounding in
        // the corners' positions. A coarse node is one quad where the twin has its texels'.
        let (mean_bound, worst_bound) = if coarse == 1 {
            (0.002, 0.05)
        } else {
            (2e-4, 0.02)
        };
        assert!(
            mean < mean_bound && worst < worst_bound,
            "coarse {coarse}: the GPU's V is {mean:.4} from its twin on average, {worst:.3} at worst"
        );
    }
}
