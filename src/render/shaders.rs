//! Where the render core's shaders come from: the embedded copies of `shaders/`, or a folder
//! set at run time (`dbuffer gui --shaders DIR`, or `DBUFFER_SHADER_DIR` for every command),
//! whose files override the embedded ones of the same name.
//!
//! A folder's files are taken as a whole and only once every whole shader (`methods/`,
//! `passes/`) that includes a changed one expands and passes naga's parse and validation
//! ([`reload`]): the accepted texts are then the ones every new pipeline is made from, until the
//! next good set. A broken file is a [`ShaderError`] naming the file, line and column in it (not
//! in the expansion) and the offending line; the texts accepted before stay, so the pipelines
//! made from them keep drawing.
//!
//! Which pipelines a change concerns is recorded as they are made: every shader expanded while
//! a [`GpuContext::shared`](super::GpuContext::shared) object is built is noted (`recording`)
//! as one of its files, so [`GpuContext::forget_shaders`](super::GpuContext::forget_shaders)
//! drops exactly the objects made from a changed file, and the next `get` builds them anew.
//!
//! [`Watcher`] looks at a folder's files (and single files such as a user's method) on a thread
//! of its own and says when one changed; the lab reloads on that signal.

use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock, RwLock};
use std::time::{Duration, SystemTime};

use naga::valid::{Capabilities, ValidationFlags, Validator};

use crate::shader_source::{self, Expanded, ShaderSourceError};

/// The environment variable that sets the folder for every command.
pub const DIR_ENV: &str = "DBUFFER_SHADER_DIR";

/// A shader that does not expand, parse or validate: where (the source file, 1-based line and
/// column, 0 where unknown), why, and the offending line of the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderError {
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub message: String,
    /// The text of line `line` of `file`.
    pub text: Option<String>,
}

impl ShaderError {
    /// `file:line:column: message`, the place as precise as it is known.
    pub fn headline(&self) -> String {
        match (self.line, self.column) {
            (0, _) => format!("{}: {}", self.file, self.message),
            (l, 0) => format!("{}:{l}: {}", self.file, self.message),
            (l, c) => format!("{}:{l}:{c}: {}", self.file, self.message),
        }
    }
}

/// The headline, then the offending line indented on a line of its own.
impl fmt::Display for ShaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.headline())?;
        if let Some(text) = &self.text {
            write!(f, "\n    {}", text.trim_end())?;
        }
        Ok(())
    }
}

impl std::error::Error for ShaderError {}

/// A folder's shaders as accepted: the folder, and the text of every file new pipelines are
/// made from (the embedded ones, overridden by the folder's once they validated).
struct Folder {
    dir: PathBuf,
    accepted: BTreeMap<String, String>,
}

fn folder() -> &'static RwLock<Option<Folder>> {
    static FOLDER: OnceLock<RwLock<Option<Folder>>> = OnceLock::new();
    FOLDER.get_or_init(|| {
        // `DBUFFER_SHADER_DIR` as it was read before: the folder's files as they are, checked
        // by pipeline creation (a command that wants them checked first calls `check_env`).
        let from_env = std::env::var_os(DIR_ENV).map(PathBuf::from).map(|dir| {
            let accepted = read_folder(&dir).unwrap_or_else(|_| embedded());
            Folder { dir, accepted }
        });
        RwLock::new(from_env)
    })
}

static GENERATION: AtomicU64 = AtomicU64::new(0);

/// Bumped whenever another set of shaders was accepted.
pub fn generation() -> u64 {
    GENERATION.load(Ordering::Relaxed)
}

/// The folder shaders are read from, if any.
pub fn dir() -> Option<PathBuf> {
    folder()
        .read()
        .ok()
        .and_then(|f| f.as_ref().map(|f| f.dir.clone()))
}

