//! Scenes: the light (a disk, or a line segment), the camera and the objects, from TOML files or
//! built-ins.

pub mod builtin;
mod error;
pub mod file;
pub mod gltf;
mod light;
mod mesh;
pub mod obj;
pub mod orbit;
pub mod shapes;

pub use error::SceneError;
pub use file::SceneFile;
pub use light::*;
pub use mesh::Mesh;

use glam::{DVec3, Mat4, Vec3};
use std::path::{Path, PathBuf};

/// A pinhole camera looking from `eye` at `target`, +Y up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub fov_y_deg: f32,
}

impl Camera {
    /// Up direction for the view: +Y, or +Z when looking straight up or down.
    fn up(&self) -> Vec3 {
        let forward = (self.target - self.eye).normalize_or_zero();
        if forward.cross(Vec3::Y).length_squared() < 1e-8 {
            Vec3::Z
        } else {
            Vec3::Y
        }
    }

    /// World to view (right-handed, looking down −Z).
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye, self.target, self.up())
    }

    /// View to clip for an aspect ratio (width / height), wgpu depth range 0..1.
    pub fn projection(&self, aspect: f32, near: f32, far: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, near, far)
    }

    /// The ray (origin, unit direction) through the centre of pixel (`px`, `py`) of a
    /// `width`×`height` image, row 0 at the top — the pixel the GPU shades there.
    pub fn pixel_ray(&self, px: u32, py: u32, width: u32, height: u32) -> (Vec3, Vec3) {
        let (w, h) = (width.max(1) as f32, height.max(1) as f32);
        let ndc_x = 2.0 * (px as f32 + 0.5) / w - 1.0;
        let ndc_y = 1.0 - 2.0 * (py as f32 + 0.5) / h;
        let tan = (0.5 * self.fov_y_deg.to_radians()).tan();
        let forward = (self.target - self.eye).normalize_or_zero();
        let right = forward.cross(self.up()).normalize_or_zero();
        let up = right.cross(forward);
        let dir = forward + right * (ndc_x * tan * w / h) + up * (ndc_y * tan);
        (self.eye, dir.normalize_or_zero())
    }
}

/// The view a scene gets when it has no camera of its own (a scene file without `[camera]`, a
/// bare `.obj` or glTF model): 45° vertical field of view, looking from the front right and
/// above (from the direction (0.6, 0.7, 1), 31° down) at the casters (every object if none
/// casts) and at the shadow they cast from the light's centre onto the plane they stand on
/// (each corner of their bounding box projected from the light, at most 4× as far as the light
/// is above it), just far enough that all of it fits a square view with a 10 % margin (a wider
/// image shows more on the sides). The light itself is left out of the frame: it is drawn
/// nowhere in a render, and taking it in would leave half the picture to the sky.
pub fn framed_camera(light: &Light, objects: &[Object]) -> Camera {
    const FOV_Y_DEG: f32 = 45.0;
    let any_caster = objects.iter().any(|o| o.casts_shadow);
    let bounds = objects
        .iter()
        .filter(|o| o.casts_shadow || !any_caster)
        .filter_map(|o| o.mesh.bounds())
        .reduce(|(lo, hi), (a, b)| (lo.min(a), hi.max(b)));
    let (mut lo, mut hi) = match bounds {
        Some(b) => b,
        None => {
            let r = Vec3::splat(light.half_extent().max(0.5));
            (light.center() - r, light.center() + r)
        }
    };
    let corners = |lo: Vec3, hi: Vec3| {
        (0..8).map(move |i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
    };
    // The shadow of the box on the plane y = lo.y, seen from the light's centre.
    let c = light.center();
    let floor = lo.y;
    if bounds.is_some() && c.y > floor {
        for p in corners(lo, hi).collect::<Vec<_>>() {
            if c.y - p.y > 1e-4 {
                let t = ((c.y - floor) / (c.y - p.y)).min(4.0);
                let q = c + (p - c) * t;
                lo = lo.min(q);
                hi = hi.max(q);
            }
        }
    }
    let target = (lo + hi) * 0.5;
    let back = Vec3::new(0.6, 0.7, 1.0).normalize();
    let forward = -back;
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let tan = (0.5 * FOV_Y_DEG).to_radians().tan() / 1.1;
    // The eye at `target + back·d`: a corner q (relative to the target) is at depth d + q·forward
    // and must have |q·up| and |q·right| within tan·depth, and lie in front of the eye.
    let mut distance: f32 = 0.5;
    for corner in corners(lo, hi) {
        let q = corner - target;
        let along = q.dot(forward);
        let side = q.dot(up).abs().max(q.dot(right).abs());
        distance = distance.max(side / tan - along).max(0.1 - along);
    }
    Camera {
        eye: target + back * distance,
        target,
        fov_y_deg: FOV_Y_DEG,
    }
}

/// An object of the scene with its mesh already in world space.
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub mesh: Mesh,
    /// Casters get umbra and penumbra volumes; every object occludes in `|cx_o|` and the oracle.
    pub casts_shadow: bool,
}

