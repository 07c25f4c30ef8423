//! Every WGSL file under `shaders/` parses and validates with naga (the one wgpu uses), so a
//! broken shader fails `cargo test` even when no test draws with it.
//!
//! `shaders/passes/*.wgsl` and `shaders/methods/*.wgsl` are whole shaders: each is expanded
//! (`// #include` lines pasted, see `shaders/README.md`) and validated on its own. Files in
//! `shaders/shared/` are validated as part of the shaders that include them, and each must be
//! included by one.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use dbuffer::shader_source::{self, Expanded};
use naga::valid::{Capabilities, ValidationFlags, Validator};

fn shader_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders")
}

/// Every `.wgsl` file under `dir`, as `/`-separated names relative to `dir`, sorted.
fn wgsl_files(dir: &Path) -> Vec<String> {
    fn walk(dir: &Path, prefix: &str, out: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries {
            let entry = entry.expect("read shaders/ entry");
            let name = entry.file_name().to_string_lossy().into_owned();
            let path = entry.path();
            if path.is_dir() {
                walk(&path, &format!("{prefix}{name}/"), out);
            } else if name.ends_with(".wgsl") {
                out.push(format!("{prefix}{name}"));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, "", &mut out);
    out.sort();
    out
}

/// Parse and validate `source`; on failure naga's own report, attributed to `path`.
fn validate(path: &str, source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| e.emit_to_string_with_path(source, path))?;
    Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string_with_path(source, path))?;
    Ok(module)
}

/// [`validate`] on an expanded shader; a failure also says which file and line each line that
/// naga's report points at came from (naga sees the expanded text, whose line numbers differ from
/// the files' once includes are pasted).
fn validate_expanded(name: &str, expanded: &Expanded) -> Result<naga::Module, String> {
    let source = &expanded.source;
    let labelled: Vec<(naga::Span, String)> = match naga::front::wgsl::parse_str(source) {
        Err(e) => e.labels().map(|(s, l)| (s, l.to_owned())).collect(),
        Ok(module) => {
            match Validator::new(ValidationFlags::all(), Capabilities::all()).validate(&module) {
                Err(e) => e.spans().cloned().collect(),
                Ok(_) => return Ok(module),
            }
        }
    };
    let mut report = validate(&format!("{name} (expanded)"), source)
        .expect_err("the same source failed just above");
    let mut lines: Vec<u32> = labelled
        .iter()
        .filter(|(span, _)| span.is_defined())
        .map(|(span, _)| span.location(source).line_number)
        .collect();
    lines.sort_unstable();
    lines.dedup();
    for line in lines {
        if let Some((file, file_line)) = expanded.origin(line) {
            report.push_str(&format!(
                "line {line} of the expanded {name} is shaders/{file}:{file_line}\n"
            ));
        }
    }
    Err(report)
}

