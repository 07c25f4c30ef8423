//! A structure-aware fuzzer for the input parsers, in-process, on stable Rust. A crate of its
//! own (a dev-dependency of `dbuffer`, never published) because four programs share it: the
//! short run in `cargo test` (`tests/cpu/fuzz_parsers.rs`), the long run
//! (`cargo run --release --example fuzz -- --execs 10000000`, `examples/fuzz.rs`) and the
//! libFuzzer targets of `fuzz/`.
//!
//! **Why not coverage-guided.** libFuzzer (`cargo fuzz`) and AFL++ (`cargo afl`) both work on
//! stable only by instrumenting every crate they build: here that is the whole dependency tree
//! of the `dbuffer` library (wgpu, naga, eframe, ...), rebuilt once more with coverage flags,
//! plus a tool to install first; neither fits a `cargo test` run. Instead each target mutates
//! inputs that know their format (TOML keys and tables, shape names with parameters, OBJ
//! statements, numbers at the edges of f32), seeded from the built-in scenes and OBJ pieces,
//! and keeps any input whose outcome (the error's shape, or success) is new: a cheap
//! stand-in for coverage that steers toward code the seeds did not reach.
//!
//! **What every execution checks.** No panic; no hang (a watchdog aborts with the input after
//! [`Limits::hang`]); allocation bounded (a counting global allocator: the peak while the input
//! runs stays under [`Limits::alloc`]); errors are one line, not huge, and never echo the input
//! (a canary word planted in inputs must not come back in an error about the file's content);
//! a scene file that parses writes back (`to_toml`) to the same scene.
//!
//! **Adding a target** (glTF, say): write its seeds, a mutator (or reuse [`mutate_bytes`]) and
//! a `run` that feeds the parser and returns `Err` for a broken property, and add it to
//! [`targets`].

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::collections::HashSet;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use dbuffer::geometry::{PreparedCasters, VolumeParams};
use dbuffer::scene::file::decode_utf8;
use dbuffer::scene::gltf::{load_gltf, MAX_FILE_BYTES, MAX_TRIANGLES};
use dbuffer::scene::obj::{parse_obj_bytes, Others};
use dbuffer::scene::{
    builtin, shapes, AreaLight, Mesh, Object, Outline, Scene, SceneError, SceneFile,
};
use glam::Vec3;
use serde_json::{json, Value};

pub mod gltf_build;

/// Planted in inputs; an error about a file's content must never contain it.
pub const CANARY: &str = "CANARYx7q";

// ---------------------------------------------------------------------------------------------
// Counting allocator

thread_local! {
    static CURRENT: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
}

/// The system allocator, counting the bytes each thread holds and its peak. Declare it in the
/// binary: `#[global_allocator] static A: CountingAlloc = CountingAlloc;`.
pub struct CountingAlloc;

fn grow(n: usize) {
    let _ = CURRENT.try_with(|c| {
        let now = c.get().saturating_add(n);
        c.set(now);
        let _ = PEAK.try_with(|p| p.set(p.get().max(now)));
    });
}

fn shrink(n: usize) {
    let _ = CURRENT.try_with(|c| c.set(c.get().saturating_sub(n)));
}

// SAFETY: every call is forwarded to `System` unchanged; the counters are plain thread-local
// cells with constant initialisers (no allocation, no destructor).
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) };
        shrink(layout.size());
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            shrink(layout.size());
            grow(new_size);
        }
        p
    }
}

/// Starts measuring this thread's peak from what it holds now; returns that baseline.
fn reset_peak() -> usize {
    let now = CURRENT.with(Cell::get);
    PEAK.with(|p| p.set(now));
    now
}

fn peak() -> usize {
    PEAK.with(Cell::get)
}

/// Runs `f` and returns what it returned and the most bytes it held at once (with
/// [`CountingAlloc`] as the global allocator).
pub fn measure<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let base = reset_peak();
    let r = f();
    (r, peak().saturating_sub(base))
}

// ---------------------------------------------------------------------------------------------
// Random numbers (SplitMix64: small, fast, reproducible from one seed)

pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9e37_79b9_7f4a_7c15)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    pub fn chance(&mut self, one_in: usize) -> bool {
        self.below(one_in) == 0
    }
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

// ---------------------------------------------------------------------------------------------
// Targets

/// Where file-based inputs resolve: small OBJ files, and things that are not files.
pub struct Sandbox {
    pub dir: PathBuf,
}