/// A scene ready for the geometry stage: everything in world space.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    pub light: Light,
    pub objects: Vec<Object>,
}

impl Scene {
    /// The objects that cast shadows (and so get volumes).
    pub fn casters(&self) -> impl Iterator<Item = &Object> {
        self.objects.iter().filter(|o| o.casts_shadow)
    }

    /// The box `(min, max)` that holds every object's vertices (min above max for a scene
    /// without any).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.objects.iter().filter_map(|o| o.mesh.bounds()).fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
        )
    }

    /// Every triangle of every object, as corners in world space.
    pub fn all_triangles(&self) -> Vec<[Vec3; 3]> {
        self.objects
            .iter()
            .flat_map(|o| o.mesh.triangle_corners())
            .collect()
    }

    /// Number of triangles over all casters.
    pub fn caster_triangle_count(&self) -> usize {
        self.casters().map(|o| o.mesh.triangles.len()).sum()
    }

    /// What will make the picture wrong although the scene loaded: a camera whose direction or
    /// field of view single precision cannot resolve, a scene smaller or larger than the render
    /// core draws right ([`MIN_SCENE_EXTENT`] to [`MAX_SCENE_EXTENT`]), an object whose
    /// vertices overflow single precision or of which nothing is left (every triangle of zero
    /// area in f32). One line each; the geometry stage passes them on with its own warnings
    /// (`PreparedCasters`), so `render`, `inspect` and the lab show them.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        let c = &self.camera;
        let apart = c.eye.distance(c.target);
        let far = c.eye.abs().max_element().max(c.target.abs().max_element());
        if apart < CAMERA_PRECISION * far {
            warnings.push(format!(
                "camera: eye and target are {apart:.1e} apart at {far:.1e} from the origin, \
                 too close for single precision (under {CAMERA_PRECISION:e} of it): the view \
                 direction is imprecise and the picture may be wrong"
            ));
        }
        if !(MIN_FOV_DEG..=MAX_FOV_DEG).contains(&c.fov_y_deg) {
            warnings.push(format!(
                "camera: fov_y_deg {} is outside {MIN_FOV_DEG}..={MAX_FOV_DEG}: {}",
                c.fov_y_deg,
                if c.fov_y_deg > MAX_FOV_DEG {
                    "the scene shrinks to a few pixels in the middle of the picture"
                } else {
                    "a pixel is finer than single precision resolves positions"
                }
            ));
        }

        let mut lo = self.light.center() - Vec3::splat(self.light.half_extent());
        let mut hi = self.light.center() + Vec3::splat(self.light.half_extent());
        for (i, o) in self.objects.iter().enumerate() {
            let who = format!("object[{i}] '{}'", shown(&o.name));
            let overflowed = o.mesh.positions.iter().filter(|p| !p.is_finite()).count();
            if overflowed > 0 {
                warnings.push(format!(
                    "{who}: {overflowed} vertices are beyond single precision (±3.4e38) after \
                     its transform: its triangles there are dropped"
                ));
            }
            let finite = o.mesh.positions.iter().filter(|p| p.is_finite());
            let bounds = finite.fold(None, |b: Option<(Vec3, Vec3)>, &p| {
                Some(b.map_or((p, p), |(l, h)| (l.min(p), h.max(p))))
            });
            if let Some((l, h)) = bounds {
                lo = lo.min(l);
                hi = hi.max(h);
            }
            let n = o.mesh.triangles.len();
            let has_area = (0..n).any(|t| {
                let [a, b, c] = o.mesh.corners(t);
                let area = (b - a).cross(c - a).length();
                area.is_finite() && area > 0.0
            });
            if !has_area {
                let across = bounds.map_or(0.0, |(l, h)| (h - l).max_element());
                warnings.push(format!(
                    "{who}: nothing is left of it: all {n} triangles have zero area in single \
                     precision (it is {across:.1e} across): it is not drawn and casts no shadow"
                ));
            }
        }
        let extent = (hi - lo).max_element();
        if extent.is_finite() && !(MIN_SCENE_EXTENT..=MAX_SCENE_EXTENT).contains(&extent) {
            warnings.push(format!(
                "the scene (objects and light) is {extent:.1e} across, outside the \
                 {MIN_SCENE_EXTENT:e}..={MAX_SCENE_EXTENT:e} the render core draws right in \
                 single precision: the picture will be wrong (scale the scene toward metres)"
            ));
        }
        warnings
    }
}

