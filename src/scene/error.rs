//! The one error type of scene loading.

use thiserror::Error;

/// Everything that can go wrong loading a scene or a mesh. Every message names the file (or the
/// built-in it came from), the key or line, and what was expected, on one line. A message
/// includes its cause's, so no variant reports a `source()`: `anyhow`'s `{:#}` would print the
/// cause a second time.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read (missing, unreadable, a directory...).
    #[error("{file}: cannot read the file: {error}")]
    Io { file: String, error: std::io::Error },

    /// Not a regular file (a directory, FIFO, device or socket), or larger than its budget:
    /// refused before reading.
    #[error("{file}: {reason}")]
    Refused {
        file: String,
        reason: crate::fsutil::ReadError,
    },

    /// TOML syntax or structure (unknown key, missing key, wrong type) at a line and column.
    /// `message` is toml's own with anything quoted from the file left out.
    #[error("{file}: line {line}, column {column}: {message}")]
    Toml {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },

    /// The scene file is not UTF-8 text: the first invalid byte, 0-based, and its line and
    /// column (1-based, in characters).
    #[error(
        "{file}: line {line}, column {column}: expected UTF-8 text, found a byte that is not \
         (byte offset {offset})"
    )]
    NotUtf8 {
        file: String,
        line: usize,
        column: usize,
        offset: usize,
    },

    /// An input over the resource budget (`crate::budget`): `found` says what it asked for,
    /// `limit` and `name` the budget it exceeds.
    #[error("{file}: {key}: {found}; the budget is {limit} ({name})")]
    OverBudget {
        file: String,
        key: String,
        found: String,
        limit: String,
        name: &'static str,
    },

    /// A value that parsed but is not acceptable; `key` is a path like `light.radius` or
    /// `object[2].scale`.
    #[error("{file}: {key}: expected {expected}, found {found}")]
    Invalid {
        file: String,
        key: String,
        expected: String,
        found: String,
    },

    /// A mesh name that is neither a built-in shape nor a path to an existing mesh file.
    #[error(
        "{file}: {key}: unknown mesh {name:?}: expected a built-in shape ({known}) \
         or a path to an existing .obj, .gltf or .glb file"
    )]
    UnknownMesh {
        file: String,
        key: String,
        name: String,
        known: String,
    },

    /// A built-in shape with invalid parameters.
    #[error("{file}: {key}: {expected}")]
    ShapeParams {
        file: String,
        key: String,
        expected: String,
    },

    /// A problem on one line of an OBJ file (1-based line number).
    #[error("{file}:{line}: {expected}")]
    ObjLine {
        file: String,
        line: usize,
        expected: String,
    },

    /// A problem with an OBJ file as a whole (no triangles, a size it cannot be shown at).
    #[error("{file}: {problem}")]
    Obj { file: String, problem: String },

    /// A problem with a glTF model (`.gltf`/`.glb`): its container, JSON, buffers, accessors or
    /// scene graph. `problem` says where (buffer, accessor, node) and what was expected.
    #[error("{file}: {problem}")]
    Gltf { file: String, problem: String },

    /// A mesh referenced from a scene file failed to load; `error` says why and where.
    #[error("{file}: {key}: {error}")]
    Mesh {
        file: String,
        key: String,
        error: Box<SceneError>,
    },

    /// `load` got something that is neither a built-in scene nor a `.toml`/`.obj`/`.gltf`/`.glb` file.
    #[error(
        "{name:?}: not a built-in scene ({known}) nor a path to a .toml scene file or an \
         .obj, .gltf or .glb model"
    )]
    UnknownScene { name: String, known: String },
}
