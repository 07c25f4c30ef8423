//! The scene being edited: its file model ([`SceneFile`]: light, camera, per-object mesh name and
//! `translate` / `rotate_deg` / `scale`) beside the objects' meshes in their own space, so an edit
//! changes the file model and rebuilds only the world meshes it moved. Saving writes the file
//! model back (atomically).

use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::scene::file::{LightSpec, ObjectSpec};
use crate::scene::{self, builtin, Camera, Light, Mesh, Object, Scene, SceneError, SceneFile};

pub struct SceneDoc {
    pub file: SceneFile,
    /// The file it came from (`.toml` or `.obj`), `None` for a built-in scene.
    pub path: Option<PathBuf>,
    /// The scene's name (built-in name or file stem).
    pub name: String,
    /// What errors call it: "built-in scene NAME" or the path.
    pub label: String,
    base_dir: PathBuf,
    /// Each object's mesh before its transform.
    local: Vec<Mesh>,
    /// What the model's reader said about an opened `.obj`/glTF (a skin drawn in its rest pose,
    /// texture extensions ignored, instances not drawn), shown with the geometry's warnings.
    pub notes: Vec<String>,
}

/// What undo and redo restore: the light and every object's placement.
#[derive(Clone, Debug, PartialEq)]
pub struct Edit {
    pub light: LightSpec,
    pub objects: Vec<ObjectSpec>,
}

impl SceneDoc {
    /// A built-in scene name, a `.toml` scene file or an `.obj` mesh, with its world-space scene.
    pub fn open(name_or_path: &str) -> Result<(SceneDoc, Scene), SceneError> {
        Self::open_with(name_or_path, scene::LoadOptions::default())
    }

    /// [`SceneDoc::open`] with options (`--scene N` for a glTF model).
    pub fn open_with(
        name_or_path: &str,
        options: scene::LoadOptions,
    ) -> Result<(SceneDoc, Scene), SceneError> {
        let (file, path, notes) = scene::load_file_with(name_or_path, options)?;
        let (label, name, base_dir) = match &path {
            None => (
                format!("built-in scene {name_or_path}"),
                name_or_path.to_string(),
                PathBuf::from("."),
            ),
            Some(p) => (
                p.display().to_string(),
                p.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| p.display().to_string()),
                match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                    _ => PathBuf::from("."),
                },
            ),
        };
        // Validated, and every mesh within the scene's budget together (not each alone).
        let local = file.load_meshes(&base_dir, &label)?;
        let doc = SceneDoc {
            file,
            path,
            name,
            label,
            base_dir,
            local,
            notes,
        };
        let scene = doc.scene();
        Ok((doc, scene))
    }

    /// A light over nothing: what the lab shows when even the default scene cannot be built (a
    /// build defect the tests catch; the window stays up regardless).
    pub fn empty() -> (SceneDoc, Scene) {
        use crate::scene::file::CameraSpec;
        let doc = SceneDoc {
            file: SceneFile {
                camera: Some(CameraSpec {
                    eye: [0.0, 3.0, 6.0],
                    target: [0.0, 0.5, 0.0],
                    fov_y_deg: 45.0,
                }),
                light: LightSpec::disk([0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 0.5),
                objects: Vec::new(),
            },
            path: None,
            name: "empty".into(),
            label: "empty scene".into(),
            base_dir: PathBuf::from("."),
            local: Vec::new(),
            notes: Vec::new(),
        };
        let scene = doc.scene();
        (doc, scene)
    }

    /// Whether `name` is a built-in scene (for menus).
    pub fn is_builtin(name: &str) -> bool {
        builtin::source(name).is_some()
    }

    /// The whole scene in world space.
    pub fn scene(&self) -> Scene {
        let objects = self.objects();
        Scene {
            name: self.name.clone(),
            camera: self.camera_for(&objects),
            light: self.light(),
            objects,
        }
    }

    fn objects(&self) -> Vec<Object> {
        (0..self.file.objects.len())
            .filter_map(|i| {
                let o = &self.file.objects[i];
                Some(Object {
                    name: o.display_name().to_string(),
                    mesh: self.world_mesh(i)?,
                    casts_shadow: o.casts_shadow,
                })
            })
            .collect()
    }

    pub fn world_mesh(&self, i: usize) -> Option<Mesh> {
        let spec = self.file.objects.get(i)?;
        Some(self.local.get(i)?.transformed(&spec.transform()))
    }

    /// The file's `[camera]`, or the framed view a scene without one gets.
    pub fn camera(&self) -> Camera {
        match &self.file.camera {
            Some(c) => c.camera(),
            None => self.camera_for(&self.objects()),
        }
    }

    fn camera_for(&self, objects: &[Object]) -> Camera {
        match &self.file.camera {
            Some(c) => c.camera(),
            None => scene::framed_camera(&self.light(), objects),
        }
    }

    pub fn light(&self) -> Light {
        self.file.light.light()
    }

    pub fn edit(&self) -> Edit {
        Edit {
            light: self.file.light.clone(),
            objects: self.file.objects.clone(),
        }
    }

    /// Put `edit` in place; returns whether the light changed and which objects moved.
    pub fn apply(&mut self, edit: &Edit) -> (bool, Vec<usize>) {
        let light = self.file.light != edit.light;
        self.file.light = edit.light.clone();
        let mut moved = Vec::new();
        for (i, (now, new)) in self.file.objects.iter_mut().zip(&edit.objects).enumerate() {
            if now != new {
                *now = new.clone();
                moved.push(i);
            }
        }
        (light, moved)
    }

    /// Check the edited file model (a radius of 0, a zero normal); the message names the key.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.file.validate(&self.label)
    }

    /// Write the scene as TOML to `path` (temporary file, then rename), with `camera` as its
    /// camera. A scene without `[camera]` gets one only if `camera` is not the framed view it
    /// shows without one. Relative mesh paths are made absolute when the file moves to another
    /// folder.
    pub fn save(&mut self, path: &Path, camera: &Camera) -> Result<(), String> {
        let mut file = self.file.clone();
        let framed = self.file.camera.is_none() && same_camera(camera, &self.camera());
        if !framed {
            file.camera = Some(crate::scene::file::CameraSpec {
                eye: f3(camera.eye),
                target: f3(camera.target),
                fov_y_deg: f64::from(camera.fov_y_deg),
            });
        }
        let target_dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let same_dir = same_path(&target_dir, &self.base_dir);
        for o in &mut file.objects {
            if !scene::shapes::is_shape_name(&o.mesh)
                && Path::new(&o.mesh).is_relative()
                && !same_dir
            {
                let absolute = std::path::absolute(self.base_dir.join(&o.mesh))
                    .unwrap_or_else(|_| self.base_dir.join(&o.mesh));
                o.mesh = absolute.display().to_string();
            }
        }
        file.validate(&path.display().to_string())
            .map_err(|e| e.to_string())?;
        crate::fsutil::write_atomic(path, file.to_toml().as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        self.file = file;
        self.base_dir = target_dir;
        self.path = Some(path.to_path_buf());
        self.label = path.display().to_string();
        Ok(())
    }

    /// The `.toml` this scene would be saved to without asking (`None`: built-in or `.obj`).
    pub fn toml_path(&self) -> Option<&Path> {
        self.path.as_deref().filter(|p| {
            p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
        })
    }
}

