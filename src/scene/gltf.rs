//! glTF 2.0 models (`.gltf` with its buffers, `.glb`): every triangle primitive of the default
//! scene (or the first one) placed by its node transforms, and the first KHR_lights_punctual
//! spot or point light, if any.
//!
//! The `gltf` crate parses and validates the JSON (indices that point nowhere, missing required
//! fields, unknown enum values). Everything that touches bytes is done here, with every length
//! checked against the bytes actually there before anything is allocated, so a hostile file
//! cannot make the loader panic or allocate more than its own size (plus the triangle budget):
//!
//! - the GLB container (magic, version 2, declared length, chunk lengths): [`split_glb`];
//! - buffers: the GLB's BIN chunk, a `data:` URI (base64), or a file beside the model (a relative
//!   path inside the model's folder: absolute paths, URL schemes and `..` that leave the folder
//!   are refused, and only regular files are read); only buffers that a mesh uses are read;
//! - accessors: FLOAT VEC3 positions, unsigned byte/short/int SCALAR indices; the accessor's
//!   offset, stride and count must fit its buffer view, and the view its buffer; every index
//!   must name a vertex; sparse accessors and accessors without a view are refused;
//! - counts: [`MAX_TRIANGLES`] triangles and [`MAX_PLACED_VERTICES`] positions over all
//!   primitives and node instances, counted from the accessors before any buffer is read;
//!   `MAX_SCENE_VERTICES` distinct positions while welding; [`MAX_FILE_BYTES`] per file read
//!   and over all buffers.
//!
//! Primitive modes: triangles, triangle strips and fans are read (strips and fans are turned
//! into triangles); points and lines are skipped with a warning. A node whose world transform
//! mirrors (negative determinant) has its winding reversed, as the glTF spec says. Exactly
//! equal positions are welded (as for OBJ), so adjacency sees one vertex where a model splits
//! vertices for normals or UVs; triangles that become degenerate are dropped. Skins, morph
//! targets, materials, textures and cameras are ignored.
//!
//! Errors are [`SceneError::Gltf`] with the file and what is wrong, e.g.
//! `m.glb: accessor 2 (indices of mesh 0, primitive 0): 36 items of 2 bytes from byte 0 need 72
//! bytes, but buffer view 1 has 48`. File content is never quoted.

use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

use glam::{Mat4, Vec3};

use super::{Mesh, SceneError};

/// The most triangles one model may have, over all primitives and node instances: the scene's
/// budget ([`crate::budget::MAX_SCENE_TRIANGLES`]); a scene file counts its other objects too.
pub const MAX_TRIANGLES: usize = crate::budget::MAX_SCENE_TRIANGLES as usize;

/// The largest file read: the model, and each buffer file; also the sum of all buffers read
/// ([`crate::budget::MAX_MODEL_FILE_BYTES`]).
pub const MAX_FILE_BYTES: u64 = crate::budget::MAX_MODEL_FILE_BYTES;

/// The byte budget of one model or buffer file.
const MODEL_FILE_BUDGET: crate::fsutil::ByteBudget = crate::fsutil::ByteBudget {
    limit: MAX_FILE_BYTES,
    name: "MAX_MODEL_FILE_BYTES",
    what: "a glTF model or buffer file",
};

/// Deepest node hierarchy followed (a chain deeper than this is refused, not walked).
const MAX_DEPTH: usize = 1024;

/// What a glTF model gives a scene.
#[derive(Clone, Debug)]
pub struct GltfModel {
    /// Every triangle in the model's scene space (node transforms applied), welded.
    pub mesh: Mesh,
    /// The first spot or point light met walking the scene (KHR_lights_punctual), if any.
    pub light: Option<GltfLight>,
    /// Things skipped on purpose (point/line primitives, directional lights), one line each.
    pub warnings: Vec<String>,
}

/// A glTF punctual light, placed in the model's scene space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfLight {
    /// The node's origin.
    pub position: Vec3,
    /// Unit direction the light points to: the node's −Z for a spot light, straight down (−Y)
    /// for a point light.
    pub direction: Vec3,
    /// `"spot"` or `"point"`.
    pub kind: &'static str,
}

