//! `dbuffer compare`'s report holds the numbers its own files give: every metric is recomputed
//! here from the written visibility EXRs, and every heatmap is the error those EXRs show.

use dbuffer::compare::{self, heatmap, montage, report, CompareRequest};
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
    let written = report::write(&dir, &comparison, None).unwrap_or_else(|e| panic!("{e}"));
    // Five files a method drawn (image, EXR, heatmap, FLIP map, cost heatmap; the reference has
    // no |ΔV| heatmap), a hard-error image per hard method drawn, the montage and the two
    // reports.
    let drawn = comparison.results.len();
    let hard = comparison
        .results
        .iter()
        .filter(|r| r.method.is_hard())
        .count();
    // A temporal method is drawn twice: its first frame, then after its history.
    let first_frames: Vec<String> = comparison
        .results
        .iter()
        .filter(|r| r.history == Some(0))
        .map(|r| r.label())
        .collect();
    assert_eq!(first_frames, ["raytraced-first-frame"]);
    assert_eq!(
        drawn - first_frames.len() + comparison.not_applicable.len(),
        Method::all().len()
    );
    assert_eq!(written.len(), 5 * drawn - 1 + hard + 3);
    assert!(hard > 0 && hard < drawn);

    // The montage: one tile per method drawn, four cells each (image, |ΔV|, FLIP, against
    // reference-hard), and each tile shows its own method.
    let layout = montage::Layout::new(W, H, drawn as u32, 4);
    let page = image::open(dir.join(montage::MONTAGE_PNG))
        .unwrap_or_else(|e| panic!("{e}"))
        .to_rgb8();
    assert_eq!(page.dimensions(), (layout.width, layout.height));
    assert_eq!(layout.factor, 1, "a small comparison is not reduced");
    let cell = |i: usize, k: u32| {
        let (x, y) = layout.cell(i as u32, k);
        image::imageops::crop_imm(&page, x, y, W, H).to_image()
    };
    let tile_of = |m: Method| {
        comparison
            .results
            .iter()
            .position(|r| r.method == m)
            .unwrap_or_else(|| panic!("{m} drawn"))
    };
    for (i, r) in comparison.results.iter().enumerate() {
        // The image cell is the method's image, pixel for pixel.
        let img = cell(i, 0);
        for (x, y, p) in img.enumerate_pixels() {
            let c = r.frame.color[(y * W + x) as usize];
            assert_eq!(p.0, [c[0], c[1], c[2]], "{} at ({x}, {y})", r.method);
        }
        // The label holds text: light pixels above the cells.
        let (tx, ty) = layout.tile(i as u32);
        let label = image::imageops::crop_imm(&page, tx, ty, W, 16).to_image();
        assert!(
            label
                .pixels()
                .filter(|p| p.0.iter().all(|&c| c > 150))
                .count()
                > 10,
            "{}: no label",
            r.method
        );
    }
    // Two methods' tiles differ: the hard shadow's image and heatmap are not the D-buffer's.
    let (d, hd) = (tile_of(Method::DBUFFER), tile_of(Method::HARD));
    assert_ne!(cell(d, 0), cell(hd, 0));
    assert_ne!(cell(d, 1), cell(hd, 1));
    // The heatmap cell shows each counted pixel's error, and the hard cell what
    // METHOD-hard-error.png shows.
    let heat = cell(hd, 1);
    let v_hard = &comparison.results[hd].frame.visibility;
    let v_reference = &comparison.reference().frame.visibility;
    for (x, y, p) in heat.enumerate_pixels() {
        let i = (y * W + x) as usize;
        let want = if comparison.mask[i] {
            heatmap::error_rgb((v_hard[i] - v_reference[i]).abs())
        } else {
            heatmap::MASKED_RGB
        };
        assert_eq!(p.0, want, "hard's heatmap cell at ({x}, {y})");
    }
    let hard_error = image::open(dir.join("hard-hard-error.png"))
        .unwrap_or_else(|e| panic!("{e}"))
        .to_rgb8();
    assert_eq!(cell(hd, 3), hard_error);
    // The FLIP cell is METHOD-flip.png's map (above its legend), and the FLIP map is what
    // geometry::flip makes of the two written images.
    let flip_png = image::open(dir.join("hard-flip.png")).unwrap().to_rgb8();
    let flip_map = image::imageops::crop_imm(&flip_png, 0, 0, W, H).to_image();
    assert_eq!(cell(hd, 2), flip_map);
    let rgb = |file: &str| -> Vec<[u8; 3]> {
        image::open(dir.join(file))
            .unwrap()
            .to_rgb8()
            .pixels()
            .map(|p| p.0)
            .collect()
    };
    let again = dbuffer::geometry::flip::ldr_flip(
        &rgb("reference.png"),
        &rgb("hard.png"),
        W,
        H,
        dbuffer::geometry::flip::DEFAULT_PPD,
    )
    .unwrap();
    assert_eq!(again, comparison.results[hd].flip);

    let text = std::fs::read_to_string(dir.join(report::REPORT_JSON)).unwrap();
    let r: report::Report = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((r.width, r.height, r.samples), (W, H, 128));
    assert!(!r.adapter.is_empty());
    assert!(r.reference_rays_per_s > 0.0);
    let methods: Vec<&str> = r.methods.iter().map(|m| m.method.as_str()).collect();
    assert_eq!(methods[0], "reference");
    // The temporal method's two rows, labelled by their history, its first frame just before.
    let at = |name: &str| methods.iter().position(|&m| m == name);
    let first = at("raytraced-first-frame").expect("the first frame's row");
    assert_eq!(at("raytraced"), Some(first + 1));
    assert_eq!(r.methods[first].history_frames, Some(0));
    assert_eq!(r.methods[first + 1].history_frames, Some(15));
    assert!(dir.join("raytraced-first-frame.png").is_file());
    for m in Method::all() {
        let skipped = r.not_applicable.iter().any(|n| n.method == m.name());
        assert!(
            methods.contains(&m.name()) != skipped,
            "{m}: in the report once, drawn or not applicable"
        );
        // A disk scene: only a method that needs a line light is left out.
        assert_eq!(skipped, m.refuses(scene.light.kind()).is_some(), "{m}");
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
    // FLIP for every method: the reference against itself 0, every other image above it, the
    // hard shadow (no penumbra) above the D-buffer; each with its map and its cost.
    assert_eq!(row("reference").flip_mean, 0.0);
    for m in &r.methods {
        assert!(
            m.flip_mean.is_finite() && (0.0..=1.0).contains(&m.flip_mean),
            "{m:?}"
        );
        assert!(dir.join(&m.flip).is_file(), "{}", m.flip);
        let cost = m
            .cost
            .as_ref()
            .unwrap_or_else(|| panic!("{}: no cost", m.method));
        assert!(dir.join(&cost.image).is_file(), "{}", cost.image);
        assert!(md.contains(&format!("| {} | {}", m.method, cost.unit)) || cost.constant);
    }
    assert!(row("hard").flip_mean > row("dbuffer").flip_mean, "{md}");
    assert!(row("dbuffer").flip_mean > 0.0);
    // invalid_px is the frame's own count, and no method returns a NaN or infinite V or t (a V a
    // rounding step outside [0, 1] counts too, but depends on the device's arithmetic); the
    // report has its out-of-range line exactly when some method has such pixels.
    for (row, result) in r.methods.iter().zip(&comparison.results) {
        let f = &result.frame;
        assert_eq!(row.invalid_px, f.out_of_range_pixels(), "{}", row.method);
        let non_finite = (0..f.len())
            .filter(|&i| f.hit(i) && !(f.visibility[i].is_finite() && f.t(i).is_finite()))
            .count();
        assert_eq!(non_finite, 0, "{}: NaN or infinite V or t", row.method);
    }
    let any = r.methods.iter().any(|m| m.invalid_px > 0);
    assert_eq!(md.contains("V or t out of range"), any);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Under a line light, the disk-only methods are listed as not applicable with their reason,
/// never drawn; the others are measured against the line reference.
#[test]
fn a_line_light_scene_lists_the_disk_only_methods_as_not_applicable() {
    let name = "line-fig2";
    let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let request = CompareRequest {
        width: 48,
        height: 40,
        dbuffer_size: 256,
        vt: VtVariant::Smoothstep,
        knobs: Knobs::default().with(&SAMPLES, 64),
    };
    let comparison = compare::run(&mut offline, name, &scene, &request, |_| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let r = report::Report::new(&comparison);
    for m in Method::all() {
        let drawn = r.methods.iter().any(|row| row.method == m.name());
        let na = r.not_applicable.iter().find(|n| n.method == m.name());
        match m.needs() {
            Some(kinds) if !kinds.contains(&dbuffer::scene::LightKind::Line) => {
                let n = na.unwrap_or_else(|| panic!("{m} must be not applicable"));
                assert!(!drawn, "{m} drawn under a line light");
                let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
                assert_eq!(n.needs, names.join(", "));
                assert!(
                    n.reason.contains(m.name()) && n.reason.contains("line"),
                    "{n:?}"
                );
            }
            _ => assert!(drawn && na.is_none(), "{m} must be drawn"),
        }
    }
    let table = r.table();
    assert!(
        table.contains("| dbuffer | n/a — needs a disk, rect or polygon light |"),
        "{table}"
    );
    // The hard shadow from the midpoint is far from the line reference; sampled much closer.
    let row = |m: &str| r.methods.iter().find(|row| row.method == m).unwrap();
    assert!(
        row("sampled").penumbra_mae < row("hard").penumbra_mae,
        "{table}"
    );
    assert!(row("hard").penumbra_pixels > 50, "{table}");
}
