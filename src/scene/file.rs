//! The scene file (docs/guide/scene-format.md): TOML, +Y up, right-handed, metres, angles in degrees.
//!
//! ```toml
//! [camera]                 # optional: without it the view is framed on the casters and the light
//! eye = [0.0, 3.0, 6.0]
//! target = [0.0, 0.5, 0.0]
//! fov_y_deg = 45.0
//!
//! [light]                  # one-sided disk, emits toward `normal`
//! center = [0.0, 4.0, 0.0]
//! normal = [0.0, -1.0, 0.0]
//! radius = 0.5
//! intensity = 1.0          # optional, default 1
//!
//! # or a linear light (docs/guide/scene-format.md), emitting all around the segment from `a` to `b`:
//! # [light]
//! # kind = "line"          # optional, default "disk"
//! # a = [-1.0, 4.0, 0.0]
//! # b = [1.0, 4.0, 0.0]    # at least MIN_LINE_LENGTH (1e-4 m) from `a`
//! # intensity = 1.0
//!
//! [[object]]
//! name = "ground"          # optional, default: the mesh name
//! mesh = "plane"           # a built-in shape name (see `shapes`), or a path to .obj/.gltf/.glb relative to this file
//! translate = [0.0, 0.0, 0.0]    # optional, default 0
//! rotate_deg = [0.0, 0.0, 0.0]   # optional, XYZ Euler, default 0
//! scale = 10.0             # optional, a number or [x, y, z], default 1
//! casts_shadow = false     # optional, default true
//! ```
//!
//! **Transform convention.** An object's mesh is placed in the world by
//! `T(translate) · R · S(scale)`: scaled first, then rotated, then translated. `R` is
//! `glam::Quat::from_euler(EulerRot::XYZ, x, y, z)` = `Rx · Ry · Rz` (intrinsic X, then Y, then
//! Z; equivalently, applied to a point: about the world Z axis first, then world Y, then world
//! X). Angles are in degrees, positive counter-clockwise looking down the axis toward the origin.
//!
//! The light's normal need not be unit length; it is normalised when the scene is built.

use super::obj::Others;
use super::{
    shapes, Camera, DiskLight, Light, LightKind, LineLight, Mesh, Object, Scene, SceneError,
    MIN_LINE_LENGTH,
};
use crate::budget::{MAX_SCENE_FILE_BYTES, MAX_SCENE_TRIANGLES, MAX_SCENE_VERTICES};
use crate::fsutil::ByteBudget;
use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::{de, Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::path::Path;

/// The byte budget of one scene file.
pub const SCENE_FILE_BUDGET: ByteBudget = ByteBudget {
    limit: MAX_SCENE_FILE_BYTES,
    name: "MAX_SCENE_FILE_BYTES",
    what: "a scene file",
};

/// A scene file's bytes as text, without a leading UTF-8 byte-order mark. Bytes that are not
/// UTF-8 are an error naming the first one's byte offset, line and column (never the text).
pub fn decode_utf8<'a>(bytes: &'a [u8], label: &str) -> Result<&'a str, SceneError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let offset = e.valid_up_to();
        let before = &bytes[..offset];
        let line_start = before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        // The part of the line before the bad byte is valid UTF-8: count its characters.
        let column = 1 + String::from_utf8_lossy(&before[line_start..])
            .chars()
            .count();
        SceneError::NotUtf8 {
            file: label.to_string(),
            line: 1 + before.iter().filter(|&&b| b == b'\n').count(),
            column,
            offset,
        }
    })
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        1 + before.matches('\n').count(),
        1 + before[line_start..].chars().count(),
    )
}

/// Words toml and serde quote in their messages that come from our schema or the TOML
/// grammar, not from the file: they are kept; anything else quoted is left out of the message.
const SCHEMA_WORDS: &[&str] = &[
    "camera",
    "light",
    "object",
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
    "kind",
    "disk",
    "line",
    "a",
    "b",
    "true",
    "false",
    "inf",
    "nan",
];

