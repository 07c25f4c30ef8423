//! The layers inside `src/render`, read from the source: every module has a rank ([`RANKS`]) and
//! names only modules of lower rank (or itself); nothing in `passes/` names `methods`; no two
//! files name each other; a method module names no other method module (what methods share is in
//! a shared module of `methods/`); no file of `src/` is over 900 lines. The checker reads paths as
//! the compiler resolves them (`crate::render::…`, `super::…`, `self::…`, grouped `use` lists),
//! with comments left out; the root's façade (`pub use` in `render/mod.rs`) is followed to the
//! module that defines a name.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The modules of `src/render` from the bottom up. A module names only modules of a lower rank
/// (and itself): the vocabulary the passes share with the methods sits below both, the frame
/// and the session above them. `mod` is the root's own items (`RenderError`, `Texture`, the
/// bind-group helpers). Every module of `src/render` has a rank here
/// ([`every_render_module_has_a_rank`]).
const RANKS: &[(&str, u32)] = &[
    ("mod", 0),
    ("adapter", 0),
    ("frame_tag", 0),
    ("watchdog", 0),
    ("shaders", 0),
    ("context", 1),
    ("readback", 2),
    ("timer", 3),
    ("gpu_scene", 2),
    ("light_maps", 2),
    ("frame_data", 3),
    ("passes", 4),
    ("methods", 5),
    ("frame", 6),
    ("truth", 6),
    ("reference", 2),
    ("gpu_reference", 6),
    ("session", 7),
    ("offline", 8),
    ("view_session", 8),
];

/// Where a module missing from [`RANKS`] is ranked while [`every_render_module_has_a_rank`]
/// fails: above every other.
const TOP: u32 = 100;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render")
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The module path of a file under `src/render`: `passes/probe.rs` → `["passes", "probe"]`,
/// `methods/mod.rs` → `["methods"]`, `mod.rs` → `[]`.
fn module_of(relative: &Path) -> Vec<String> {
    let mut parts: Vec<String> = relative
        .with_extension("")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The code of a file with comments (line, doc and block) and string literals left out (each
/// string as `""`, each character as `' '`; lines keep their numbers), so that a path in a doc
/// link or a message is not read as one the code names. A `mod NAME {` at the
/// start of a line (a test module at the end of a file) is marked with `\u{1}` so that
/// [`paths_named`] resolves `super::` inside it one level deeper.
pub fn code_of(source: &str) -> String {
    let c: Vec<char> = source.chars().collect();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < c.len() {
        let line_start = i == 0 || c[i - 1] == '\n';
        if line_start {
            let line: String = c[i..].iter().take_while(|&&x| x != '\n').collect();
            let words: Vec<&str> = line.split_whitespace().collect();
            if matches!(
                words.as_slice(),
                ["mod", _, "{", ..] | ["pub", "mod", _, "{", ..]
            ) {
                out.push('\u{1}');
            }
        }
        match (c[i], at(i + 1)) {
            ('/', '/') => {
                while i < c.len() && c[i] != '\n' {
                    i += 1;
                }
                continue;
            }
            ('/', '*') => {
                let mut depth = 0;
                while i < c.len() {
                    if c[i] == '/' && at(i + 1) == '*' {
                        depth += 1;
                        i += 2;
                    } else if c[i] == '*' && at(i + 1) == '/' {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        newlines(c[i], &mut out);
                        i += 1;
                    }
                }
                out.push(' ');
                continue;
            }
            ('r', '#' | '"') if i == 0 || !is_ident(c[i - 1]) => {
                // A raw string: r"…", r#"…"#.
                let mut j = i + 1;
                while at(j) == '#' {
                    j += 1;
                }
                if at(j) == '"' {
                    let hashes = j - i - 1;
                    j += 1;
                    while j < c.len() && !(c[j] == '"' && (1..=hashes).all(|k| at(j + k) == '#')) {
                        newlines(c[j], &mut out);
                        j += 1;
                    }
                    i = j + 1 + hashes;
                    out.push_str("\"\"");
                    continue;
                }
            }
            ('"', _) => {
                i += 1;
                while i < c.len() && c[i] != '"' {
                    let step = if c[i] == '\\' { 2 } else { 1 };
                    newlines(at(i + step - 1), &mut out);
                    i += step;
                }
                i += 1;
                out.push_str("\"\"");
                continue;
            }
            ('\'', '\\') => {
                // A character literal with an escape: '\n', '\'', '\u{1}'.
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push_str("' '");
                continue;
            }
            ('\'', _) if at(i + 2) == '\'' => {
                i += 3;
                out.push_str("' '");
                continue;
            }
            _ => {}
        }
        out.push(c[i]);
        i += 1;
    }
    out
}

/// A newline inside a comment or a string is kept, so that lines keep their numbers.
fn newlines(c: char, out: &mut String) {
    if c == '\n' {
        out.push('\n');
    }
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths of a `use` group body or a path's tail, expanded: `a::{b, c::{d, e}}` →
/// `a::b`, `a::c::d`, `a::c::e`.
fn expand(prefix: &[String], text: &str, out: &mut Vec<Vec<String>>) {
    let text = text.trim();
    if let Some(i) = text.find('{') {
        let head = &text[..i];
        let Some(close) = text.rfind('}') else { return };
        let mut base = prefix.to_vec();
        base.extend(segments(head));
        let body = &text[i + 1..close];
        let mut depth = 0;
        let mut start = 0;
        for (k, c) in body.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand(&base, &body[start..k], out);
                    start = k + 1;
                }
                _ => {}
            }
        }
        expand(&base, &body[start..], out);
    } else {
        let mut path = prefix.to_vec();
        let name = text.split(" as ").next().unwrap_or("");
        path.extend(segments(name));
        if path.len() > prefix.len() || !prefix.is_empty() {
            out.push(path);
        }
    }
}