impl Sandbox {
    /// Creates the sandbox under the system temp dir (`tag` keeps runs apart).
    pub fn new(tag: &str) -> Sandbox {
        let dir = std::env::temp_dir().join(format!("dbuffer-fuzz-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("meshes")).expect("sandbox dir");
        for (name, text) in OBJ_FILES {
            std::fs::write(dir.join(name), text).expect("sandbox file");
        }
        std::fs::create_dir_all(dir.join("folder.obj")).expect("sandbox dir");
        // Buffer files for `.gltf` inputs: the tetrahedron's, one that is empty, one over
        // MAX_MODEL_FILE_BYTES (sparse: it takes no disk), and things that are not files.
        let (_, tet_bin) = gltf_build::tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
        for name in ["tet.bin", "sub/tet.bin", "CANARYx7q.bin"] {
            let path = dir.join(name);
            let _ = std::fs::create_dir_all(path.parent().unwrap_or(&dir));
            std::fs::write(path, &tet_bin).expect("sandbox file");
        }
        // Models a scene file can name.
        let (mut doc, _) = gltf_build::tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
        std::fs::write(dir.join("tet.glb"), gltf_build::glb(&doc, &tet_bin)).expect("sandbox file");
        doc["buffers"][0]["uri"] = json!("tet.bin");
        std::fs::write(
            dir.join("tet.gltf"),
            serde_json::to_vec(&doc).unwrap_or_default(),
        )
        .expect("sandbox file");
        std::fs::create_dir_all(dir.join("folder.glb")).expect("sandbox dir");
        std::fs::write(dir.join("empty.bin"), b"").expect("sandbox file");
        std::fs::File::create(dir.join("huge.bin"))
            .and_then(|f| f.set_len(MAX_FILE_BYTES + 1))
            .expect("sandbox file");
        std::fs::create_dir_all(dir.join("folder.bin")).expect("sandbox dir");
        #[cfg(unix)]
        {
            for name in ["zero.obj", "zero.bin", "zero.glb"] {
                let _ = std::os::unix::fs::symlink("/dev/zero", dir.join(name));
            }
            for name in ["fifo.obj", "fifo.bin"] {
                let _ = std::process::Command::new("mkfifo")
                    .arg(dir.join(name))
                    .status();
            }
        }
        Sandbox { dir }
    }
}

impl Drop for Sandbox {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

const OBJ_FILES: &[(&str, &str)] = &[
    (
        "tet.obj",
        "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    ),
    (
        "meshes/quad.obj",
        "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3 4\n",
    ),
    ("bad.obj", "v 0 0 0\nv 1 0\n"),
    ("bom.obj", "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
    ("tiny.obj", "v 0 0 0\nv 1e-45 0 0\nv 0 1e-45 0\nf 1 2 3\n"),
];

/// A parser under test.
pub struct Target {
    pub name: &'static str,
    /// Inputs to start from.
    pub seeds: fn() -> Vec<Vec<u8>>,
    /// Changes an input (`corpus` is there to splice from).
    pub mutate: fn(&mut Rng, &mut Vec<u8>, &[Vec<u8>]),
    /// Feeds the parser. `Ok(outcome)`: a short description of what happened (kept inputs are
    /// those with a new one); `Err`: a property broke.
    pub run: fn(&Sandbox, &[u8]) -> Result<String, String>,
    /// Inputs are cut to this many bytes.
    pub max_len: usize,
}

/// Every target.
pub fn targets() -> Vec<Target> {
    vec![
        Target {
            name: "scene-toml",
            seeds: toml_seeds,
            mutate: mutate_toml,
            run: run_toml,
            max_len: 16 << 10,
        },
        Target {
            name: "obj",
            seeds: obj_seeds,
            mutate: mutate_obj,
            run: run_obj,
            max_len: 32 << 10,
        },
        Target {
            name: "gltf",
            seeds: gltf_seeds,
            mutate: mutate_gltf,
            run: run_gltf,
            // The Fox is 163 KB.
            max_len: 256 << 10,
        },
    ]
}

/// Limits every execution is held to.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Peak bytes allocated while one input runs.
    pub alloc: usize,
    /// Time one input may take before the watchdog calls it a hang.
    pub hang: Duration,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            alloc: 256 << 20,
            hang: Duration::from_secs(20),
        }
    }
}

/// A broken property, with the input that broke it.
#[derive(Clone, Debug)]
pub struct Failure {
    pub target: &'static str,
    pub input: Vec<u8>,
    pub problem: String,
}

/// What a run did.
#[derive(Debug, Default)]
pub struct Report {
    pub execs: u64,
    pub corpus: usize,
    pub outcomes: usize,
    pub failures: Vec<Failure>,
}

/// Runs `target` for `execs` executions from `seed`. Failures are returned (and passed to
/// `on_failure` as they happen); the run goes on after one.
pub fn fuzz(
    target: &Target,
    sandbox: &Sandbox,
    seed: u64,
    execs: u64,
    limits: Limits,
    mut on_failure: impl FnMut(&Failure),
) -> Report {
    let mut rng = Rng::new(seed);
    let mut corpus: Vec<Vec<u8>> = (target.seeds)();
    let mut outcomes: HashSet<String> = HashSet::new();
    let mut failures: Vec<Failure> = Vec::new();
    let mut known_problems: HashSet<String> = HashSet::new();
    let watchdog = Watchdog::start(target.name, limits.hang);
    // The seeds first, unchanged.
    let seeds = corpus.len() as u64;
    let mut input = Vec::new();
    for i in 0..execs {
        input.clear();
        if i < seeds {
            input.extend_from_slice(&corpus[i as usize]);
        } else {
            let from = rng.below(corpus.len());
            input.extend_from_slice(&corpus[from]);
            for _ in 0..1 + rng.below(4) {
                (target.mutate)(&mut rng, &mut input, &corpus);
            }
            input.truncate(target.max_len);
        }
        watchdog.begin(&input);
        let base = reset_peak();
        let result = catch_unwind(AssertUnwindSafe(|| (target.run)(sandbox, &input)));
        let used = peak().saturating_sub(base);
        watchdog.end();
        let problem = match result {
            Err(panic) => Some(format!("panicked: {}", panic_message(&panic))),
            Ok(Err(broken)) => Some(broken),
            Ok(Ok(_)) if used > limits.alloc => Some(format!(
                "allocated {used} bytes at its peak, over the {} allowed",
                limits.alloc
            )),
            Ok(Ok(outcome)) => {
                if outcomes.insert(outcome) && corpus.len() < 4096 {
                    corpus.push(input.clone());
                }
                None
            }
        };
        if let Some(problem) = problem {
            // One report per kind of problem (digits stripped), not one per input.
            let kind: String = problem
                .chars()
                .filter(|c| !c.is_ascii_digit())
                .take(120)
                .collect();
            if known_problems.insert(kind) {
                let f = Failure {
                    target: target.name,
                    input: input.clone(),
                    problem,
                };
                on_failure(&f);
                failures.push(f);
            }
        }
    }
    Report {
        execs,
        corpus: corpus.len(),
        outcomes: outcomes.len(),
        failures,
    }
}

fn panic_message(panic: &Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a non-string panic".into())
}

/// Aborts the process, printing the input, if one execution runs longer than the limit.
struct Watchdog {
    started_ms: Arc<AtomicU64>,
    input: Arc<Mutex<Vec<u8>>>,
    stop: Arc<AtomicBool>,
    epoch: Instant,
}

impl Watchdog {
    fn start(target: &'static str, limit: Duration) -> Watchdog {
        let started_ms = Arc::new(AtomicU64::new(u64::MAX));
        let input = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let epoch = Instant::now();
        let (s, i, st) = (started_ms.clone(), input.clone(), stop.clone());
        std::thread::spawn(move || {
            while !st.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(100));
                let t = s.load(Ordering::Relaxed);
                let now = epoch.elapsed().as_millis() as u64;
                if t != u64::MAX && now.saturating_sub(t) > limit.as_millis() as u64 {
                    let bytes = i.lock().map(|b| b.clone()).unwrap_or_default();
                    eprintln!(
                        "fuzz {target}: an input ran over {limit:?} (a hang): {}",
                        escape(&bytes)
                    );
                    std::process::abort();
                }
            }
        });
        Watchdog {
            started_ms,
            input,
            stop,
            epoch,
        }
    }
    fn begin(&self, input: &[u8]) {
        if let Ok(mut b) = self.input.lock() {
            b.clear();
            b.extend_from_slice(input);
        }
        self.started_ms
            .store(self.epoch.elapsed().as_millis() as u64, Ordering::Relaxed);
    }
    fn end(&self) {
        self.started_ms.store(u64::MAX, Ordering::Relaxed);
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// An input as a Rust byte-string literal body, for reports and regression tests.
pub fn escape(bytes: &[u8]) -> String {
    bytes.escape_ascii().to_string()
}

// ---------------------------------------------------------------------------------------------
// Checks shared by the targets

/// May an error echo text of the input? Messages about a file's content never may; names a
/// scene gives as values (a mesh name or path) may be repeated.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Echo {
    Never,
    Names,
}

/// The error's message is one line, not huge, and (unless `echo` allows names) does not
/// contain the canary.
fn check_message(what: &str, msg: &str, echo: Echo) -> Result<(), String> {
    if msg.contains(['\n', '\r']) {
        return Err(format!("{what} is not one line: {msg:?}"));
    }
    if msg.len() > 2048 {
        return Err(format!("{what} is {} bytes long", msg.len()));
    }
    if echo == Echo::Never && msg.contains(CANARY) {
        return Err(format!("{what} echoes the input: {msg:?}"));
    }
    Ok(())
}

/// The shape of an outcome, for the corpus: the message without digits, cut short.
fn outcome(msg: &str) -> String {
    msg.chars()
        .filter(|c| !c.is_ascii_digit())
        .take(100)
        .collect()
}

fn scene_error_echo(e: &SceneError) -> Echo {
    match e {
        SceneError::Toml { .. } | SceneError::NotUtf8 { .. } | SceneError::ObjLine { .. } => {
            Echo::Never
        }
        _ => Echo::Names,
    }
}

/// The geometry stage on a small scene: no panic, warnings one line each. Returns the shape
/// of what it found (warnings without their numbers, a rough size) as an outcome.
fn check_geometry(scene: &Scene) -> Result<String, String> {
    // The D-buffer's geometry stage takes a disk; a line light's scene gets the zero-radius
    // disk at its midpoint (what the twins fall back to), so the stage still sees its casters.
    let prepared = PreparedCasters::new(scene);
    let light = scene.light.area_or_centre();
    let geometry = prepared.build(&light, &VolumeParams::for_scene(scene));
    let mut kinds: Vec<String> = Vec::new();
    for w in &geometry.warnings {
        check_message("a warning", w, Echo::Names)?;
        kinds.push(outcome(w).chars().take(40).collect());
    }
    kinds.sort();
    kinds.dedup();
    let size = |n: usize| usize::BITS - n.leading_zeros();
    Ok(format!(
        "geometry {} {} {}",
        size(geometry.stats.triangles),
        size(geometry.stats.umbra_edges + geometry.stats.penumbra_edges),
        kinds.join("|")
    ))
}

// ---------------------------------------------------------------------------------------------
// Scene TOML

const KEYS: &[&str] = &[
    "eye",
    "target",
    "fov_y_deg",
    "center",
    "normal",
    "radius",
    "intensity",
    "name",
    "mesh",
    "translate",
    "rotate_deg",
    "scale",
    "casts_shadow",
];

const TABLES: &[&str] = &[
    "[camera]",
    "[light]",
    "[[object]]",
    "[object]",
    "[[light]]",
    "[x]",
];

const NUMBERS: &[&str] = &[
    "0",
    "-0.0",
    "1",
    "-1",
    "0.5",
    "1e-45",
    "1.4e-45",
    "1e-38",
    "3.4e38",
    "3.5e38",
    "-3.5e38",
    "1e300",
    "1e-300",
    "nan",
    "+inf",
    "-inf",
    "179.9999",
    "180",
    "0.0000001",
    "16777217",
    "4294967296",
    "9223372036854775807",
    "99999999999999999999",
    "1e30",
    "5e-7",
    "0x10",
    "1_000",
    "00",
    "1.",
    ".5",
];

const STRINGS: &[&str] = &[
    "\"cube\"",
    "\"plane\"",
    "\"sphere\"",
    "\"sphere:3x2\"",
    "\"sphere:2000x1000\"",
    "\"sphere:2001x1000\"",
    "\"torus:2000x1000\"",
    "\"icosphere:7\"",
    "\"icosphere:8\"",
    "\"cylinder:4096\"",
    "\"torus-knot:8x3\"",
    "\"bunny\"",
    "\"bunny-open\"",
    "\"tet.obj\"",
    "\"meshes/quad.obj\"",
    "\"bad.obj\"",
    "\"bom.obj\"",
    "\"tiny.obj\"",
    "\"zero.obj\"",
    "\"fifo.obj\"",
    "\"folder.obj\"",
    "\"missing.obj\"",
    "\"tet.glb\"",
    "\"tet.gltf\"",
    "\"tet.bin\"",
    "\"folder.glb\"",
    "\"zero.glb\"",
    "\"missing.glb\"",
    "\"a\\nb.glb\"",
    "\"CANARYx7q.gltf\"",
    "\"../../../../etc/passwd\"",
    "\"/dev/zero\"",
    "\"/dev/null\"",
    "\"\"",
    "\" \"",
    "\"\\n\"",
    "\"\\u0000\"",
    "\"sphere:\\n3x2\"",
    "\"CANARYx7q\"",
    "\"CANARYx7q.obj\"",
    "\"a\\nb.obj\"",
    "\"\\u001b[31mred.obj\"",
    "\"sphere:3x2\\n\"",
    "\"sphere:99999999999x2\"",
    "'''multi\nline'''",
    LONG_NAME,
];

/// A mesh name of 3000 characters: errors that repeat it must not grow with it.
const LONG_NAME: &str = concat!(
    "\"",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
    ".obj\""
);

fn toml_seeds() -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = builtin::names()
        .iter()
        .filter_map(|n| builtin::source(n))
        .map(|s| s.as_bytes().to_vec())
        .collect();
    let head = "[camera]\neye = [0, 3, 6]\ntarget = [0, 0.5, 0]\nfov_y_deg = 45\n\n[light]\n\
                center = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0.5\n";
    for name in shapes::NAMES {
        seeds.push(format!("{head}\n[[object]]\nmesh = \"{name}\"\n").into_bytes());
    }
    for mesh in [
        "tet.obj",
        "meshes/quad.obj",
        "bom.obj",
        "tiny.obj",
        "tet.glb",
        "tet.gltf",
    ] {
        seeds.push(
            format!("{head}\n[[object]]\nmesh = \"{mesh}\"\ntranslate = [0, 1, 0]\n").into_bytes(),
        );
    }
    seeds.push(format!("\u{feff}{head}# {CANARY}\n").into_bytes());
    seeds
}

