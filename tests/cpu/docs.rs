//! The documentation holds together:
//! - every relative link and picture in `README.md` and `docs/**/*.md` resolves: the file exists,
//!   and a `#anchor` names a heading of the target by GitHub's rule;
//! - no tracked file points outside the repository (the three needles of [`outside_needles`]);
//! - the README's method table is the registry: the names of `methods::ALL` in order, each with
//!   the light kinds its `takes` accepts;
//! - `docs/guide/command-line.md` names every subcommand and every `--flag` the binary's help
//!   prints;
//! - no code comment, method page or the README names an issue by number or a commit hash.
//!
//! Each checker is a function over text and paths, and the `*_catches_*` tests feed it broken
//! input, so every assertion here is one that can fail.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Component, Path, PathBuf};
use std::process::Command;

use dbuffer::render::methods::ALL;
use dbuffer::scene::LightKind;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `README.md` and every `.md` under `docs/`, sorted.
fn markdown_files(root: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut out = vec![root.join("README.md")];
    walk(&root.join("docs"), &mut out);
    out.sort();
    out
}

/// The lines of a Markdown text outside fenced code blocks, with their 1-based numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fence: Option<&str> = None;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        let marker = if t.starts_with("```") {
            Some("```")
        } else if t.starts_with("~~~") {
            Some("~~~")
        } else {
            None
        };
        match (fence, marker) {
            (None, Some(m)) => fence = Some(m),
            (Some(f), Some(m)) if f == m => fence = None,
            (None, None) => out.push((i + 1, line)),
            _ => {}
        }
    }
    out
}

/// `line` without its inline code spans (a run of backticks up to the next run of the same
/// length), so a link written as code is not a link.
fn without_code_spans(line: &str) -> String {
    let chars: Vec<char> = line.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let run = chars[i..].iter().take_while(|&&c| c == '`').count();
        let mut j = i + run;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '`' {
                let r = chars[j..].iter().take_while(|&&c| c == '`').count();
                if r == run {
                    close = Some(j + r);
                    break;
                }
                j += r;
            } else {
                j += 1;
            }
        }
        match close {
            Some(end) => {
                out.push(' ');
                i = end;
            }
            None => {
                // An unmatched run is literal text.
                out.extend(&chars[i..i + run]);
                i += run;
            }
        }
    }
    out
}

/// The targets of the inline links and pictures of a Markdown text, with their line numbers.
fn link_targets(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in prose_lines(text) {
        let line = without_code_spans(line);
        let mut rest = line.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            // Up to the matching parenthesis (targets may hold balanced ones).
            let mut depth = 0usize;
            let mut end = None;
            for (k, c) in after.char_indices() {
                match c {
                    '(' => depth += 1,
                    ')' if depth == 0 => {
                        end = Some(k);
                        break;
                    }
                    ')' => depth -= 1,
                    _ => {}
                }
            }
            let Some(end) = end else { break };
            let target = after[..end].trim();
            // `[text](path "title")`: the title is not part of the path.
            let target = target.split_whitespace().next().unwrap_or("");
            let target = target.trim_start_matches('<').trim_end_matches('>');
            if !target.is_empty() {
                out.push((n, target.to_string()));
            }
            rest = &after[end..];
        }
    }
    out
}

/// GitHub's anchor for a heading: lowercase, spaces to `-`, every other character that is not a
/// letter, a digit, `-` or `_` dropped (backticks and emphasis included).
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            '-' | '_' => Some(c),
            c if c.is_alphanumeric() => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a Markdown text's ATX headings; a repeated heading gets `-1`, `-2`, … as on
/// GitHub.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    for (_, line) in prose_lines(text) {
        let t = line.trim_start();
        let hashes = t.chars().take_while(|&c| c == '#').count();
        if !(1..=6).contains(&hashes) || !t[hashes..].starts_with(' ') {
            continue;
        }
        let title = t[hashes..].trim().trim_end_matches('#').trim();
        let base = slug(title);
        let count = seen.entry(base.clone()).or_insert(0);
        let anchor = if *count == 0 {
            base.clone()
        } else {
            format!("{base}-{count}")
        };
        *count += 1;
        out.insert(anchor);
    }
    out
}