#[test]
fn every_wgsl_file_parses_and_validates() {
    let dir = shader_dir();
    let files = wgsl_files(&dir);
    let (passes, shared): (Vec<_>, Vec<_>) = files.iter().partition(|f| !f.starts_with("shared/"));
    println!(
        "found {} WGSL file(s) under {}: {} pass shader(s), {} shared",
        files.len(),
        dir.display(),
        passes.len(),
        shared.len()
    );

    let mut failures = Vec::new();
    let mut included = BTreeSet::new();
    for name in &passes {
        let expanded = match shader_source::from_dir_mapped(&dir, name) {
            Ok(e) => e,
            Err(e) => {
                failures.push(format!("shaders/{name}: {e}"));
                continue;
            }
        };
        // Every line of the expansion names its file: collect the included ones.
        for line in 1..=expanded.source.lines().count() as u32 {
            if let Some((file, _)) = expanded.origin(line) {
                included.insert(file.to_owned());
            }
        }
        match validate_expanded(&format!("shaders/{name}"), &expanded) {
            Ok(_) => println!("  ok  shaders/{name}"),
            Err(report) => failures.push(report),
        }
    }
    // A user's method's shader (render::methods::user): a least file and the code generated for
    // it, with the scene's BVH bound, includes and validates like a pass shader.
    {
        use dbuffer::render::methods::user::{generated_code, GENERATED};
        let least = "// #include shared/camera.wgsl\n\
                     fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {\n\
                     \x20   return plain(select(1.0, 0.0, scene_occluded(x, light_sample(vec2<f32>(0.5)))));\n\
                     }\n";
        match shader_source::expand_user(
            "user.wgsl",
            least,
            (GENERATED, &generated_code(&[], true)),
        ) {
            Ok(expanded) => {
                for line in 1..=expanded.source.lines().count() as u32 {
                    if let Some((file, _)) = expanded.origin(line) {
                        included.insert(file.to_owned());
                    }
                }
                if let Err(report) = validate_expanded("a user's method", &expanded) {
                    failures.push(report);
                }
            }
            Err(e) => failures.push(format!("a user's method: {e}")),
        }
    }
    for name in &shared {
        if !included.contains(name.as_str()) {
            failures.push(format!(
                "shaders/{name} is included by no pass shader, so nothing validates it: \
                 include it from a shaders/*.wgsl or delete it"
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} shader problem(s):\n\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn no_shader_directory_means_no_files() {
    // Before the render core adds its shaders the walk finds nothing and the test above passes,
    // printing "found 0 WGSL file(s)".
    assert!(wgsl_files(&shader_dir().join("no-such-dir")).is_empty());
}

#[test]
fn every_wgsl_file_is_embedded_in_the_library() {
    let dir = shader_dir();
    let on_disk: BTreeSet<String> = wgsl_files(&dir).into_iter().collect();
    let embedded: BTreeSet<String> = shader_source::EMBEDDED
        .iter()
        .map(|(n, _)| (*n).to_owned())
        .collect();
    assert_eq!(
        on_disk, embedded,
        "shader_source::EMBEDDED must list every file under shaders/ (left: on disk, right: embedded)"
    );
    for name in on_disk.iter().filter(|n| !n.contains('/')) {
        assert_eq!(
            shader_source::load(name).expect("embedded shader expands"),
            shader_source::from_dir(&dir, name).expect("shader on disk expands"),
            "{name}: embedded copy differs from the file"
        );
    }
}

#[test]
fn a_broken_shader_fails_with_its_file_and_line() {
    // A parse error: a missing semicolon on line 3.
    let parse = "fn f() -> f32 {\n    let x = 1.0\n    return x;\n}\n";
    let report = validate("broken.wgsl", parse).expect_err("must not parse");
    assert!(report.contains("broken.wgsl:3:"), "{report}");
    assert!(report.contains("return x;"), "{report}");

    // Parses, but the validator rejects it: returning a u32 from an f32 function, line 2. The
    // report starts at the function (line 1) and quotes the offending line.
    let invalid = "fn g() -> f32 {\n    return 1u;\n}\n";
    assert!(naga::front::wgsl::parse_str(invalid).is_ok(), "must parse");
    let report = validate("invalid.wgsl", invalid).expect_err("must not validate");
    assert!(report.contains("invalid.wgsl:1:"), "{report}");
    assert!(report.contains("2 │ │     return 1u;"), "{report}");
    assert!(
        report.contains("does not match the declared return type"),
        "{report}"
    );
}

#[test]
fn an_error_in_an_included_file_names_that_file() {
    let main = "// #include shared/bad.wgsl\n@fragment\nfn fs() -> @location(0) vec4<f32> { return c(); }\n";
    let expanded = shader_source::expand_named("pass.wgsl", main, |n| match n {
        "shared/bad.wgsl" => Some("// a comment\nfn c() -> vec4<f32> { return vec4<f32>(1.0) }\n"),
        _ => None,
    })
    .expect("expands");
    let report = validate_expanded("shaders/pass.wgsl", &expanded).expect_err("must fail");
    assert!(report.contains("is shaders/shared/bad.wgsl:2"), "{report}");
}
