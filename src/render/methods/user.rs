//! A user's method from one WGSL file: `--method file:PATH.wgsl`.
//!
//! The file defines `method_visibility` as a built-in method's shader does, and is drawn by the
//! D-buffer's state ([`super::dbuffer::DBuffer::user`]): the same light pass, the same group 1
//! (`ShadowUniforms` and the centre's map at 0 and 1, `params` at 2, the channels `d_u` and
//! `d_p` at 3 and 4, the closing fans' corners at 5), and the user's knobs at 6. Those bindings
//! are declared for it in code generated here ([`GENERATED`], pasted after the file's own
//! lines, so the file's line numbers stay its own), with an accessor `knob_NAME()` per knob of
//! its header (`// knob: NAME MIN..MAX = DEFAULT`, up to [`MAX_USER_KNOBS`]).
//!
//! Everything is checked when the file is loaded, and again when the lab reloads it
//! ([`UserMethod::reload`], which keeps the last good version), before any GPU work: the file,
//! its knob header, that it defines `method_visibility`, that it binds nothing in groups 0 and 1
//! itself, and naga's parse and validation of the whole shader; each refusal is a
//! [`ShaderError`] that names the user's file and the line (and column) in it, with that line.

use std::path::Path;

use std::sync::{Mutex, RwLock};

use super::dbuffer::{
    DBuffer, UserValues, BVH_BINDING, BVH_COUNTS_BINDING, NEEDS, NEEDS_WITH_BVH, USER_BINDING,
    USER_KNOBS,
};
use super::{Cost, MakeState, Method, MethodSpec, MethodState};
use crate::render::shaders::{self, ShaderError};
use crate::render::GpuContext;
use crate::shader_source::{self, Expanded};

/// What `--method` takes before a user's file: `file:PATH.wgsl`.
pub const PREFIX: &str = "file:";

/// At most this many knobs in a file's header (one `vec4<f32>` of the uniforms).
pub const MAX_USER_KNOBS: usize = 4;

/// The name of the code generated for a user's file, as its errors name it.
pub const GENERATED: &str = "generated/user_method.wgsl";

/// A knob of a user's file: `// knob: NAME MIN..MAX = DEFAULT` on line `line`.
#[derive(Clone, Debug, PartialEq)]
pub struct UserKnob {
    pub name: String,
    pub min: f32,
    pub max: f32,
    pub default: f32,
    pub line: u32,
}

/// A user's method as loaded: its file, knobs and their values, and the expanded shader; the
/// knobs and the shader are those of the file's last good version ([`UserMethod::reload`]),
/// the values what the `--knob` settings or the lab's sliders set.
#[derive(Debug)]
pub struct UserMethod {
    /// The path as given on the command line.
    pub path: String,
    loaded: RwLock<Loaded>,
    /// The knobs' values in header order, unused slots 0 (`user_params.values` of the shader).
    values: UserValues,
    /// The version before the last good reload, and its knob values ([`UserMethod::revert`]).
    previous: RwLock<Option<(Loaded, [f32; MAX_USER_KNOBS])>>,
}

/// What a version of the file gives.
#[derive(Debug)]
struct Loaded {
    text: String,
    knobs: Vec<UserKnob>,
    /// The shader: the file, its includes and the generated code.
    source: String,
    /// The file calls `scene_occluded`: the scene's BVH is bound for it.
    bvh: bool,
}

impl UserMethod {
    /// The knobs of its header.
    pub fn knobs(&self) -> Vec<UserKnob> {
        self.loaded
            .read()
            .map(|l| l.knobs.clone())
            .unwrap_or_default()
    }

    /// The knobs' values, in header order.
    pub fn values(&self) -> [f32; MAX_USER_KNOBS] {
        self.values.get()
    }

    /// Set knob `name` to `value`, clamped to its range; false for a name it lacks.
    pub fn set_value(&self, name: &str, value: f32) -> bool {
        let knobs = self.knobs();
        let Some(i) = knobs.iter().position(|k| k.name == name) else {
            return false;
        };
        let k = &knobs[i];
        let v = if value.is_finite() {
            value.clamp(k.min, k.max)
        } else {
            k.default
        };
        self.values.set(i, v);
        true
    }

