//! glTF 2.0 models (`.gltf` with its buffers, `.glb`): every triangle primitive of the default
//! scene (or the first one, or the one `--scene N` names) placed by its node transforms, and
//! the first KHR_lights_punctual spot or point light, if any.
//!
//! **Only what dbuffer draws is read, so only that is validated.** The JSON is parsed into
//! `serde_json`'s tree and each object the scene reaches (scene, nodes, meshes, the POSITION and
//! indices accessors, their buffer views and buffers, the lights) is read from it field by
//! field when it is reached ([`json`]); materials, textures, images, samplers, animations, skins
//! and cameras are never read, so they may be missing, partial or extended in any way. (The
//! `gltf` crate, used before, validated the whole document: it refused a texture format dbuffer
//! never decodes, an animation channel without a node, an accessor without a bufferView, and
//! named no extension in its messages.) A skinned mesh is drawn in its bind pose and morph
//! targets are left out, each with a warning. `extensionsRequired` ([`extensions`]): geometry
//! dbuffer decodes (`KHR_mesh_quantization`, `EXT_meshopt_compression`,
//! `KHR_meshopt_compression`, `KHR_lights_punctual`) is read; an extension that only changes
//! materials, textures or animation is accepted with a one-line note; anything else is refused
//! by name, `requires KHR_draco_mesh_compression, which dbuffer cannot decode` (a name is said
//! back only if it has the shape of an extension name, `VENDOR_name`; anything else is file
//! content and is referred to by its index). A file without `scenes` is drawn from its root
//! nodes, and a scene that places no triangle mesh from each mesh once, with a note.
//!
//! Everything that touches bytes is done here, with every length checked against the bytes
//! actually there before anything is allocated, so a hostile file cannot make the loader panic
//! or allocate more than its own size (plus the triangle budget):
//!
//! - the GLB container (magic, version 2, declared length, chunk lengths): [`split_glb`](glb::split_glb);
//! - buffers: the GLB's BIN chunk, a `data:` URI (base64), or a file beside the model (a relative
//!   path inside the model's folder: absolute paths, URL schemes and `..` that leave the folder
//!   are refused, and only regular files are read); only buffers that a mesh uses are read; a
//!   meshopt fallback buffer (no data) is never read;
//! - buffer views with `EXT_meshopt_compression` ([`meshopt`]): decoded once by the `meshopt`
//!   crate (meshoptimizer 1.3) after every field the decoder asserts on is checked (mode,
//!   filter, stride), and after the decoded size, `count × byteStride`, is checked against the
//!   view's `byteLength`, against what the stream can decode to (1024 bytes per byte at most)
//!   and against [`MAX_FILE_BYTES`] with the buffers read;
//! - accessors ([`accessors`]): FLOAT VEC3 positions, or BYTE/SHORT (signed or not, normalized
//!   or not) with KHR_mesh_quantization; unsigned byte/short/int SCALAR indices; the accessor's
//!   offset, stride and count must fit its buffer view; an accessor without a view is zeros;
//!   sparse values are put in (their indices checked against the count); every index must name
//!   a vertex;
//! - counts: [`MAX_TRIANGLES`] triangles and [`MAX_PLACED_VERTICES`] positions over all
//!   primitives and node instances, counted from the accessors before any buffer is read or
//!   stream decoded; `MAX_SCENE_VERTICES` distinct positions while welding; [`MAX_FILE_BYTES`]
//!   per file read and over all buffers and decoded views.
//!
//! Primitive modes: triangles, triangle strips and fans are read (strips and fans are turned
//! into triangles); points and lines are skipped with a warning. A node whose world transform
//! mirrors (negative determinant) has its winding reversed, as the glTF spec says. Exactly
//! equal positions are welded (as for OBJ), so adjacency sees one vertex where a model splits
//! vertices for normals or UVs; triangles that become degenerate are dropped.
//!
//! Errors are [`SceneError::Gltf`] with the file and what is wrong, naming the JSON path of the
//! field, the accessor, the buffer view or the extension, e.g. `m.glb: accessor 2 (indices of
//! mesh 0, primitive 0): 36 items of 2 bytes from byte 0 need 72 bytes, but buffer view 1 has
//! 48`, `m.glb: invalid glTF: nodes[3].mesh is 7, but the file has 2 meshes`. File content is
//! never quoted.
//!
//! One file per step: [`glb`] (the binary container), [`json`] (the document, read field by
//! field, and its errors told without quoting the file), [`extensions`] (what is required),
//! [`buffers`] (the bytes behind each buffer view), [`meshopt`] (compressed views),
//! [`document`] (the scene's nodes, primitives and lights, within the budget) and
//! [`accessors`] (positions and indices, every range checked).

