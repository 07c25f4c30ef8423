//! WGSL sources with `// #include` lines expanded.
//!
//! WGSL has no include mechanism, so common code in `shaders/shared/` is pasted into each pass
//! shader by concatenation. A line whose text (after leading white space) is
//!
//! ```text
//! // #include shared/fullscreen_vs.wgsl
//! ```
//!
//! is replaced by the text of that file. Names are relative to `shaders/`, never to the including
//! file, and may not leave it (no `..`, no absolute paths). Included files may include others;
//! each file is pasted at most once per expansion (a second include of it becomes a comment), and a
//! file that includes itself, directly or through others, is an error. The same rules are
//! documented for shader authors in `shaders/README.md`.
//!
//! The expansion keeps a map from each line of the result back to its file and line
//! ([`Expanded::origin`]), so a naga error in the expanded text can be pointed at the real file.

use std::borrow::Cow;
use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// The directive that starts an include line (followed by white space and the name).
pub const INCLUDE_DIRECTIVE: &str = "// #include";

/// How a shader source could not be put together.
#[derive(Debug, thiserror::Error)]
pub enum ShaderSourceError {
    /// An `// #include` names a file that does not exist.
    #[error("{file}:{line}: included file `{include}` not found")]
    MissingInclude {
        /// The file that holds the include line.
        file: String,
        /// 1-based line of the include in `file`.
        line: u32,
        /// The name it asks for.
        include: String,
    },
    /// An `// #include` line without a usable name.
    #[error("{file}:{line}: bad include `{include}`: {reason}")]
    BadInclude {
        /// The file that holds the include line.
        file: String,
        /// 1-based line of the include in `file`.
        line: u32,
        /// The name as written.
        include: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A shader name that is not a plain relative path under `shaders/`.
    #[error("bad shader name `{name}`: {reason}")]
    BadName {
        /// The name as given.
        name: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A file includes itself, directly or through other files.
    #[error("include cycle: {}", chain.join(" -> "))]
    Cycle {
        /// The files on the cycle, starting and ending with the same one.
        chain: Vec<String>,
    },
    /// The top-level shader itself does not exist.
    #[error("shader `{name}` not found")]
    NotFound {
        /// The name asked for.
        name: String,
    },
    /// A shader file exists but could not be read.
    #[error("cannot read shader {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
}

/// An expanded shader: the source to hand to naga or wgpu, and where each of its lines came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expanded {
    /// The WGSL text with every include pasted in.
    pub source: String,
    files: Vec<String>,
    /// For each line of `source`: (index into `files`, 1-based line in that file).
    lines: Vec<(usize, u32)>,
}

impl Expanded {
    /// Every file pasted into it, the top-level one first.
    pub fn files(&self) -> &[String] {
        &self.files
    }

    /// The file and 1-based line that 1-based line `line` of [`Expanded::source`] came from.
    pub fn origin(&self, line: u32) -> Option<(&str, u32)> {
        let index = usize::try_from(line).ok()?.checked_sub(1)?;
        let &(file, file_line) = self.lines.get(index)?;
        Some((self.files[file].as_str(), file_line))
    }
}

impl fmt::Display for Expanded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.source)
    }
}

/// Expand the includes of `main` (a top-level shader's text), taking included files from
/// `lookup` (name relative to `shaders/` → text). Errors name `<main>` for lines of `main`; use
/// [`expand_named`] to give it a name.
pub fn expand(
    main: &str,
    lookup: impl Fn(&str) -> Option<&'static str>,
) -> Result<String, ShaderSourceError> {
    expand_named("<main>", main, lookup).map(|e| e.source)
}

/// [`expand`] with a name for `main`, keeping the line map.
pub fn expand_named(
    name: &str,
    main: &str,
    lookup: impl Fn(&str) -> Option<&'static str>,
) -> Result<Expanded, ShaderSourceError> {
    expand_with(name, main, &mut |n| Ok(lookup(n).map(Cow::Borrowed)))
}

/// Read `dir/name` (e.g. `dir` = `shaders/`, `name` = `passes/view.wgsl`) and expand its includes
/// from files under `dir`.
pub fn from_dir(dir: &Path, name: &str) -> Result<String, ShaderSourceError> {
    from_dir_mapped(dir, name).map(|e| e.source)
}