fn mutate_toml(rng: &mut Rng, input: &mut Vec<u8>, corpus: &[Vec<u8>]) {
    match rng.below(12) {
        0..=2 => replace_token(rng, input, |rng| {
            if rng.chance(2) {
                rng.pick(NUMBERS).to_string()
            } else {
                rng.pick(STRINGS).to_string()
            }
        }),
        3 => {
            let key = *rng.pick(KEYS);
            let value = match rng.below(4) {
                0 => rng.pick(NUMBERS).to_string(),
                1 => rng.pick(STRINGS).to_string(),
                2 => format!(
                    "[{}, {}, {}]",
                    rng.pick(NUMBERS),
                    rng.pick(NUMBERS),
                    rng.pick(NUMBERS)
                ),
                _ => ["true", "false", "[]", "{}", "[1, 2]", "[[1]]"][rng.below(6)].to_string(),
            };
            insert_line(rng, input, &format!("{key} = {value}"));
        }
        4 => {
            let table = *rng.pick(TABLES);
            insert_line(rng, input, table);
        }
        5 => {
            // A shape with random parameters.
            let name = *rng.pick(shapes::NAMES);
            let params = match rng.below(3) {
                0 => String::new(),
                1 => format!(":{}", rng.below(5000)),
                _ => format!(":{}x{}", rng.below(5000), rng.below(5000)),
            };
            insert_line(
                rng,
                input,
                &format!("[[object]]\nmesh = \"{name}{params}\""),
            );
        }
        6 => insert_line(rng, input, &format!("{CANARY} = 1")),
        7 => line_edit(rng, input),
        8 => splice(rng, input, corpus),
        _ => mutate_bytes(rng, input, corpus),
    }
}

fn run_toml(sandbox: &Sandbox, bytes: &[u8]) -> Result<String, String> {
    let label = "fuzz.toml";
    let text = match decode_utf8(bytes, label) {
        Ok(t) => t,
        Err(e) => {
            check_message("a UTF-8 error", &e.to_string(), Echo::Never)?;
            return Ok(outcome(&e.to_string()));
        }
    };
    let file = match SceneFile::parse(text, label) {
        Ok(f) => f,
        Err(e) => {
            let msg = e.to_string();
            check_message("a parse error", &msg, scene_error_echo(&e))?;
            return Ok(outcome(&msg));
        }
    };
    // What the lab saves reads back as the same scene.
    let again = SceneFile::parse(&file.to_toml(), "again.toml")
        .map_err(|e| format!("to_toml wrote a file that does not parse: {e}"))?;
    if again != file {
        return Err("to_toml wrote a different scene".into());
    }
    // Build small scenes only (the budget allows 16M triangles; building them is slow, not
    // wrong): the shapes' count is known from their parameters.
    let shape_triangles: u64 = file
        .objects
        .iter()
        .filter_map(|o| shapes::triangle_count(&o.mesh).ok())
        .sum();
    if shape_triangles > 20_000 {
        return Ok("valid, large".into());
    }
    match file.build(&sandbox.dir, label) {
        Ok(scene) => {
            if scene
                .objects
                .iter()
                .map(|o| o.mesh.triangles.len())
                .sum::<usize>()
                <= 20_000
            {
                return check_geometry(&scene);
            }
            Ok(format!("built {} objects", scene.objects.len().min(3)))
        }
        Err(e) => {
            let msg = e.to_string();
            check_message("a build error", &msg, scene_error_echo(&e))?;
            Ok(outcome(&msg))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ

const OBJ_STATEMENTS: &[&str] = &[
    "v 0 0 0",
    "v 1 0 0",
    "v 0 1 0",
    "v 0 0 1",
    "v 1 1 1 1",
    "v 1 1 1 0",
    "v 1 2 3 0.5 0.5 0.5",
    "v 1e-45 0 0",
    "v 3e38 3e38 3e38",
    "v 1e39 0 0",
    "v nan 0 0",
    "v 1 inf 0",
    "v 1 2",
    "vt 0 0",
    "vt 0.5",
    "vn 0 0 1",
    "vn 0 1",
    "f 1 2 3",
    "f 1 2 3 4",
    "f 1 2 3 4 5 6 7 8",
    "f -1 -2 -3",
    "f -3 -2 -1 -4",
    "f 1/1 2/1 3/1",
    "f 1//1 2//1 3//1",
    "f 1/1/1 2/1/1 3/1/1",
    "f 1 1 2",
    "f 1 2",
    "f 0 1 2",
    "f 1 2 99999999",
    "f 1 2 16777217",
    "f 1 2 -99999999999999999999",
    "f 1/2/3/4 2 3",
    "f 1/ 2 3",
    "f //1 2 3",
    "o part",
    "g group",
    "s 1",
    "usemtl x",
    "mtllib x.mtl",
    "l 1 2",
    "p 1",
    "# comment CANARYx7q",
    "CANARYx7q 1 2 3",
    "v 0 0 CANARYx7q",
    "f 1 2 CANARYx7q",
    "",
];

fn obj_seeds() -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = OBJ_FILES
        .iter()
        .map(|(_, t)| t.as_bytes().to_vec())
        .collect();
    seeds.push(b"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n".to_vec());
    seeds.push(
        b"o a\nv 0 0 0\nv 1 0 0\nv 1 0 1\nvn 0 1 0\nf 1//1 3//1 2//1\no b\nv -0.0 0 0\nv 1 0 1\n\
          v 0 0 1\nv 0 0 2\nf 4 6 5\ng c\nf -4 -1 -2\n"
            .to_vec(),
    );
    // A slice of the bunny: real-world number formatting.
    let bunny = include_str!("../../../assets/bunny.obj");
    let vertices: Vec<&str> = bunny
        .lines()
        .filter(|l| l.starts_with("v "))
        .take(60)
        .collect();
    let mut piece = vertices.join("\n");
    piece.push_str("\nf 1 2 3\nf 3 2 4\nf 5 6 7 8\n");
    seeds.push(piece.into_bytes());
    seeds
}

fn mutate_obj(rng: &mut Rng, input: &mut Vec<u8>, corpus: &[Vec<u8>]) {
    match rng.below(10) {
        0..=2 => {
            let s = *rng.pick(OBJ_STATEMENTS);
            insert_line(rng, input, s);
        }
        3 => {
            // A face over random indices, absolute or relative.
            let n = 3 + rng.below(6);
            let mut line = String::from("f");
            for _ in 0..n {
                let i = rng.below(40) as i64 - 10;
                line.push_str(&format!(" {i}"));
                if rng.chance(4) {
                    line.push_str(&format!("/{}", rng.below(4)));
                }
            }
            insert_line(rng, input, &line);
        }
        4 => replace_token(rng, input, |rng| rng.pick(NUMBERS).to_string()),
        5 => line_edit(rng, input),
        6 => splice(rng, input, corpus),
        _ => mutate_bytes(rng, input, corpus),
    }
}

fn run_obj(_sandbox: &Sandbox, bytes: &[u8]) -> Result<String, String> {
    match parse_obj_bytes(bytes, "fuzz.obj", Others::default()) {
        Ok(mesh) => {
            check_mesh(&mesh)?;
            if mesh.triangles.len() <= 20_000 {
                return check_geometry(&scene_of(mesh));
            }
            Ok("mesh".into())
        }
        Err(e) => {
            let msg = e.to_string();
            // The label is fixed, so nothing in the message may come from the file.
            check_message("an OBJ error", &msg, Echo::Never)?;
            Ok(outcome(&msg))
        }
    }
}

/// A loaded mesh is well formed: indices in range, no repeated corner, finite positions.
fn check_mesh(mesh: &Mesh) -> Result<(), String> {
    let n = mesh.positions.len() as u32;
    for t in &mesh.triangles {
        if t.iter().any(|&i| i >= n) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(format!("a triangle {t:?} of a mesh with {n} vertices"));
        }
    }
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err("a non-finite position".into());
    }
    Ok(())
}