mod accessors;
mod buffers;
mod document;
mod extensions;
mod glb;
mod json;
mod meshopt;
mod skin;

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{Mesh, SceneError};

pub use document::SceneChoice;
pub use glb::split_glb;

use buffers::Buffers;
use document::read_document;
use glb::describe_magic;

/// The most triangles one model may have, over all primitives and node instances: the scene's
/// budget ([`crate::budget::MAX_SCENE_TRIANGLES`]); a scene file counts its other objects too.
pub const MAX_TRIANGLES: usize = crate::budget::MAX_SCENE_TRIANGLES as usize;

/// The largest file read: the model, and each buffer file; also the sum of all buffers read
/// ([`crate::budget::MAX_MODEL_FILE_BYTES`]).
pub const MAX_FILE_BYTES: u64 = crate::budget::MAX_MODEL_FILE_BYTES;

/// Most positions placed over all instances (each instance of a primitive places all of its
/// positions): three per triangle of the budget.
pub const MAX_PLACED_VERTICES: usize = 3 * MAX_TRIANGLES;

/// Most distinct positions after welding: the scene's vertex budget
/// ([`crate::budget::MAX_SCENE_VERTICES`]), checked while welding so that the positions and the
/// weld table never outgrow it.
const MAX_WELDED_VERTICES: usize = crate::budget::MAX_SCENE_VERTICES as usize;

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
    load_gltf_scene(path, SceneChoice::default())
}

/// [`load_gltf`], drawing the scene `choice` names (`--scene N`).
pub fn load_gltf_scene(path: &Path, choice: SceneChoice) -> Result<GltfModel, SceneError> {
    // Control characters escaped, a long path cut: the error stays one short line.
    let label = crate::scene::shown(&path.display().to_string());
    let bytes = read_regular_file(path, &label)?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    parse_gltf_scene(&bytes, &label, Some(&base_dir), choice)
}

/// Parses a glTF model from its bytes (`.gltf` JSON or `.glb`); `label` names it in errors.
/// Buffer files are looked up in `base_dir`; with `None`, only the GLB chunk and `data:` URIs
/// can be used.
pub fn parse_gltf(
    bytes: &[u8],
    label: &str,
    base_dir: Option<&Path>,
) -> Result<GltfModel, SceneError> {
    parse_gltf_scene(bytes, label, base_dir, SceneChoice::default())
}

/// [`parse_gltf`], drawing the scene `choice` names.
pub fn parse_gltf_scene(
    bytes: &[u8],
    label: &str,
    base_dir: Option<&Path>,
    choice: SceneChoice,
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
    let doc = json::parse(json).map_err(fail)?;
    let notes = extensions::check_required(&doc).map_err(fail)?;
    let mut buffers = Buffers::new(&doc, base_dir, bin, looks_glb);
    read_document(&doc, &mut buffers, choice, notes).map_err(fail)
}

/// Reads `path` if it is a regular file of at most [`MAX_FILE_BYTES`] (never a directory, a
/// FIFO or a device: those are refused before being opened).
fn read_regular_file(path: &Path, label: &str) -> Result<Vec<u8>, SceneError> {
    crate::fsutil::read_regular(path, MODEL_FILE_BUDGET)
        .map_err(|e| crate::scene::read_error(label, e))
}