/// Smallest scene (objects and light, the longest side of their bounds) the render core draws
/// right. Measured: `fig7-concave` (about 10 m across) with every length scaled by 1e-4 to 1e7
/// gives the same shadow classes at 48×48; by 1e-5 the picture is black, by 1e8 it drifts and
/// by 1e9 it is all umbra.
pub const MIN_SCENE_EXTENT: f32 = 1e-3;
/// Largest scene the render core draws right (see [`MIN_SCENE_EXTENT`]).
pub const MAX_SCENE_EXTENT: f32 = 1e8;
/// Narrowest vertical field of view worth a warning-free picture, in degrees.
pub const MIN_FOV_DEG: f32 = 0.01;
/// Widest vertical field of view worth a warning-free picture (at 179° the scene shrinks to a
/// few pixels; at 175° fig7-concave covers 8 of 2304).
pub const MAX_FOV_DEG: f32 = 179.0;
/// Eye and target closer than this share of their distance from the origin give an imprecise
/// view direction (f32 resolves about 1.2e-7 of it).
pub const CAMERA_PRECISION: f32 = 1e-5;

/// Loads a scene: a built-in scene name (see [`builtin::names`]), else a path to a `.toml` scene
/// file (mesh paths in it are relative to the file), else a path to an `.obj` mesh or a
/// `.gltf`/`.glb` model, which is shown on a default ground under a default light (see
/// [`obj_scene`], [`gltf_scene`]).
pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
    load_with(name_or_path, LoadOptions::default()).map(|l| l.scene)
}

/// How [`load_with`] opens a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Which scene of a glTF model to draw (`--scene N`); only a `.gltf`/`.glb` takes it.
    pub gltf_scene: Option<usize>,
}

/// A scene and what loading its model said: a bare glTF model's warnings (a skinned mesh in
/// its bind pose, an extension ignored, no `scenes`), one line each.
#[derive(Clone, Debug)]
pub struct Loaded {
    pub scene: Scene,
    pub notes: Vec<String>,
}

/// [`load`] with options, and the model's notes.
pub fn load_with(name_or_path: &str, options: LoadOptions) -> Result<Loaded, SceneError> {
    let source = load_source(name_or_path, options)?;
    let scene = source
        .file
        .build_named(&source.base_dir, &source.label, &source.name)?;
    Ok(Loaded {
        scene,
        notes: source.notes,
    })
}

/// Like [`load`] but stops before loading meshes: the parsed scene file and the file it came from
/// (`None` for a built-in scene). For an `.obj` or glTF path the scene file is the generated
/// one, its mesh an absolute path, and the path returned is the model's. Useful to edit and save
/// a scene.
pub fn load_file(name_or_path: &str) -> Result<(SceneFile, Option<PathBuf>), SceneError> {
    load_file_with(name_or_path, LoadOptions::default()).map(|(file, path, _)| (file, path))
}

/// [`load_file`] with options (a glTF model's scene is recorded in its object's `gltf_scene`),
/// and a bare model's notes (what of it is not drawn, or drawn otherwise), as [`load_with`] gives.
pub fn load_file_with(
    name_or_path: &str,
    options: LoadOptions,
) -> Result<(SceneFile, Option<PathBuf>, Vec<String>), SceneError> {
    let source = load_source(name_or_path, options)?;
    Ok((source.file, source.path, source.notes))
}

struct Source {
    file: SceneFile,
    path: Option<PathBuf>,
    base_dir: PathBuf,
    label: String,
    name: String,
    notes: Vec<String>,
}