/// The mesh as the caster of a small scene, over a ground, under a disk light above it.
fn scene_of(mesh: Mesh) -> Scene {
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let top = hi.y.max(lo.y) + (hi - lo).max_element().max(1.0);
    Scene {
        name: "fuzz".into(),
        camera: dbuffer::scene::Camera {
            eye: Vec3::new(0.0, top, top * 2.0),
            target: (lo + hi) / 2.0,
            fov_y_deg: 45.0,
        },
        light: AreaLight {
            center: Vec3::new((lo.x + hi.x) / 2.0, top, (lo.z + hi.z) / 2.0),
            normal: Vec3::NEG_Y,
            radius: 0.5,
            intensity: 1.0,
            outline: Outline::Disk,
        }
        .into(),
        objects: vec![Object {
            name: "fuzz".into(),
            mesh,
            casts_shadow: true,
        }],
    }
}

// ---------------------------------------------------------------------------------------------
// glTF

/// The Fox of `assets/models` (576 triangles, a skin, animations, a texture): an exporter's file.
const FOX: &[u8] = include_bytes!("../../../assets/models/Fox.glb");

/// The Fox as the shipping tools write it (`tests/models/shipped/`, made by its `make.sh`):
/// quantized, meshopt-compressed by gltf-transform and by gltfpack, Draco, and a fan whose
/// positions are sparse on zeros without a bufferView.
const SHIPPED: &[&[u8]] = &[
    include_bytes!("../../models/shipped/fox-quant.glb"),
    include_bytes!("../../models/shipped/fox-meshopt.glb"),
    include_bytes!("../../models/shipped/fox-pack.glb"),
    include_bytes!("../../models/shipped/fox-draco.glb"),
    include_bytes!("../../models/shipped/fan-sparse.glb"),
];

/// A model whose triangles or placed vertices, counted from its JSON ([`gltf_size`]), pass
/// these is within the budget but slow to build (seconds, hundreds of MB): it is not loaded.
/// Over the budget it is, and must be refused.
const GLTF_SMALL_TRIANGLES: u64 = 200_000;
const GLTF_SMALL_VERTICES: u64 = 600_000;
/// The loader's limit on positions placed over all node instances (three per triangle).
const GLTF_MAX_PLACED: u64 = 3 * MAX_TRIANGLES as u64;

/// A GLB's JSON and BIN chunks, or a `.gltf`'s JSON, to mutate one and put the file back
/// together with every length right (the container's own mutations break them on purpose).
struct GltfParts {
    glb: bool,
    json: Vec<u8>,
    bin: Option<Vec<u8>>,
}

impl GltfParts {
    /// Leniently: a length that says more than there is takes what there is.
    fn split(bytes: &[u8]) -> GltfParts {
        if !bytes.starts_with(b"glTF") || bytes.len() < 20 {
            return GltfParts {
                glb: false,
                json: bytes.to_vec(),
                bin: None,
            };
        }
        let u32_at = |at: usize| {
            bytes
                .get(at..at + 4)
                .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        };
        let json_end = 20usize.saturating_add(u32_at(12)).min(bytes.len());
        let json = bytes[20..json_end].to_vec();
        let next = json_end.next_multiple_of(4);
        let bin = (next + 8 <= bytes.len()).then(|| {
            let end = (next + 8).saturating_add(u32_at(next)).min(bytes.len());
            bytes[next + 8..end].to_vec()
        });
        GltfParts {
            glb: true,
            json,
            bin,
        }
    }

    fn join(&self) -> Vec<u8> {
        if self.glb {
            gltf_build::glb_raw(&self.json, self.bin.as_deref())
        } else {
            self.json.clone()
        }
    }
}

fn gltf_seeds() -> Vec<Vec<u8>> {
    use gltf_build::{base64, f32_bytes, glb, tet_doc};
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let to_vec = |v: &Value| serde_json::to_vec(v).unwrap_or_default();
    let mut seeds = vec![FOX.to_vec()];
    seeds.extend(SHIPPED.iter().map(|s| s.to_vec()));
    // The tetrahedron quantized to each integer type, normalized or not.
    for ty in [5120, 5121, 5122, 5123] {
        for normalized in [true, false] {
            let (doc, bin) = gltf_build::quantized_tet(ty, normalized);
            seeds.push(glb(&doc, &bin));
        }
    }
    // Positions without a bufferView, with sparse values on the zeros.
    let (doc, bin) = gltf_build::sparse_tet();
    seeds.push(glb(&doc, &bin));
    // The tetrahedron with each index type, and without indices.
    for ty in [Some(5121), Some(5123), Some(5125), None] {
        let (doc, bin) = tet_doc(ty, json!([{"mesh": 0}]), json!([0]));
        seeds.push(glb(&doc, &bin));
    }
    // Nested TRS, a mirroring matrix, two instances, a spot, a point and a directional light.
    let nodes = json!([
        {"translation": [1, 0, 0], "scale": [2, 2, 2], "children": [1]},
        {"rotation": [0, s, 0, s], "mesh": 0},
        {"matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 5, 0, 1], "mesh": 0},
        {"translation": [0, 4, 0], "rotation": [-s, 0, 0, s],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"translation": [0, 9, 0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"extensions": {"KHR_lights_punctual": {"light": 2}}}
    ]);
    let (mut doc, bin) = tet_doc(Some(5123), nodes, json!([0, 2, 3, 4, 5]));
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.7}, "intensity": 10},
        {"type": "point", "range": 20},
        {"type": "directional"}
    ]}});
    seeds.push(glb(&doc, &bin));
    // The JSON form: the buffer as a base64 data: URI, and as files beside the model. Names
    // carry the canary: they may not come back in an error about the file's content.
    let (mut doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0, "name": CANARY}]), json!([0]));
    doc["asset"]["generator"] = json!(CANARY);
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64(&bin)
    ));
    seeds.push(serde_json::to_vec_pretty(&doc).unwrap_or_default());
    for uri in [
        "tet.bin",
        "sub/tet.bin",
        "./sub/../tet.bin",
        "CANARYx7q.bin",
        "huge.bin",
    ] {
        doc["buffers"][0]["uri"] = json!(uri);
        seeds.push(to_vec(&doc));
    }
    // A strip, a fan and a line primitive over one square.
    let quad = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
        [1.0, 0.0, -1.0],
    ];
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [0, 1, 0], "scale": [1, -1, 1]}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0}, "mode": 5},
            {"attributes": {"POSITION": 0}, "mode": 6},
            {"attributes": {"POSITION": 0}, "mode": 1}
        ]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}],
        "bufferViews": [{"buffer": 0, "byteLength": 48, "byteStride": 12}],
        "buffers": [{"byteLength": 48}],
        "extras": {"CANARYx7q": CANARY},
    });
    seeds.push(glb(&doc, &f32_bytes(&quad)));
    // Over the triangle budget by instancing: a strip of 60 000 one-byte indices (59 998
    // triangles) used by 300 nodes, 18M triangles from a 64 KB file.
    seeds.push(gltf_build::instanced_strip(60_000, 300));
    seeds
}

/// Buffer URIs: data, files in the sandbox, and files that must be refused.
const GLTF_URIS: &[&str] = &[
    "tet.bin",
    "sub/tet.bin",
    "sub%2Ftet.bin",
    "tet%2ebin",
    "./tet.bin",
    "sub/../tet.bin",
    "sub/../../tet.bin",
    "../tet.bin",
    "/etc/passwd",
    "file:///etc/passwd",
    "http://example.com/a.bin",
    "C:\\a.bin",
    "empty.bin",
    "huge.bin",
    "zero.bin",
    "fifo.bin",
    "folder.bin",
    "missing.bin",
    "",
    "%",
    "%zz",
    "%ff%fe.bin",
    "%00.bin",
    "a%0Ab.bin",
    "a\nb.bin",
    "\u{1b}[31mred.bin",
    "CANARYx7q.bin",
    "CANARYx7q",
    "data:",
    "data:application/octet-stream;base64,",
    "data:application/octet-stream;base64,AAAA",
    "data:application/octet-stream;base64,AAAAAA==",
    "data:application/octet-stream;base64,AAA=A",
    "data:application/octet-stream;base64,CANARYx7q",
    "data:application/octet-stream,CANARYx7q",
    "data:;base64,////",
];

/// Fields of the top-level arrays, with what kind of value to give them.
const GLTF_FIELDS: &[(&str, &[&str])] = &[
    (
        "accessors",
        &[
            "count",
            "byteOffset",
            "componentType",
            "type",
            "bufferView",
            "normalized",
            "sparse",
        ],
    ),
    (
        "bufferViews",
        &["byteLength", "byteStride", "byteOffset", "buffer", "target"],
    ),
    ("buffers", &["byteLength", "uri"]),
    (
        "nodes",
        &[
            "mesh",
            "children",
            "matrix",
            "translation",
            "rotation",
            "scale",
            "skin",
            "camera",
            "weights",
        ],
    ),
    ("scenes", &["nodes"]),
    ("meshes", &["primitives", "weights"]),
];

const GLTF_TYPES: &[&str] = &[
    "SCALAR",
    "VEC2",
    "VEC3",
    "VEC4",
    "MAT2",
    "MAT3",
    "MAT4",
    "vec3",
    "",
    "CANARYx7q",
];