/// [`from_dir`], keeping the line map.
pub fn from_dir_mapped(dir: &Path, name: &str) -> Result<Expanded, ShaderSourceError> {
    if let Some(reason) = bad_name(name) {
        return Err(ShaderSourceError::BadName {
            name: name.into(),
            reason,
        });
    }
    let main = read_optional(&dir.join(name))?
        .ok_or_else(|| ShaderSourceError::NotFound { name: name.into() })?;
    expand_with(name, &main, &mut |n| {
        Ok(read_optional(&dir.join(n))?.map(Cow::Owned))
    })
}

// `EMBEDDED`: every `.wgsl` file under `shaders/` as (name relative to `shaders/`, text), so
// [`load`] needs no files at run time. `build.rs` writes the table from the file tree.
include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Every embedded shader file: (name relative to `shaders/`, text, not expanded).
pub fn embedded_files() -> impl Iterator<Item = (&'static str, &'static str)> {
    EMBEDDED.iter().copied()
}

/// The top-level shader `name` and its includes, every file's text from `lookup` (name → text).
pub fn expand_lookup(
    name: &str,
    lookup: impl Fn(&str) -> Option<String>,
) -> Result<Expanded, ShaderSourceError> {
    if let Some(reason) = bad_name(name) {
        return Err(ShaderSourceError::BadName {
            name: name.into(),
            reason,
        });
    }
    let main = lookup(name).ok_or_else(|| ShaderSourceError::NotFound { name: name.into() })?;
    expand_with(name, &main, &mut |n| Ok(lookup(n).map(Cow::Owned)))
}

/// The embedded text of `name` (relative to `shaders/`), not expanded.
pub fn embedded(name: &str) -> Option<&'static str> {
    EMBEDDED.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// The top-level shader `name` (e.g. `passes/view.wgsl`) from the embedded copies, includes
/// expanded.
pub fn load(name: &str) -> Result<String, ShaderSourceError> {
    load_mapped(name).map(|e| e.source)
}

/// [`load`], keeping the line map.
pub fn load_mapped(name: &str) -> Result<Expanded, ShaderSourceError> {
    let main = embedded(name).ok_or_else(|| ShaderSourceError::NotFound { name: name.into() })?;
    expand_named(name, main, embedded)
}

/// A user's shader `main` (its path as `name`), its includes taken from the embedded shaders
/// and from `generated` (`(name, text)`: code made for it at run time, which it need not
/// include: it is pasted at the end, after the file's own lines, so their numbers are kept).
pub fn expand_user(
    name: &str,
    main: &str,
    generated: (&str, &str),
) -> Result<Expanded, ShaderSourceError> {
    let (generated_name, generated_text) = generated;
    let mut text = String::with_capacity(main.len() + 64);
    text.push_str(main);
    if !text.ends_with('\n') && !text.is_empty() {
        text.push('\n');
    }
    text.push_str(INCLUDE_DIRECTIVE);
    text.push(' ');
    text.push_str(generated_name);
    text.push('\n');
    expand_with(name, &text, &mut |n| {
        Ok(if n == generated_name {
            Some(Cow::Owned(generated_text.to_owned()))
        } else {
            embedded(n).map(Cow::Borrowed)
        })
    })
}

type Lookup<'a, 's> = dyn FnMut(&str) -> Result<Option<Cow<'s, str>>, ShaderSourceError> + 'a;

fn expand_with(
    name: &str,
    main: &str,
    lookup: &mut Lookup<'_, '_>,
) -> Result<Expanded, ShaderSourceError> {
    let mut out = Expanded {
        source: String::with_capacity(main.len()),
        files: Vec::new(),
        lines: Vec::new(),
    };
    let mut stack = vec![name.to_owned()];
    paste(name, main, lookup, &mut stack, &mut out)?;
    Ok(out)
}