    /// The expanded shader of the file's last good version.
    pub fn source(&self) -> String {
        self.loaded
            .read()
            .map(|l| l.source.clone())
            .unwrap_or_default()
    }

    /// Whether the file's last good version calls `scene_occluded` (the scene's BVH is bound).
    pub fn traces_scene(&self) -> bool {
        self.loaded.read().is_ok_and(|l| l.bvh)
    }

    /// The name its pipelines are kept under and that a change of its file is noted as
    /// ([`crate::render::shaders`]): `file:PATH`.
    pub fn shader_key(&self) -> String {
        format!("{PREFIX}{}", self.path)
    }

    /// Read the file again: `Ok(false)` when its text is the same, `Ok(true)` when the new text
    /// checked through and is now the method's (a knob kept by name keeps its value, clamped to
    /// its new range; a new one starts at its default), else why not (the last good version
    /// stays).
    pub fn reload(&self) -> Result<bool, ShaderError> {
        let path = &self.path;
        let text = std::fs::read_to_string(path).map_err(|e| ShaderError {
            file: path.clone(),
            line: 0,
            column: 0,
            message: format!("cannot read the method file: {e}"),
            text: None,
        })?;
        if self.loaded.read().is_ok_and(|l| l.text == text) {
            return Ok(false);
        }
        let old = (self.knobs(), self.values());
        let loaded = checked(path, text)?;
        for (i, k) in loaded.knobs.iter().enumerate() {
            let v = old
                .0
                .iter()
                .position(|o| o.name == k.name)
                .map_or(k.default, |j| old.1[j].clamp(k.min, k.max));
            self.values.set(i, v);
        }
        for i in loaded.knobs.len()..MAX_USER_KNOBS {
            self.values.set(i, 0.0);
        }
        if let Ok(mut l) = self.loaded.write() {
            let before = std::mem::replace(&mut *l, loaded);
            if let Ok(mut p) = self.previous.write() {
                *p = Some((before, old.1));
            }
        }
        Ok(true)
    }

    /// Go back to the version before the last good reload, with its knob values (the lab, when
    /// the new version's trial frame failed: [`crate::render::offline::trial`]); false where
    /// there is none. The file itself is left as the user saved it.
    pub fn revert(&self) -> bool {
        let Some((before, values)) = self.previous.write().ok().and_then(|mut p| p.take()) else {
            return false;
        };
        for (i, v) in values.into_iter().enumerate() {
            self.values.set(i, v);
        }
        if let Ok(mut l) = self.loaded.write() {
            *l = before;
        }
        true
    }
}

/// Its state: the D-buffer's, drawing the file's shader with its knobs.
impl MakeState for UserMethod {
    fn state(&'static self, ctx: &GpuContext, spec: &'static MethodSpec) -> Box<dyn MethodState> {
        Box::new(DBuffer::user(
            ctx,
            spec,
            &self.source(),
            &self.values,
            self.traces_scene(),
        ))
    }
}

