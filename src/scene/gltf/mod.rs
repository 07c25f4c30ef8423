//! glTF 2.0 models (`.gltf` with its buffers, `.glb`): every triangle primitive of the default
//! scene (or the first one) placed by its node transforms, and the first KHR_lights_punctual
//! spot or point light, if any.
//!
//! The `gltf` crate parses and validates the JSON (indices that point nowhere, missing required
//! fields, unknown enum values). Everything that touches bytes is done here, with every length
//! checked against the bytes actually there before anything is allocated, so a hostile file
//! cannot make the loader panic or allocate more than its own size (plus the triangle budget):
//!
//! - the GLB container (magic, version 2, declared length, chunk lengths): [`split_glb`](glb::split_glb);
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
//!
//! One file per step: [`glb`] (the binary container), [`json`] (the document, parsed and
//! validated, and its errors told without quoting the file), [`buffers`] (the bytes behind each
//! buffer), [`document`] (the scene's nodes, primitives and lights, within the budget) and
//! [`accessors`] (positions and indices, every range checked).

mod accessors;
mod buffers;
mod document;
mod glb;
mod json;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{Mesh, SceneError};

pub use glb::split_glb;

use buffers::Buffers;
use document::read_document;
use glb::describe_magic;
use json::{describe_gltf_error, document};

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
    // Control characters escaped, a long path cut: the error stays one short line.
    let label = crate::scene::shown(&path.display().to_string());
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

/// Reads `path` if it is a regular file of at most [`MAX_FILE_BYTES`] (never a directory, a
/// FIFO or a device: those are refused before being opened).
fn read_regular_file(path: &Path, label: &str) -> Result<Vec<u8>, SceneError> {
    crate::fsutil::read_regular(path, MODEL_FILE_BUDGET)
        .map_err(|e| crate::scene::read_error(label, e))
}
