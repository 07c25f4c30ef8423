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
//!
//! One file per step: [`text`] (the bytes as text, and toml's messages without what they quote of
//! the file), [`spec`] (the schema: what a file holds, and how it reads and writes), [`validate`]
//! (every value TOML accepts but a scene cannot use) and [`meshes`] (a mesh name resolved to a
//! built-in shape or a model file, within the scene's budget).

mod meshes;
mod spec;
mod text;
mod validate;

use super::obj::Others;
use super::{shapes, Mesh, Object, Scene, SceneError};
use crate::budget::MAX_SCENE_FILE_BYTES;
use crate::fsutil::ByteBudget;
use std::path::Path;

pub use meshes::{resolve_mesh, resolve_mesh_within};
pub use spec::{CameraSpec, LightSpec, ObjectSpec, Scale, SceneFile};
pub use text::{decode_utf8, line_column};

use text::sanitize_toml_message;

/// The byte budget of one scene file.
pub const SCENE_FILE_BUDGET: ByteBudget = ByteBudget {
    limit: MAX_SCENE_FILE_BYTES,
    name: "MAX_SCENE_FILE_BYTES",
    what: "a scene file",
};

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

    /// Loads the meshes (relative paths are resolved against `base_dir`) and places every
    /// object in world space; without `[camera]` the view is [`crate::scene::framed_camera`]'s. `label` names the scene file in errors; the scene is named after
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
                    name: crate::scene::shown(o.display_name()),
                    mesh,
                    casts_shadow: o.casts_shadow,
                }
            })
            .collect();
        let light = l.light();
        let camera = match &self.camera {
            Some(c) => c.camera(),
            None => crate::scene::framed_camera(&light, &objects),
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
                if let Some(n) = o.gltf_scene {
                    return Err(SceneError::Gltf {
                        file: label.to_string(),
                        problem: format!(
                            "object[{i}]: gltf_scene = {n} is for a .gltf or .glb mesh"
                        ),
                    });
                }
                resolve_mesh(&o.mesh, base_dir, label, &key)?
            } else {
                let choice = crate::scene::gltf::SceneChoice {
                    scene: o.gltf_scene,
                };
                let mesh = resolve_mesh_within(&o.mesh, base_dir, label, &key, used, choice)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
            s.light.as_area().map(|d| d.normal),
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
            gltf_scene: None,
        };
        // Rx(90)·Ry(90)·x: Ry takes +X to -Z, then Rx takes -Z to +Y.
        let p = o.transform().transform_point3(Vec3::X);
        assert!((p - Vec3::Y).length() < 1e-5, "{p}");
    }
}