/// `path` with `.` and `..` resolved lexically (the file may not exist).
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// Every broken relative link of `files`, as `file:line: target: why`.
fn broken_links(files: &[PathBuf]) -> Vec<String> {
    let mut problems = Vec::new();
    for file in files {
        let Ok(text) = std::fs::read_to_string(file) else {
            problems.push(format!("{}: cannot be read", file.display()));
            continue;
        };
        let dir = file.parent().unwrap_or(Path::new("."));
        for (line, target) in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() {
                file.clone()
            } else {
                normalise(&dir.join(path))
            };
            let at = format!("{}:{line}: {target}", file.display());
            if !resolved.exists() {
                problems.push(format!("{at}: {} does not exist", resolved.display()));
                continue;
            }
            let Some(anchor) = anchor else { continue };
            if resolved.extension().is_none_or(|e| e != "md") {
                problems.push(format!("{at}: an anchor into a file that is not Markdown"));
                continue;
            }
            let target_text = std::fs::read_to_string(&resolved).unwrap_or_default();
            let known = anchors(&target_text);
            if !known.contains(anchor) {
                problems.push(format!(
                    "{at}: no heading of {} has the anchor #{anchor}",
                    resolved.display()
                ));
            }
        }
    }
    problems
}

#[test]
fn every_relative_link_resolves() {
    let files = markdown_files(&root());
    assert!(
        files.len() > 20,
        "expected README.md and the docs/ tree, found {} files",
        files.len()
    );
    let problems = broken_links(&files);
    assert!(
        problems.is_empty(),
        "{} broken links:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// A scratch folder of its own under the system's temporary directory.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dbuffer-docs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("sub")).expect("make a scratch folder");
    dir
}

#[test]
fn the_link_checker_catches_a_missing_file_and_a_missing_anchor() {
    let dir = scratch("links");
    std::fs::write(
        dir.join("sub/target.md"),
        "# The `D-buffer`, as implemented\n\n## V(t) variants\n\n## V(t) variants\n\n```\n# not a heading\n```\n",
    )
    .expect("write");
    let good = "[a](sub/target.md) [b](sub/target.md#the-d-buffer-as-implemented) \
                [c](sub/target.md#vt-variants) [d](sub/target.md#vt-variants-1) [e](#top) \
                ![f](sub) [g](https://example.com/nowhere) `[h](nowhere.md)`\n\n# Top\n";
    std::fs::write(dir.join("good.md"), good).expect("write");
    assert_eq!(
        broken_links(&[dir.join("good.md")]),
        Vec::<String>::new(),
        "every link of good.md resolves"
    );
    let bad = "[a](sub/missing.md)\n[b](sub/target.md#no-such-heading)\n[c](sub/target.md#not-a-heading)\n";
    std::fs::write(dir.join("bad.md"), bad).expect("write");
    let problems = broken_links(&[dir.join("bad.md")]);
    assert_eq!(problems.len(), 3, "{problems:#?}");
    assert!(problems[0].contains("missing.md") && problems[0].contains("does not exist"));
    assert!(problems[1].contains("#no-such-heading"));
    assert!(problems[2].contains("#not-a-heading"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn slugs_follow_githubs_rule() {
    assert_eq!(
        slug("The visibility parameter t"),
        "the-visibility-parameter-t"
    );
    assert_eq!(slug("V(t) variants"), "vt-variants");
    assert_eq!(slug("`render`"), "render");
    assert_eq!(slug("On the GPU (measured)"), "on-the-gpu-measured");
    assert_eq!(
        slug("`dbuffer bench --quick`, 2026-11-30"),
        "dbuffer-bench---quick-2026-11-30"
    );
    assert_eq!(slug("snake_case and CAPS"), "snake_case-and-caps");
}

/// The strings no tracked file may contain, built here so this file does not contain them: the
/// names of documents outside a clone.
fn outside_needles() -> [String; 3] {
    [
        concat!("design", ".md").to_string(),
        format!("{} {}", "seed", "00"),
        format!("{}/{}", "..", "shared"),
    ]
}

/// Extensions of the binary files the scan skips.
const BINARY: &[&str] = &["png", "glb", "obj", "exr", "jpg", "bin", "ttf"];

/// The needles (case-insensitive) each of `files` (relative to `root`) contains, as `file: needle`.
fn outside_references(root: &Path, files: &[String]) -> Vec<String> {
    let needles = outside_needles();
    let mut found = Vec::new();
    for name in files {
        let Some(text) = text_of(root, name) else {
            continue;
        };
        let text = text.to_lowercase();
        for needle in &needles {
            if text.contains(needle.as_str()) {
                found.push(format!("{name}: {needle}"));
            }
        }
    }
    found
}

/// The files git tracks, relative to `root`; `None` (said loudly) outside a git checkout.
fn tracked_files(root: &Path, test: &str) -> Option<Vec<String>> {
    let listed = Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root)
        .output();
    match listed {
        Ok(out) if out.status.success() => Some(
            out.stdout
                .split(|&b| b == 0)
                .filter(|s| !s.is_empty())
                .map(|s| String::from_utf8_lossy(s).into_owned())
                .collect(),
        ),
        other => {
            eprintln!(
                "\n*** SKIPPED {test}: `git ls-files` failed in {} ({other:?}); not a git \
                 checkout? ***\n",
                root.display()
            );
            None
        }
    }
}

/// The text of a tracked file worth scanning: `None` for the binary files.
fn text_of(root: &Path, name: &str) -> Option<String> {
    let binary = Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| BINARY.contains(&e.to_ascii_lowercase().as_str()));
    if binary {
        return None;
    }
    // A tracked file deleted in the working tree, or not readable: nothing to scan.
    let bytes = std::fs::read(root.join(name)).ok()?;
    if bytes.contains(&0) {
        return None; // binary content under another extension
    }
    Some(String::from_utf8_lossy(&bytes).into_owned())
}

#[test]
fn no_tracked_file_points_outside_the_repository() {
    let root = root();
    let Some(files) = tracked_files(&root, "no_tracked_file_points_outside_the_repository") else {
        return;
    };
    assert!(
        files.iter().any(|f| f == "README.md") && files.len() > 100,
        "git ls-files listed {} files",
        files.len()
    );
    let found = outside_references(&root, &files);
    assert!(
        found.is_empty(),
        "tracked files name documents outside the repository (cite papers by author and year, \
         point at docs/):\n{}",
        found.join("\n")
    );
}

/// Every `docs/….md` or `docs/….md#anchor` a text names (code comments, scripts, docs), as
/// root-relative paths with their anchors.
fn docs_mentions(text: &str) -> Vec<(String, Option<String>)> {
    let path_char = |c: char| c.is_ascii_alphanumeric() || matches!(c, '/' | '-' | '_' | '.');
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(at) = text[from..].find("docs/") {
        let start = from + at;
        from = start + 5;
        let before = text[..start].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
            continue; // `mydocs/`, not this repository's docs/
        }
        let path: String = text[start..]
            .chars()
            .take_while(|&c| path_char(c))
            .collect();
        let path = path.trim_end_matches('.').to_string();
        if !path.ends_with(".md") {
            continue;
        }
        let after = &text[start + path.len()..];
        let anchor = after.strip_prefix('#').map(|a| {
            a.chars()
                .take_while(|&c| c.is_alphanumeric() || c == '-' || c == '_')
                .collect::<String>()
        });
        out.push((path, anchor.filter(|a| !a.is_empty())));
    }
    out
}

#[test]
fn every_docs_path_named_in_the_tree_exists() {
    let root = root();
    let Some(files) = tracked_files(&root, "every_docs_path_named_in_the_tree_exists") else {
        return;
    };
    let mut problems = Vec::new();
    for name in &files {
        let Some(text) = text_of(&root, name) else {
            continue;
        };
        for (path, anchor) in docs_mentions(&text) {
            let target = root.join(&path);
            let Ok(target_text) = std::fs::read_to_string(&target) else {
                problems.push(format!("{name}: {path} does not exist"));
                continue;
            };
            if let Some(anchor) = anchor {
                if !anchors(&target_text).contains(&anchor) {
                    problems.push(format!("{name}: {path} has no heading #{anchor}"));
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "files name docs that are not there:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_docs_path_scan_reads_paths_and_anchors() {
    let text =
        "//! (docs/method/dbuffer.md#the-visibility-parameter-t) and docs/guide/limits.md.\n\
                see ../docs/references.md, `docs/images/lab.png`, mydocs/x.md";
    assert_eq!(
        docs_mentions(text),
        [
            (
                "docs/method/dbuffer.md".to_string(),
                Some("the-visibility-parameter-t".to_string())
            ),
            ("docs/guide/limits.md".to_string(), None),
            ("docs/references.md".to_string(), None),
        ]
    );
}

#[test]
fn the_outside_scan_catches_each_needle() {
    let dir = scratch("needles");
    let needles = outside_needles();
    let mut names = Vec::new();
    for (i, needle) in needles.iter().enumerate() {
        let name = format!("sub/f{i}.rs");
        // Upper case: the scan ignores case.
        std::fs::write(
            dir.join(&name),
            format!("// see {}\n", needle.to_uppercase()),
        )
        .expect("write");
        names.push(name);
    }
    std::fs::write(dir.join("clean.md"), "nothing here\n").expect("write");
    std::fs::write(dir.join("sub/pic.png"), needles[0].as_bytes()).expect("write");
    names.push("clean.md".into());
    names.push("sub/pic.png".into());
    names.push("sub/deleted.md".into());
    let found = outside_references(&dir, &names);
    assert_eq!(found.len(), 3, "{found:#?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every kind of light, for the table's light column. A new kind fails to compile here until it
/// is added (and the README's table gets a word for it).
fn light_kinds() -> Vec<LightKind> {
    let all = [
        LightKind::Disk,
        LightKind::Rect,
        LightKind::Polygon,
        LightKind::Line,
    ];
    for k in all {
        match k {
            LightKind::Disk | LightKind::Rect | LightKind::Polygon | LightKind::Line => {}
        }
    }
    all.to_vec()
}

/// The cells of a Markdown table row (`\|` is a pipe inside a cell).
pub(crate) fn cells(row: &str) -> Vec<String> {
    let row = row.trim();
    let row = row.strip_prefix('|').unwrap_or(row);
    let row = row.strip_suffix('|').unwrap_or(row);
    let mut out = vec![String::new()];
    let mut chars = row.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                chars.next();
                if let Some(cell) = out.last_mut() {
                    cell.push('|');
                }
            }
            '|' => out.push(String::new()),
            c => {
                if let Some(cell) = out.last_mut() {
                    cell.push(c);
                }
            }
        }
    }
    out.iter().map(|c| c.trim().to_string()).collect()
}

/// The README's method table: per row, the method's name and its light kinds as written.
fn method_table(readme: &str) -> Result<Vec<(String, BTreeSet<String>)>, String> {
    let lines: Vec<&str> = readme.lines().collect();
    let header = lines
        .iter()
        .position(|l| {
            let c = cells(l);
            c.len() >= 4 && c[0] == "method" && c[1] == "paper" && c[2] == "light"
        })
        .ok_or("no table with the header | method | paper | light | … |")?;
    let mut rows = Vec::new();
    for line in lines[header + 2..]
        .iter()
        .take_while(|l| l.trim_start().starts_with('|'))
    {
        let c = cells(line);
        if c.len() < 4 {
            return Err(format!("a row with {} cells: {line}", c.len()));
        }
        let name = c[0].trim_matches('`').to_string();
        let kinds = c[2]
            .split(',')
            .map(|k| k.trim().to_string())
            .filter(|k| !k.is_empty())
            .collect();
        rows.push((name, kinds));
    }
    Ok(rows)
}

/// What the table should say: the registry in order, each method with the kinds it takes.
fn registry_table() -> Vec<(String, BTreeSet<String>)> {
    ALL.iter()
        .map(|m| {
            let kinds = light_kinds()
                .into_iter()
                .filter(|&k| m.takes(k))
                .map(|k| k.name().to_string())
                .collect();
            (m.name().to_string(), kinds)
        })
        .collect()
}

#[test]
fn readme_method_table_is_the_registry() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("read README.md");
    let table = method_table(&readme).unwrap_or_else(|e| panic!("README.md: {e}"));
    let want = registry_table();
    let names: Vec<&str> = table.iter().map(|(n, _)| n.as_str()).collect();
    let want_names: Vec<&str> = want.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names, want_names,
        "the README's method table must list methods::ALL, in its order"
    );
    for ((name, kinds), (_, want_kinds)) in table.iter().zip(&want) {
        assert_eq!(
            kinds, want_kinds,
            "README.md, method `{name}`: the light column says {kinds:?}, its takes() says {want_kinds:?}"
        );
    }
}

#[test]
fn the_table_check_catches_a_wrong_row() {
    let mut rows: Vec<String> = registry_table()
        .iter()
        .map(|(n, k)| {
            let k: Vec<&str> = k.iter().map(String::as_str).collect();
            format!(
                "| `{n}` | a paper \\| another | {} | it errs |",
                k.join(", ")
            )
        })
        .collect();
    let head = "| method | paper | light | what it gets wrong |\n|---|---|---|---|\n";
    let good = format!("intro\n\n{head}{}\n\nafter\n", rows.join("\n"));
    assert_eq!(method_table(&good), Ok(registry_table()));
    // Two rows swapped, and a light kind dropped: both differ from the registry.
    rows.swap(0, 1);
    let swapped = format!("{head}{}\n", rows.join("\n"));
    assert_ne!(method_table(&swapped), Ok(registry_table()));
    rows.swap(0, 1);
    rows[3] = rows[3].replace("disk, line", "disk");
    let narrowed = format!("{head}{}\n", rows.join("\n"));
    assert_ne!(method_table(&narrowed), Ok(registry_table()));
    assert!(method_table("no table here").is_err());
}

/// Runs the binary with `args`; its standard output.
fn help(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_dbuffer"))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("run dbuffer {args:?}: {e}"));
    assert!(out.status.success(), "dbuffer {args:?} failed: {out:?}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The subcommands a clap help text lists under `Commands:`.
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

/// Every `--long-flag` in a text.
fn long_flags(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    while i + 2 < bytes.len() {
        let starts = bytes[i] == b'-'
            && bytes[i + 1] == b'-'
            && bytes[i + 2].is_ascii_lowercase()
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'-'));
        if starts {
            let end = bytes[i + 2..]
                .iter()
                .position(|b| !(b.is_ascii_lowercase() || b.is_ascii_digit() || *b == b'-'))
                .map_or(bytes.len(), |p| i + 2 + p);
            out.insert(text[i..end].trim_end_matches('-').to_string());
            i = end;
        } else {
            i += 1;
        }
    }
    out
}

/// What `page` fails to name of `subs` and `flags`: a subcommand as a code span starting with it
/// (`` `render `` …), a flag as a whole word.
fn missing_from_page(page: &str, subs: &[String], flags: &BTreeSet<String>) -> Vec<String> {
    let named = long_flags(page);
    let mut missing: Vec<String> = subs
        .iter()
        .filter(|s| !(page.contains(&format!("`{s} ")) || page.contains(&format!("`{s}`"))))
        .map(|s| format!("subcommand {s}"))
        .collect();
    missing.extend(
        flags
            .iter()
            .filter(|f| !named.contains(*f))
            .map(|f| format!("flag {f}")),
    );
    missing
}

#[test]
fn command_line_page_names_every_subcommand_and_flag() {
    let top = help(&["--help"]);
    let subs = subcommands(&top);
    for expected in [
        "gui", "render", "compare", "animate", "bench", "scenes", "inspect",
    ] {
        assert!(
            subs.iter().any(|s| s == expected),
            "`dbuffer --help` lists no {expected}: {subs:?}\n{top}"
        );
    }
    let mut flags = long_flags(&top);
    for sub in subs.iter().filter(|s| *s != "help") {
        let text = help(&[sub, "--help"]);
        let found = long_flags(&text);
        assert!(
            sub == "scenes" || sub == "gui" || found.len() > 2,
            "`dbuffer {sub} --help` prints almost no flags:\n{text}"
        );
        flags.extend(found);
    }
    let page = std::fs::read_to_string(root().join("docs/guide/command-line.md"))
        .expect("read docs/guide/command-line.md");
    let missing = missing_from_page(&page, &subs, &flags);
    assert!(
        missing.is_empty(),
        "docs/guide/command-line.md does not name: {}",
        missing.join(", ")
    );
}

#[test]
fn the_command_line_check_catches_a_missing_flag() {
    let help = "Usage: x\n\nCommands:\n  render   Render\n  scenes   List\n\nOptions:\n  \
                --out <OUT>  where\n  --dbuffer-size <N>  texels\n  -h, --help  help\n";
    let subs = subcommands(help);
    assert_eq!(subs, ["render", "scenes"]);
    let flags = long_flags(help);
    assert_eq!(
        flags.iter().map(String::as_str).collect::<Vec<_>>(),
        ["--dbuffer-size", "--help", "--out"]
    );
    let page = "`render SCENE --out DIR`, `scenes`, `--dbuffer-size N`, `--help`";
    assert!(missing_from_page(page, &subs, &flags).is_empty());
    // `--dbuffer` alone is not `--dbuffer-size`, and `render` must appear as a command.
    let page = "`--out`, `--dbuffer`, `--help`, scenes";
    assert_eq!(
        missing_from_page(page, &subs, &flags),
        [
            "subcommand render",
            "subcommand scenes",
            "flag --dbuffer-size"
        ]
    );
}

/// Where a text names an issue by number (the word, an optional plural `s`, a space, an optional
/// `#` and a digit; case-insensitive), as `line: excerpt`: a reader of the repository cannot look issues up, so the
/// code and the method pages say what holds instead.
fn issue_numbers(text: &str) -> Vec<String> {
    let word = concat!("iss", "ue");
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let lower = line.to_ascii_lowercase();
        let mut from = 0;
        while let Some(at) = lower[from..].find(word) {
            let start = from + at;
            from = start + word.len();
            let rest = lower[from..].strip_prefix('s').unwrap_or(&lower[from..]);
            let Some(rest) = rest.strip_prefix(' ') else {
                continue;
            };
            let rest = rest.strip_prefix('#').unwrap_or(rest);
            if rest.starts_with(|c: char| c.is_ascii_digit()) {
                out.push(format!("{}: {}", n + 1, line.trim()));
                break;
            }
        }
    }
    out
}

/// Words in a text that look like a commit hash: 7 to 40 hex digits with a letter and a digit
/// among them, standing alone (not part of a longer word, a number or a `0x` literal).
fn commit_hashes(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for word in text.split(|c: char| !c.is_ascii_alphanumeric() && c != '_') {
        let hex = (7..=40).contains(&word.len())
            && word
                .chars()
                .all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase());
        if hex
            && word.chars().any(|c| c.is_ascii_digit())
            && word.chars().any(|c| c.is_ascii_alphabetic())
        {
            out.push(word.to_string());
        }
    }
    out
}