/// Whether `path` names a glTF model by its extension (`.gltf` or `.glb`, any case).
pub fn is_gltf_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Loads the `.gltf` or `.glb` at `path` (either is recognised by its content: a GLB starts with
/// `glTF`). Errors name the file as `path` displays.
pub fn load_gltf(path: &Path) -> Result<GltfModel, SceneError> {
    // Control characters escaped, a long path cut: the error stays one short line.
    let label = super::shown(&path.display().to_string());
    let bytes = read_regular_file(path, &label)?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    parse_gltf(&bytes, &label, Some(&base_dir))
}

/// Parses a glTF model from its bytes (`.gltf` JSON or `.glb`); `label` names it in errors.
/// Buffer files are looked up in `base_dir`; with `None`, only the GLB chunk and `data:` URIs
/// can be used.
pub fn parse_gltf(
    bytes: &[u8],
    label: &str,
    base_dir: Option<&Path>,
) -> Result<GltfModel, SceneError> {
    let fail = |problem: String| SceneError::Gltf {
        file: label.to_string(),
        problem,
    };
    let looks_glb = bytes.starts_with(b"glTF");
    let is_glb_name = Path::new(label)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let (json, bin) = if looks_glb {
        split_glb(bytes).map_err(fail)?
    } else if is_glb_name {
        return Err(fail(format!(
            "not a binary glTF file: expected it to start with the magic `glTF`, found {}",
            describe_magic(bytes)
        )));
    } else {
        (bytes, None)
    };
    let document = document(json).map_err(|e| fail(describe_gltf_error(&e)))?;
    let mut buffers = Buffers {
        base_dir,
        bin,
        loaded: HashMap::new(),
        total: 0,
    };
    read_document(&document, &mut buffers).map_err(fail)
}

/// The JSON parsed and validated by the `gltf` crate, except that a POSITION accessor without
/// `min`/`max` (required by the spec, left out by some exporters, and not used here) is let
/// through.
fn document(json: &[u8]) -> Result<::gltf::Document, ::gltf::Error> {
    use ::gltf::json::validation::{Error, Validate};
    let root: ::gltf::json::Root =
        ::gltf::json::deserialize::from_slice(json).map_err(::gltf::Error::Deserialize)?;
    // gltf-json 1.4.1 validates a primitive by indexing `accessors` with its POSITION before
    // checking that index (a 300-byte file with `"POSITION": 3` and two accessors panics in
    // `validate`): those indices are checked here first.
    let mut errors = Vec::new();
    let position = ::gltf::json::validation::Checked::Valid(::gltf::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            match primitive.attributes.get(&position) {
                Some(i) if i.value() >= root.accessors.len() => errors.push((
                    ::gltf::json::Path::new()
                        .field("meshes")
                        .index(m)
                        .field("primitives")
                        .index(p)
                        .field("attributes")
                        .key("POSITION"),
                    Error::IndexOutOfBounds,
                )),
                _ => {}
            }
        }
    }
    if !errors.is_empty() {
        return Err(::gltf::Error::Validation(errors));
    }
    root.validate(&root, ::gltf::json::Path::new, &mut |path, error| {
        let path = path();
        let bounds = path.0.ends_with(".min") || path.0.ends_with(".max");
        if !(bounds && matches!(error, Error::Missing)) {
            errors.push((path, error));
        }
    });
    if errors.is_empty() {
        Ok(::gltf::Document::from_json_without_validation(root))
    } else {
        Err(::gltf::Error::Validation(errors))
    }
}

/// Reads `path` if it is a regular file of at most [`MAX_FILE_BYTES`] (never a directory, a
/// FIFO or a device: those are refused before being opened).
fn read_regular_file(path: &Path, label: &str) -> Result<Vec<u8>, SceneError> {
    crate::fsutil::read_regular(path, MODEL_FILE_BUDGET).map_err(|e| super::read_error(label, e))
}

