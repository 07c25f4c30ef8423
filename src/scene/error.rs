//! The one error type of scene loading.

use thiserror::Error;

/// Everything that can go wrong loading a scene or a mesh. Every message names the file (or the
/// built-in it came from), the key or line, and what was expected.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read (missing, unreadable, a directory...).
    #[error("{file}: cannot read the file: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },

    /// TOML syntax or structure (unknown key, missing key, wrong type). `message` is toml's own,
    /// which carries the line and column and quotes the offending line.
    #[error("{file}: {message}")]
    Toml { file: String, message: String },

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

    /// A problem with an OBJ file as a whole (no triangles, tobj's own errors).
    #[error("{file}: {problem}")]
    Obj { file: String, problem: String },

    /// A problem with a glTF model (`.gltf`/`.glb`): its container, JSON, buffers, accessors or
    /// scene graph. `problem` says where (buffer, accessor, node) and what was expected.
    #[error("{file}: {problem}")]
    Gltf { file: String, problem: String },

    /// A mesh referenced from a scene file failed to load; `source` says why and where.
    #[error("{file}: {key}: {source}")]
    Mesh {
        file: String,
        key: String,
        #[source]
        source: Box<SceneError>,
    },

    /// `load` got something that is neither a built-in scene nor a `.toml`/`.obj`/`.gltf`/`.glb` file.
    #[error(
        "{name:?}: not a built-in scene ({known}) nor a path to a .toml scene file or an \
         .obj, .gltf or .glb model"
    )]
    UnknownScene { name: String, known: String },
}