/// toml's message without anything it quotes from the file, one line ("; " between lines).
///
/// serde and toml quote the file in a few known shapes: `unknown field `X``, `duplicate key
/// `X``, `invalid type: string "X"` (a Debug string), `character `X``. Those parts are
/// dropped by shape; what follows the last ", expected " is the schema's or the grammar's
/// (field lists, types). Elsewhere a `` `word` `` or `"word"` is kept only if it is a schema
/// key path or TOML punctuation, and anything after a quote left unmatched is cut.
fn sanitize_toml_message(message: &str) -> String {
    let lines: Vec<String> = message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(sanitize_toml_line)
        .collect();
    let mut text = lines.join("; ");
    if text.len() > 400 {
        let mut cut = 400;
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        text.truncate(cut);
        text.push('…');
    }
    text
}

fn sanitize_toml_line(line: &str) -> String {
    // Without the input, toml ends with the key path: `in `light.radius``.
    if let Some(path) = line.strip_prefix("in `").and_then(|r| r.strip_suffix('`')) {
        return if is_schema_path(path) {
            line.to_string()
        } else {
            "in a key of the file".into()
        };
    }
    for prefix in ["duplicate key", "unknown field", "unknown variant"] {
        if line.starts_with(prefix) {
            // The quoted name comes first; the list of what is expected (ours) after it.
            let tail = line.rfind(", expected").map_or("", |i| &line[i..]);
            return format!("{prefix}{}", strip_quoted(tail));
        }
    }
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = line.strip_prefix(prefix) {
            // `string "..."`, `integer `5``, `character `x``...: the kind, not the value.
            let kind: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphabetic() || *c == ' ')
                .collect();
            let kind = match kind.trim() {
                "" => "value",
                k => k,
            };
            let tail = rest.rfind(", expected").map_or("", |i| &rest[i..]);
            return format!("{prefix}{kind}{}", strip_quoted(tail));
        }
    }
    strip_quoted(line)
}

/// `text` without its quoted words, but for schema key paths and TOML punctuation; after a
/// quote left unmatched nothing is kept. Double-quoted words may hold `\"` escapes.
fn strip_quoted(text: &str) -> String {
    let keep = |quoted: &str| {
        is_schema_path(quoted)
            || (!quoted.is_empty()
                && quoted.len() <= 3
                && quoted.chars().all(|c| c.is_ascii_punctuation() || c == ' '))
            || (quoted.len() == 2 && quoted.starts_with('\\'))
    };
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find(['`', '"']) {
        let quote = rest.as_bytes()[open];
        let after = &rest[open + 1..];
        // The closing quote: the next one, skipping `\x` escapes inside double quotes.
        let mut close = None;
        let mut escaped = false;
        for (k, b) in after.bytes().enumerate() {
            if escaped {
                escaped = false;
            } else if b == b'\\' && quote == b'"' {
                escaped = true;
            } else if b == quote {
                close = Some(k);
                break;
            }
        }
        let Some(len) = close else {
            out.push_str(rest[..open].trim_end_matches(' '));
            return out;
        };
        let quoted = &after[..len];
        if keep(quoted) {
            out.push_str(&rest[..open + 1 + len + 1]);
        } else {
            out.push_str(rest[..open].trim_end_matches(' '));
        }
        rest = &after[len + 1..];
    }
    out.push_str(rest);
    out
}

/// A key path such as `object.1.scale` of schema words and indices.
fn is_schema_path(path: &str) -> bool {
    path.split('.').all(|k| {
        SCHEMA_WORDS.contains(&k) || (!k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
    })
}

/// A parsed scene file, before meshes are loaded. Numbers are kept as `f64` so a file written
/// back by [`SceneFile::to_toml`] reads `0.1`, not `0.10000000149011612`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[camera]` is optional: without it the scene is seen by [`super::framed_camera`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraSpec>,
    pub light: LightSpec,
    #[serde(rename = "object", default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectSpec>,
}

/// `[camera]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub fov_y_deg: f64,
}

/// `[light]`: a disk (`center`, `normal`, `radius`) or, with `kind = "line"`, a segment (`a`,
/// `b`). One flat table rather than a tagged enum, so `kind` can default to a disk (old files
/// load unchanged), unknown keys stay errors, and the keys of the other kind get the house's
/// messages ([`SceneFile::validate`]). A disk writes back exactly the keys it always had.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<LightKind>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<[f64; 3]>,
    #[serde(default = "one")]
    pub intensity: f64,
}

impl LightSpec {
    /// A disk light's keys.
    pub fn disk(center: [f64; 3], normal: [f64; 3], radius: f64) -> LightSpec {
        LightSpec {
            kind: None,
            center: Some(center),
            normal: Some(normal),
            radius: Some(radius),
            a: None,
            b: None,
            intensity: 1.0,
        }
    }