/// The user's methods loaded so far in this process, the latest last.
fn registry() -> &'static Mutex<Vec<(Method, &'static UserMethod)>> {
    static LOADED: Mutex<Vec<(Method, &'static UserMethod)>> = Mutex::new(Vec::new());
    &LOADED
}

/// The user's methods loaded so far, each name once (its latest load).
pub fn loaded() -> Vec<(Method, &'static UserMethod)> {
    let all = registry().lock().map(|r| r.clone()).unwrap_or_default();
    let mut out: Vec<(Method, &'static UserMethod)> = Vec::new();
    for (m, u) in all.into_iter().rev() {
        if !out.iter().any(|(o, _)| *o == m) {
            out.push((m, u));
        }
    }
    out.reverse();
    out
}

/// The user's method of `method`, if it is one.
pub fn of(method: Method) -> Option<&'static UserMethod> {
    method.is_user().then_some(())?;
    loaded()
        .into_iter()
        .find(|(m, _)| *m == method)
        .map(|(_, u)| u)
}

/// The loaded user's method named `name` (`user-STEM`).
pub fn by_name(name: &str) -> Option<Method> {
    loaded()
        .into_iter()
        .find(|(m, _)| m.name() == name)
        .map(|(m, _)| m)
}

/// `file:PATH` → `PATH`, for any other name `None`.
pub fn path_of(name: &str) -> Option<&str> {
    name.strip_prefix(PREFIX)
}

/// Load the user's method at `path` with the knob settings `settings` (`NAME=VALUE` as given
/// to `--knob`), checked through: the method, or one line saying why not.
///
/// Each call leaks one [`MethodSpec`] and its [`UserMethod`] (`Box::leak`): a [`Method`] is a
/// `&'static MethodSpec`, and a command line loads a file once for the whole run.
pub fn load(path: &str, settings: &[String]) -> Result<Method, String> {
    load_checked(path, settings).map_err(|e| match e {
        LoadError::Shader(e) => e.headline(),
        LoadError::Other(e) => e,
    })
}

/// Why a user's file is not a method: its shader (where, why, the offending line), or anything
/// else (the file unread, a `--knob` setting) in one line.
#[derive(Debug)]
pub enum LoadError {
    Shader(ShaderError),
    Other(String),
}

/// [`load`], a shader's error kept whole: the command line prints its offending line too.
pub fn load_checked(path: &str, settings: &[String]) -> Result<Method, LoadError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| LoadError::Other(format!("cannot read the method file {path}: {e}")))?;
    let loaded = checked(path, text).map_err(LoadError::Shader)?;
    let values = knob_values(path, &loaded.knobs, settings).map_err(LoadError::Other)?;
    let user: &'static UserMethod = Box::leak(Box::new(UserMethod {
        path: path.to_owned(),
        loaded: RwLock::new(loaded),
        values: UserValues::new(values),
        previous: RwLock::new(None),
    }));
    let name: &'static str = Box::leak(method_name(path).into_boxed_str());
    let shader: &'static str = Box::leak(user.shader_key().into_boxed_str());
    let about: &'static str = Box::leak(format!("a user's method from {path}").into_boxed_str());
    // The D-buffer's needs, knobs and lights: its state draws the file.
    let spec = MethodSpec::new(name, shader, |ctx| Box::new(DBuffer::new(ctx, false)))
        .adapter(if user.traces_scene() {
            NEEDS_WITH_BVH
        } else {
            NEEDS
        })
        .knobs(&USER_KNOBS)
        .lights(super::AREA_LIGHTS)
        .user(user)
        .about(about)
        .cost(Cost::DEFAULT)
        .fixed_quality("a user's method has no quality settings the study knows");
    let method = Method(Box::leak(Box::new(spec)));
    if let Ok(mut r) = registry().lock() {
        r.push((method, user));
    }
    Ok(method)
}

/// The file's `text` checked through: its knobs and expanded shader, or where and why not.
fn checked(path: &str, text: String) -> Result<Loaded, ShaderError> {
    let at_file = |message: String| {
        // The messages of the header and the expansion start with the place themselves.
        let rest = message
            .strip_prefix(path)
            .map(|r| r.trim_start_matches(':').trim_start())
            .unwrap_or(&message);
        let (line, message) = match rest.split_once(": ") {
            Some((l, m)) if l.parse::<u32>().is_ok() => (l.parse().unwrap_or(0), m.to_owned()),
            _ => (0, rest.to_owned()),
        };
        let text = (line > 0)
            .then(|| text.lines().nth(line as usize - 1).map(str::to_owned))
            .flatten();
        ShaderError {
            file: path.to_owned(),
            line,
            column: 0,
            message,
            text,
        }
    };
    let knobs = parse_header(path, &text).map_err(at_file)?;
    let bvh = uses_scene_bvh(&text);
    let generated = generated_code(&knobs, bvh);
    let expanded = shader_source::expand_user(path, &text, (GENERATED, &generated))
        .map_err(|e| at_file(format!("{path}: {e}")))?;
    check(path, &text, &expanded)?;
    Ok(Loaded {
        text,
        knobs,
        source: expanded.source,
        bvh,
    })
}