/// Read shaders from `dir` (`None`: the embedded ones). Its files are checked as [`reload`]
/// does; a broken one is the error, and until a good set is saved the embedded texts are drawn
/// (the folder stays set: [`reload`] picks the fixed file up).
pub fn set_dir(dir: Option<&Path>) -> Result<(), ShaderError> {
    {
        let Ok(mut f) = folder().write() else {
            return Ok(());
        };
        *f = dir.map(|dir| Folder {
            dir: dir.to_owned(),
            accepted: embedded(),
        });
    }
    GENERATION.fetch_add(1, Ordering::Relaxed);
    reload().map(|_| ())
}

/// For a command line: `DBUFFER_SHADER_DIR`'s files checked before any GPU work, so a broken one
/// is reported as its file and line, not as a pipeline's error.
pub fn check_env() -> Result<(), ShaderError> {
    match std::env::var_os(DIR_ENV) {
        Some(dir) => set_dir(Some(Path::new(&dir))),
        None => Ok(()),
    }
}

/// What a [`reload`] accepted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Reloaded {
    /// The files (names relative to `shaders/`) whose text changed.
    pub changed: BTreeSet<String>,
    /// The [`generation`] now.
    pub generation: u64,
}

/// Read the folder again: `Ok(None)` when nothing changed (or no folder is set), the changed
/// files once every whole shader that includes one of them expands and validates, else the
/// first error (the accepted texts stay as they were).
pub fn reload() -> Result<Option<Reloaded>, ShaderError> {
    let Some((dir, accepted)) = folder()
        .read()
        .ok()
        .and_then(|f| f.as_ref().map(|f| (f.dir.clone(), f.accepted.clone())))
    else {
        return Ok(None);
    };
    let candidate = read_folder(&dir).map_err(|(path, e)| ShaderError {
        file: path.display().to_string(),
        line: 0,
        column: 0,
        message: format!("cannot read: {e}"),
        text: None,
    })?;
    let changed: BTreeSet<String> = candidate
        .iter()
        .filter(|(name, text)| accepted.get(*name) != Some(*text))
        .map(|(name, _)| name.clone())
        .chain(
            accepted
                .keys()
                .filter(|n| !candidate.contains_key(*n))
                .cloned(),
        )
        .collect();
    if changed.is_empty() {
        return Ok(None);
    }
    check_set(&dir, &candidate, &changed)?;
    if let Ok(mut f) = folder().write() {
        if let Some(f) = f.as_mut().filter(|f| f.dir == dir) {
            f.accepted = candidate;
        }
    }
    let generation = GENERATION.fetch_add(1, Ordering::Relaxed) + 1;
    Ok(Some(Reloaded {
        changed,
        generation,
    }))
}

/// Every whole shader of `files` (`methods/` and `passes/`, as `tests/gpu/shaders.rs` has them)
/// that includes one of `changed`, expanded and validated.
fn check_set(
    dir: &Path,
    files: &BTreeMap<String, String>,
    changed: &BTreeSet<String>,
) -> Result<(), ShaderError> {
    let path_of = |name: &str| dir.join(name).display().to_string();
    let whole = |n: &&String| n.starts_with("methods/") || n.starts_with("passes/");
    for name in files.keys().filter(whole) {
        let expanded = shader_source::expand_lookup(name, |n| files.get(n).cloned())
            .map_err(|e| source_error(e, name, &path_of, files))?;
        if expanded.files().iter().any(|f| changed.contains(f)) {
            validate(&expanded, &path_of)?;
        }
    }
    Ok(())
}

/// An expansion's error as a [`ShaderError`] at the include line it names.
pub fn source_error(
    e: ShaderSourceError,
    name: &str,
    path_of: &dyn Fn(&str) -> String,
    files: &BTreeMap<String, String>,
) -> ShaderError {
    let line_text = |file: &str, line: u32| {
        files
            .get(file)
            .and_then(|t| t.lines().nth(line.saturating_sub(1) as usize))
            .map(str::to_owned)
    };
    match &e {
        ShaderSourceError::MissingInclude {
            file,
            line,
            include,
        } => ShaderError {
            file: path_of(file),
            line: *line,
            column: 0,
            message: format!("included file `{include}` not found"),
            text: line_text(file, *line),
        },
        ShaderSourceError::BadInclude {
            file,
            line,
            include,
            reason,
        } => ShaderError {
            file: path_of(file),
            line: *line,
            column: 0,
            message: format!("bad include `{include}`: {reason}"),
            text: line_text(file, *line),
        },
        _ => ShaderError {
            file: path_of(name),
            line: 0,
            column: 0,
            message: e.to_string(),
            text: None,
        },
    }
}

