//! The short run of the parser fuzzer (`tests/support/fuzz.rs`): a few thousand executions per
//! target from a fixed seed, and every input a longer run ever found, replayed. The long run:
//! `cargo run --release --example fuzz -- --execs 10000000` (see `examples/fuzz.rs`).

#[path = "support/fuzz.rs"]
mod fuzz;

use fuzz::{escape, CountingAlloc, Limits, Sandbox};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

/// Executions per target in `cargo test` (a few seconds in the dev profile).
const EXECS: u64 = 3000;

#[test]
fn every_target_survives_a_short_run() {
    let sandbox = Sandbox::new("test");
    for target in fuzz::targets() {
        let report = fuzz::fuzz(&target, &sandbox, 2004, EXECS, Limits::default(), |_| {});
        let failures: Vec<String> = report
            .failures
            .iter()
            .map(|f| {
                format!(
                    "{}: {}\n  input: b\"{}\"",
                    f.target,
                    f.problem,
                    escape(&f.input)
                )
            })
            .collect();
        assert!(failures.is_empty(), "{}", failures.join("\n"));
        // The outcomes are many, not one: the mutations reach past the first error.
        assert!(report.outcomes > 20, "{}: {report:?}", target.name);
    }
}

/// Inputs the fuzzer found that broke a property once (minimised by hand); each must pass now.
const REGRESSIONS: &[(&str, &[u8])] = &[
    // A name with a newline repeated in warnings and errors: they were two lines.
    (
        "scene-toml",
        b"[camera]\neye = [0, 3, 6]\ntarget = [0, 0.5, 0]\nfov_y_deg = 45\n[light]\n\
          center = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0.5\n[[object]]\n\
          name = \"a\\nb.obj\"\nmesh = \"plane\"\n[[object]]\nmesh = \"a\\nb.obj\"\n",
    ),
    (
        "scene-toml",
        b"[camera]\neye = [0, 3, 6]\ntarget = [0, 0.5, 0]\nfov_y_deg = 45\n[[object]]\n\
          mesh = \"sphere:3x2\\n\"\n[light]\ncenter = [0, 4, 0]\nnormal = [0, 1, 0]\n\
          radius = 0.5\n",
    ),
    // A string with escaped quotes in a type error: the sanitiser ended the quoted value at
    // its first `\"` and echoed the rest of the file.
    (
        "scene-toml",
        b"[camera]\neye = [0, 3, 6]\ntarget = [0, 0.5, 0]\nfov_y_deg = 45\n[light]\n\
          center = [0, 4, 0]\nnormal = [0, -1, 0]\n\
          radius = '''a\"b\nCANARYx7q = 1\n\"c'''\n",
    ),
    // A mesh name of 3000 characters came back whole in the error.
    ("scene-toml", LONG_MESH_NAME.as_bytes()),
    // A cone of 3967 segments scaled to 1e-7 welds its rim together: thousands of silhouette
    // edge ends at one vertex, and pairing them compared every two (1.1 GB, 2 s).
    (
        "scene-toml",
        b"[camera]\neye = [0.8, 5.5, 7.5]\ntarget = [0.8, 0.4, 0.0]\nfov_y_deg = 45.0\n\
          [light]\ncenter = [4294967296, 5.0, 3.4e38]\nnormal = [0.0, -1.0, 0.0]\n\
          radius = 0.5\n[[object]]\nmesh = \"cone:3967\"\ntranslate = [0.0, 1.25, 0.0]\n\
          scale = 0.0000001\n",
    ),
];

/// A scene whose mesh is a 3000-character name.
const LONG_MESH_NAME: &str = concat!(
    "[camera]\neye = [0, 3, 6]\ntarget = [0, 0.5, 0]\nfov_y_deg = 45\n[light]\n",
    "center = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0.5\n[[object]]\nmesh = \"",
    include_str!("support/long-name.txt"),
    ".obj\"\n",
);

#[test]
fn inputs_found_by_fuzzing_stay_fixed() {
    let sandbox = Sandbox::new("regressions");
    for target in fuzz::targets() {
        let inputs: Vec<&[u8]> = REGRESSIONS
            .iter()
            .filter(|(t, _)| *t == target.name)
            .map(|(_, i)| *i)
            .collect();
        let failures = fuzz::replay(&target, &sandbox, &inputs);
        assert!(
            failures.is_empty(),
            "{}",
            failures
                .iter()
                .map(|f| format!("{}: {} (b\"{}\")", f.target, f.problem, escape(&f.input)))
                .collect::<Vec<_>>()
                .join("\n")
        );
    }
}