    /// A line light's keys.
    pub fn line(a: [f64; 3], b: [f64; 3]) -> LightSpec {
        LightSpec {
            kind: Some(LightKind::Line),
            center: None,
            normal: None,
            radius: None,
            a: Some(a),
            b: Some(b),
            intensity: 1.0,
        }
    }

    pub fn kind(&self) -> LightKind {
        self.kind.unwrap_or_default()
    }

    /// The light, in `f32`, for a spec that [`SceneFile::validate`] accepted; missing keys of
    /// an unchecked spec read as zero (a zero normal becomes straight down).
    pub fn light(&self) -> Light {
        let v = |a: Option<[f64; 3]>| a.map_or(Vec3::ZERO, v3);
        match self.kind() {
            LightKind::Disk => Light::Disk(DiskLight {
                center: v(self.center),
                normal: v(self.normal).try_normalize().unwrap_or(Vec3::NEG_Y),
                radius: self.radius.unwrap_or(0.0) as f32,
                intensity: self.intensity as f32,
            }),
            LightKind::Line => Light::Line(LineLight {
                a: v(self.a),
                b: v(self.b),
                intensity: self.intensity as f32,
            }),
        }
    }

    /// The disk's centre or the segment's midpoint, as written in the file.
    pub fn center_f64(&self) -> [f64; 3] {
        match (self.kind(), self.center, self.a, self.b) {
            (LightKind::Disk, Some(c), _, _) => c,
            (LightKind::Line, _, Some(a), Some(b)) => std::array::from_fn(|i| 0.5 * (a[i] + b[i])),
            _ => [0.0; 3],
        }
    }

    /// The same place as a light of `kind` ([`Light::converted`]).
    pub fn converted(&self, kind: LightKind) -> LightSpec {
        if kind == self.kind() {
            return self.clone();
        }
        let f = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        let mut out = match self.light().converted(kind) {
            Light::Disk(d) => LightSpec::disk(f(d.center), f(d.normal), f64::from(d.radius)),
            Light::Line(l) => LightSpec::line(f(l.a), f(l.b)),
        };
        out.intensity = self.intensity;
        out
    }

    /// The light moved so its centre (a line's midpoint) is at `to`; a line keeps its
    /// direction and length.
    pub fn set_center(&mut self, to: [f64; 3]) {
        match self.kind() {
            LightKind::Disk => self.center = Some(to),
            LightKind::Line => {
                let c = self.center_f64();
                let shift =
                    |p: Option<[f64; 3]>| p.map(|p| std::array::from_fn(|i| p[i] + to[i] - c[i]));
                self.a = shift(self.a);
                self.b = shift(self.b);
            }
        }
    }
}

/// One `[[object]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub mesh: String,
    #[serde(default)]
    pub translate: [f64; 3],
    #[serde(default)]
    pub rotate_deg: [f64; 3],
    #[serde(default)]
    pub scale: Scale,
    #[serde(default = "yes")]
    pub casts_shadow: bool,
}

/// `scale`: one number for all axes, or `[x, y, z]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

impl Scale {
    /// The three per-axis factors.
    pub fn xyz(&self) -> [f64; 3] {
        match *self {
            Scale::Uniform(s) => [s; 3],
            Scale::PerAxis(v) => v,
        }
    }
}

impl Serialize for Scale {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Scale::Uniform(x) => s.serialize_f64(*x),
            Scale::PerAxis(v) => v.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> de::Visitor<'de> for V {
            type Value = Scale;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of three numbers [x, y, z]")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<Scale, E> {
                Ok(Scale::Uniform(x))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<Scale, E> {
                Ok(Scale::Uniform(x as f64))
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<Scale, E> {
                Ok(Scale::Uniform(x as f64))
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Scale, A::Error> {
                let mut v = [0.0; 3];
                for (i, slot) in v.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<f64>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Scale::PerAxis(v))
            }
        }
        d.deserialize_any(V)
    }
}

fn one() -> f64 {
    1.0
}

fn yes() -> bool {
    true
}

fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

fn show(a: &[f64]) -> String {
    let parts: Vec<String> = a.iter().map(|x| format!("{x}")).collect();
    if parts.len() == 1 {
        parts[0].clone()
    } else {
        format!("[{}]", parts.join(", "))
    }
}