/// Append `text` (the file `name`, which is on top of `stack`) to `out`, pasting its includes.
fn paste(
    name: &str,
    text: &str,
    lookup: &mut Lookup<'_, '_>,
    stack: &mut Vec<String>,
    out: &mut Expanded,
) -> Result<(), ShaderSourceError> {
    let file_index = out.files.len();
    out.files.push(name.to_owned());
    for (i, line) in text.lines().enumerate() {
        let line_no = u32::try_from(i + 1).unwrap_or(u32::MAX);
        let Some(include) = include_name(line) else {
            push_line(out, line, file_index, line_no);
            continue;
        };
        if let Some(reason) = bad_name(include) {
            return Err(ShaderSourceError::BadInclude {
                file: name.into(),
                line: line_no,
                include: include.into(),
                reason,
            });
        }
        if let Some(start) = stack.iter().position(|f| f == include) {
            let mut chain = stack[start..].to_vec();
            chain.push(include.to_owned());
            return Err(ShaderSourceError::Cycle { chain });
        }
        if out.files.iter().any(|f| f == include) {
            // Already pasted earlier in this shader: pasting it again would redefine its items.
            push_line(
                out,
                &format!("// (already included: {include})"),
                file_index,
                line_no,
            );
            continue;
        }
        let Some(included) = lookup(include)? else {
            return Err(ShaderSourceError::MissingInclude {
                file: name.into(),
                line: line_no,
                include: include.into(),
            });
        };
        stack.push(include.to_owned());
        paste(include, &included, lookup, stack, out)?;
        stack.pop();
    }
    Ok(())
}

/// The name in `line` if it is an include line (`// #include` + white space + name, or
/// `// #include` alone, which is an error later).
fn include_name(line: &str) -> Option<&str> {
    let rest = line.trim_start().strip_prefix(INCLUDE_DIRECTIVE)?;
    (rest.is_empty() || rest.starts_with(char::is_whitespace)).then(|| rest.trim())
}

fn push_line(out: &mut Expanded, line: &str, file: usize, line_no: u32) {
    out.source.push_str(line);
    out.source.push('\n');
    out.lines.push((file, line_no));
}

/// Why `name` cannot be a shader name, if it cannot.
fn bad_name(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("no file name")
    } else if name.starts_with('/') || name.contains('\\') || name.contains(':') {
        Some("names are relative to shaders/ and use `/`")
    } else if name
        .split('/')
        .any(|part| part.is_empty() || part == "." || part == "..")
    {
        Some("names may not contain empty, `.` or `..` parts")
    } else if name.contains(char::is_whitespace) {
        Some("names may not contain white space")
    } else {
        None
    }
}