/// The name in reports and compare's files: `user-` and the file's stem, with anything but
/// letters, digits, `-` and `_` made `_`.
pub fn method_name(path: &str) -> String {
    let stem = Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let clean: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("user-{clean}")
}

/// The knobs of the file's header lines (`// knob: NAME MIN..MAX = DEFAULT`).
pub fn parse_header(path: &str, text: &str) -> Result<Vec<UserKnob>, String> {
    let mut knobs: Vec<UserKnob> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = u32::try_from(i + 1).unwrap_or(u32::MAX);
        // `// knob:`, with any white space after the slashes.
        let header = line.trim_start().strip_prefix("//").map(str::trim_start);
        let Some(rest) = header.and_then(|h| h.strip_prefix("knob:")) else {
            continue;
        };
        let bad = |why: &str| {
            format!(
                "{path}:{line_no}: bad knob header `{}`: {why} (expected `// knob: NAME MIN..MAX \
                 = DEFAULT`, e.g. `// knob: softness 0..1 = 0.5`)",
                line.trim()
            )
        };
        let knob = parse_knob(rest, line_no).map_err(|why| bad(&why))?;
        if knobs.iter().any(|k| k.name == knob.name) {
            return Err(bad(&format!("a second knob `{}`", knob.name)));
        }
        if knobs.len() == MAX_USER_KNOBS {
            return Err(bad(&format!("more than {MAX_USER_KNOBS} knobs")));
        }
        knobs.push(knob);
    }
    Ok(knobs)
}

fn parse_knob(rest: &str, line: u32) -> Result<UserKnob, String> {
    let (lhs, default) = rest.split_once('=').ok_or("no `= DEFAULT`")?;
    let mut words = lhs.split_whitespace();
    let name = words.next().ok_or("no name")?;
    let range = words.next().ok_or("no range MIN..MAX")?;
    if words.next().is_some() {
        return Err("more than a name and a range before `=`".into());
    }
    let mut chars = name.chars();
    let ident = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ident {
        return Err(format!(
            "the name `{name}` is not letters, digits and `_` starting with a letter"
        ));
    }
    let number = |s: &str, what: &str| {
        s.trim()
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("the {what} `{}` is not a number", s.trim()))
    };
    let (min, max) = range.split_once("..").ok_or("no range MIN..MAX")?;
    let (min, max) = (number(min, "minimum")?, number(max, "maximum")?);
    let default = number(default, "default")?;
    if min >= max {
        return Err(format!("the range {min}..{max} is empty"));
    }
    if !(min..=max).contains(&default) {
        return Err(format!("the default {default} is outside {min}..{max}"));
    }
    Ok(UserKnob {
        name: name.to_owned(),
        min,
        max,
        default,
        line,
    })
}

/// The knobs' values: their defaults, with `settings` (`NAME=VALUE`) applied, each checked.
fn knob_values(
    path: &str,
    knobs: &[UserKnob],
    settings: &[String],
) -> Result<[f32; MAX_USER_KNOBS], String> {
    let mut values = [0.0; MAX_USER_KNOBS];
    for (v, k) in values.iter_mut().zip(knobs) {
        *v = k.default;
    }
    for setting in settings {
        let (name, value) = setting
            .split_once('=')
            .ok_or_else(|| format!("--knob {setting}: expected NAME=VALUE"))?;
        let Some(i) = knobs.iter().position(|k| k.name == name.trim()) else {
            let names: Vec<&str> = knobs.iter().map(|k| k.name.as_str()).collect();
            return Err(format!(
                "--knob {setting}: {path} has no knob `{}` (its knobs: {})",
                name.trim(),
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            ));
        };
        let k = &knobs[i];
        let v = value
            .trim()
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("--knob {setting}: `{}` is not a number", value.trim()))?;
        if !(k.min..=k.max).contains(&v) {
            return Err(format!(
                "--knob {setting}: {} takes {} to {} ({path}:{}), found {v}",
                k.name, k.min, k.max, k.line
            ));
        }
        values[i] = v;
    }
    Ok(values)
}