/// Numbers at the edges: of u8/u16/u32/usize, of f32, component types, modes.
fn gltf_number(rng: &mut Rng) -> Value {
    const UNSIGNED: &[u64] = &[
        0,
        1,
        2,
        3,
        4,
        5,
        6,
        7,
        8,
        11,
        12,
        16,
        24,
        48,
        72,
        253,
        255,
        256,
        1727,
        1728,
        65535,
        65536,
        5120,
        5121,
        5122,
        5123,
        5125,
        5126,
        34962,
        16_777_216,
        50_331_648,
        2_147_483_647,
        2_147_483_648,
        4_294_967_295,
        4_294_967_296,
        (1 << 30) + 1,
        1 << 40,
        9_007_199_254_740_993,
        u64::MAX / 2,
        u64::MAX,
    ];
    const FLOATS: &[f64] = &[
        0.5, -0.0, -1.0, 1e-45, 1e-38, 1e-7, 1e7, 1e30, 1e38, 3.4e38, 3.5e38, 1e39, -1e39, 1e300,
        -1e300,
    ];
    match rng.below(4) {
        0 => json!(rng.below(8)),
        1 | 2 => json!(*rng.pick(UNSIGNED)),
        _ if rng.chance(4) => json!(-(rng.below(3) as i64) - 1),
        _ => json!(*rng.pick(FLOATS)),
    }
}

/// A number array of `n` entries (a transform), one or all of them at an edge.
fn gltf_numbers(rng: &mut Rng, n: usize) -> Value {
    let n = if rng.chance(8) { rng.below(17) } else { n };
    let identity = |i: usize| {
        if n == 16 && i.is_multiple_of(5) {
            1.0
        } else {
            0.0
        }
    };
    let mut out: Vec<Value> = (0..n).map(|i| json!(identity(i))).collect();
    let all = rng.chance(4);
    for (i, v) in out.iter_mut().enumerate() {
        if all || i == 0 {
            *v = gltf_number(rng);
        }
    }
    if !all && n > 1 {
        out.swap(0, rng.below(n));
    }
    Value::Array(out)
}

/// A value for `field` of an element of `array`.
fn gltf_field_value(rng: &mut Rng, field: &str, old: Option<&Value>, doc: &Value) -> Value {
    let len = |name: &str| doc[name].as_array().map_or(0, Vec::len);
    match field {
        "type" => json!(*rng.pick(GLTF_TYPES)),
        "uri" => json!(*rng.pick(GLTF_URIS)),
        "normalized" => json!(rng.chance(2)),
        "children" | "nodes" => {
            let mut list: Vec<Value> = old.and_then(Value::as_array).cloned().unwrap_or_default();
            match rng.below(3) {
                0 => list.push(json!(rng.below(len("nodes") + 2))),
                1 if !list.is_empty() => {
                    let i = rng.below(list.len());
                    list.insert(i, list[i].clone());
                }
                _ => {
                    list = (0..rng.below(5))
                        .map(|_| json!(rng.below(len("nodes") + 2)))
                        .collect()
                }
            }
            Value::Array(list)
        }
        "matrix" => gltf_numbers(rng, 16),
        "rotation" => gltf_numbers(rng, 4),
        "translation" | "scale" => gltf_numbers(rng, 3),
        "weights" => gltf_numbers(rng, 2),
        "sparse" => json!({"count": gltf_number(rng),
            "indices": {"bufferView": 0, "componentType": 5123},
            "values": {"bufferView": 0}}),
        "primitives" => {
            let mut list: Vec<Value> = old.and_then(Value::as_array).cloned().unwrap_or_default();
            if let Some(first) = list.first().cloned() {
                let most = if rng.chance(4) { 300 } else { 3 };
                for _ in 0..1 + rng.below(most) {
                    list.push(first.clone());
                }
            }
            Value::Array(list)
        }
        _ => match old.and_then(Value::as_u64) {
            // Near the old value, or at an edge.
            Some(n) if rng.chance(2) => match rng.below(4) {
                0 => json!(n.saturating_add(1)),
                1 => json!(n.saturating_sub(1)),
                2 => json!(n.saturating_mul(2)),
                _ => json!(n.saturating_add(4)),
            },
            _ => gltf_number(rng),
        },
    }
}

/// The element `i` of the top-level `array`, as an object (made one if it is not).
fn gltf_element<'a>(doc: &'a mut Value, array: &str, rng: &mut Rng) -> Option<&'a mut Value> {
    let list = doc.get_mut(array)?.as_array_mut()?;
    if list.is_empty() {
        return None;
    }
    let i = rng.below(list.len());
    Some(&mut list[i])
}

/// A random place in `v`: the value itself or something inside it.
fn descend<'a>(rng: &mut Rng, v: &'a mut Value, depth: usize) -> &'a mut Value {
    let inner = match v {
        Value::Array(a) => a.len(),
        Value::Object(o) => o.len(),
        _ => 0,
    };
    if inner == 0 || depth > 12 || rng.chance(4) {
        return v;
    }
    let i = rng.below(inner);
    if v.is_array() {
        return descend(rng, &mut v[i], depth + 1);
    }
    match v.as_object().and_then(|o| o.keys().nth(i).cloned()) {
        Some(key) => descend(rng, &mut v[key.as_str()], depth + 1),
        None => v,
    }
}

/// One structural change to a glTF document.
fn mutate_gltf_json(rng: &mut Rng, doc: &mut Value) {
    if !doc.is_object() {
        *doc = json!({"asset": {"version": "2.0"}});
    }
    match rng.below(14) {
        // The geometry extensions: a meshopt stream's description, or what is required.
        12 => mutate_gltf_extensions(rng, doc),
        // A field of an accessor, view, buffer, node, scene or mesh.
        0..=3 => {
            let (array, fields) = *rng.pick(GLTF_FIELDS);
            let field = *rng.pick(fields);
            let snapshot = doc.clone();
            if let Some(Value::Object(e)) = gltf_element(doc, array, rng) {
                let value = gltf_field_value(rng, field, e.get(field), &snapshot);
                e.insert(field.to_string(), value);
            }
        }
        // A primitive: its mode, indices, POSITION, or a morph target.
        4 => {
            let Some(mesh) = gltf_element(doc, "meshes", rng) else {
                return;
            };
            let Some(list) = mesh.get_mut("primitives").and_then(Value::as_array_mut) else {
                return;
            };
            if list.is_empty() {
                return;
            }
            let i = rng.below(list.len());
            let Value::Object(p) = &mut list[i] else {
                return;
            };
            match rng.below(5) {
                0 => {
                    p.insert("mode".into(), json!(rng.below(8)));
                }
                1 => {
                    p.insert("indices".into(), gltf_number(rng));
                }
                2 => {
                    p.remove("indices");
                }
                3 => {
                    if let Some(Value::Object(a)) = p.get_mut("attributes") {
                        if rng.chance(3) {
                            a.remove("POSITION");
                        } else {
                            a.insert("POSITION".into(), json!(rng.below(4)));
                        }
                    }
                }
                _ => {
                    p.insert("targets".into(), json!([{"POSITION": 0}]));
                }
            }
        }
        // A key dropped anywhere.
        5 => {
            if let Value::Object(o) = descend(rng, doc, 0) {
                if !o.is_empty() {
                    let i = rng.below(o.len());
                    if let Some(k) = o.keys().nth(i).cloned() {
                        o.remove(&k);
                    }
                }
            }
        }
        // An array element repeated or removed anywhere.
        6 => {
            if let Value::Array(a) = descend(rng, doc, 0) {
                if !a.is_empty() {
                    let i = rng.below(a.len());
                    if rng.chance(2) {
                        a.remove(i);
                    } else {
                        a.insert(i, a[i].clone());
                    }
                }
            }
        }
        // Instances: many nodes holding a mesh, all in the scene.
        7 => {
            let most = if rng.chance(4) { 2000 } else { 4 };
            let n = 1 + rng.below(most);
            let mesh = rng.below(2);
            let Some(nodes) = doc.get_mut("nodes").and_then(Value::as_array_mut) else {
                return;
            };
            let first = nodes.len();
            let translate = rng.chance(2);
            for k in 0..n {
                nodes.push(if translate {
                    json!({"mesh": mesh, "translation": [k, 0, 0]})
                } else {
                    json!({"mesh": mesh})
                });
            }
            if let Some(Value::Array(roots)) = doc.pointer_mut("/scenes/0/nodes") {
                roots.extend((first..first + n).map(|i| json!(i)));
            }
        }
        // A KHR_lights_punctual light changed, and put on a node.
        8 => {
            let lights = doc
                .pointer("/extensions/KHR_lights_punctual/lights")
                .and_then(Value::as_array)
                .map_or(0, Vec::len);
            if lights == 0 || rng.chance(4) {
                let kind = *rng.pick(&["spot", "point", "directional", "area", ""]);
                let light = json!({"type": kind, "spot": {
                    "innerConeAngle": gltf_number(rng), "outerConeAngle": gltf_number(rng)},
                    "intensity": gltf_number(rng), "range": gltf_number(rng),
                    "color": gltf_numbers(rng, 3)});
                if let Value::Object(root) = doc {
                    let ext = root.entry("extensions").or_insert_with(|| json!({}));
                    if let Value::Object(ext) = ext {
                        let l = ext
                            .entry("KHR_lights_punctual")
                            .or_insert_with(|| json!({"lights": []}));
                        if let Some(Value::Array(list)) = l.get_mut("lights") {
                            list.push(light);
                        }
                    }
                }
            }
            let light = if rng.chance(8) {
                gltf_number(rng)
            } else {
                json!(rng.below(lights + 1))
            };
            if let Some(Value::Object(node)) = gltf_element(doc, "nodes", rng) {
                node.insert(
                    "extensions".into(),
                    json!({"KHR_lights_punctual": {"light": light}}),
                );
                if rng.chance(2) {
                    let (field, n) = *rng.pick(&[
                        ("matrix", 16),
                        ("translation", 3),
                        ("rotation", 4),
                        ("scale", 3),
                    ]);
                    node.insert(field.into(), gltf_numbers(rng, n));
                }
            }
        }
        // The scene: which one, its roots.
        9 => {
            if rng.chance(2) {
                doc["scene"] = json!(rng.below(3));
            } else if let Some(Value::Object(scene)) = gltf_element(doc, "scenes", rng) {
                let snapshot = json!({});
                let value = gltf_field_value(rng, "nodes", scene.get("nodes"), &snapshot);
                scene.insert("nodes".into(), value);
            }
        }
        // The canary, where a file's text could be repeated: a key, a name, an extension.
        10 => {
            let place = descend(rng, doc, 0);
            match (rng.below(4), place) {
                (0, Value::Object(o)) => {
                    o.insert(CANARY.into(), json!(1));
                }
                (1, Value::Object(o)) => {
                    o.insert("name".into(), json!(CANARY));
                }
                (2, v) => *v = json!(CANARY),
                _ => {
                    let key = *rng.pick(&["extensionsUsed", "extensionsRequired"]);
                    doc[key] = json!([CANARY]);
                }
            }
        }
        // Any value anywhere becomes a number at an edge.
        _ => *descend(rng, doc, 0) = gltf_number(rng),
    }
}

