//! A scene file's mesh names: a built-in shape, or an `.obj`, `.gltf` or `.glb` file beside the
//! scene, within what the scene's other objects leave of its budget.

use crate::budget::{MAX_SCENE_TRIANGLES, MAX_SCENE_VERTICES};
use crate::scene::gltf::SceneChoice;
use crate::scene::obj::Others;
use crate::scene::{shapes, Mesh, SceneError};
use std::path::Path;

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
    resolve_mesh_within(
        mesh,
        base_dir,
        label,
        key,
        Others::default(),
        SceneChoice::default(),
    )
}

/// Like [`resolve_mesh`] in a scene whose other objects have `others` triangles: an `.obj` may
/// have what is left of `MAX_SCENE_TRIANGLES` (counted while it is read). `choice` says which
/// scene of a glTF model to draw (`gltf_scene`); it is refused on any other mesh.
pub fn resolve_mesh_within(
    mesh_name: &str,
    base_dir: &Path,
    label: &str,
    key: &str,
    others: Others,
    choice: SceneChoice,
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
    if let (Some(n), false) = (choice.scene, crate::scene::gltf::is_gltf_path(&path)) {
        return Err(SceneError::Gltf {
            file: label.to_string(),
            problem: format!(
                "{}: gltf_scene = {n} is for a .gltf or .glb mesh",
                key.trim_end_matches(".mesh")
            ),
        });
    }
    if crate::scene::gltf::is_gltf_path(&path) {
        let mesh = crate::scene::gltf::load_gltf_scene(&path, choice)
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
        return crate::scene::obj::load_obj_within(&path, others).map_err(in_file);
    }
    Err(unknown_mesh(label, key, mesh))
}

pub(super) fn shape_error(e: shapes::ShapeError, label: &str, key: &str) -> SceneError {
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
pub(super) fn check_budget(
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
            let mesh = crate::scene::shown(mesh);
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
        name: crate::scene::truncated(name),
        known: shapes::NAMES.join(", "),
    }
}
