//! The registry holds a method together: walking `methods::ALL`, every method has its camera
//! shader (embedded and valid under naga), its snapshot, its bench row, its place in the study
//! (a sweep over its quality knobs, or why it has none) and a command-line flag per knob — with no list of methods kept here — and no code outside the method modules names a
//! method by a string literal (a rename cannot break a match elsewhere silently).

use std::path::{Path, PathBuf};

use dbuffer::bench::{Case, Config};
use dbuffer::render::methods::{all_knobs, KnobKind, Quality};
use dbuffer::render::Method;
use dbuffer::scene::LightKind;
use dbuffer::shader_source;
use naga::valid::{Capabilities, ValidationFlags, Validator};

use crate::support as cli;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn every_method_has_a_valid_embedded_shader() {
    for m in Method::all() {
        let shader = m.spec().shader;
        assert!(
            shader_source::embedded(shader).is_some(),
            "{m}: its shader {shader} is not under shaders/"
        );
        let source = shader_source::load(shader).unwrap_or_else(|e| panic!("{m}: {e}"));
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{m}: {}", e.emit_to_string_with_path(&source, shader)));
        Validator::new(ValidationFlags::all(), Capabilities::all())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{m}: {}", e.emit_to_string_with_path(&source, shader)));
        assert!(
            source.contains("fn method_visibility"),
            "{m}: {shader} has no method_visibility"
        );
    }
}

#[test]
fn every_method_has_a_snapshot() {
    // The scene `tests/gpu/render_snapshots.rs` draws each method on: fig7-concave, or line-fig9 for
    // a method that needs a line light.
    for m in Method::all() {
        let scene = if m.takes(LightKind::Disk) {
            "fig7-concave"
        } else {
            "line-fig9"
        };
        let png = root().join(format!("tests/snapshots/method-{m}-{scene}.png"));
        assert!(png.is_file(), "{m}: no snapshot {}", png.display());
    }
}

#[test]
fn every_method_has_a_bench_row_with_valid_knobs() {
    for config in [Config::full(), Config::quick()] {
        for &m in Method::all() {
            let case = config
                .cases
                .iter()
                .find(|c| c.method == m)
                .unwrap_or_else(|| panic!("{m} has no bench row"));
            assert!(!case.label.is_empty());
            case.knobs
                .validate()
                .unwrap_or_else(|e| panic!("{m}'s bench knobs: {e}"));
        }
    }
    // What a module asks for is what the case carries.
    for &m in Method::all() {
        let case = Case::for_method(m);
        for &(knob, value) in m.spec().bench.knobs {
            assert_eq!(case.knobs.raw(knob), value, "{m}: --{}", knob.name);
        }
    }
}

#[test]
fn every_method_states_its_study_sweep() {
    for &m in Method::all() {
        let sweep = m.sweep();
        assert!(
            sweep.is_stated(),
            "{m}: its MethodSpec says neither .sweep(..) over its quality knobs nor \
             .fixed_quality(why) (docs/development/adding-a-method.md)"
        );
        if let Some(why) = sweep.fixed {
            assert!(
                sweep.settings.is_empty(),
                "{m}: fixed ({why}) with settings"
            );
            assert!(!why.trim().is_empty(), "{m}: fixed without a reason");
            continue;
        }
        // The quick study takes three settings of every method that has a quality knob.
        assert!(
            sweep.settings.len() >= 3,
            "{m}: a sweep of {} settings (at least 3)",
            sweep.settings.len()
        );
        for axis in sweep.axes {
            if let Quality::Knob(k) = axis {
                assert!(
                    m.knobs().iter().any(|own| own.name == k.name),
                    "{m}: sweeps --{} which is not one of its knobs",
                    k.name
                );
            }
        }
        for (i, setting) in sweep.settings.iter().enumerate() {
            assert_eq!(setting.len(), sweep.axes.len(), "{m}: setting {i}");
            for (axis, &v) in sweep.axes.iter().zip(setting.iter()) {
                assert!(
                    axis.check(v).is_none(),
                    "{m}: setting {i}: {:?}",
                    axis.check(v)
                );
            }
            assert!(
                !sweep.settings[..i].contains(setting),
                "{m}: setting {i} repeats an earlier one"
            );
        }
    }
}

#[test]
fn every_knob_is_a_flag_of_render_and_compare() {
    for command in ["render", "compare"] {
        let out = cli::dbuffer()
            .args([command, "--help"])
            .output()
            .expect("the binary runs");
        let help = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{command} --help: {help}");
        for m in Method::all() {
            for knob in m.knobs() {
                let (min, max) = knob.range();
                let flag = format!("--{} <N>", knob.name);
                assert!(
                    help.contains(&flag),
                    "{command} --help lacks {flag}:\n{help}"
                );
                assert!(
                    help.contains(&format!("{min} to {max} (default {})", knob.default)),
                    "{command} --help: --{} has no range",
                    knob.name
                );
            }
        }
    }
}

#[test]
fn a_switch_takes_numbers_and_words_and_refuses_the_rest_by_flag() {
    let switch = all_knobs()
        .iter()
        .find(|k| k.kind == KnobKind::Switch)
        .expect("a method has an on/off knob");
    let dir = cli::temp_dir("registry", "switch");
    for (value, error) in [("2", true), ("true", false), ("0", false)] {
        let out = cli::dbuffer()
            .args([
                "render",
                "fig7-concave",
                "--size",
                "4x4",
                "--dbuffer-size",
                "16",
            ])
            .arg(format!("--{}", switch.name))
            .arg(value)
            .arg("--out")
            .arg(&dir)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            !out.status.success(),
            error,
            "--{} {value}: {stderr}",
            switch.name
        );
        if error {
            assert!(
                stderr.contains(&format!("--{} expects 0 to 1, found {value}", switch.name)),
                "{stderr}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src/") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn no_method_name_is_a_string_literal_outside_the_method_modules() {
    let methods = root().join("src/render/methods");
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    let mut found = Vec::new();
    // A module's unit tests kept in a file of their own (`output/tests.rs`) are tests too.
    let unit_tests = |f: &PathBuf| f.file_name().is_some_and(|n| n == "tests.rs");
    for file in files
        .iter()
        .filter(|f| !f.starts_with(&methods) && !unit_tests(f))
    {
        let text = std::fs::read_to_string(file).expect("read a source file");
        // Unit tests may name methods: only the code before them counts.
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        for (i, line) in code.lines().enumerate() {
            for m in Method::all() {
                if line.contains(&format!("\"{m}\"")) {
                    let at = file.strip_prefix(root()).unwrap_or(file);
                    found.push(format!("{}:{}: \"{m}\"", at.display(), i + 1));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "method names as literals outside src/render/methods (use the MethodSpec, or Method's \
         constants):\n{}",
        found.join("\n")
    );
}