/// naga's parse and validation of `expanded`, an error placed in the file and line it came
/// from (`path_of` says how to name a file of the expansion).
pub fn validate(
    expanded: &Expanded,
    path_of: &dyn Fn(&str) -> String,
) -> Result<naga::Module, ShaderError> {
    let module = parse(expanded, path_of)?;
    check_module(expanded, &module, path_of)?;
    Ok(module)
}

/// naga's parse of `expanded` alone (what [`validate`] does first), an error placed as it places
/// them: for a caller that looks at the module before it is validated.
pub fn parse(
    expanded: &Expanded,
    path_of: &dyn Fn(&str) -> String,
) -> Result<naga::Module, ShaderError> {
    let source = &expanded.source;
    naga::front::wgsl::parse_str(source).map_err(|e| {
        let label = e
            .labels()
            .next()
            .map(|(_, l)| l.to_owned())
            .filter(|l| !l.is_empty() && l != e.message());
        let message = match label {
            Some(l) => format!("{} ({l})", e.message()),
            None => e.message().to_owned(),
        };
        place(expanded, path_of, e.location(source), message)
    })
}

/// naga's validation of `module`, parsed from `expanded` ([`parse`]).
pub fn check_module(
    expanded: &Expanded,
    module: &naga::Module,
    path_of: &dyn Fn(&str) -> String,
) -> Result<(), ShaderError> {
    Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(module)
        .map(|_| ())
        .map_err(|e| {
            let mut message = e.as_inner().to_string();
            let mut cause = std::error::Error::source(e.as_inner());
            while let Some(c) = cause {
                message.push_str(": ");
                message.push_str(&c.to_string());
                cause = c.source();
            }
            let location = e.location(&expanded.source);
            place(expanded, path_of, location, message.replace('\n', " "))
        })
}

/// `message` at `location` of the expansion, placed in the file and line it came from.
fn place(
    expanded: &Expanded,
    path_of: &dyn Fn(&str) -> String,
    location: Option<naga::SourceLocation>,
    message: String,
) -> ShaderError {
    let source = &expanded.source;
    match location.and_then(|l| Some((l, expanded.origin(l.line_number)?))) {
        Some((l, (file, line))) => ShaderError {
            file: path_of(file),
            line,
            column: l.line_position,
            message,
            text: source
                .lines()
                .nth(l.line_number.saturating_sub(1) as usize)
                .map(str::to_owned),
        },
        None => ShaderError {
            file: path_of(expanded.files().first().map_or("", String::as_str)),
            line: 0,
            column: 0,
            message,
            text: None,
        },
    }
}

/// The expanded source of top-level shader `name` as shaders are read now (the folder's
/// accepted texts, else the embedded ones), its files noted for the recording under way.
pub(crate) fn expanded(name: &str) -> Result<Expanded, ShaderSourceError> {
    let out = match folder().read() {
        Ok(f) => match f.as_ref() {
            Some(f) => shader_source::expand_lookup(name, |n| f.accepted.get(n).cloned()),
            None => shader_source::load_mapped(name),
        },
        Err(_) => shader_source::load_mapped(name),
    };
    match &out {
        Ok(e) => note(e.files().iter().map(String::as_str)),
        Err(_) => note([name]),
    }
    out
}

fn embedded() -> BTreeMap<String, String> {
    shader_source::embedded_files()
        .map(|(n, t)| (n.to_owned(), t.to_owned()))
        .collect()
}