fn same_camera(a: &Camera, b: &Camera) -> bool {
    let close = |p: Vec3, q: Vec3| (p - q).length() <= 1e-5 * (1.0 + p.length().max(q.length()));
    close(a.eye, b.eye) && close(a.target, b.target) && (a.fov_y_deg - b.fov_y_deg).abs() < 1e-4
}

fn same_path(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

pub fn f3(v: Vec3) -> [f64; 3] {
    // Through the shortest decimal of the f32, so a saved 0.1 reads 0.1.
    let f = |x: f32| format!("{x}").parse::<f64>().unwrap_or(f64::from(x));
    [f(v.x), f(v.y), f(v.z)]
}

/// The light's normal as tilt from straight down and azimuth about +Y, in degrees.
pub fn tilt_azimuth(normal: [f64; 3]) -> (f64, f64) {
    let n = glam::DVec3::from(normal)
        .try_normalize()
        .unwrap_or(glam::DVec3::NEG_Y);
    let tilt = (-n.y).clamp(-1.0, 1.0).acos().to_degrees();
    let azimuth = if n.x.abs() + n.z.abs() < 1e-12 {
        0.0
    } else {
        n.z.atan2(n.x).to_degrees()
    };
    (tilt, azimuth)
}

/// The unit normal tilted `tilt` degrees from straight down toward azimuth `azimuth`.
pub fn normal_from(tilt: f64, azimuth: f64) -> [f64; 3] {
    let (t, a) = (tilt.to_radians(), azimuth.to_radians());
    let round = |x: f64| (x * 1e9).round() / 1e9;
    [
        round(t.sin() * a.cos()),
        round(-t.cos()),
        round(t.sin() * a.sin()),
    ]
}

/// Undo and redo: snapshots of [`Edit`]s. One gesture (a drag, a slider pull) is one step.
#[derive(Default)]
pub struct History {
    undo: Vec<Edit>,
    redo: Vec<Edit>,
    /// A gesture is going on: its first change already saved the state before it.
    open: bool,
}

/// Undo steps kept.
const MAX_UNDO: usize = 200;

impl History {
    /// Call before changing the scene, with the state before the change.
    pub fn checkpoint(&mut self, before: Edit) {
        if !self.open {
            self.undo.push(before);
            if self.undo.len() > MAX_UNDO {
                self.undo.remove(0);
            }
            self.redo.clear();
            self.open = true;
        }
    }

    /// The gesture ended (the pointer is up): the next change starts a new step.
    pub fn close(&mut self) {
        self.open = false;
    }

    pub fn undo(&mut self, now: Edit) -> Option<Edit> {
        self.open = false;
        let before = self.undo.pop()?;
        self.redo.push(now);
        Some(before)
    }

    pub fn redo(&mut self, now: Edit) -> Option<Edit> {
        self.open = false;
        let after = self.redo.pop()?;
        self.undo.push(now);
        Some(after)
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    pub fn clear(&mut self) {
        *self = History::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_scene_round_trips_through_the_file_model() {
        let (doc, scene) = SceneDoc::open("fig7-concave").unwrap();
        let reference = scene::load("fig7-concave").unwrap();
        assert_eq!(scene.light, reference.light);
        assert_eq!(scene.camera, reference.camera);
        assert_eq!(scene.objects.len(), reference.objects.len());
        for (a, b) in scene.objects.iter().zip(&reference.objects) {
            assert_eq!(a.mesh, b.mesh, "{}", a.name);
        }
        assert!(doc.path.is_none());
    }

    #[test]
    fn edits_move_only_what_changed_and_undo_restores() {
        let (mut doc, _) = SceneDoc::open("fig7-concave").unwrap();
        let mut history = History::default();
        let before = doc.edit();
        let mut edit = doc.edit();
        edit.objects[1].translate[0] += 0.5;
        history.checkpoint(doc.edit());
        // A second change in the same gesture is not a second step.
        history.checkpoint(doc.edit());
        let (light, moved) = doc.apply(&edit);
        assert!(!light);
        assert_eq!(moved, vec![1]);
        history.close();
        let undone = history.undo(doc.edit()).unwrap();
        assert_eq!(undone, before);
        assert!(history.undo(doc.edit()).is_none(), "one gesture, one step");
        doc.apply(&undone);
        let redone = history.redo(doc.edit()).unwrap();
        assert_eq!(redone, edit);
    }

    #[test]
    fn tilt_and_azimuth_round_trip() {
        for (t, a) in [(0.0, 0.0), (30.0, 45.0), (60.0, -120.0)] {
            let (t2, a2) = tilt_azimuth(normal_from(t, a));
            assert!((t - t2).abs() < 1e-6, "{t} {t2}");
            if t > 0.0 {
                assert!((a - a2).abs() < 1e-6, "{a} {a2}");
            }
        }
    }

    /// A scene without `[camera]` (here a glTF model) shows the framed view and saves without
    /// a camera unless the view was moved.
    #[test]
    fn a_camera_less_scene_saves_a_camera_only_when_moved() {
        let fox = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/Fox.glb");
        let (mut doc, scene) = SceneDoc::open(fox.to_str().unwrap()).unwrap();
        assert!(doc.file.camera.is_none());
        assert_eq!(scene.objects.len(), 2);
        assert_eq!(doc.camera(), scene.camera);
        let dir = std::env::temp_dir().join(format!("dbuffer-doc-cam-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("fox.toml");
        let framed = doc.camera();
        doc.save(&path, &framed).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(!text.contains("[camera]"), "{text}");
        let moved = Camera {
            eye: framed.eye + Vec3::new(1.0, 0.0, 0.0),
            ..framed
        };
        doc.save(&path, &moved).unwrap();
        let (again, scene) = SceneDoc::open(path.to_str().unwrap()).unwrap();
        assert!(again.file.camera.is_some());
        assert!((scene.camera.eye - moved.eye).length() < 1e-5);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn save_is_readable_and_keeps_edits() {
        let dir = std::env::temp_dir().join(format!("dbuffer-doc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("edited.toml");
        let (mut doc, _) = SceneDoc::open("fig7-concave").unwrap();
        doc.file.light.radius = Some(0.75);
        let camera = doc.camera();
        doc.save(&path, &camera).unwrap();
        let (again, scene) = SceneDoc::open(path.to_str().unwrap()).unwrap();
        assert_eq!(scene.light.half_extent(), 0.75);
        assert_eq!(again.toml_path(), Some(path.as_path()));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