fn segments(path: &str) -> Vec<String> {
    path.split("::")
        .map(str::trim)
        .filter(|s| !s.is_empty() && *s != "self")
        .map(String::from)
        .collect()
}

/// The paths under `crate::render` that `code` (of the module at `module`) names, resolved to
/// absolute segments under `render` (`["passes", "camera", "ScreenView"]`), and the paths that
/// leave `crate::render` for a layer above it (`["crate", "app", …]`).
pub fn paths_named(module: &[String], code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes: Vec<char> = code.chars().collect();
    let mut inline = false;
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == '\u{1}' {
            inline = true;
            i += 1;
            continue;
        }
        let starts_word = i == 0 || !is_ident(bytes[i - 1]) && bytes[i - 1] != ':';
        let rest: String = bytes[i..bytes.len().min(i + 16)].iter().collect();
        let anchor = ["crate::", "super::", "self::"]
            .into_iter()
            .find(|a| rest.starts_with(a));
        let (true, Some(_)) = (starts_word, anchor) else {
            i += 1;
            continue;
        };
        // The whole path: identifiers, `::`, and a balanced `{…}` group.
        let mut j = i;
        let mut depth = 0;
        while j < bytes.len() {
            let c = bytes[j];
            if c == '{' {
                depth += 1;
            } else if c == '}' {
                if depth == 0 {
                    break;
                }
                depth -= 1;
                if depth == 0 {
                    j += 1;
                    break;
                }
            } else if depth == 0 && !(is_ident(c) || c == ':') {
                break;
            }
            j += 1;
        }
        let text: String = bytes[i..j].iter().collect();
        i = j.max(i + 1);
        let mut expanded = Vec::new();
        expand(&[], &text.replace('\n', " "), &mut expanded);
        for path in expanded {
            if let Some(resolved) = resolve(module, inline, &path) {
                out.push(resolved);
            }
        }
    }
    out
}

/// `path` as named in the module at `module` (inside an inline module when `inline`), as
/// segments under `render`; `["crate", …]` for a path outside it; `None` for `crate::` paths into
/// the layers below (`geometry`, `scene`), which any module of `render` may name.
fn resolve(module: &[String], inline: bool, path: &[String]) -> Option<Vec<String>> {
    let mut at: Vec<String> = module.to_vec();
    if inline {
        at.push("tests".into());
    }
    let mut rest = path;
    match rest.first().map(String::as_str) {
        Some("crate") => {
            if rest.get(1).map(String::as_str) != Some("render") {
                let layer = rest.get(1).map(String::as_str).unwrap_or("");
                return ["app", "cli", "compare", "bench", "study"]
                    .contains(&layer)
                    .then(|| rest.to_vec());
            }
            return Some(rest[2..].to_vec());
        }
        Some("self") => rest = &rest[1..],
        _ => {
            while rest.first().map(String::as_str) == Some("super") {
                at.pop()?;
                rest = &rest[1..];
            }
        }
    }
    at.extend(rest.iter().cloned());
    // A path that climbed out of `render` (`super::super::geometry` from `render/passes`) is not
    // inside it; such paths do not occur.
    Some(at)
}