/// The code pasted after the user's file: the includes every method of the D-buffer's state
/// has, its group 1 and the knobs' accessors.
pub fn generated_code(knobs: &[UserKnob], bvh: bool) -> String {
    let mut out = String::from(
        "// Generated for a user's method (render::methods::user): the D-buffer's inputs in \
         group 1 and the knobs.\n\
         // #include shared/camera.wgsl\n\
         // #include shared/shadow_lookup.wgsl\n\
         // #include shared/frame_tag.wgsl\n\
         // #include shared/light_sample.wgsl\n\
         struct DBufferParams {\n    horizon: u32,\n    corners: u32,\n    tag: u32,\n    _pad0: u32,\n};\n\
         @group(1) @binding(2) var<uniform> params: DBufferParams;\n\
         @group(1) @binding(3) var d_u: texture_2d<f32>;\n\
         @group(1) @binding(4) var d_p: texture_2d<f32>;\n\
         @group(1) @binding(5) var corners: texture_2d<f32>;\n\
         struct UserParams {\n    values: vec4<f32>,\n};\n",
    );
    out.push_str(&format!(
        "@group(1) @binding({USER_BINDING}) var<uniform> user_params: UserParams;\n"
    ));
    for (i, k) in knobs.iter().enumerate() {
        out.push_str(&format!(
            "fn knob_{}() -> f32 {{\n    return user_params.values[{i}];\n}}\n",
            k.name
        ));
    }
    if bvh {
        out.push_str(&format!(
            "// The scene's BVH (geometry::bvh::FlatBvh), traced by shared/bvh_trace.wgsl.\n\
             @group(1) @binding({BVH_BINDING}) var<storage, read> bvh: array<vec4<f32>>;\n\
             // (nodes, triangles, 0, 0)\n\
             @group(1) @binding({BVH_COUNTS_BINDING}) var<uniform> bvh_counts: vec4<u32>;\n\
             // #include shared/bvh_trace.wgsl\n\
             // Whether a triangle of the scene crosses the segment from `a` to `b` (its \
             ends left out by 1e-4 of its length, as the reference's rays leave theirs).\n\
             fn scene_occluded(a: vec3<f32>, b: vec3<f32>) -> bool {{\n\
             \x20   return bvh_any_hit(a, b - a, 1e-4, 1.0 - 1e-4, bvh_counts.x, bvh_counts.y).hit;\n\
             }}\n"
        ));
    }
    out
}

/// Whether the file calls `scene_occluded` outside comments: the scene's BVH is then bound for
/// it (a storage buffer the fragment stage reads, which the weakest adapters lack).
fn uses_scene_bvh(text: &str) -> bool {
    text.lines().any(|line| {
        line.split("//")
            .next()
            .unwrap_or_default()
            .contains("scene_occluded(")
    })
}

/// Whether `text` defines `fn method_visibility` outside comments.
fn defines_visibility(text: &str) -> bool {
    text.lines().any(|line| {
        let code = line.split("//").next().unwrap_or_default();
        let mut words = code.split(|c: char| c.is_whitespace() || c == '(');
        let mut previous = "";
        for word in words.by_ref() {
            if previous == "fn" && word == "method_visibility" {
                return true;
            }
            if !word.is_empty() {
                previous = word;
            }
        }
        false
    })
}