/// Whether `name` (a tracked path) is code whose comments the scan reads.
fn is_code(name: &str) -> bool {
    let code_dir = [
        "src/",
        "shaders/",
        "tests/",
        "examples/",
        "scripts/",
        ".ci/",
    ]
    .iter()
    .any(|d| name.starts_with(d));
    code_dir || name == "build.rs"
}

#[test]
fn code_and_method_pages_name_no_issue_number_or_commit() {
    let root = root();
    let test = "code_and_method_pages_name_no_issue_number_or_commit";
    let Some(files) = tracked_files(&root, test) else {
        return;
    };
    let mut problems = Vec::new();
    for name in &files {
        let reference_doc = name == "README.md" || name.starts_with("docs/method/");
        if !(reference_doc || is_code(name)) {
            continue;
        }
        let Some(text) = text_of(&root, name) else {
            continue;
        };
        for hit in issue_numbers(&text) {
            problems.push(format!("{name}:{hit}"));
        }
        if reference_doc {
            for hash in commit_hashes(&text) {
                problems.push(format!("{name}: {hash} (a commit?)"));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "issue numbers or commit hashes where the text should say what holds (history goes to \
         docs/results/ under a date):\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_issue_and_commit_scans_catch_each_form() {
    let word = concat!("Iss", "ue");
    for bad in [
        format!("// see {word} 12 for why"),
        format!("//! {}s 13–14", word.to_lowercase()),
        format!("/// ({} #2)", word.to_lowercase()),
    ] {
        assert_eq!(issue_numbers(&bad).len(), 1, "{bad}");
    }
    for fine in [
        format!("// the {word}'s bound"),
        format!("// {word}: none"),
        "// 12 issues".to_string(),
    ] {
        assert!(issue_numbers(&fine).is_empty(), "{fine}");
    }
    assert_eq!(
        commit_hashes("measured at ee55f32 and 43e40ff4"),
        ["ee55f32", "43e40ff4"]
    );
    assert!(commit_hashes("0x1f2e3d4c, 1234567, deadbeefcafe, #ffcc00, a_1b2c3d4e").is_empty());
}