fn load_source(name_or_path: &str, options: LoadOptions) -> Result<Source, SceneError> {
    let path = Path::new(name_or_path);
    if let Some(n) = options.gltf_scene {
        if !gltf::is_gltf_path(path) || builtin::source(name_or_path).is_some() {
            return Err(SceneError::Gltf {
                file: shown(name_or_path),
                problem: format!(
                    "--scene {n} picks a scene of a glTF model: expected a .gltf or .glb file"
                ),
            });
        }
    }
    if let Some(text) = builtin::source(name_or_path) {
        let label = format!("built-in scene {name_or_path}");
        return Ok(Source {
            file: SceneFile::parse(text, &label)?,
            path: None,
            base_dir: PathBuf::from("."),
            label,
            name: name_or_path.to_string(),
            notes: Vec::new(),
        });
    }
    let label = shown(&path.display().to_string());
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| label.clone());
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("toml") => {
            let bytes = crate::fsutil::read_regular(path, file::SCENE_FILE_BUDGET)
                .map_err(|e| read_error(&label, e))?;
            let text = file::decode_utf8(&bytes, &label)?;
            Ok(Source {
                file: SceneFile::parse(text, &label)?,
                path: Some(path.to_path_buf()),
                base_dir,
                label,
                name,
                notes: Vec::new(),
            })
        }
        Some("obj") => Ok(Source {
            file: obj_scene(path)?,
            path: Some(path.to_path_buf()),
            base_dir,
            label,
            name,
            notes: Vec::new(),
        }),
        Some("gltf" | "glb") => {
            let choice = gltf::SceneChoice {
                scene: options.gltf_scene,
            };
            let model = gltf::load_gltf_scene(path, choice)?;
            let mut file = model_scene(path, &model.mesh, model.light)?;
            // The model is the generated scene's last object (after the ground).
            if let Some(o) = file.objects.last_mut() {
                o.gltf_scene = options.gltf_scene;
            }
            Ok(Source {
                file,
                path: Some(path.to_path_buf()),
                base_dir,
                notes: model
                    .warnings
                    .iter()
                    .map(|w| format!("{label}: {w}"))
                    .collect(),
                label,
                name,
            })
        }
        _ => Err(SceneError::UnknownScene {
            name: name_or_path.to_string(),
            known: builtin::names().join(", "),
        }),
    }
}

/// `text` cut to at most about 160 characters (its start and end, `…` between): names from
/// scene files and paths repeated in messages keep them short.
pub fn truncated(text: &str) -> String {
    const HEAD: usize = 100;
    const TAIL: usize = 50;
    let n = text.chars().count();
    if n <= HEAD + TAIL + 10 {
        return text.to_string();
    }
    let head: String = text.chars().take(HEAD).collect();
    let tail: String = text.chars().skip(n - TAIL).collect();
    format!("{head}…{tail}")
}

/// [`truncated`], with control characters escaped (a newline in a path becomes `\n`): what a
/// one-line message may repeat of a name or path.
pub fn shown(text: &str) -> String {
    truncated(text)
        .chars()
        .flat_map(|c| {
            let escaped: Vec<char> = if c.is_control() {
                c.escape_default().collect()
            } else {
                vec![c]
            };
            escaped
        })
        .collect()
}

/// A file that could not be read, as a [`SceneError`] naming `file`.
pub(crate) fn read_error(file: &str, e: crate::fsutil::ReadError) -> SceneError {
    match e {
        crate::fsutil::ReadError::Io(error) => SceneError::Io {
            file: file.to_string(),
            error,
        },
        reason => SceneError::Refused {
            file: file.to_string(),
            reason,
        },
    }
}

/// `[x, y, z]` in scientific notation, 4 significant digits.
fn sci(v: glam::DVec3) -> String {
    format!("[{:.3e}, {:.3e}, {:.3e}]", v.x, v.y, v.z)
}

/// Smallest extent of a bare `.obj` that can be scaled to 1.5 m in f32 (1.5 over the largest
/// f32 number).
pub const MIN_BARE_EXTENT: f64 = 1.5 / f32::MAX as f64;
/// Largest extent of a bare `.obj` that can be scaled to 1.5 m in f32 (1.5 over the smallest
/// normal f32 number).
pub const MAX_BARE_EXTENT: f64 = 1.5 / f32::MIN_POSITIVE as f64;