/// Refuse the file unless it defines `method_visibility`, binds nothing in groups 0 and 1 and
/// naga parses and validates the expanded shader.
fn check(path: &str, text: &str, expanded: &Expanded) -> Result<(), ShaderError> {
    if !defines_visibility(text) {
        return Err(ShaderError {
            file: path.to_owned(),
            line: 0,
            column: 0,
            message: "defines no `fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: \
                      vec2<f32>) -> Visibility`"
                .into(),
            text: None,
        });
    }
    // A line of a shared file is named as the user's file, then that file and its line.
    let path_of = |file: &str| {
        if file == path {
            path.to_owned()
        } else {
            format!("{path}: {file}")
        }
    };
    let module = shaders::parse(expanded, &path_of)?;
    let source = &expanded.source;
    for (handle, var) in module.global_variables.iter() {
        let Some(binding) = &var.binding else {
            continue;
        };
        let span = module.global_variables.get_span(handle);
        let Some((file, line)) = expanded.origin(span.location(source).line_number) else {
            continue;
        };
        if file == path && binding.group <= 1 {
            return Err(ShaderError {
                file: path.to_owned(),
                line,
                column: 0,
                message: format!(
                    "declares `{}` at @group({}) @binding({}); groups 0 and 1 are the camera \
                     pass's and the D-buffer's, whose bindings are declared for the file \
                     (params, d_u, d_p, corners, user_params): a user's method binds nothing \
                     itself",
                    var.name.as_deref().unwrap_or("?"),
                    binding.group,
                    binding.binding
                ),
                text: text.lines().nth(line as usize - 1).map(str::to_owned),
            });
        }
    }
    shaders::check_module(expanded, &module, &path_of)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knob_headers_parse_and_refuse_with_their_line() {
        let text = "// x\n// knob: softness 0..1 = 0.5\n//   knob: scale -2..4.5=1\n";
        let knobs = parse_header("a.wgsl", text).expect("parses");
        assert_eq!(knobs.len(), 2);
        assert_eq!(knobs[0].name, "softness");
        assert_eq!(
            (knobs[0].min, knobs[0].max, knobs[0].default),
            (0.0, 1.0, 0.5)
        );
        assert_eq!((knobs[1].min, knobs[1].max, knobs[1].line), (-2.0, 4.5, 3));
        for (bad, why) in [
            ("// knob: s 0..1", "no `= DEFAULT`"),
            ("// knob: 1s 0..1 = 0", "is not letters"),
            ("// knob: s 1..0 = 0", "is empty"),
            ("// knob: s 0..1 = 2", "outside"),
            ("// knob: s 0..x = 0", "maximum `x`"),
        ] {
            let err = parse_header("a.wgsl", &format!("\n{bad}\n")).expect_err(bad);
            assert!(err.starts_with("a.wgsl:2: bad knob header"), "{err}");
            assert!(err.contains(why), "{bad}: {err}");
        }
        let five = "// knob: a 0..1 = 0\n// knob: b 0..1 = 0\n// knob: c 0..1 = 0\n\
                    // knob: d 0..1 = 0\n// knob: e 0..1 = 0\n";
        let err = parse_header("a.wgsl", five).expect_err("five");
        assert!(
            err.starts_with("a.wgsl:5:") && err.contains("more than 4"),
            "{err}"
        );
    }

    #[test]
    fn knob_settings_are_checked_against_the_header() {
        let knobs = parse_header("a.wgsl", "// knob: softness 0..1 = 0.5\n").expect("parses");
        let v = knob_values("a.wgsl", &knobs, &["softness=0.25".into()]).expect("in range");
        assert_eq!(v, [0.25, 0.0, 0.0, 0.0]);
        let err = knob_values("a.wgsl", &knobs, &["softness=2".into()]).expect_err("range");
        assert_eq!(
            err,
            "--knob softness=2: softness takes 0 to 1 (a.wgsl:1), found 2"
        );
        let err = knob_values("a.wgsl", &knobs, &["hardness=0".into()]).expect_err("name");
        assert!(
            err.contains("has no knob `hardness` (its knobs: softness)"),
            "{err}"
        );
    }

    #[test]
    fn names_are_file_names() {
        assert_eq!(
            method_name("examples/methods/dbuffer_vt.wgsl"),
            "user-dbuffer_vt"
        );
        assert_eq!(method_name("a b/c d.e.wgsl"), "user-c_d_e");
    }

    #[test]
    fn visibility_is_found_outside_comments() {
        assert!(defines_visibility("fn method_visibility(x: vec3<f32>)"));
        assert!(defines_visibility("  fn  method_visibility ("));
        assert!(!defines_visibility("// fn method_visibility("));
        assert!(!defines_visibility("fn method_visibility_2("));
    }
}