/// The render modules: files and directories directly under `src/render`.
fn top_modules(dir: &Path) -> BTreeSet<String> {
    fs::read_dir(dir)
        .expect("src/render")
        .filter_map(|e| {
            let path = e.ok()?.path();
            let name = path.file_stem()?.to_string_lossy().into_owned();
            (path.is_dir() || path.extension().is_some_and(|x| x == "rs")).then_some(name)
        })
        .collect()
}

/// The root's façade: the names `render/mod.rs` re-exports, and the module that defines each.
fn facade(root_source: &str) -> BTreeMap<String, String> {
    let code = code_of(root_source);
    let mut out = BTreeMap::new();
    for statement in code.split(';') {
        let s = statement.trim();
        let Some(body) = s.strip_prefix("pub use ") else {
            continue;
        };
        let mut paths = Vec::new();
        expand(&[], body, &mut paths);
        for p in paths {
            if let (Some(first), Some(last)) = (p.first(), p.last()) {
                if first != "crate" {
                    out.insert(last.clone(), first.clone());
                }
            }
        }
    }
    out
}

/// The unit (top module, or `mod` for the root's own items) a path under `render` lands in.
fn unit_of(
    path: &[String],
    modules: &BTreeSet<String>,
    facade: &BTreeMap<String, String>,
) -> String {
    match path.first() {
        None => "mod".into(),
        Some(first) if first == "crate" => path[..2.min(path.len())].join("::"),
        Some(first) if modules.contains(first) => first.clone(),
        Some(first) => facade.get(first).cloned().unwrap_or_else(|| "mod".into()),
    }
}

fn rank(unit: &str) -> u32 {
    RANKS
        .iter()
        .find(|(m, _)| *m == unit)
        .map_or(TOP, |&(_, r)| r)
}

/// One file's code, by its path under `src/render`.
struct File {
    relative: PathBuf,
    module: Vec<String>,
    code: String,
}

fn files() -> Vec<File> {
    let dir = root();
    rust_files(&dir)
        .into_iter()
        .map(|path| {
            let relative = path
                .strip_prefix(&dir)
                .expect("under src/render")
                .to_path_buf();
            let source = fs::read_to_string(&path).expect("a source file");
            File {
                module: module_of(&relative),
                code: code_of(&source),
                relative,
            }
        })
        .collect()
}

/// Every path in `files` that runs against the ranks: `file: path (unit rank → unit rank)`.
/// The root's own `pub use` lines are its façade, not imports, and are skipped.
fn upward(files: &[File]) -> Vec<String> {
    let dir = root();
    let modules = top_modules(&dir);
    let facade = facade(&fs::read_to_string(dir.join("mod.rs")).expect("render/mod.rs"));
    let mut out = Vec::new();
    for f in files {
        let from = f.module.first().cloned().unwrap_or_else(|| "mod".into());
        let code = if f.module.is_empty() {
            f.code
                .split(';')
                .filter(|s| !s.trim_start().starts_with("pub use "))
                .collect::<Vec<_>>()
                .join(";")
        } else {
            f.code.clone()
        };
        for path in paths_named(&f.module, &code) {
            let to = unit_of(&path, &modules, &facade);
            if to == from {
                continue;
            }
            if to.starts_with("crate::") || rank(&to) >= rank(&from) {
                let line = format!(
                    "{}: {} ({from} {} → {to} {})",
                    f.relative.display(),
                    path.join("::"),
                    rank(&from),
                    rank(&to)
                );
                if !out.contains(&line) {
                    out.push(line);
                }
            }
        }
    }
    out
}

/// Whether the module at `module` names `methods` (any path into `render::methods`).
pub fn names_methods(module: &[String], source: &str) -> Vec<String> {
    paths_named(module, &code_of(source))
        .into_iter()
        .filter(|p| p.first().is_some_and(|m| m == "methods"))
        .map(|p| p.join("::"))
        .collect()
}

