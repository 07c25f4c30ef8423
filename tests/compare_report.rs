//! `dbuffer compare`'s report holds the numbers its own files give: every metric is recomputed
//! here from the written visibility EXRs, and every heatmap is the error those EXRs show.

use dbuffer::compare::{self, heatmap, report, CompareRequest};
use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::{metrics, view, VtVariant};
use dbuffer::output::read_exr_rgba;
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Knobs, Method};
use dbuffer::scene;

const W: u32 = 72;
const H: u32 = 64;

#[test]
fn the_report_matches_the_written_files() {
    let name = "fig7-concave";
    let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let request = CompareRequest {
        width: W,
        height: H,
        dbuffer_size: 512,
        vt: VtVariant::Exact,
        knobs: Knobs::default().with(&SAMPLES, 128),
    };
    let mut heard = Vec::new();
    let comparison = compare::run(&mut offline, name, &scene, &request, |what| {
        heard.push(what.to_string())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        heard.len(),
        Method::all().len(),
        "one progress line a method"
    );
    let dir = std::env::temp_dir().join(format!("dbuffer-compare-test-{}", std::process::id()));
    let written = report::write(&dir, &comparison).unwrap_or_else(|e| panic!("{e}"));
    // Image, visibility and heatmap per method (none for the reference), a hard-error image per
    // hard method, the two reports.
    let hard = Method::all().iter().filter(|m| m.is_hard()).count();
    assert_eq!(written.len(), 3 * Method::all().len() - 1 + hard + 2);

    let text = std::fs::read_to_string(dir.join(report::REPORT_JSON)).unwrap();
    let r: report::Report = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((r.width, r.height, r.samples), (W, H, 128));
    assert!(!r.adapter.is_empty());
    assert!(r.reference_rays_per_s > 0.0);
    let methods: Vec<&str> = r.methods.iter().map(|m| m.method.as_str()).collect();
    assert_eq!(methods[0], "reference");
    for m in Method::all() {
        assert!(methods.contains(&m.name()), "{m} missing from the report");
    }
    let md = std::fs::read_to_string(dir.join(report::REPORT_MD)).unwrap();

    // The pixels that count, as the report defines them, from the files alone.
    let read = |file: &str| {
        let (w, h, px) = read_exr_rgba(&dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!((w, h), (W, H));
        px
    };
    let reference = read(&r.methods[0].visibility);
    let receivers = view::receivers(&scene, &Bvh::build(scene.all_triangles()), W, H);
    let mask: Vec<bool> = receivers
        .iter()
        .zip(&reference)
        .map(|(rc, p)| p[3] > 0.5 && rc.is_some_and(|rc| rc.faces_light))
        .collect();
    assert_eq!(mask.iter().filter(|&&m| m).count(), r.pixels);
    let v_ref: Vec<f32> = reference.iter().map(|p| p[0]).collect();
    for row in &r.methods {
        let v: Vec<f32> = read(&row.visibility).iter().map(|p| p[0]).collect();
        let m = metrics::compare(&v_ref, &v, &mask);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
        assert!(
            close(m.class_mismatch_pct, row.class_mismatch_pct),
            "{}",
            row.method
        );
        assert!(close(m.mae, row.mae), "{}", row.method);
        assert!(close(m.penumbra_mae, row.penumbra_mae), "{}", row.method);
        assert!(close(m.p99, row.p99), "{}", row.method);
        assert_eq!(m.penumbra_pixels, row.penumbra_pixels, "{}", row.method);
        assert!(md.contains(&format!(
            "| {} | {:.2} |",
            row.method, row.class_mismatch_pct
        )));
        let image = image::open(dir.join(&row.image)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((image.width(), image.height()), (W, H));
        match &row.heatmap {
            None => assert_eq!(row.method, "reference"),
            Some(file) => {
                let heat = image::open(dir.join(file)).unwrap().to_rgb8();
                assert!(heat.height() > H, "{file} has no legend");
                // Every counted pixel shows its own error's colour.
                for i in (0..(W * H) as usize).step_by(7) {
                    let want = if mask[i] {
                        heatmap::error_rgb((v[i] - v_ref[i]).abs())
                    } else {
                        heatmap::MASKED_RGB
                    };
                    let got = heat.get_pixel(i as u32 % W, i as u32 / W).0;
                    assert_eq!(got, want, "{file} pixel {i}");
                }
            }
        }
    }
    // The reference against itself is perfect, and the comparison shows what it is for: the
    // hard shadow misses the penumbra the D-buffer gets.
    let row = |n: &str| r.methods.iter().find(|m| m.method == n).unwrap();
    assert_eq!(row("reference").mae, 0.0);
    assert!(row("dbuffer").penumbra_mae < 0.5 * row("hard").penumbra_mae);
    let _ = std::fs::remove_dir_all(&dir);
}