fn describe_magic(bytes: &[u8]) -> String {
    if bytes.len() < 4 {
        format!("a file of {} bytes", bytes.len())
    } else {
        let hex: Vec<String> = bytes[..4].iter().map(|b| format!("{b:02x}")).collect();
        format!("bytes {}", hex.join(" "))
    }
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The JSON chunk and the BIN chunk (if any) of a GLB file, every length checked.
pub fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    if !bytes.starts_with(b"glTF") {
        return Err(format!(
            "not a binary glTF file: expected the magic `glTF`, found {}",
            describe_magic(bytes)
        ));
    }
    let (Some(version), Some(length)) = (u32_at(bytes, 4), u32_at(bytes, 8)) else {
        return Err(format!(
            "truncated: the 12-byte GLB header is cut off after {} bytes",
            bytes.len()
        ));
    };
    if version != 2 {
        return Err(format!(
            "GLB version {version}: expected version 2 (glTF 2.0)"
        ));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(format!(
            "truncated: the GLB header says {length} bytes, the file has {}",
            bytes.len()
        ));
    }
    if length < 20 {
        return Err(format!(
            "the GLB header says {length} bytes: too short for a header and a JSON chunk (20 bytes at least)"
        ));
    }
    let body = &bytes[..length];
    let chunk = |at: usize, what: &str| -> Result<(u32, &[u8]), String> {
        let (Some(len), Some(kind)) = (u32_at(body, at), u32_at(body, at + 4)) else {
            return Err(format!(
                "truncated: the {what} chunk header at byte {at} is cut off (the GLB has {length} bytes)"
            ));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&end| end <= body.len())
            .ok_or_else(|| {
                format!(
                    "truncated: the {what} chunk at byte {at} says {len} bytes, only {} follow",
                    body.len() - start
                )
            })?;
        Ok((kind, &body[start..end]))
    };
    let (kind, json) = chunk(12, "first")?;
    if kind != JSON {
        return Err(format!(
            "the first GLB chunk has type 0x{kind:08x}: expected JSON (0x{JSON:08x})"
        ));
    }
    let next = (12 + 8 + json.len()).next_multiple_of(4);
    let bin = if next + 8 <= body.len() {
        let (kind, data) = chunk(next, "second")?;
        (kind == BIN).then_some(data)
    } else {
        None
    };
    Ok((json, bin))
}

/// The `gltf` crate's error, without quoting the file.
fn describe_gltf_error(e: &::gltf::Error) -> String {
    match e {
        ::gltf::Error::Validation(list) => {
            let shown: Vec<String> = list
                .iter()
                .take(3)
                .map(|(path, err)| format!("{}: {err}", path_shown(path.as_str())))
                .collect();
            let more = if list.len() > 3 {
                format!(" (and {} more)", list.len() - 3)
            } else {
                String::new()
            };
            format!("invalid glTF: {}{more}", shown.join("; "))
        }
        ::gltf::Error::Deserialize(e) => format!(
            "not glTF JSON: {} at line {}, column {}",
            match e.classify() {
                serde_json::error::Category::Io => "cannot read",
                serde_json::error::Category::Syntax => "a JSON syntax error",
                serde_json::error::Category::Data => "a value of the wrong type or a missing field",
                serde_json::error::Category::Eof => "the JSON ends early (truncated?)",
            },
            e.line(),
            e.column()
        ),
        other => format!("invalid glTF: {other}"),
    }
}

/// A validation error's JSON path without what it quotes of the file: gltf-json appends the
/// value (`extensionsRequired[0] = "NAME"`) and names keys (`attributes["NAME"]`); a value is
/// dropped, a key kept only if it is a standard attribute name.
fn path_shown(path: &str) -> String {
    let path = path.split_once(" = ").map_or(path, |(p, _)| p);
    let standard = |key: &str| {
        ["POSITION", "NORMAL", "TANGENT"].contains(&key)
            || ["TEXCOORD_", "COLOR_", "JOINTS_", "WEIGHTS_"]
                .iter()
                .any(|p| {
                    key.strip_prefix(p).is_some_and(|n| {
                        !n.is_empty() && n.len() <= 3 && n.bytes().all(|b| b.is_ascii_digit())
                    })
                })
    };
    let mut out = String::new();
    let mut rest = path;
    while let Some(at) = rest.find("[\"") {
        out.push_str(&rest[..at]);
        let after = &rest[at + 2..];
        match after.find("\"]") {
            Some(end) => {
                let key = &after[..end];
                out.push_str(if standard(key) { "[\"" } else { "[\"…" });
                if standard(key) {
                    out.push_str(key);
                }
                out.push_str("\"]");
                rest = &after[end + 2..];
            }
            None => {
                out.push_str("[\"…");
                rest = "";
            }
        }
    }
    out.push_str(rest);
    super::shown(&out)
}