/// Extension names a file may require: decoded, ignored (textures, materials), refused
/// (geometry dbuffer cannot decode), unknown, and not a name at all.
const GLTF_EXTENSIONS: &[&str] = &[
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_draco_mesh_compression",
    "KHR_lights_punctual",
    "EXT_texture_webp",
    "KHR_texture_basisu",
    "KHR_materials_unlit",
    "KHR_animation_pointer",
    "EXT_mesh_gpu_instancing",
    "EXT_unknown_geometry",
    "CANARYx7q",
    "",
];

/// One change to the geometry extensions: a field of a buffer view's meshopt extension (its
/// stream's place, length, count, stride, mode or filter), the extension moved or dropped, an
/// accessor's quantized type, or `extensionsRequired`.
fn mutate_gltf_extensions(rng: &mut Rng, doc: &mut Value) {
    const FIELDS: &[&str] = &[
        "count",
        "byteStride",
        "byteLength",
        "byteOffset",
        "buffer",
        "mode",
        "filter",
    ];
    match rng.below(5) {
        0..=2 => {
            let Some(views) = doc.get_mut("bufferViews").and_then(Value::as_array_mut) else {
                return;
            };
            let with: Vec<usize> = (0..views.len())
                .filter(|&i| {
                    views[i]
                        .pointer("/extensions/EXT_meshopt_compression")
                        .is_some()
                })
                .collect();
            let i = if with.is_empty() || rng.chance(8) {
                rng.below(views.len().max(1))
            } else {
                *rng.pick(&with)
            };
            let Some(Value::Object(view)) = views.get_mut(i) else {
                return;
            };
            let ext = view
                .entry("extensions")
                .or_insert_with(|| json!({}))
                .as_object_mut()
                .map(|e| {
                    e.entry("EXT_meshopt_compression").or_insert_with(|| {
                        json!({"buffer": 0, "byteLength": 16, "byteStride": 4,
                               "count": 4, "mode": "ATTRIBUTES"})
                    })
                });
            let Some(Value::Object(ext)) = ext else {
                return;
            };
            let field = *rng.pick(FIELDS);
            let value = match field {
                "mode" => json!(*rng.pick(&["ATTRIBUTES", "TRIANGLES", "INDICES", "POINTS", ""])),
                "filter" => json!(*rng.pick(&[
                    "NONE",
                    "OCTAHEDRAL",
                    "QUATERNION",
                    "EXPONENTIAL",
                    "COLOR",
                    "CANARYx7q"
                ])),
                "byteStride" if rng.chance(2) => {
                    json!(*rng.pick(&[0, 1, 2, 3, 4, 6, 8, 12, 16, 252, 256, 260]))
                }
                _ => {
                    let snapshot = json!({});
                    gltf_field_value(rng, field, ext.get(field), &snapshot)
                }
            };
            ext.insert(field.into(), value);
            // The view's own byteLength kept in step with count × byteStride, half the time:
            // a count that lies consistently reaches the decoder's budget.
            if rng.chance(2) {
                let n = ext.get("count").and_then(Value::as_u64).unwrap_or(0);
                let st = ext.get("byteStride").and_then(Value::as_u64).unwrap_or(0);
                view.insert("byteLength".into(), json!(n.saturating_mul(st)));
            }
        }
        3 => {
            let (field, value) = match rng.below(3) {
                0 => (
                    "componentType",
                    json!(*rng.pick(&[5120, 5121, 5122, 5123, 5125, 5126])),
                ),
                1 => ("normalized", json!(rng.chance(2))),
                _ => ("bufferView", Value::Null),
            };
            if let Some(Value::Object(a)) = gltf_element(doc, "accessors", rng) {
                if value.is_null() {
                    a.remove(field);
                } else {
                    a.insert(field.into(), value);
                }
            }
        }
        _ => {
            let key = *rng.pick(&["extensionsRequired", "extensionsUsed"]);
            let name = json!(*rng.pick(GLTF_EXTENSIONS));
            match doc.get_mut(key) {
                Some(Value::Array(list)) if !list.is_empty() && rng.chance(2) => {
                    let i = rng.below(list.len());
                    list.remove(i);
                }
                Some(Value::Array(list)) => list.push(name),
                _ => doc[key] = json!([name]),
            }
        }
    }
}

/// Edits of the JSON text that a `Value` cannot hold: numbers JSON has no words for, keys
/// twice, deep nesting, a byte-order mark.
fn gltf_json_text(rng: &mut Rng, json: &mut Vec<u8>) {
    const TOKENS: &[&str] = &[
        "NaN",
        "Infinity",
        "-Infinity",
        "1e400",
        "-1e400",
        "1e-400",
        "-0",
        "00",
        "1.",
        "0x10",
        "18446744073709551616",
        "-9223372036854775809",
        "4294967296",
        "1e39",
        "null",
        "true",
        "\"\"",
        "\"CANARYx7q\"",
        "[]",
        "{}",
    ];
    const KEYS: &[&str] = &[
        "count",
        "byteOffset",
        "byteLength",
        "byteStride",
        "componentType",
        "type",
        "mesh",
        "children",
        "nodes",
        "scene",
        "buffer",
        "bufferView",
        "indices",
        "mode",
        "POSITION",
        "uri",
        "matrix",
        "extensions",
        "KHR_lights_punctual",
        "light",
        "CANARYx7q",
    ];
    let braces: Vec<usize> = (0..json.len()).filter(|&i| json[i] == b'{').collect();
    match rng.below(5) {
        0 => replace_token(rng, json, |rng| rng.pick(TOKENS).to_string()),
        // A key again, right after an opening brace.
        1 | 2 if !braces.is_empty() => {
            let at = *rng.pick(&braces) + 1;
            let value = match rng.below(3) {
                0 => gltf_number(rng).to_string(),
                1 => rng.pick(TOKENS).to_string(),
                _ => "[0, 0, 0]".to_string(),
            };
            let piece = format!("\"{}\": {value},", rng.pick(KEYS));
            json.splice(at..at, piece.bytes());
        }
        3 if !braces.is_empty() => {
            let at = *rng.pick(&braces) + 1;
            let depth = 1 + rng.below(200);
            let piece = format!("\"extras\": {}{},", "[".repeat(depth), "]".repeat(depth));
            json.splice(at..at, piece.bytes());
        }
        _ => {
            if rng.chance(2) {
                json.splice(0..0, *b"\xef\xbb\xbf");
            } else {
                json.splice(0..0, *b" \r\n\t");
            }
        }
    }
}