impl CameraSpec {
    /// The camera, in `f32`.
    pub fn camera(&self) -> Camera {
        Camera {
            eye: v3(self.eye),
            target: v3(self.target),
            fov_y_deg: self.fov_y_deg as f32,
        }
    }
}

impl ObjectSpec {
    /// The object's name: `name`, or else the mesh name.
    pub fn display_name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.mesh)
    }

    /// The object-to-world transform `T · R · S` (see the module documentation).
    pub fn transform(&self) -> Affine3A {
        let r = self.rotate_deg;
        let rotation = Quat::from_euler(
            EulerRot::XYZ,
            (r[0] as f32).to_radians(),
            (r[1] as f32).to_radians(),
            (r[2] as f32).to_radians(),
        );
        Affine3A::from_scale_rotation_translation(
            v3(self.scale.xyz()),
            rotation,
            v3(self.translate),
        )
    }
}

impl SceneFile {
    /// Parses and validates scene TOML; `label` names the file in errors.
    /// A leading byte-order mark is skipped. Errors never quote the text: toml's message is
    /// kept without what it quotes from the file, with the line and column.
    pub fn parse(text: &str, label: &str) -> Result<SceneFile, SceneError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let file: SceneFile = toml::from_str(text).map_err(|mut e| {
            let (line, column) = e.span().map_or((1, 1), |s| line_column(text, s.start));
            // Without the input, toml's message names the key path instead of quoting the line.
            e.set_input(None);
            SceneError::Toml {
                file: label.to_string(),
                line,
                column,
                message: sanitize_toml_message(&e.to_string()),
            }
        })?;
        file.validate(label)?;
        Ok(file)
    }

    /// Checks every value that TOML accepts but a scene cannot use. `parse` calls it; call it
    /// again after editing a `SceneFile` in code.
    pub fn validate(&self, label: &str) -> Result<(), SceneError> {
        let invalid = |key: &str, expected: &str, found: String| SceneError::Invalid {
            file: label.to_string(),
            key: key.to_string(),
            expected: expected.to_string(),
            found,
        };
        let finite = |key: &str, v: &[f64]| {
            // Meshes and the GPU use f32: a number past f32::MAX is infinite there.
            if v.iter().all(|&x| x.is_finite() && (x as f32).is_finite()) {
                Ok(())
            } else {
                Err(invalid(
                    key,
                    "finite numbers (no nan or inf; magnitude below 3.4e38)",
                    show(v),
                ))
            }
        };

        if let Some(c) = &self.camera {
            finite("camera.eye", &c.eye)?;
            finite("camera.target", &c.target)?;
            finite("camera.fov_y_deg", &[c.fov_y_deg])?;
            if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
                return Err(invalid(
                    "camera.fov_y_deg",
                    "a vertical field of view in degrees strictly between 0 and 180",
                    show(&[c.fov_y_deg]),
                ));
            }
            if v3(c.eye) == v3(c.target) {
                return Err(invalid(
                    "camera.target",
                    "a point different from camera.eye",
                    show(&c.target),
                ));
            }
        }

        let l = &self.light;
        // The keys of the other kind are mistakes, not options: say which kind reads them.
        let foreign = |key: &str, found: String, kind: LightKind| {
            let expected = match kind {
                LightKind::Line => {
                    "no such key for a line light (kind = \"line\" reads a, b and intensity)"
                }
                LightKind::Disk => {
                    "no such key for a disk light (a disk reads center, normal, radius and \
                     intensity; end points a and b need kind = \"line\")"
                }
            };
            invalid(key, expected, found)
        };
        let missing = |key: &str, expected: &str| invalid(key, expected, "nothing".into());
        match l.kind() {
            LightKind::Disk => {
                for (key, value) in [("light.a", l.a), ("light.b", l.b)] {
                    if let Some(v) = value {
                        return Err(foreign(key, show(&v), LightKind::Disk));
                    }
                }
                let center = l
                    .center
                    .ok_or_else(|| missing("light.center", "the disk's centre [x, y, z]"))?;
                let normal = l.normal.ok_or_else(|| {
                    missing(
                        "light.normal",
                        "the disk's normal [x, y, z] (it emits toward it)",
                    )
                })?;
                let radius = l
                    .radius
                    .ok_or_else(|| missing("light.radius", "the disk's radius"))?;
                finite("light.center", &center)?;
                finite("light.normal", &normal)?;
                finite("light.radius", &[radius])?;
                let n = v3(normal);
                if n.length() <= 1e-6 || n.try_normalize().is_none() {
                    return Err(invalid(
                        "light.normal",
                        "a non-zero direction (it is normalised)",
                        show(&normal),
                    ));
                }
                if radius <= 0.0 {
                    return Err(invalid(
                        "light.radius",
                        "a positive disk radius",
                        show(&[radius]),
                    ));
                }
            }
            LightKind::Line => {
                for (key, value) in [("light.center", l.center), ("light.normal", l.normal)] {
                    if let Some(v) = value {
                        return Err(foreign(key, show(&v), LightKind::Line));
                    }
                }
                if let Some(r) = l.radius {
                    return Err(foreign("light.radius", show(&[r]), LightKind::Line));
                }
                let a = l.a.ok_or_else(|| {
                    missing("light.a", "the first end point [x, y, z] of the line light")
                })?;
                let b = l.b.ok_or_else(|| {
                    missing(
                        "light.b",
                        "the second end point [x, y, z] of the line light",
                    )
                })?;
                finite("light.a", &a)?;
                finite("light.b", &b)?;
                // In f32, as the light is used: a and b must stay apart there too.
                if (v3(b) - v3(a)).length() < MIN_LINE_LENGTH as f32 {
                    return Err(invalid(
                        "light.b",
                        &format!(
                            "an end point at least {MIN_LINE_LENGTH} m from light.a (the line \
                             light has zero length)"
                        ),
                        show(&b),
                    ));
                }
            }
        }
        finite("light.intensity", &[l.intensity])?;
        if l.intensity < 0.0 {
            return Err(invalid(
                "light.intensity",
                "a non-negative number",
                show(&[l.intensity]),
            ));
        }

        let mut shapes_use = Others::default();
        for (i, o) in self.objects.iter().enumerate() {
            let key = |k: &str| format!("object[{i}].{k}");
            if o.mesh.trim().is_empty() {
                return Err(invalid(
                    &key("mesh"),
                    "a built-in shape name or a path to an .obj, .gltf or .glb file",
                    "an empty string".into(),
                ));
            }
            if shapes::is_shape_name(&o.mesh) {
                // Parameters and size are known before anything is built.
                let shape = shapes::Shape::parse(&o.mesh)
                    .map_err(|e| shape_error(e, label, &key("mesh")))?;
                check_budget(label, &key("mesh"), &o.mesh, &shape, shapes_use)?;
                shapes_use.add(&shape);
            }
            finite(&key("translate"), &o.translate)?;
            finite(&key("rotate_deg"), &o.rotate_deg)?;
            let s = o.scale.xyz();
            finite(&key("scale"), &s)?;
            // f32 is what the mesh gets: a scale that underflows to 0 there is zero too.
            if s.iter().any(|&x| x as f32 == 0.0) {
                return Err(invalid(
                    &key("scale"),
                    "non-zero scale factors (negative ones mirror)",
                    match o.scale {
                        Scale::Uniform(x) => show(&[x]),
                        Scale::PerAxis(v) => show(&v),
                    },
                ));
            }
        }
        Ok(())
    }

    /// Loads the meshes (relative paths are resolved against `base_dir`) and places every
    /// object in world space; without `[camera]` the view is [`super::framed_camera`]'s. `label` names the scene file in errors; the scene is named after
    /// `label`'s file stem.
    pub fn build(&self, base_dir: &Path, label: &str) -> Result<Scene, SceneError> {
        let name = Path::new(label)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| label.to_string());
        self.build_named(base_dir, label, &name)
    }

    /// Like [`SceneFile::build`] with an explicit scene name.
    pub fn build_named(
        &self,
        base_dir: &Path,
        label: &str,
        name: &str,
    ) -> Result<Scene, SceneError> {
        let meshes = self.load_meshes(base_dir, label)?;
        let l = &self.light;
        let objects: Vec<Object> = self
            .objects
            .iter()
            .zip(meshes)
            .map(|(o, mut mesh)| {
                mesh.transform_in_place(&o.transform());
                Object {
                    // Shown in warnings and lists: one line, not too long.
                    name: super::shown(o.display_name()),
                    mesh,
                    casts_shadow: o.casts_shadow,
                }
            })
            .collect();
        let light = l.light();
        let camera = match &self.camera {
            Some(c) => c.camera(),
            None => super::framed_camera(&light, &objects),
        };
        Ok(Scene {
            name: name.to_string(),
            camera,
            light,
            objects,
        })
    }

    /// Every object's mesh in its own space (before its transform), within the scene's triangle
    /// budget (`MAX_SCENE_TRIANGLES`): the built-in shapes are counted from their parameters
    /// before any is built, the `.obj` files while they are read, each with what the shapes
    /// and the files before it leave. Validates the file first.
    pub fn load_meshes(&self, base_dir: &Path, label: &str) -> Result<Vec<Mesh>, SceneError> {
        self.validate(label)?;
        // What the shapes use (validated above), then each file in turn.
        let mut used = Others::default();
        for o in &self.objects {
            if let Ok(shape) = shapes::Shape::parse(&o.mesh) {
                used.add(&shape);
            }
        }
        let mut meshes = Vec::with_capacity(self.objects.len());
        for (i, o) in self.objects.iter().enumerate() {
            let key = format!("object[{i}].mesh");
            let mesh = if shapes::is_shape_name(&o.mesh) {
                resolve_mesh(&o.mesh, base_dir, label, &key)?
            } else {
                let mesh = resolve_mesh_within(&o.mesh, base_dir, label, &key, used)?;
                used.triangles += mesh.triangles.len() as u64;
                used.vertices += mesh.positions.len() as u64;
                mesh
            };
            meshes.push(mesh);
        }
        Ok(meshes)
    }

    /// The scene as TOML in the format [`SceneFile::parse`] reads.
    pub fn to_toml(&self) -> String {
        // Serialising plain structs of numbers, strings and arrays cannot fail; fall back to a
        // comment rather than panic if it ever does.
        toml::to_string(self).unwrap_or_else(|e| format!("# could not serialise the scene: {e}\n"))
    }
}