fn read_optional(path: &Path) -> Result<Option<String>, ShaderSourceError> {
    match std::fs::read_to_string(path) {
        Ok(text) => Ok(Some(text)),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(ShaderSourceError::Read {
            path: path.to_owned(),
            source,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files(name: &str) -> Option<&'static str> {
        match name {
            "shared/a.wgsl" => Some("fn a() -> f32 { return 1.0; }"),
            "shared/b.wgsl" => Some("// #include shared/a.wgsl\nfn b() -> f32 { return a(); }\n"),
            "shared/self.wgsl" => Some("// #include shared/loop.wgsl\n"),
            "shared/loop.wgsl" => Some("// #include shared/self.wgsl\n"),
            _ => None,
        }
    }

    #[test]
    fn pastes_includes_in_place() {
        let main = "// #include shared/a.wgsl\nfn main_fn() -> f32 { return a(); }";
        let out = expand(main, files).expect("expands");
        assert_eq!(
            out,
            "fn a() -> f32 { return 1.0; }\nfn main_fn() -> f32 { return a(); }\n"
        );
    }

    #[test]
    fn text_without_includes_is_unchanged_but_for_the_final_newline() {
        let main = "fn f() {}\n\n  // #includes are not this\n// #include_not\n";
        assert_eq!(expand(main, files).expect("expands"), main);
    }

    #[test]
    fn nested_and_repeated_includes_paste_each_file_once() {
        let main = "// #include shared/a.wgsl\n  // #include shared/b.wgsl  \nfn m() {}\n";
        let out = expand_named("m.wgsl", main, files).expect("expands");
        assert_eq!(out.source.matches("fn a()").count(), 1, "{}", out.source);
        assert!(out.source.contains("// (already included: shared/a.wgsl)"));
        // Line map: line 1 is a.wgsl:1, line 2 is b.wgsl's repeated include, 3 is b.wgsl:2,
        // 4 is m.wgsl:3.
        assert_eq!(out.origin(1), Some(("shared/a.wgsl", 1)));
        assert_eq!(out.origin(2), Some(("shared/b.wgsl", 1)));
        assert_eq!(out.origin(3), Some(("shared/b.wgsl", 2)));
        assert_eq!(out.origin(4), Some(("m.wgsl", 3)));
        assert_eq!(out.origin(5), None);
        assert_eq!(out.origin(0), None);
    }

    #[test]
    fn missing_include_names_file_and_line() {
        let main = "fn f() {}\n// #include shared/nope.wgsl\n";
        let err = expand_named("pass.wgsl", main, files).expect_err("must fail");
        assert!(matches!(
            err,
            ShaderSourceError::MissingInclude { line: 2, .. }
        ));
        assert_eq!(
            err.to_string(),
            "pass.wgsl:2: included file `shared/nope.wgsl` not found"
        );
        // A missing file inside an included file names that file.
        let err = expand("// #include shared/x.wgsl", |n| match n {
            "shared/x.wgsl" => Some("\n\n// #include shared/gone.wgsl"),
            _ => None,
        })
        .expect_err("must fail");
        assert_eq!(
            err.to_string(),
            "shared/x.wgsl:3: included file `shared/gone.wgsl` not found"
        );
    }

    #[test]
    fn cycles_are_errors() {
        let err = expand("// #include shared/self.wgsl", files).expect_err("cycle");
        assert_eq!(
            err.to_string(),
            "include cycle: shared/self.wgsl -> shared/loop.wgsl -> shared/self.wgsl"
        );
        let err = expand_named("p.wgsl", "// #include p.wgsl", |_| Some("")).expect_err("self");
        assert_eq!(err.to_string(), "include cycle: p.wgsl -> p.wgsl");
    }

    #[test]
    fn names_may_not_leave_the_shader_directory() {
        assert!(matches!(
            expand("// #include", |_| Some("")),
            Err(ShaderSourceError::BadInclude { .. })
        ));
        for bad in [
            "",
            "../secret.wgsl",
            "/etc/passwd",
            "shared//a.wgsl",
            "a b.wgsl",
        ] {
            let main = format!("// #include {bad}\n");
            let err = expand(&main, |_| Some("")).expect_err(bad);
            assert!(
                matches!(err, ShaderSourceError::BadInclude { line: 1, .. }),
                "{bad}: {err}"
            );
        }
    }

    #[test]
    fn from_dir_reads_files_and_reports_missing_ones() {
        let dir = std::env::temp_dir().join(format!("dbuffer-shader-src-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("shared")).expect("temp dir");
        std::fs::write(dir.join("shared/c.wgsl"), "const C: f32 = 2.0;\n").expect("write");
        std::fs::write(
            dir.join("p.wgsl"),
            "// #include shared/c.wgsl\nconst D = C;\n",
        )
        .expect("write");
        std::fs::write(dir.join("q.wgsl"), "\n// #include shared/none.wgsl\n").expect("write");
        let out = from_dir(&dir, "p.wgsl").expect("expands");
        assert_eq!(out, "const C: f32 = 2.0;\nconst D = C;\n");
        let err = from_dir(&dir, "q.wgsl").expect_err("missing include");
        assert_eq!(
            err.to_string(),
            "q.wgsl:2: included file `shared/none.wgsl` not found"
        );
        let err = from_dir(&dir, "r.wgsl").expect_err("missing shader");
        assert_eq!(err.to_string(), "shader `r.wgsl` not found");
        assert!(matches!(
            from_dir(&dir, "../p.wgsl"),
            Err(ShaderSourceError::BadName { .. })
        ));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_users_file_keeps_its_line_numbers_and_gets_the_generated_code() {
        let main = "// #include shared/frame_tag.wgsl\nfn f() {}\nfn g() {}";
        let out =
            expand_user("my.wgsl", main, ("generated/x.wgsl", "const K = 1;\n")).expect("expands");
        let g = out
            .source
            .lines()
            .position(|l| l == "fn g() {}")
            .expect("g")
            + 1;
        assert_eq!(out.origin(g as u32), Some(("my.wgsl", 3)));
        let k = out
            .source
            .lines()
            .position(|l| l == "const K = 1;")
            .expect("K")
            + 1;
        assert_eq!(out.origin(k as u32), Some(("generated/x.wgsl", 1)));
        assert!(out
            .source
            .contains(embedded("shared/frame_tag.wgsl").expect("embedded")));
    }

    #[test]
    fn embedded_shaders_load() {
        let src = load("passes/view.wgsl").expect("embedded shader expands");
        assert!(
            src.contains("fn vs_main") && src.contains("fn fs_main"),
            "{src}"
        );
        assert!(matches!(
            load("nope.wgsl"),
            Err(ShaderSourceError::NotFound { .. })
        ));
    }
}