/// The buffers read so far, by index.
struct Buffers<'a> {
    base_dir: Option<&'a Path>,
    bin: Option<&'a [u8]>,
    loaded: HashMap<usize, Vec<u8>>,
    total: u64,
}

impl Buffers<'_> {
    /// The bytes of `buffer`, at least its declared `byteLength` long (checked), read on first use.
    fn get(&mut self, buffer: &::gltf::Buffer) -> Result<&[u8], String> {
        let index = buffer.index();
        let declared = buffer.length();
        if !self.loaded.contains_key(&index) {
            let bytes = match buffer.source() {
                ::gltf::buffer::Source::Bin => {
                    let bin = self.bin.ok_or_else(|| {
                        format!("buffer {index} has no uri and the file has no GLB BIN chunk")
                    })?;
                    if bin.len() < declared {
                        return Err(format!(
                            "buffer {index} says {declared} bytes but the GLB BIN chunk has {}",
                            bin.len()
                        ));
                    }
                    bin[..declared].to_vec()
                }
                ::gltf::buffer::Source::Uri(uri) => self.read_uri(index, uri)?,
            };
            if bytes.len() < declared {
                return Err(format!(
                    "buffer {index} says {declared} bytes but its data has {}",
                    bytes.len()
                ));
            }
            self.total += bytes.len() as u64;
            if self.total > MAX_FILE_BYTES {
                return Err(format!(
                    "its buffers add up to more than the limit of {MAX_FILE_BYTES} bytes"
                ));
            }
            self.loaded.insert(index, bytes);
        }
        Ok(self.loaded.get(&index).map(Vec::as_slice).unwrap_or(&[]))
    }

    fn read_uri(&self, index: usize, uri: &str) -> Result<Vec<u8>, String> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, data) = rest.split_once(";base64,").ok_or_else(|| {
                format!("buffer {index}: a data: URI must be base64 (`;base64,`)")
            })?;
            return decode_base64(data.as_bytes())
                .ok_or_else(|| format!("buffer {index}: the data: URI is not valid base64"));
        }
        let relative = percent_decode(uri)
            .ok_or_else(|| format!("buffer {index}: the uri is not valid percent-encoded UTF-8"))?;
        let rel = Path::new(&relative);
        let has_scheme = relative.split_once(':').is_some_and(|(s, _)| {
            !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        });
        let mut depth = 0i32;
        let mut escapes = false;
        for c in rel.components() {
            match c {
                Component::Normal(_) => depth += 1,
                Component::CurDir => {}
                Component::ParentDir => {
                    depth -= 1;
                    escapes |= depth < 0;
                }
                Component::RootDir | Component::Prefix(_) => escapes = true,
            }
        }
        if has_scheme || rel.is_absolute() || escapes {
            return Err(format!(
                "buffer {index}: the uri must be a relative path inside the model's folder \
                 (no scheme, no absolute path, no `..` leaving the folder)"
            ));
        }
        let Some(base) = self.base_dir else {
            return Err(format!(
                "buffer {index} is in a separate file, but the model was not read from a folder"
            ));
        };
        let path = base.join(rel);
        read_regular_file(&path, &super::shown(&path.display().to_string()))
            .map_err(|e| format!("buffer {index}: {e}"))
    }
}