/// A mesh name from a scene file: a built-in shape, else a path to an `.obj`, `.gltf` or `.glb`
/// file relative to `base_dir` (a glTF model gives every triangle of its scene, placed by its
/// node transforms; its lights are not used here). `key` (e.g. `object[2].mesh`) names it in
/// errors. The mesh alone may have the scene's whole triangle budget;
/// [`SceneFile::load_meshes`] checks the sum over a scene.
pub fn resolve_mesh(
    mesh: &str,
    base_dir: &Path,
    label: &str,
    key: &str,
) -> Result<Mesh, SceneError> {
    resolve_mesh_within(mesh, base_dir, label, key, Others::default())
}

/// Like [`resolve_mesh`] in a scene whose other objects have `others` triangles: an `.obj` may
/// have what is left of `MAX_SCENE_TRIANGLES` (counted while it is read).
pub fn resolve_mesh_within(
    mesh_name: &str,
    base_dir: &Path,
    label: &str,
    key: &str,
    others: Others,
) -> Result<Mesh, SceneError> {
    let mesh = mesh_name;
    if shapes::is_shape_name(mesh) {
        let shape = shapes::Shape::parse(mesh).map_err(|e| shape_error(e, label, key))?;
        check_budget(label, key, mesh, &shape, others)?;
        return shape.build().map_err(|e| shape_error(e, label, key));
    }
    let path = base_dir.join(mesh);
    let in_file = |error| SceneError::Mesh {
        file: label.to_string(),
        key: key.to_string(),
        error: Box::new(error),
    };
    if super::gltf::is_gltf_path(&path) {
        let mesh = super::gltf::load_gltf(&path)
            .map(|m| m.mesh)
            .map_err(in_file)?;
        // The model's own budget bounds its reading; the scene's counts what the others use.
        check_counts(
            label,
            key,
            mesh_name,
            mesh.triangles.len() as u64,
            mesh.positions.len() as u64,
            others,
        )?;
        return Ok(mesh);
    }
    let is_obj = Path::new(mesh)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    // `metadata` follows symlinks: only a regular file without the .obj extension is tried as
    // one (a directory or a device never is; an .obj that is not a file is refused by the
    // loader, before reading).
    if is_obj || std::fs::metadata(&path).is_ok_and(|m| m.is_file()) {
        return super::obj::load_obj_within(&path, others).map_err(in_file);
    }
    Err(unknown_mesh(label, key, mesh))
}