#[test]
fn passes_name_no_method() {
    let bad: Vec<String> = files()
        .iter()
        .filter(|f| f.module.first().is_some_and(|m| m == "passes"))
        .flat_map(|f| {
            paths_named(&f.module, &f.code)
                .into_iter()
                .filter(|p| p.first().is_some_and(|m| m == "methods"))
                .map(move |p| format!("{}: {}", f.relative.display(), p.join("::")))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "passes/ names render::methods (what a pass needs lives below it, or comes in as an \
         argument):\n{}",
        bad.join("\n")
    );
}

#[test]
fn every_render_module_has_a_rank() {
    let unranked: Vec<String> = top_modules(&root())
        .into_iter()
        .filter(|m| m != "mod" && !RANKS.iter().any(|(r, _)| r == m))
        .collect();
    assert!(
        unranked.is_empty(),
        "modules of src/render without a rank: add each to RANKS in tests/cpu/layers.rs (and to \
         \"Layers inside render/\" in docs/development/architecture.md): {unranked:?}"
    );
}

#[test]
fn render_imports_run_downward() {
    let bad = upward(&files());
    assert!(
        bad.is_empty(),
        "imports inside src/render that run against the ranks in tests/cpu/layers.rs:\n{}",
        bad.join("\n")
    );
}

/// The files each file of `src/render` names (by their paths under `render`, resolved to the
/// longest prefix that is a file).
fn file_graph(files: &[File]) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let known: BTreeSet<Vec<String>> = files.iter().map(|f| f.module.clone()).collect();
    let mut graph = BTreeMap::new();
    for f in files {
        let mut to = BTreeSet::new();
        for path in paths_named(&f.module, &f.code) {
            let target = (0..=path.len())
                .rev()
                .map(|n| path[..n].to_vec())
                .find(|p| known.contains(p));
            if let Some(t) = target.filter(|t| *t != f.module) {
                to.insert(t);
            }
        }
        graph.insert(f.module.clone(), to);
    }
    graph
}

/// Pairs of files that still name each other or methods that still name another method, each
/// `(from, to)` by module path, which work in progress removes (ground truth as one
/// interface): the tests hold every other pair, and fail on an entry here that no longer
/// occurs, so that the list only shrinks.
const PENDING: &[(&str, &str)] = &[("methods/reference_hard", "methods/reference")];

fn pending(from: &[String], to: &[String]) -> bool {
    PENDING
        .iter()
        .any(|&(a, b)| a == from.join("/") && b == to.join("/"))
}

#[test]
fn pending_pairs_still_occur() {
    let graph = file_graph(&files());
    let gone: Vec<String> = PENDING
        .iter()
        .filter(|&&(a, b)| {
            !graph
                .iter()
                .any(|(f, to)| f.join("/") == a && to.iter().any(|t| t.join("/") == b))
        })
        .map(|(a, b)| format!("{a} → {b}"))
        .collect();
    assert!(
        gone.is_empty(),
        "no longer named: take them off PENDING in tests/cpu/layers.rs:\n{}",
        gone.join("\n")
    );
}

#[test]
fn no_two_render_files_name_each_other() {
    let graph = file_graph(&files());
    let mut pairs = Vec::new();
    for (a, to) in &graph {
        for b in to {
            // A parent names its children to declare them; a child naming its parent's items
            // (`super::X`) is the usual shape of a module tree.
            let parent_child = b.starts_with(a) || a.starts_with(b);
            let known = pending(a, b) || pending(b, a);
            if a < b && !parent_child && !known && graph.get(b).is_some_and(|t| t.contains(a)) {
                pairs.push(format!("{} ⇄ {}", a.join("/"), b.join("/")));
            }
        }
    }
    assert!(
        pairs.is_empty(),
        "files of src/render that name each other:\n{}",
        pairs.join("\n")
    );
}

/// The method modules: files of `methods/` that define a method of the registry
/// (`… : MethodSpec =`).
fn method_modules(files: &[File]) -> BTreeSet<Vec<String>> {
    let dir = root();
    files
        .iter()
        .filter(|f| f.module.first().is_some_and(|m| m == "methods") && f.module.len() == 2)
        .filter(|f| {
            fs::read_to_string(dir.join(&f.relative)).is_ok_and(|s| s.contains(": MethodSpec ="))
        })
        .map(|f| f.module.clone())
        .collect()
}