/// Standard base64 (RFC 4648, `+/`, `=` padding optional, whitespace not allowed).
fn decode_base64(text: &[u8]) -> Option<Vec<u8>> {
    let text = match text.iter().position(|&b| b == b'=') {
        Some(p) if text[p..].iter().all(|&b| b == b'=') && text.len() - p <= 2 => &text[..p],
        Some(_) => return None,
        None => text,
    };
    let value = |b: u8| -> Option<u32> {
        Some(match b {
            b'A'..=b'Z' => b - b'A',
            b'a'..=b'z' => b - b'a' + 26,
            b'0'..=b'9' => b - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    if text.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 2);
    for chunk in text.chunks(4) {
        let mut acc = 0u32;
        for (i, &b) in chunk.iter().enumerate() {
            acc |= value(b)? << (18 - 6 * i);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// `%XX` sequences decoded; `None` if one is malformed or the result is not UTF-8.
fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// A mesh placed in the model's scene by its node.
struct Instance<'a> {
    mesh: ::gltf::Mesh<'a>,
    world: Mat4,
}

/// A primitive's positions and triangles (indices into them), as read from its accessors.
type Primitive = (Vec<Vec3>, Vec<[u32; 3]>);

/// Most positions placed over all instances (each instance of a primitive places all of its
/// positions): three per triangle of the budget.
pub const MAX_PLACED_VERTICES: usize = 3 * MAX_TRIANGLES;

/// Most distinct positions after welding: the scene's vertex budget
/// ([`crate::budget::MAX_SCENE_VERTICES`]), checked while welding so that the positions and the
/// weld table never outgrow it.
const MAX_WELDED_VERTICES: usize = crate::budget::MAX_SCENE_VERTICES as usize;

/// Whether a primitive of this mode is read (triangles, strips, fans), not skipped.
fn has_triangles(mode: ::gltf::mesh::Mode) -> bool {
    use ::gltf::mesh::Mode;
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

/// How many triangles [`assemble`] makes of `corners` corners in `mode`.
fn triangles_of(mode: ::gltf::mesh::Mode, corners: u64) -> u64 {
    use ::gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
        Mode::Triangles => corners / 3,
        _ => 0,
    }
}

/// An accessor's count, or fewer: at most what its buffer view's declared length can hold (a
/// larger count is refused with the accessor's own range error when it is read).
fn readable_count(acc: &::gltf::Accessor) -> u64 {
    let count = acc.count() as u64;
    match acc.view() {
        Some(view) => {
            let stride = view.stride().unwrap_or(acc.size()).max(1) as u64;
            count.min((view.length() as u64 / stride).saturating_add(1))
        }
        None => count,
    }
}

/// The triangles and positions the scene's instances would place, from the accessors' counts,
/// before a byte of a buffer is read: a small file can place one big primitive many times
/// (2 KB of nodes over a 60 KB strip is 18M triangles), so the budget is checked here, not
/// once they are made.
fn check_instances_budget(instances: &[Instance]) -> Result<(), String> {
    let (mut assembled, mut placed) = (0u64, 0u64);
    for inst in instances {
        for primitive in inst.mesh.primitives() {
            let mode = primitive.mode();
            if !has_triangles(mode) {
                continue;
            }
            let vertices = primitive
                .get(&::gltf::Semantic::Positions)
                .map_or(0, |a| readable_count(&a));
            let corners = primitive.indices().map_or(vertices, |a| readable_count(&a));
            assembled = assembled.saturating_add(triangles_of(mode, corners));
            placed = placed.saturating_add(vertices);
        }
        if assembled > MAX_TRIANGLES as u64 || placed > MAX_PLACED_VERTICES as u64 {
            return Err(format!(
                "its scene places at least {assembled} triangles and {placed} vertices over its                  node instances (counted from the accessors, before reading them): the budget                  is {MAX_TRIANGLES} triangles per scene (MAX_SCENE_TRIANGLES) and                  {MAX_PLACED_VERTICES} placed vertices, three per triangle"
            ));
        }
    }
    Ok(())
}

fn read_document(doc: &::gltf::Document, buffers: &mut Buffers) -> Result<GltfModel, String> {
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| "has no scene: expected at least one entry in `scenes`".to_string())?;
    let mut warnings = Vec::new();
    let mut instances: Vec<Instance> = Vec::new();
    let mut light = None;
    // Depth-first over the node forest, without recursion; each node at most once.
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(::gltf::Node, Mat4, usize)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    stack.reverse();
    while let Some((node, parent, depth)) = stack.pop() {
        let i = node.index();
        if seen.get(i).copied().unwrap_or(true) {
            return Err(format!(
                "node {i} is reached twice from scene {}: the node hierarchy must be a tree",
                scene.index()
            ));
        }
        seen[i] = true;
        if depth > MAX_DEPTH {
            return Err(format!(
                "the node hierarchy is deeper than {MAX_DEPTH} levels (at node {i})"
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(format!(
                "node {i}: its transform has a number that is not finite"
            ));
        }
        if let Some(mesh) = node.mesh() {
            instances.push(Instance { mesh, world });
        }
        if let Some(l) = node.light() {
            use ::gltf::khr_lights_punctual::Kind;
            let position = world.transform_point3(Vec3::ZERO);
            match l.kind() {
                Kind::Spot { .. } | Kind::Point if light.is_none() => {
                    let spot = matches!(l.kind(), Kind::Spot { .. });
                    let direction = if spot {
                        world.transform_vector3(Vec3::NEG_Z).try_normalize()
                    } else {
                        Some(Vec3::NEG_Y)
                    };
                    match direction {
                        Some(direction) if position.is_finite() => {
                            light = Some(GltfLight {
                                position,
                                direction,
                                kind: if spot { "spot" } else { "point" },
                            })
                        }
                        _ => warnings.push(format!(
                            "light {} on node {i}: its transform collapses it; ignored",
                            l.index()
                        )),
                    }
                }
                Kind::Directional => warnings.push(format!(
                    "light {} on node {i} is directional (no position): ignored; a disk light \
                     needs a spot or point light",
                    l.index()
                )),
                _ => warnings.push(format!(
                    "light {} on node {i}: only the first spot or point light is used",
                    l.index()
                )),
            }
        }
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }

    check_instances_budget(&instances)?;

    let mut positions: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    // Each primitive's positions and triangles, read once however many nodes use it.
    let mut read: HashMap<(usize, usize), Primitive> = HashMap::new();
    let mut skipped = 0usize;
    let mut primitives = 0usize;
    for inst in &instances {
        for primitive in inst.mesh.primitives() {
            let what = format!(
                "mesh {}, primitive {}",
                inst.mesh.index(),
                primitive.index()
            );
            let mode = primitive.mode();
            if !has_triangles(mode) {
                skipped += 1;
                continue;
            }
            primitives += 1;
            let (local, tris) = match read.entry((inst.mesh.index(), primitive.index())) {
                Entry::Occupied(e) => &*e.into_mut(),
                Entry::Vacant(e) => {
                    let position = primitive
                        .get(&::gltf::Semantic::Positions)
                        .ok_or_else(|| format!("{what} has no POSITION attribute"))?;
                    let local = read_positions(&position, &format!("POSITION of {what}"), buffers)?;
                    let corners = match primitive.indices() {
                        Some(acc) => {
                            read_indices(&acc, &format!("indices of {what}"), buffers, local.len())?
                        }
                        None => (0..local.len() as u32).collect(),
                    };
                    let tris = assemble(mode, &corners);
                    &*e.insert((local, tris))
                }
            };
            let flip = Mat4::determinant(&inst.world) < 0.0;
            let mut remap = Vec::with_capacity(local.len());
            for p in local {
                let p = inst.world.transform_point3(*p);
                if !p.is_finite() {
                    return Err(format!(
                        "{what}: a position is not finite once placed by its node"
                    ));
                }
                let p = Vec3::new(p.x + 0.0, p.y + 0.0, p.z + 0.0);
                let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                let next = positions.len() as u32;
                let id = *welded.entry(key).or_insert_with(|| {
                    positions.push(p);
                    next
                });
                remap.push(id);
            }
            if positions.len() > MAX_WELDED_VERTICES {
                return Err(format!(
                    "has more than {MAX_WELDED_VERTICES} distinct vertices over its node \
                     instances, reached at {what}: the budget is {MAX_WELDED_VERTICES} vertices \
                     per scene (MAX_SCENE_VERTICES)"
                ));
            }
            for &[a, b, c] in tris {
                let (a, b, c) = (remap[a as usize], remap[b as usize], remap[c as usize]);
                if a != b && b != c && a != c {
                    triangles.push(if flip { [a, c, b] } else { [a, b, c] });
                }
            }
        }
    }
    if skipped > 0 {
        warnings.push(format!(
            "{skipped} point or line primitive{} skipped: only triangles cast shadows",
            if skipped == 1 { "" } else { "s" }
        ));
    }
    if triangles.is_empty() {
        return Err(format!(
            "contains no triangles: scene {} has {primitives} triangle primitive{} with no \
             non-degenerate triangle{}",
            scene.index(),
            if primitives == 1 { "" } else { "s" },
            if skipped > 0 {
                format!(" and {skipped} point or line primitives")
            } else {
                String::new()
            }
        ));
    }
    Ok(GltfModel {
        mesh: Mesh::new(positions, triangles),
        light,
        warnings,
    })
}

/// Triangles (as indices into the primitive's vertices) from a triangle list, strip or fan.
fn assemble(mode: ::gltf::mesh::Mode, corners: &[u32]) -> Vec<[u32; 3]> {
    use ::gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => corners
            .windows(3)
            .enumerate()
            .map(|(i, w)| {
                if i % 2 == 0 {
                    [w[0], w[1], w[2]]
                } else {
                    [w[1], w[0], w[2]]
                }
            })
            .collect(),
        Mode::TriangleFan => match corners.split_first() {
            Some((&first, rest)) => rest.windows(2).map(|w| [first, w[0], w[1]]).collect(),
            None => Vec::new(),
        },
        _ => corners
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    }
}

/// The bytes of an accessor's elements: (bytes, element size, stride, count), every range
/// checked against the view and the buffer actually read.
fn accessor_bytes<'b>(
    acc: &::gltf::Accessor,
    what: &str,
    buffers: &'b mut Buffers,
) -> Result<(&'b [u8], usize, usize, usize), String> {
    let i = acc.index();
    if acc.sparse().is_some() {
        return Err(format!(
            "accessor {i} ({what}) is sparse: sparse accessors are not supported"
        ));
    }
    let view = acc.view().ok_or_else(|| {
        format!("accessor {i} ({what}) has no bufferView: expected its data in a buffer view")
    })?;
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    let count = acc.count();
    if stride < elem {
        return Err(format!(
            "buffer view {} has byteStride {stride}, smaller than accessor {i}'s {elem}-byte elements",
            view.index()
        ));
    }
    let needed = if count == 0 {
        Some(0u64)
    } else {
        (stride as u64)
            .checked_mul(count as u64 - 1)
            .and_then(|x| x.checked_add(elem as u64))
            .and_then(|x| x.checked_add(acc.offset() as u64))
    };
    let view_len = view.length() as u64;
    match needed {
        Some(n) if n <= view_len => {}
        _ => {
            return Err(format!(
                "accessor {i} ({what}) is out of range: {count} items of {elem} bytes \
                 (stride {stride}) from byte {} do not fit buffer view {}'s {view_len} bytes",
                acc.offset(),
                view.index()
            ))
        }
    }
    let buffer = view.buffer();
    let start = view.offset() as u64;
    let data = buffers.get(&buffer)?;
    let has = data.len().min(buffer.length()) as u64;
    // A byteOffset near 2^64 must not wrap around.
    let end = match start.checked_add(view_len) {
        Some(end) if end <= has => end,
        _ => {
            return Err(format!(
                "buffer view {} is out of range: {view_len} bytes from byte {start} of buffer {}, \
                 which has {has}",
                view.index(),
                buffer.index(),
            ))
        }
    };
    let bytes = &data[start as usize + acc.offset()..end as usize];
    Ok((bytes, elem, stride, count))
}

fn read_positions(
    acc: &::gltf::Accessor,
    what: &str,
    buffers: &mut Buffers,
) -> Result<Vec<Vec3>, String> {
    use ::gltf::accessor::{DataType, Dimensions};
    if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "accessor {} ({what}) is {:?} {:?}: expected FLOAT VEC3 positions",
            acc.index(),
            acc.data_type(),
            acc.dimensions()
        ));
    }
    let (bytes, _, stride, count) = accessor_bytes(acc, what, buffers)?;
    // Bounded by the bytes checked above (12 bytes a position).
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let at = k * stride;
        let f = |j: usize| {
            let b = &bytes[at + 4 * j..at + 4 * j + 4];
            f32::from_le_bytes([b[0], b[1], b[2], b[3]])
        };
        let p = Vec3::new(f(0), f(1), f(2));
        if !p.is_finite() {
            return Err(format!(
                "accessor {} ({what}): position {k} is not finite",
                acc.index()
            ));
        }
        out.push(p);
    }
    Ok(out)
}