/// Changes to a GLB's container: magic, version, declared lengths, chunk types and order.
fn mutate_glb_container(rng: &mut Rng, input: &mut Vec<u8>) {
    let edge = |rng: &mut Rng, len: usize| -> u32 {
        let len = len as u32;
        *rng.pick(&[
            0,
            1,
            3,
            4,
            8,
            11,
            12,
            19,
            20,
            len.wrapping_sub(1),
            len,
            len.wrapping_add(1),
            len.wrapping_add(4),
            0x7fff_ffff,
            u32::MAX - 7,
            u32::MAX,
        ])
    };
    let set = |input: &mut Vec<u8>, at: usize, v: u32| {
        if let Some(b) = input.get_mut(at..at + 4) {
            b.copy_from_slice(&v.to_le_bytes());
        }
    };
    let u32_at = |input: &[u8], at: usize| {
        input
            .get(at..at + 4)
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let second = (20 + u32_at(input, 12))
        .next_multiple_of(4)
        .min(input.len());
    let len = input.len();
    match rng.below(9) {
        0 => {
            let i = rng.below(4);
            if let Some(b) = input.get_mut(i) {
                *b ^= 1 << rng.below(8);
            }
        }
        1 => {
            let v = *rng.pick(&[0, 1, 3, u32::MAX]);
            set(input, 4, v);
        }
        2 => {
            let v = edge(rng, len);
            set(input, 8, v);
        }
        3 => {
            let v = edge(rng, u32_at(input, 12));
            set(input, 12, v);
        }
        4 => {
            let v = edge(rng, u32_at(input, second));
            set(input, second, v);
        }
        5 => {
            let at = if rng.chance(2) { 16 } else { second + 4 };
            let v = *rng.pick(&[0x4E4F_534A, 0x004E_4942, 0, 0x1234_5678]);
            set(input, at, v);
        }
        // The BIN chunk dropped, the header's length fixed or not.
        6 => {
            input.truncate(second);
            if rng.chance(2) {
                let n = input.len() as u32;
                set(input, 8, n);
            }
        }
        // A chunk of an unknown type after the others, or before BIN.
        7 => {
            let at = if rng.chance(2) { input.len() } else { second };
            let n = 4 * rng.below(4);
            let mut chunk = (n as u32).to_le_bytes().to_vec();
            chunk.extend(b"XTRA");
            chunk.extend(std::iter::repeat_n(0u8, n));
            input.splice(at..at, chunk);
            let n = input.len() as u32;
            set(input, 8, n);
        }
        // The chunks in the other order.
        _ => {
            if second > 20 && second < input.len() {
                let json: Vec<u8> = input[12..second].to_vec();
                input.drain(12..second);
                input.extend(json);
            }
        }
    }
}

/// Changes to the binary data: indices and floats at their edges.
fn mutate_gltf_bin(rng: &mut Rng, bin: &mut Vec<u8>, corpus: &[Vec<u8>]) {
    if bin.is_empty() || rng.chance(6) {
        mutate_bytes(rng, bin, corpus);
        return;
    }
    let at = rng.below(bin.len()) & !3;
    let word: u32 = *rng.pick(&[
        0,
        1,
        2,
        3,
        255,
        256,
        65535,
        65536,
        u32::MAX,
        0x7fc0_0000, // NaN
        0x7f80_0000, // +inf
        0xff80_0000, // -inf
        0x7f7f_ffff, // f32::MAX
        0x0000_0001, // the smallest subnormal
        0x8000_0000, // -0.0
    ]);
    match rng.below(3) {
        0 => {
            if let Some(b) = bin.get_mut(at..at + 4) {
                b.copy_from_slice(&word.to_le_bytes());
            }
        }
        1 => {
            if let Some(b) = bin.get_mut(at..at + 2) {
                b.copy_from_slice(&(word as u16).to_le_bytes());
            }
        }
        _ => {
            let end = (at + 4 * (1 + rng.below(64))).min(bin.len());
            bin.truncate(if rng.chance(2) { end } else { at });
        }
    }
}

/// Changes inside a meshopt stream of the BIN chunk (where the JSON says one lies): its header
/// byte (the codec's version), a byte anywhere in it, or its tail (the last vertex, the
/// channel modes); the JSON is left saying what it said.
fn mutate_meshopt_stream(rng: &mut Rng, json: &[u8], bin: &mut [u8]) {
    let Ok(doc) = serde_json::from_slice::<Value>(json) else {
        return;
    };
    let streams: Vec<(usize, usize)> = doc["bufferViews"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|v| {
            let e = v.pointer("/extensions/EXT_meshopt_compression")?;
            let at = e.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
            let len = e.get("byteLength")?.as_u64()? as usize;
            (at < bin.len() && len > 0).then(|| (at, len.min(bin.len() - at)))
        })
        .collect();
    if streams.is_empty() {
        return;
    }
    let (at, len) = *rng.pick(&streams);
    let stream = &mut bin[at..at + len];
    let value = *rng.pick(&[
        0u8, 1, 0x0f, 0x10, 0x7f, 0x80, 0xa0, 0xa1, 0xa2, 0xe0, 0xe1, 0xff,
    ]);
    let k = match rng.below(3) {
        0 => 0,
        1 => len - 1 - rng.below(len.min(32)),
        _ => rng.below(len),
    };
    stream[k] = if rng.chance(2) {
        value
    } else {
        stream[k] ^ (1 << rng.below(8))
    };
}

fn mutate_gltf(rng: &mut Rng, input: &mut Vec<u8>, corpus: &[Vec<u8>]) {
    let mut parts = GltfParts::split(input);
    match rng.below(16) {
        0..=6 => {
            match serde_json::from_slice::<Value>(&parts.json) {
                Ok(mut doc) => {
                    mutate_gltf_json(rng, &mut doc);
                    parts.json = serde_json::to_vec(&doc).unwrap_or_default();
                }
                Err(_) => mutate_bytes(rng, &mut parts.json, corpus),
            }
            *input = parts.join();
        }
        7 | 8 => {
            gltf_json_text(rng, &mut parts.json);
            *input = parts.join();
        }
        9 => {
            mutate_bytes(rng, &mut parts.json, corpus);
            *input = parts.join();
        }
        10 if parts.glb => {
            let mut bin = parts.bin.take().unwrap_or_default();
            if rng.chance(2) {
                mutate_meshopt_stream(rng, &parts.json, &mut bin);
            } else {
                mutate_gltf_bin(rng, &mut bin, corpus);
            }
            parts.bin = Some(bin);
            *input = parts.join();
        }
        11 | 12 if parts.glb => mutate_glb_container(rng, input),
        13 => splice(rng, input, corpus),
        14 => {
            let at = rng.below(input.len() + 1);
            input.truncate(at);
        }
        _ => mutate_bytes(rng, input, corpus),
    }
}

/// Triangles assembled and positions placed over every node instance of the model's scene,
/// from the JSON alone (accessor counts and primitive modes; what the loader counts before it
/// reads a byte of a buffer). `None` where the JSON does not say.
fn gltf_size(bytes: &[u8]) -> Option<(u64, u64)> {
    let parts = GltfParts::split(bytes);
    // As the loader: a byte-order mark before the JSON is allowed (the long run found a model
    // whose size this missed behind one, loaded in full: 285 MB).
    let json = parts
        .json
        .strip_prefix(b"\xEF\xBB\xBF")
        .unwrap_or(&parts.json);
    let doc: Value = serde_json::from_slice(json).ok()?;
    let scene = doc.get("scene").map_or(Some(0), Value::as_u64)? as usize;
    let empty = Vec::new();
    // As the loader: the scene's roots; without scenes, every node no node holds; if those
    // place no mesh, every mesh once (counted as a node of its own, below).
    let roots: Vec<Value> = match doc.get("scenes").and_then(Value::as_array) {
        Some(list) if !list.is_empty() => list
            .get(scene)?
            .get("nodes")
            .and_then(Value::as_array)
            .unwrap_or(&empty)
            .clone(),
        _ => {
            let nodes = doc.get("nodes").and_then(Value::as_array).unwrap_or(&empty);
            let held: HashSet<u64> = nodes
                .iter()
                .filter_map(|n| n.get("children")?.as_array())
                .flatten()
                .filter_map(Value::as_u64)
                .collect();
            (0..nodes.len() as u64)
                .filter(|i| !held.contains(i))
                .map(|i| json!(i))
                .collect()
        }
    };
    let (t, v) = gltf_walk(&doc, &roots, None);
    if t == 0 {
        let meshes = doc
            .get("meshes")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        return Some(gltf_walk(&doc, &[], Some(meshes)));
    }
    Some((t, v))
}

/// Triangles and positions placed from `roots` (or, with `Some(n)`, each of `n` meshes once).
fn gltf_walk(doc: &Value, roots: &[Value], all_meshes: Option<usize>) -> (u64, u64) {
    let mut stack: Vec<u64> = roots.iter().filter_map(Value::as_u64).collect();
    let mut seen = HashSet::new();
    let (mut triangles, mut vertices) = (0u64, 0u64);
    let mut meshes: Vec<u64> = Vec::new();
    while let Some(n) = stack.pop() {
        if !seen.insert(n) {
            continue;
        }
        let Some(node) = doc.get("nodes").and_then(|l| l.get(n as usize)) else {
            continue;
        };
        if let Some(children) = node.get("children").and_then(Value::as_array) {
            stack.extend(children.iter().filter_map(Value::as_u64));
        }
        if let Some(mesh) = node.get("mesh").and_then(Value::as_u64) {
            meshes.push(mesh);
        }
    }
    if let Some(n) = all_meshes {
        meshes = (0..n as u64).collect();
    }
    let count = |accessor: &Value| -> Option<u64> {
        let i = accessor.as_u64()? as usize;
        doc.get("accessors")?.get(i)?.get("count")?.as_u64()
    };
    for mesh in meshes {
        let primitives = doc
            .get("meshes")
            .and_then(|m| m.get(mesh as usize))
            .and_then(|m| m.get("primitives"))
            .and_then(Value::as_array);
        for p in primitives.into_iter().flatten() {
            let mode = p.get("mode").map_or(Some(4), Value::as_u64).unwrap_or(4);
            let positions = p
                .get("attributes")
                .and_then(|a| a.get("POSITION"))
                .and_then(count)
                .unwrap_or(0);
            let corners = p.get("indices").map_or(Some(positions), count).unwrap_or(0);
            let t = match mode {
                4 => corners / 3,
                5 | 6 => corners.saturating_sub(2),
                _ => continue,
            };
            triangles = triangles.saturating_add(t);
            vertices = vertices.saturating_add(positions);
        }
    }
    (triangles, vertices)
}

/// The error names the file, is one line, and quotes nothing of it: the canary may come back
/// only as part of a path in the sandbox (a buffer's file name), never from the JSON.
fn check_gltf_error(sandbox: &Sandbox, name: &str, msg: &str) -> Result<(), String> {
    check_message("a glTF error", msg, Echo::Names)?;
    if !msg.contains(name) {
        return Err(format!("a glTF error does not name the file: {msg:?}"));
    }
    let dir = sandbox.dir.display().to_string();
    let mut rest = msg;
    while let Some(at) = rest.find(CANARY) {
        if !rest[..at].contains(&dir) {
            return Err(format!("a glTF error echoes the input: {msg:?}"));
        }
        rest = &rest[at + CANARY.len()..];
    }
    Ok(())
}

/// The input as the file `dbuffer render fuzz.glb` opens: written into the sandbox (`.gltf` if
/// it starts as JSON, `.glb` otherwise), read by the loader (buffer files beside it, the
/// budget's checks), then opened as a scene (the generated scene around the model, built).
fn run_gltf(sandbox: &Sandbox, bytes: &[u8]) -> Result<String, String> {
    let json = bytes
        .iter()
        .find(|b| !b" \t\r\n".contains(b))
        .is_some_and(|&b| b == b'{');
    let name = if json { "fuzz.gltf" } else { "fuzz.glb" };
    let path = sandbox.dir.join(name);
    std::fs::write(&path, bytes).map_err(|e| format!("cannot write the input: {e}"))?;
    let over = match gltf_size(bytes) {
        Some((t, v)) if t > MAX_TRIANGLES as u64 || v > GLTF_MAX_PLACED => true,
        Some((t, v)) if t > GLTF_SMALL_TRIANGLES || v > GLTF_SMALL_VERTICES => {
            return Ok("valid, large".into())
        }
        _ => false,
    };
    let model = match load_gltf(&path) {
        Ok(m) => m,
        Err(e) => {
            let msg = e.to_string();
            check_gltf_error(sandbox, name, &msg)?;
            return Ok(outcome(&msg));
        }
    };
    if over {
        return Err(format!(
            "a model over the budget loaded: {} triangles",
            model.mesh.triangles.len()
        ));
    }
    check_mesh(&model.mesh)?;
    for w in &model.warnings {
        check_message("a glTF warning", w, Echo::Never)?;
    }
    if let Some(l) = model.light {
        if !l.position.is_finite() || (l.direction.length() - 1.0).abs() > 1e-3 {
            return Err(format!(
                "a light at {} pointing {}",
                l.position, l.direction
            ));
        }
    }
    let path_text = path.to_str().ok_or("the sandbox path is not UTF-8")?;
    let light = if model.light.is_some() {
        "lit"
    } else {
        "unlit"
    };
    match dbuffer::scene::load(path_text) {
        Ok(scene) => {
            let geometry = if scene.caster_triangle_count() <= 20_000 {
                check_geometry(&scene)?
            } else {
                "large".into()
            };
            Ok(format!(
                "{light} {} {geometry}",
                model.warnings.len().min(3)
            ))
        }
        Err(e) => {
            let msg = e.to_string();
            check_gltf_error(sandbox, name, &msg)?;
            Ok(format!("{light} {}", outcome(&msg)))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Mutations shared by the targets

/// Random byte-level changes: flip, insert, delete, repeat, bytes that matter to parsers.
pub fn mutate_bytes(rng: &mut Rng, input: &mut Vec<u8>, _corpus: &[Vec<u8>]) {
    const SPECIAL: &[&[u8]] = &[
        b"\xff",
        b"\xfe",
        b"\xef\xbb\xbf",
        b"\xc3",
        b"\x00",
        b"\r",
        b"\n",
        b"#",
        b"/",
        b"-",
        b".",
        b"e",
        b"=",
        b"[",
        b"]",
        b"\"",
        b"'",
        b"\\",
        b" ",
        b"\t",
        b":",
        b"x",
    ];
    let pos = rng.below(input.len() + 1);
    match rng.below(6) {
        0 if !input.is_empty() => {
            let i = rng.below(input.len());
            input[i] ^= 1 << rng.below(8);
        }
        1 => {
            let s = *rng.pick(SPECIAL);
            input.splice(pos..pos, s.iter().copied());
        }
        2 if !input.is_empty() => {
            let end = (pos + 1 + rng.below(16)).min(input.len());
            input.drain(pos.min(end)..end);
        }
        3 if !input.is_empty() => {
            let end = (pos + 1 + rng.below(64)).min(input.len());
            let piece: Vec<u8> = input[pos.min(end)..end].to_vec();
            input.splice(pos..pos, piece);
        }
        4 => input.truncate(pos),
        _ => {
            let b = rng.next_u64() as u8;
            input.insert(pos, b);
        }
    }
}

/// Replaces one whitespace-, comma- or bracket-delimited token with `make(rng)`.
fn replace_token(rng: &mut Rng, input: &mut Vec<u8>, make: impl Fn(&mut Rng) -> String) {
    let is_sep = |b: u8| b" \t\r\n,[]=".contains(&b);
    let starts: Vec<usize> = (0..input.len())
        .filter(|&i| !is_sep(input[i]) && (i == 0 || is_sep(input[i - 1])))
        .collect();
    if starts.is_empty() {
        return;
    }
    let start = *rng.pick(&starts);
    let end = (start..input.len())
        .find(|&i| is_sep(input[i]))
        .unwrap_or(input.len());
    let token = make(rng);
    input.splice(start..end, token.bytes());
}

/// Inserts `line` at the start of a random line.
fn insert_line(rng: &mut Rng, input: &mut Vec<u8>, line: &str) {
    let starts: Vec<usize> = std::iter::once(0)
        .chain(
            (0..input.len())
                .filter(|&i| input[i] == b'\n')
                .map(|i| i + 1),
        )
        .collect();
    let at = *rng.pick(&starts);
    let mut piece = line.as_bytes().to_vec();
    piece.push(b'\n');
    input.splice(at..at, piece);
}

/// Deletes, repeats or swaps whole lines.
fn line_edit(rng: &mut Rng, input: &mut Vec<u8>) {
    let mut lines: Vec<Vec<u8>> = input.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
    if lines.is_empty() {
        return;
    }
    let i = rng.below(lines.len());
    match rng.below(3) {
        0 => {
            lines.remove(i);
        }
        1 => {
            let l = lines[i].clone();
            for _ in 0..1 + rng.below(8) {
                lines.insert(i, l.clone());
            }
        }
        _ => {
            let j = rng.below(lines.len());
            lines.swap(i, j);
        }
    }
    *input = lines.join(&b'\n');
}

/// Replaces the tail of `input` with the tail of another corpus entry.
fn splice(rng: &mut Rng, input: &mut Vec<u8>, corpus: &[Vec<u8>]) {
    let other = &corpus[rng.below(corpus.len())];
    let at = rng.below(input.len() + 1);
    let from = rng.below(other.len() + 1);
    input.truncate(at);
    input.extend_from_slice(&other[from..]);
}

/// Runs the regression inputs of `target` once each: every one must pass the checks.
pub fn replay(target: &Target, sandbox: &Sandbox, inputs: &[&[u8]]) -> Vec<Failure> {
    let mut failures = Vec::new();
    for input in inputs {
        let base = reset_peak();
        let result = catch_unwind(AssertUnwindSafe(|| (target.run)(sandbox, input)));
        let used = peak().saturating_sub(base);
        let problem = match result {
            Err(panic) => Some(format!("panicked: {}", panic_message(&panic))),
            Ok(Err(broken)) => Some(broken),
            Ok(Ok(_)) if used > Limits::default().alloc => Some(format!("allocated {used} bytes")),
            Ok(Ok(_)) => None,
        };
        if let Some(problem) = problem {
            failures.push(Failure {
                target: target.name,
                input: input.to_vec(),
                problem,
            });
        }
    }
    failures
}

/// Whether `path` names the sandbox (for callers that print it).
pub fn in_sandbox(sandbox: &Sandbox, path: &Path) -> bool {
    path.starts_with(&sandbox.dir)
}