/// The embedded files with `dir`'s `.wgsl` files over them, by name relative to `dir`.
fn read_folder(dir: &Path) -> Result<BTreeMap<String, String>, (PathBuf, std::io::Error)> {
    let mut files = embedded();
    for (name, path) in wgsl_files(dir).map_err(|e| (dir.to_owned(), e))? {
        let text = std::fs::read_to_string(&path).map_err(|e| (path.clone(), e))?;
        files.insert(name, text);
    }
    Ok(files)
}

/// Every `.wgsl` file under `dir`: (`/`-separated name relative to `dir`, path).
fn wgsl_files(dir: &Path) -> std::io::Result<Vec<(String, PathBuf)>> {
    fn walk(dir: &Path, prefix: &str, out: &mut Vec<(String, PathBuf)>) -> std::io::Result<()> {
        for entry in std::fs::read_dir(dir)? {
            let entry = entry?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let path = entry.path();
            if path.is_dir() {
                walk(&path, &format!("{prefix}{name}/"), out)?;
            } else if name.ends_with(".wgsl") {
                out.push((format!("{prefix}{name}"), path));
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, "", &mut out)?;
    out.sort();
    Ok(out)
}

thread_local! {
    /// The files noted by each recording under way on this thread, innermost last.
    static RECORDING: RefCell<Vec<BTreeSet<String>>> = const { RefCell::new(Vec::new()) };
}

/// Note `files` as files of what the recordings under way make.
pub(crate) fn note<'a>(files: impl IntoIterator<Item = &'a str>) {
    RECORDING.with(|r| {
        if let Some(top) = r.borrow_mut().last_mut() {
            top.extend(files.into_iter().map(str::to_owned));
        }
    });
}

/// Run `make`, and the files of every shader it expanded (or noted: an object it took from a
/// cache notes the files that object was made from). They count for the recording around it
/// too.
pub(crate) fn recording<T>(make: impl FnOnce() -> T) -> (T, BTreeSet<String>) {
    RECORDING.with(|r| r.borrow_mut().push(BTreeSet::new()));
    let made = make();
    let files = RECORDING.with(|r| r.borrow_mut().pop()).unwrap_or_default();
    note(files.iter().map(String::as_str));
    (made, files)
}

/// A file's stamp: changed when its modification time or length is another.
type Stamp = Option<(SystemTime, u64)>;

fn stamp(path: &Path) -> Stamp {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

/// What the watcher's thread shares with its owner.
#[derive(Default)]
struct Watched {
    /// The folder (every `.wgsl` under it) and the single files looked at.
    dir: Option<PathBuf>,
    files: Vec<PathBuf>,
    /// Each file's stamp at the last look.
    seen: BTreeMap<PathBuf, Stamp>,
    /// Changes seen so far, and whether one is waiting to be taken.
    changes: u64,
    pending: bool,
}

impl Watched {
    /// Look at every file: whether one changed since the last look (a file newly there is no
    /// change; one gone is).
    fn look(&mut self) -> bool {
        let mut now: BTreeMap<PathBuf, Stamp> = BTreeMap::new();
        if let Some(dir) = &self.dir {
            for (_, path) in wgsl_files(dir).unwrap_or_default() {
                let st = stamp(&path);
                now.insert(path, st);
            }
        }
        for path in &self.files {
            now.insert(path.clone(), stamp(path));
        }
        let changed = now
            .iter()
            .any(|(p, st)| self.seen.get(p).is_some_and(|old| old != st))
            || self.seen.keys().any(|p| !now.contains_key(p));
        self.seen = now;
        changed
    }
}

/// Looks at a shader folder and single files on a thread of its own (their modification times
/// and lengths, every [`WATCH_PERIOD`]) and signals a change: [`Watcher::take`] says whether one
/// came, [`Watcher::wait_for_change`] waits for one, and `wake` (the window's repaint) is
/// called on each. What is there when it starts (or when a file is added) is the baseline: a
/// save after that is a change. The thread ends with the watcher.
pub struct Watcher {
    shared: Arc<(Mutex<Watched>, Condvar)>,
    stop: Arc<AtomicBool>,
}

/// How often the watcher looks.
pub const WATCH_PERIOD: Duration = Duration::from_millis(100);

impl Watcher {
    pub fn new(dir: Option<PathBuf>, wake: Box<dyn Fn() + Send>) -> Watcher {
        let mut watched = Watched {
            dir,
            ..Default::default()
        };
        watched.look();
        let shared = Arc::new((Mutex::new(watched), Condvar::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let (s, halt) = (Arc::clone(&shared), Arc::clone(&stop));
        let spawned = std::thread::Builder::new()
            .name("shader-watcher".into())
            .spawn(move || {
                while !halt.load(Ordering::Relaxed) {
                    std::thread::park_timeout(WATCH_PERIOD);
                    let changed = match s.0.lock() {
                        Ok(mut w) => {
                            let changed = w.look();
                            if changed {
                                w.changes += 1;
                                w.pending = true;
                            }
                            changed
                        }
                        Err(_) => return,
                    };
                    if changed {
                        s.1.notify_all();
                        wake();
                    }
                }
            });
        if spawned.is_err() {
            // No thread: nothing is watched, and the lab says nothing changed.
            stop.store(true, Ordering::Relaxed);
        }
        Watcher { shared, stop }
    }

    /// Watch `path` too (a user's method file).
    pub fn watch(&self, path: &Path) {
        if let Ok(mut w) = self.shared.0.lock() {
            if !w.files.iter().any(|p| p == path) {
                w.files.push(path.to_owned());
                let st = stamp(path);
                w.seen.insert(path.to_owned(), st);
            }
        }
    }

    /// Whether a change came since the last call.
    pub fn take(&self) -> bool {
        self.shared
            .0
            .lock()
            .map(|mut w| std::mem::take(&mut w.pending))
            .unwrap_or(false)
    }

    /// Changes seen so far.
    pub fn changes(&self) -> u64 {
        self.shared.0.lock().map(|w| w.changes).unwrap_or(0)
    }

    /// Wait at most `timeout` for more than `seen` changes; the count then.
    pub fn wait_for_change(&self, seen: u64, timeout: Duration) -> u64 {
        let (lock, cvar) = &*self.shared;
        let Ok(guard) = lock.lock() else { return seen };
        match cvar.wait_timeout_while(guard, timeout, |w| w.changes <= seen) {
            Ok((w, _)) => w.changes,
            Err(_) => seen,
        }
    }
}

impl Drop for Watcher {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_source_file_and_line_with_the_line() {
        let main = "// #include shared/a.wgsl\nfn f() -> f32 {\n    return 1.0 +;\n}\n";
        let expanded = shader_source::expand_named("m.wgsl", main, |n| {
            (n == "shared/a.wgsl").then_some("const A: f32 = 1.0;\nconst B: f32 = 2.0;\n")
        })
        .expect("expands");
        let err = validate(&expanded, &|f| format!("dir/{f}")).expect_err("broken");
        assert_eq!((err.file.as_str(), err.line), ("dir/m.wgsl", 3));
        assert_eq!(err.text.as_deref(), Some("    return 1.0 +;"));
        assert!(
            err.to_string().starts_with("dir/m.wgsl:3:"),
            "{}",
            err.to_string()
        );
        // An error in an included file names that file.
        let main = "// #include shared/a.wgsl\nfn f() -> f32 { return A; }\n";
        let expanded = shader_source::expand_named("m.wgsl", main, |n| {
            (n == "shared/a.wgsl")
                .then_some("const A: f32 = 1.0;\nfn g() -> f32 { return true; }\n")
        })
        .expect("expands");
        let err = validate(&expanded, &|f| f.to_owned()).expect_err("broken");
        assert_eq!(err.file, "shared/a.wgsl", "{err}");
    }

    #[test]
    fn recordings_nest() {
        let ((), outer) = recording(|| {
            note(["a.wgsl"]);
            let ((), inner) = recording(|| note(["b.wgsl"]));
            assert_eq!(inner.into_iter().collect::<Vec<_>>(), ["b.wgsl"]);
        });
        assert_eq!(outer.into_iter().collect::<Vec<_>>(), ["a.wgsl", "b.wgsl"]);
    }
}