fn shape_error(e: shapes::ShapeError, label: &str, key: &str) -> SceneError {
    match e {
        shapes::ShapeError::Unknown(name) => unknown_mesh(label, key, &name),
        shapes::ShapeError::BadParams(expected) => SceneError::ShapeParams {
            file: label.to_string(),
            key: key.to_string(),
            expected,
        },
    }
}

/// Whether shape `mesh` fits in what `others` leave of the scene's budget; the error names
/// the object, the shape's size, the total and the budget.
fn check_budget(
    label: &str,
    key: &str,
    mesh: &str,
    shape: &shapes::Shape,
    others: Others,
) -> Result<(), SceneError> {
    check_counts(
        label,
        key,
        mesh,
        shape.triangles(),
        shape.vertices(),
        others,
    )
}

/// A mesh of `triangles` and `vertices` in a scene whose other objects use `others`, against the
/// scene's budget.
fn check_counts(
    label: &str,
    key: &str,
    mesh: &str,
    triangles: u64,
    vertices: u64,
    others: Others,
) -> Result<(), SceneError> {
    let limits = [
        (
            triangles,
            others.triangles,
            MAX_SCENE_TRIANGLES,
            "triangles",
            "MAX_SCENE_TRIANGLES",
        ),
        (
            vertices,
            others.vertices,
            MAX_SCENE_VERTICES,
            "vertices",
            "MAX_SCENE_VERTICES",
        ),
    ];
    for (count, before, limit, what, name) in limits {
        let total = before + count;
        if total > limit {
            let mesh = super::shown(mesh);
            let found = if before == 0 {
                format!("`{mesh}` has {count} {what}")
            } else {
                format!("`{mesh}` has {count} {what}, {total} with the scene's other objects")
            };
            return Err(SceneError::OverBudget {
                file: label.to_string(),
                key: key.to_string(),
                found,
                limit: format!("{limit} {what} per scene"),
                name,
            });
        }
    }
    Ok(())
}