/// The scene shown for a bare `.obj`: the mesh scaled to 1.5 m across its largest extent,
/// centred over the origin and standing on a 10 m ground plane, under a disk light of radius 0.5
/// at 4 m pointing down, seen by [`framed_camera`] (the file has no `[camera]`). The mesh path
/// is made absolute so the scene can be saved anywhere.
pub fn obj_scene(obj_path: &Path) -> Result<SceneFile, SceneError> {
    let mesh = obj::load_obj(obj_path)?;
    model_scene(obj_path, &mesh, None)
}

/// The scene shown for a bare `.gltf`/`.glb`: as [`obj_scene`], with the model's first spot or
/// point light (KHR_lights_punctual) as the disk light when it has one: the light is placed by
/// the same scale and translation as the model, points where the spot points (a point light
/// points down), and gets radius 0.5, or less where that would reach the model (half the
/// distance from the light to the model's bounding box, at least 1 cm).
pub fn gltf_scene(path: &Path) -> Result<SceneFile, SceneError> {
    let model = gltf::load_gltf(path)?;
    model_scene(path, &model.mesh, model.light)
}

/// A default ground, the model standing on it, a light, no camera.
fn model_scene(
    path: &Path,
    mesh: &Mesh,
    light: Option<gltf::GltfLight>,
) -> Result<SceneFile, SceneError> {
    let (lo, hi) = mesh.bounds().ok_or_else(|| SceneError::Obj {
        file: path.display().to_string(),
        problem: "contains no vertices".into(),
    })?;
    // In f64: the extent of a mesh spanning ±3e38 overflows f32, and 1.5 / 1e-45 does too.
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let extent = (hi - lo).max_element();
    let scale = if extent > 0.0 { 1.5 / extent } else { 1.0 };
    // The transform is applied in f32: the scale must be a normal f32 number.
    if !(scale as f32).is_normal() {
        let size = if scale as f32 == f32::INFINITY || scale > 1.0 {
            "too small"
        } else {
            "too large"
        };
        return Err(SceneError::Obj {
            file: shown(&path.display().to_string()),
            problem: format!(
                "its vertices span {extent:.3e} (from {} to {}), {size} to be scaled to the \
                 1.5 m a bare mesh is shown at in single precision (f32): expected an extent \
                 between {MIN_BARE_EXTENT:.1e} and {MAX_BARE_EXTENT:.1e}",
                sci(lo),
                sci(hi)
            ),
        });
    }
    let centre = (lo + hi) / 2.0;
    let shift = DVec3::new(-centre.x * scale, -lo.y * scale, -centre.z * scale);
    let translate = shift.to_array();
    if translate.iter().any(|&t| !(t as f32).is_finite()) {
        return Err(SceneError::Obj {
            file: shown(&path.display().to_string()),
            problem: format!(
                "its vertices lie around {}, {:.1e} times their extent away from the \
                 origin: too far to be moved to it in single precision (f32)",
                sci(centre),
                centre.abs().max_element() / extent
            ),
        });
    }
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    const TEXT: &str = r#"
[light]
center = [0.0, 4.0, 0.0]
normal = [0.0, -1.0, 0.0]
radius = 0.5

[[object]]
name = "ground"
mesh = "plane"
scale = 10.0
casts_shadow = false
"#;
    let mut file = SceneFile::parse(TEXT, "generated model scene")?;
    if let Some(l) = light {
        let center = l.position.as_dvec3() * scale + shift;
        let (blo, bhi) = (lo * scale + shift, hi * scale + shift);
        let gap = (center.clamp(blo, bhi) - center).length();
        let radius = (0.5 * gap).clamp(0.01, 0.5);
        file.light.center = Some(center.to_array());
        file.light.normal = Some(l.direction.as_dvec3().to_array());
        file.light.radius = Some(radius);
    }
    file.objects.push(file::ObjectSpec {
        name: path.file_stem().map(|s| s.to_string_lossy().into_owned()),
        mesh: absolute.display().to_string(),
        translate,
        rotate_deg: [0.0; 3],
        scale: file::Scale::Uniform(scale),
        casts_shadow: true,
        gltf_scene: None,
    });
    file.validate(&path.display().to_string())?;
    Ok(file)
}
