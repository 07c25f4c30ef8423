//! A structure-aware fuzzer for the input parsers, in-process, on stable Rust. Shared by the
//! short run in `cargo test` (`tests/fuzz_parsers.rs`) and the long run
//! (`cargo run --release --example fuzz -- --execs 10000000`, `examples/fuzz.rs`).
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

#![allow(dead_code)]

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
use dbuffer::scene::obj::{parse_obj_bytes, Others};
use dbuffer::scene::{builtin, shapes, DiskLight, Mesh, Object, Scene, SceneError, SceneFile};
use glam::Vec3;

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

// ---------------------------------------------------------------------------------------------
// Random numbers (SplitMix64: small, fast, reproducible from one seed)

pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9e37_79b9_7f4a_7c15)
    }
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
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
        #[cfg(unix)]
        {
            let _ = std::os::unix::fs::symlink("/dev/zero", dir.join("zero.obj"));
            let _ = std::process::Command::new("mkfifo")
                .arg(dir.join("fifo.obj"))
                .status();
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
    let light = scene.light.disk_or_centre();
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
    for mesh in ["tet.obj", "meshes/quad.obj", "bom.obj", "tiny.obj"] {
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
    let bunny = include_str!("../../assets/bunny.obj");
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
        light: DiskLight {
            center: Vec3::new((lo.x + hi.x) / 2.0, top, (lo.z + hi.z) / 2.0),
            normal: Vec3::NEG_Y,
            radius: 0.5,
            intensity: 1.0,
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
            let b = rng.next() as u8;
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