#[test]
fn methods_name_no_other_method() {
    let files = files();
    let methods = method_modules(&files);
    assert!(methods.len() > 10, "found the method modules: {methods:?}");
    let graph = file_graph(&files);
    let mut bad = Vec::new();
    for m in &methods {
        for to in graph.get(m).into_iter().flatten() {
            if methods.contains(to) && !pending(m, to) {
                bad.push(format!("{} → {}", m.join("/"), to.join("/")));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "method modules that name another method module (what they share belongs in a shared \
         module of methods/):\n{}",
        bad.join("\n")
    );
}

/// The checker itself, on lines written to break the rules.
#[test]
fn the_checker_sees_bad_lines() {
    let passes = |m: &str| vec!["passes".to_string(), m.to_string()];
    let bad = [
        "use crate::render::methods::LightMaps;",
        "use crate::render::{buffer_entry, methods::Channel};",
        "use super::super::methods::{\n    Channel,\n    Empty,\n};",
        "fn f() { let s = rec.span(crate::render::methods::wedges::WEDGES.name); }",
        "use crate::render::{\n    methods::{self, LightMaps},\n    GpuContext,\n};",
    ];
    for line in bad {
        assert!(
            !names_methods(&passes("probe"), line).is_empty(),
            "the checker missed: {line}"
        );
    }
    let fine = [
        "use crate::render::light_maps::LightMaps;",
        "// use crate::render::methods::LightMaps;",
        "/// [`crate::render::methods::CameraGroup`] binds it.",
        "let s = \"crate::render::methods\";",
        "use super::camera::CameraTargets;",
        "use crate::geometry::methods::Nothing;",
    ];
    for line in fine {
        assert!(
            names_methods(&passes("probe"), line).is_empty(),
            "the checker flagged: {line}"
        );
    }
    // `super` from the passes' own root is `render`.
    assert_eq!(
        names_methods(&["passes".to_string()], "use super::methods::Knobs;"),
        ["methods::Knobs"]
    );
    // Inside a test module, `super` is the file's own module.
    let tests = "mod tests {\n    use super::methods::X;\n}\n";
    assert!(names_methods(&passes("probe"), tests).is_empty());
}

/// Consecutive lines of the same shape two method modules may share.
const SHARED_SHAPE_LINES: usize = 6;

/// The shape of one line of code (from [`code_of`]): trimmed, every number as `0`; `None` for
/// boilerplate — a blank line, a `use` or `mod` line, an attribute, a line of brackets and
/// punctuation alone (`}`, `});`, `],`).
pub fn shape(line: &str) -> Option<String> {
    let t = line.trim().trim_start_matches('\u{1}').trim();
    let boilerplate = t.is_empty()
        || t.starts_with("use ")
        || t.starts_with("pub use ")
        || t.starts_with("#[")
        || t.starts_with("#![")
        || (t.starts_with("mod ") || t.starts_with("pub mod ")) && t.ends_with(';')
        || t.chars().all(|c| "{}()[];,".contains(c));
    if boilerplate {
        return None;
    }
    let mut out = String::with_capacity(t.len());
    let mut previous = ' ';
    let mut in_number = false;
    for c in t.chars() {
        let starts = c.is_ascii_digit() && !is_ident(previous) && !in_number;
        let continues = in_number && (is_ident(c) || c == '.');
        if starts {
            out.push('0');
            in_number = true;
        } else if !continues {
            in_number = false;
            out.push(c);
        }
        previous = c;
    }
    Some(out)
}

/// The runs of at least [`SHARED_SHAPE_LINES`] consecutive same-shape lines (boilerplate left
/// out) that two of `sources` (name, text) share: `a:line ⇄ b:line` and the first line's shape,
/// one entry per pair of sources.
pub fn shared_shapes(sources: &[(String, String)]) -> Vec<String> {
    let shaped: Vec<Vec<(usize, String)>> = sources
        .iter()
        .map(|(_, text)| {
            code_of(text)
                .lines()
                .enumerate()
                .filter_map(|(i, l)| shape(l).map(|s| (i + 1, s)))
                .collect()
        })
        .collect();
    let mut windows: BTreeMap<Vec<&str>, Vec<(usize, usize)>> = BTreeMap::new();
    for (f, lines) in shaped.iter().enumerate() {
        for w in lines.windows(SHARED_SHAPE_LINES) {
            let key: Vec<&str> = w.iter().map(|(_, s)| s.as_str()).collect();
            windows.entry(key).or_default().push((f, w[0].0));
        }
    }
    let mut pairs: BTreeMap<(usize, usize), (usize, usize, String)> = BTreeMap::new();
    for (key, at) in &windows {
        for (i, &(a, la)) in at.iter().enumerate() {
            for &(b, lb) in &at[i + 1..] {
                if a != b {
                    let (a, la, b, lb) = if a < b {
                        (a, la, b, lb)
                    } else {
                        (b, lb, a, la)
                    };
                    let first = (la, lb, key[0].to_string());
                    pairs
                        .entry((a, b))
                        .and_modify(|e| *e = e.clone().min(first.clone()))
                        .or_insert(first);
                }
            }
        }
    }
    pairs
        .into_iter()
        .map(|((a, b), (la, lb, first))| {
            format!("{}:{la} ⇄ {}:{lb}: {first}", sources[a].0, sources[b].0)
        })
        .collect()
}

/// The files of `src/render/methods/`, by name.
fn method_sources() -> Vec<(String, String)> {
    let dir = root().join("methods");
    rust_files(&dir)
        .into_iter()
        .map(|p| {
            let name = p
                .strip_prefix(&dir)
                .expect("under methods/")
                .display()
                .to_string();
            (name, fs::read_to_string(&p).expect("a method module"))
        })
        .collect()
}

#[test]
fn no_two_method_modules_share_six_lines_of_the_same_shape() {
    let shared = shared_shapes(&method_sources());
    assert!(
        shared.is_empty(),
        "method modules that share {SHARED_SHAPE_LINES} or more consecutive lines of the same \
         shape (make the shared part one piece in a shared module of methods/):\n{}",
        shared.join("\n")
    );
}

/// The duplicate check on sources written to share, and not to share, a run of lines.
#[test]
fn the_shape_check_sees_a_copied_run() {
    // Six lines of the same shape; comments, strings, numbers, `use` lines and brackets differ.
    let a = "use crate::render::one;\n\nfn f() {\n    let a = 1;\n    let b = a + 1;\n    \
             let c = b * 2; // one\n    let d = \"one\";\n\n    let e = c - 1;\n    \
             let f = e / 3;\n}\n";
    let b = "// Two.\nuse crate::render::{one, two};\n\nfn f() {\n    let a = 7;\n    \
             let b = a + 2;\n    let c = b * 9;\n    let d = \"two\";\n    {\n    \
             let e = c - 1;\n    }\n    let f = e / 5;\n}\n";
    let found = shared_shapes(&[("a.rs".into(), a.into()), ("b.rs".into(), b.into())]);
    assert_eq!(found, ["a.rs:3 ⇄ b.rs:4: fn f() {"]);
    // One name changed in the middle leaves runs of three and three.
    let c = a.replace("let c = b * 2;", "let c = a * 2;");
    let found = shared_shapes(&[("b.rs".into(), b.into()), ("c.rs".into(), c)]);
    assert!(found.is_empty(), "{found:?}");
    assert_eq!(shape("    });"), None);
    assert_eq!(shape("use super::Knobs;"), None);
    assert_eq!(
        shape("  let x = f(1.5e3, 0x1f, a2);"),
        Some("let x = f(0, 0, a2);".into())
    );
}

/// The longest a file of `src/` may be: past it, a file holds more than one job.
const MAX_SOURCE_LINES: usize = 900;

/// The files of `dir` (recursively) longer than `max` lines, as `path: lines`.
fn long_files(dir: &Path, max: usize) -> Vec<String> {
    rust_files(dir)
        .into_iter()
        .filter_map(|path| {
            let text = fs::read_to_string(&path).ok()?;
            let lines = text.lines().count();
            (lines > max).then(|| format!("{}: {lines} lines", path.display()))
        })
        .collect()
}

#[test]
fn no_source_file_is_over_900_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let long = long_files(&src, MAX_SOURCE_LINES);
    assert!(
        long.is_empty(),
        "files over {MAX_SOURCE_LINES} lines (split them by job):\n{}",
        long.join("\n")
    );
    // The check sees a long file: the render core has files of more than a hundred lines.
    assert!(!long_files(&root(), 100).is_empty());
}