fn unknown_mesh(label: &str, key: &str, name: &str) -> SceneError {
    SceneError::UnknownMesh {
        file: label.to_string(),
        key: key.to_string(),
        name: super::truncated(name),
        known: shapes::NAMES.join(", "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
[camera]
eye = [0, 3, 6]
target = [0, 0.5, 0]
fov_y_deg = 45

[light]
center = [0, 4, 0]
normal = [0, -2, 0]
radius = 0.5

[[object]]
mesh = "sphere:8x4"
scale = [1, 2, 3]
"#;

    #[test]
    fn defaults() {
        let f = SceneFile::parse(MINIMAL, "m.toml").unwrap();
        assert_eq!(f.light.intensity, 1.0);
        let o = &f.objects[0];
        assert!(o.casts_shadow);
        assert_eq!(o.display_name(), "sphere:8x4");
        assert_eq!(o.scale, Scale::PerAxis([1.0, 2.0, 3.0]));
        let s = f.build(Path::new("."), "m.toml").unwrap();
        assert_eq!(s.name, "m");
        assert_eq!(
            s.light.as_disk().map(|d| d.normal),
            Some(Vec3::new(0.0, -1.0, 0.0))
        );
        assert_eq!(s.objects[0].mesh.triangles.len(), 2 * 8 * 3);
    }

    #[test]
    fn round_trip() {
        let f = SceneFile::parse(MINIMAL, "m.toml").unwrap();
        let text = f.to_toml();
        assert!(text.contains("[[object]]"), "{text}");
        assert_eq!(SceneFile::parse(&text, "again.toml").unwrap(), f);
    }

    #[test]
    fn euler_convention_is_rx_ry_rz() {
        let o = ObjectSpec {
            name: None,
            mesh: "cube".into(),
            translate: [0.0; 3],
            rotate_deg: [90.0, 90.0, 0.0],
            scale: Scale::default(),
            casts_shadow: true,
        };
        // Rx(90)·Ry(90)·x: Ry takes +X to -Z, then Rx takes -Z to +Y.
        let p = o.transform().transform_point3(Vec3::X);
        assert!((p - Vec3::Y).length() < 1e-5, "{p}");
    }
}