fn read_indices(
    acc: &::gltf::Accessor,
    what: &str,
    buffers: &mut Buffers,
    vertices: usize,
) -> Result<Vec<u32>, String> {
    use ::gltf::accessor::{DataType, Dimensions};
    let size = match acc.data_type() {
        DataType::U8 => 1,
        DataType::U16 => 2,
        DataType::U32 => 4,
        other => {
            return Err(format!(
                "accessor {} ({what}) has component type {other:?}: expected unsigned byte, \
                 short or int indices",
                acc.index()
            ))
        }
    };
    if acc.dimensions() != Dimensions::Scalar {
        return Err(format!(
            "accessor {} ({what}) is {:?}: expected SCALAR indices",
            acc.index(),
            acc.dimensions()
        ));
    }
    if acc.count() / 3 > MAX_TRIANGLES {
        return Err(format!(
            "accessor {} ({what}) has {} indices: more than {MAX_TRIANGLES} triangles (the \
             limit for one model)",
            acc.index(),
            acc.count()
        ));
    }
    let (bytes, _, stride, count) = accessor_bytes(acc, what, buffers)?;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let b = &bytes[k * stride..k * stride + size];
        let v = match size {
            1 => u32::from(b[0]),
            2 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        };
        if v as usize >= vertices {
            return Err(format!(
                "accessor {} ({what}): index {v} at item {k} is out of range: the primitive has \
                 {vertices} vertices",
                acc.index()
            ));
        }
        out.push(v);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_values() {
        assert_eq!(decode_base64(b"").unwrap(), b"");
        assert_eq!(decode_base64(b"Zg==").unwrap(), b"f");
        assert_eq!(decode_base64(b"Zm8=").unwrap(), b"fo");
        assert_eq!(decode_base64(b"Zm9v").unwrap(), b"foo");
        assert_eq!(decode_base64(b"Zm9vYmE").unwrap(), b"fooba");
        assert_eq!(decode_base64(b"AAEC/w==").unwrap(), [0, 1, 2, 255]);
        assert!(decode_base64(b"Zm9v!").is_none());
        assert!(decode_base64(b"Z").is_none());
        assert!(decode_base64(b"Zg=a").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("plain.bin").unwrap(), "plain.bin");
        assert!(percent_decode("bad%2").is_none());
        assert!(percent_decode("bad%zz").is_none());
    }

    #[test]
    fn validation_paths_quote_nothing_of_the_file() {
        assert_eq!(
            path_shown("extensionsRequired[0] = \"SECRET\""),
            "extensionsRequired[0]"
        );
        assert_eq!(
            path_shown("meshes[0].primitives[1].attributes[\"POSITION\"]"),
            "meshes[0].primitives[1].attributes[\"POSITION\"]"
        );
        assert_eq!(
            path_shown("meshes[0].primitives[0].attributes[\"_SECRET\"].x"),
            "meshes[0].primitives[0].attributes[\"…\"].x"
        );
        assert_eq!(path_shown("a[\"TEXCOORD_1\"]"), "a[\"TEXCOORD_1\"]");
        assert_eq!(path_shown("a[\"TEXCOORD_\"]"), "a[\"…\"]");
        assert_eq!(path_shown("a[\"SEC\nRET"), "a[\"…");
    }

    #[test]
    fn strips_and_fans_become_triangles() {
        use ::gltf::mesh::Mode;
        assert_eq!(
            assemble(Mode::TriangleStrip, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [2, 1, 3]]
        );
        assert_eq!(
            assemble(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [0, 2, 3]]
        );
        assert_eq!(assemble(Mode::Triangles, &[0, 1, 2, 3]), vec![[0, 1, 2]]);
    }

    #[test]
    fn glb_header_lengths_are_checked() {
        assert!(split_glb(b"glTF").unwrap_err().contains("truncated"));
        let mut h = b"glTF".to_vec();
        h.extend(2u32.to_le_bytes());
        h.extend(4u32.to_le_bytes());
        assert!(
            split_glb(&h).unwrap_err().contains("too short"),
            "a length under 12 must not underflow"
        );
        let mut h = b"glTF".to_vec();
        h.extend(1u32.to_le_bytes());
        h.extend(12u32.to_le_bytes());
        assert!(split_glb(&h).unwrap_err().contains("version 1"));
    }
}
