//! Writing one render's files (design.md §3, `dbuffer render`), all or nothing.
//!
//! [`write_render`] writes the seven files of [`FILE_NAMES`] into a folder:
//!
//! | file | size | content |
//! |---|---|---|
//! | `image.png` | width×height | the shaded image, 8-bit sRGB ([`linear_to_srgb8`]) |
//! | `visibility.exr` | width×height | RGBA f32: R = G = B = V, A = 1 where hit, else 0 |
//! | `position.exr` | width×height | RGBA f32: RGB = world position, A = 1 where hit, else 0 |
//! | `dbuffer.exr` | dbuffer_size² | RGBA f32: \|cx_o\|, \|cx_uv\|, \|cx_pv\|, \|cx_s\| (umbra) |
//! | `dbuffer_s.exr` | dbuffer_size² | RGBA f32: R = \|cx_s\| umbra, G = \|cx_s\| penumbra, B = 0, A = 1 |
//! | `classes.png` | width×height | 8-bit RGB, the colours of [`class_rgb`] and [`NOT_HIT_RGB`] |
//! | `meta.json` | | [`RenderMeta`], pretty-printed |
//!
//! Every EXR is uncompressed, 32-bit float, row 0 at the top, and holds exactly the values given:
//! they read back bit for bit ([`read_exr_rgba`]), infinity and NaN included. In particular a
//! missing |cx_o| stays `+inf` in `dbuffer.exr` (the EXR format and the `image` crate's encoder
//! both take it as it is; no large finite stand-in is needed).
//!
//! Under a line light (which the D-buffer refuses), `dbuffer.exr` holds the hard shadow map from
//! the segment's midpoint as its `|cx_o|` and 0 (no crossing) in the volume channels.
//!
//! **Never a half-written folder.** The files are first written (and flushed to disk) into a fresh
//! hidden folder inside the output folder (`.dbuffer-render-PID-N`, [`TEMP_PREFIX`]). Only when
//! all seven are there does each previous file of the same name get a hard link (or a copy) in
//! that folder as a backup, and each new file is renamed over its target. If anything fails, the
//! files already moved are put back as they were, the hidden folder is removed, and the output
//! folder holds exactly what it held before. (Two renders into the same folder at the same time
//! are not supported: each is all or nothing, but the last rename wins file by file.)

use std::fs::{self, File};
use std::io::{self, BufReader, Cursor, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use image::codecs::openexr::{OpenExrDecoder, OpenExrEncoder};
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageDecoder, ImageEncoder};
use serde::ser::{SerializeMap, Serializer};

use crate::geometry::metrics::ShadowClass;
use crate::render::passes::shadow_map::NO_SURFACE;
use crate::render::Frame;

/// The shaded image.
pub const IMAGE_PNG: &str = "image.png";
/// Visibility per pixel.
pub const VISIBILITY_EXR: &str = "visibility.exr";
/// World position per pixel.
pub const POSITION_EXR: &str = "position.exr";
/// The light-view D-buffer.
pub const DBUFFER_EXR: &str = "dbuffer.exr";
/// |cx_s| of both volumes.
pub const DBUFFER_S_EXR: &str = "dbuffer_s.exr";
/// Shadow classes per pixel.
pub const CLASSES_PNG: &str = "classes.png";
/// Everything else about the render.
pub const META_JSON: &str = "meta.json";

/// Every file [`write_render`] writes, in the order it writes them (and returns their paths).
pub const FILE_NAMES: [&str; 7] = [
    IMAGE_PNG,
    VISIBILITY_EXR,
    POSITION_EXR,
    DBUFFER_EXR,
    DBUFFER_S_EXR,
    CLASSES_PNG,
    META_JSON,
];

/// The name of the hidden temporary folder [`write_render`] makes inside the output folder
/// starts so (followed by the process id and a counter); none is left behind on return.
pub const TEMP_PREFIX: &str = ".dbuffer-render-";

/// `classes.png` colour of a pixel that saw no surface: black.
pub const NOT_HIT_RGB: [u8; 3] = [0, 0, 0];
/// `classes.png` colour of a lit pixel (V ≥ 1 − ε): light warm gray.
pub const LIT_RGB: [u8; 3] = [224, 218, 204];
/// `classes.png` colour of a penumbra pixel: mid orange.
pub const PENUMBRA_RGB: [u8; 3] = [230, 140, 40];
/// `classes.png` colour of an umbra pixel (V ≤ ε): dark blue.
pub const UMBRA_RGB: [u8; 3] = [30, 50, 130];

/// The `classes.png` colour of a shadow class (class 0 lit, 1 penumbra, 2 umbra):
///
/// | class | colour | RGB |
/// |---|---|---|
/// | lit (0) | light warm gray | (224, 218, 204) |
/// | penumbra (1) | mid orange | (230, 140, 40) |
/// | umbra (2) | dark blue | (30, 50, 130) |
/// | no surface hit | black | (0, 0, 0) |
pub fn class_rgb(class: ShadowClass) -> [u8; 3] {
    match class {
        ShadowClass::Lit => LIT_RGB,
        ShadowClass::Penumbra => PENUMBRA_RGB,
        ShadowClass::Umbra => UMBRA_RGB,
    }
}

/// Everything `dbuffer render` writes, read back from the GPU. Row-major, row 0 at the top.
#[derive(Clone, Debug)]
pub struct RenderOutputs {
    pub width: u32,
    pub height: u32,
    /// Shaded image, linear RGB in [0,1] (converted to sRGB 8-bit when written).
    pub color: Vec<[f32; 3]>,
    /// Visibility V per pixel in [0,1]; only meaningful where `hit`.
    pub visibility: Vec<f32>,
    /// The pixel saw a surface.
    pub hit: Vec<bool>,
    /// World position per pixel (meaningful where `hit`).
    pub position: Vec<[f32; 3]>,
    /// Shadow class per pixel where hit: 0 lit, 1 penumbra, 2 umbra (design.md §4 thresholds).
    pub class: Vec<u8>,
    /// The light-view D-buffer, `dbuffer_size`², row-major, row 0 at the top.
    pub dbuffer_size: u32,
    /// Per texel: |cx_o|, |cx_uv|, |cx_pv|, |cx_s| for the umbra volume, |cx_s| for the penumbra volume.
    /// Missing values (no surface, no volume along that ray) are `f32::INFINITY` for |cx_o| and 0 for the others.
    pub d_o: Vec<f32>,
    pub d_u: Vec<f32>,
    pub d_p: Vec<f32>,
    pub s_u: Vec<f32>,
    pub s_p: Vec<f32>,
    /// Everything for meta.json (see below).
    pub meta: RenderMeta,
}

impl RenderOutputs {
    /// A frame read back from the render core, as the files hold it: colour back to linear,
    /// shadow classes by the thresholds of design.md §4, the D-buffer's "no surface" as `+inf`.
    /// A frame without its D-buffer gets an empty one (0×0).
    pub fn from_frame(frame: &Frame, meta: RenderMeta) -> RenderOutputs {
        let hit: Vec<bool> = (0..frame.position.len()).map(|i| frame.hit(i)).collect();
        let class = frame
            .visibility
            .iter()
            .zip(&hit)
            .map(|(&v, &h)| match (h, ShadowClass::of(f64::from(v))) {
                (false, _) | (true, ShadowClass::Lit) => 0,
                (true, ShadowClass::Penumbra) => 1,
                (true, ShadowClass::Umbra) => 2,
            })
            .collect();
        let maps = frame.maps.as_ref();
        // A map with one channel (a line light's: the midpoint's shadow map) has no volume
        // channels: they read "no crossing" (0).
        let raw = |slot: usize, component: usize| {
            maps.map_or_else(Vec::new, |m| {
                if slot > 0 && m.channels.len() < 4 {
                    vec![0.0; m.size as usize * m.size as usize]
                } else {
                    m.raw(slot, component)
                }
            })
        };
        RenderOutputs {
            width: frame.width,
            height: frame.height,
            color: frame
                .color
                .iter()
                .map(|c| {
                    [
                        srgb8_to_linear(c[0]),
                        srgb8_to_linear(c[1]),
                        srgb8_to_linear(c[2]),
                    ]
                })
                .collect(),
            visibility: frame.visibility.clone(),
            hit,
            position: frame.position.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            class,
            dbuffer_size: maps.map_or(0, |m| m.size),
            d_o: raw(0, 0)
                .into_iter()
                .map(|d| {
                    if f64::from(d) >= NO_SURFACE * 0.5 {
                        f32::INFINITY
                    } else {
                        d
                    }
                })
                .collect(),
            d_u: raw(1, 0),
            d_p: raw(2, 0),
            s_u: raw(1, 1),
            s_p: raw(2, 1),
            meta,
        }
    }
}

/// `meta.json` of a frame rendered offline: the request, the adapter, the timings, the geometry
/// stage's counts and warnings (and whether the D-buffer's frustum had to cut a penumbra).
pub fn render_meta(
    name: &str,
    scene: &crate::scene::Scene,
    request: &crate::render::FrameRequest,
    ctx: &crate::render::GpuContext,
    frame: &Frame,
    report: &crate::render::offline::FrameReport,
) -> RenderMeta {
    let mut warnings = report.warnings.clone();
    if report.clipped {
        warnings.push(format!(
            "the casters' penumbrae reach beyond {}° from the D-buffer's axis; shadows there are cut",
            crate::geometry::light_view::MAX_HALF_ANGLE_DEG
        ));
    }
    let g = report.geometry;
    RenderMeta {
        scene: name.to_string(),
        method: request.method.name().to_string(),
        variant: request.vt.name().to_string(),
        width: frame.width,
        height: frame.height,
        dbuffer_size: frame.maps.as_ref().map_or(0, |m| m.size),
        adapter: ctx.adapter.name.clone(),
        backend: format!("{:?}", ctx.adapter.backend),
        cpu_ms: report.cpu_ms.clone(),
        gpu_ms: frame.gpu_ms.clone(),
        triangles: scene.objects.iter().map(|o| o.mesh.triangles.len()).sum(),
        caster_triangles: scene.caster_triangle_count(),
        umbra_silhouette_edges: g.umbra_edges,
        penumbra_silhouette_edges: g.penumbra_edges,
        umbra_volume_triangles: g.umbra_triangles,
        penumbra_volume_triangles: g.penumbra_triangles,
        warnings,
    }
}

/// The sRGB transfer function, inverted: [`linear_to_srgb8`] takes it back to the same byte.
pub fn srgb8_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// What `meta.json` holds. The two timing lists are written as JSON objects in their order,
/// `{"geometry": 0.4, ...}`; a name that repeats gets ` #2`, ` #3`, ... so that no timing is lost,
/// and a non-finite time is written as `null`.
#[derive(serde::Serialize, Clone, Debug)]
pub struct RenderMeta {
    pub scene: String,
    pub method: String,
    pub variant: String,
    pub width: u32,
    pub height: u32,
    pub dbuffer_size: u32,
    pub adapter: String,
    pub backend: String,
    /// Per stage, e.g. [("geometry", 0.4)], CPU milliseconds.
    #[serde(serialize_with = "ms_map")]
    pub cpu_ms: Vec<(String, f64)>,
    /// Per GPU pass, GPU milliseconds from timestamp queries (empty if the adapter has none).
    #[serde(serialize_with = "ms_map")]
    pub gpu_ms: Vec<(String, f64)>,
    pub triangles: usize,
    pub caster_triangles: usize,
    pub umbra_silhouette_edges: usize,
    pub penumbra_silhouette_edges: usize,
    pub umbra_volume_triangles: usize,
    pub penumbra_volume_triangles: usize,
    pub warnings: Vec<String>,
}

/// A list of (name, milliseconds) as a JSON object in list order; repeated names get ` #k`.
fn ms_map<S: Serializer>(list: &[(String, f64)], s: S) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(list.len()))?;
    for (i, (name, ms)) in list.iter().enumerate() {
        let earlier = list[..i].iter().filter(|(n, _)| n == name).count();
        if earlier == 0 {
            map.serialize_entry(name, ms)?;
        } else {
            map.serialize_entry(&format!("{name} #{}", earlier + 1), ms)?;
        }
    }
    map.end()
}

impl RenderMeta {
    /// The text of `meta.json`: pretty-printed, with a final newline.
    pub fn to_json_pretty(&self) -> Result<String, serde_json::Error> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        Ok(text)
    }
}

/// Why a render's files could not be written or read; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{file}: {field} is 0; it must be positive")]
    ZeroSize {
        file: &'static str,
        field: &'static str,
    },
    #[error("{file}: {width}x{height} is too large")]
    TooLarge {
        file: &'static str,
        width: u32,
        height: u32,
    },
    #[error("{file}: {field} has {found} values, expected {expected} ({width}x{height})")]
    Length {
        file: &'static str,
        field: &'static str,
        found: usize,
        expected: usize,
        width: u32,
        height: u32,
    },
    #[error("meta.json: meta.{field} is {in_meta} but the render outputs have {actual}")]
    MetaMismatch {
        field: &'static str,
        in_meta: u32,
        actual: u32,
    },
    #[error(
        "classes.png: pixel ({x}, {y}) has class {class}; expected 0 (lit), 1 (penumbra) or 2 (umbra)"
    )]
    BadClass { x: u32, y: u32, class: u8 },
    #[error("{}: exists and is not a directory", path.display())]
    NotADirectory { path: PathBuf },
    #[error("{}: is a directory; it cannot be replaced by a render output file", path.display())]
    TargetIsDirectory { path: PathBuf },
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        source: io::Error,
    },
    #[error("{}: cannot encode: {source}", path.display())]
    Encode {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("{}: cannot write JSON: {source}", path.display())]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("{}: cannot read as an RGBA float EXR: {source}", path.display())]
    Decode {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error(
        "{}: {cause}; putting the previous files back failed too ({rollback}), \
         they are kept in {}",
        dir.display(),
        temp.display()
    )]
    RollbackFailed {
        dir: PathBuf,
        temp: PathBuf,
        cause: Box<OutputError>,
        rollback: io::Error,
    },
}

fn io_err(path: &Path, action: &'static str) -> impl FnOnce(io::Error) -> OutputError {
    let path = path.to_path_buf();
    move |source| OutputError::Io {
        path,
        action,
        source,
    }
}

/// Linear [0, 1] to 8-bit sRGB with the sRGB transfer function (IEC 61966-2-1: `12.92 c` up to
/// 0.0031308, `1.055 c^(1/2.4) − 0.055` above), rounded to nearest. Values outside [0, 1] are
/// clamped; NaN becomes 0. 0 → 0, 0.5 → 188, 1 → 255.
pub fn linear_to_srgb8(c: f32) -> u8 {
    if c.is_nan() {
        return 0;
    }
    let c = f64::from(c.clamp(0.0, 1.0));
    let s = if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    // In [0, 255] by the clamp above.
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Write one render's files into `dir` (created with its parents if missing), all or nothing
/// (see the module docs). Returns the paths written, in the order of [`FILE_NAMES`].
///
/// The input is checked first: positive sizes, every per-pixel list `width·height` long, every
/// D-buffer list `dbuffer_size²` long, `meta`'s sizes equal to the outputs', class 0–2 at every
/// hit pixel. Nothing is touched on disk unless it passes.
pub fn write_render(dir: &Path, out: &RenderOutputs) -> Result<Vec<PathBuf>, OutputError> {
    write_render_with(dir, out, &mut |_| Ok(()))
}

/// A point where writing can fail; the tests inject failures there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    /// Writing file `i` of [`FILE_NAMES`] into the temporary folder.
    Stage(usize),
    /// Keeping a backup of the previous file `i`.
    Backup(usize),
    /// Renaming file `i` into the output folder.
    Install(usize),
}

type Fault<'a> = dyn FnMut(Step) -> io::Result<()> + 'a;

fn write_render_with(
    dir: &Path,
    out: &RenderOutputs,
    fault: &mut Fault<'_>,
) -> Result<Vec<PathBuf>, OutputError> {
    validate(out)?;
    let names: Vec<String> = FILE_NAMES.iter().map(|n| n.to_string()).collect();
    prepare_dir(dir, &names)?;
    let temp = create_temp_dir(dir)?;
    if let Err(e) = stage(dir, &temp, out, fault) {
        let _ = fs::remove_dir_all(&temp);
        return Err(e);
    }
    finish(dir, temp, &names, &[], fault)
}

/// The output folder exists (created with its parents if missing) and is a folder, and none of
/// `names` in it is a folder.
fn prepare_dir(dir: &Path, names: &[String]) -> Result<(), OutputError> {
    match fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(OutputError::NotADirectory {
                path: dir.to_path_buf(),
            })
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            fs::create_dir_all(dir).map_err(io_err(dir, "create the directory"))?
        }
        Err(e) => return Err(io_err(dir, "read")(e)),
    }
    for name in names {
        let target = dir.join(name);
        if fs::symlink_metadata(&target).is_ok_and(|m| m.is_dir()) {
            return Err(OutputError::TargetIsDirectory { path: target });
        }
    }
    Ok(())
}

/// Move the staged `names` from `temp` into `dir` and remove `stale` from it, all or nothing;
/// `temp` is removed unless putting things back failed (then it keeps the previous files).
fn finish(
    dir: &Path,
    temp: PathBuf,
    names: &[String],
    stale: &[String],
    fault: &mut Fault<'_>,
) -> Result<Vec<PathBuf>, OutputError> {
    match install(dir, &temp, names, stale, fault) {
        Ok(paths) => {
            let _ = fs::remove_dir_all(&temp);
            // Make the renames durable where the platform can (best effort: not on Windows).
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
            Ok(paths)
        }
        Err(InstallError::RolledBack(e)) => {
            let _ = fs::remove_dir_all(&temp);
            Err(e)
        }
        Err(InstallError::Stuck(cause, rollback)) => Err(OutputError::RollbackFailed {
            dir: dir.to_path_buf(),
            temp,
            cause: Box::new(cause),
            rollback,
        }),
    }
}

/// Any set of files written into one folder all or nothing, by the same rules as
/// [`write_render`]: each file is written (and flushed) into a hidden folder inside `dir` as it
/// is [`add`](Staged::add)ed, so a long job holds only one file in memory at a time; nothing in
/// `dir` changes until [`commit`](Staged::commit), which moves them all into place (and removes
/// the files named [`stale`](Staged::remove_on_commit)), or puts everything back as it was. A
/// `Staged` dropped without a commit leaves `dir` untouched.
pub struct Staged {
    dir: PathBuf,
    temp: Option<PathBuf>,
    names: Vec<String>,
    stale: Vec<String>,
}

impl Staged {
    /// Start writing into `dir` (created with its parents if missing; an error if it is not a
    /// folder).
    pub fn new(dir: &Path) -> Result<Staged, OutputError> {
        prepare_dir(dir, &[])?;
        let temp = create_temp_dir(dir)?;
        Ok(Staged {
            dir: dir.to_path_buf(),
            temp: Some(temp),
            names: Vec::new(),
            stale: Vec::new(),
        })
    }

    /// Stage file `name` (a plain file name, no folders) with `bytes`.
    pub fn add(&mut self, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
        let target = self.dir.join(name);
        let plain = Path::new(name).file_name().is_some_and(|n| n == name);
        if !plain || name.starts_with(TEMP_PREFIX) || self.names.iter().any(|n| n == name) {
            return Err(io_err(&target, "write")(io::Error::new(
                io::ErrorKind::InvalidInput,
                "expected a new plain file name",
            )));
        }
        if fs::symlink_metadata(&target).is_ok_and(|m| m.is_dir()) {
            return Err(OutputError::TargetIsDirectory { path: target });
        }
        let Some(temp) = &self.temp else {
            return Err(io_err(&target, "write")(io::Error::other(
                "already committed",
            )));
        };
        let result = (|| {
            let mut f = File::create(temp.join(name))?;
            f.write_all(bytes)?;
            f.sync_all()
        })();
        result.map_err(io_err(&target, "write"))?;
        self.names.push(name.to_string());
        Ok(())
    }

    /// Remove file `name` from `dir` when committing (a previous run's file the new set does
    /// not replace); put back if the commit fails.
    pub fn remove_on_commit(&mut self, name: &str) {
        if !self.names.iter().any(|n| n == name) && !self.stale.iter().any(|n| n == name) {
            self.stale.push(name.to_string());
        }
    }

    /// Move every staged file into place, all or nothing. Returns their paths in the order
    /// they were added.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, OutputError> {
        let Some(temp) = self.temp.take() else {
            return Ok(Vec::new());
        };
        let stale: Vec<String> = self
            .stale
            .iter()
            .filter(|n| fs::symlink_metadata(self.dir.join(n)).is_ok_and(|m| m.is_file()))
            .cloned()
            .collect();
        finish(&self.dir, temp, &self.names, &stale, &mut |_| Ok(()))
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let _ = fs::remove_dir_all(temp);
        }
    }
}

/// `n = a·b` as a count of values, or `TooLarge` naming `file`.
fn count(file: &'static str, width: u32, height: u32) -> Result<usize, OutputError> {
    usize::try_from(u64::from(width) * u64::from(height)).map_err(|_| OutputError::TooLarge {
        file,
        width,
        height,
    })
}

fn validate(out: &RenderOutputs) -> Result<(), OutputError> {
    let (w, h, ds) = (out.width, out.height, out.dbuffer_size);
    for (field, value) in [("width", w), ("height", h)] {
        if value == 0 {
            return Err(OutputError::ZeroSize {
                file: IMAGE_PNG,
                field,
            });
        }
    }
    if ds == 0 {
        return Err(OutputError::ZeroSize {
            file: DBUFFER_EXR,
            field: "dbuffer_size",
        });
    }
    let n = count(IMAGE_PNG, w, h)?;
    let nd = count(DBUFFER_EXR, ds, ds)?;
    let lengths = [
        (IMAGE_PNG, "color", out.color.len(), n, w, h),
        (VISIBILITY_EXR, "visibility", out.visibility.len(), n, w, h),
        (VISIBILITY_EXR, "hit", out.hit.len(), n, w, h),
        (POSITION_EXR, "position", out.position.len(), n, w, h),
        (CLASSES_PNG, "class", out.class.len(), n, w, h),
        (DBUFFER_EXR, "d_o", out.d_o.len(), nd, ds, ds),
        (DBUFFER_EXR, "d_u", out.d_u.len(), nd, ds, ds),
        (DBUFFER_EXR, "d_p", out.d_p.len(), nd, ds, ds),
        (DBUFFER_EXR, "s_u", out.s_u.len(), nd, ds, ds),
        (DBUFFER_S_EXR, "s_p", out.s_p.len(), nd, ds, ds),
    ];
    for (file, field, found, expected, width, height) in lengths {
        if found != expected {
            return Err(OutputError::Length {
                file,
                field,
                found,
                expected,
                width,
                height,
            });
        }
    }
    let meta = &out.meta;
    for (field, in_meta, actual) in [
        ("width", meta.width, w),
        ("height", meta.height, h),
        ("dbuffer_size", meta.dbuffer_size, ds),
    ] {
        if in_meta != actual {
            return Err(OutputError::MetaMismatch {
                field,
                in_meta,
                actual,
            });
        }
    }
    let bad_class = out
        .hit
        .iter()
        .zip(&out.class)
        .position(|(&hit, &c)| hit && usize::from(c) >= ShadowClass::ALL.len());
    if let Some(i) = bad_class {
        // i < w·h, both u32, so x and y fit.
        let (x, y) = ((i % w as usize) as u32, (i / w as usize) as u32);
        return Err(OutputError::BadClass {
            x,
            y,
            class: out.class[i],
        });
    }
    Ok(())
}

/// A fresh `dir/.dbuffer-render-PID-N`.
fn create_temp_dir(dir: &Path) -> Result<PathBuf, OutputError> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let mut last = dir.join(TEMP_PREFIX);
    for _ in 0..100 {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        last = dir.join(format!("{TEMP_PREFIX}{}-{n}", std::process::id()));
        match fs::create_dir(&last) {
            Ok(()) => return Ok(last),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io_err(&last, "create a temporary directory")(e)),
        }
    }
    Err(io_err(&last, "create a temporary directory")(
        io::Error::new(io::ErrorKind::AlreadyExists, "100 names tried, all taken"),
    ))
}

/// Encode every file into `temp`, flushed to disk. Errors name the file's place in `dir`.
fn stage(
    dir: &Path,
    temp: &Path,
    out: &RenderOutputs,
    fault: &mut Fault<'_>,
) -> Result<(), OutputError> {
    for (i, name) in FILE_NAMES.iter().enumerate() {
        let target = dir.join(name);
        let bytes = encode(name, &target, out)?;
        let result = fault(Step::Stage(i)).and_then(|()| {
            let mut f = File::create(temp.join(name))?;
            f.write_all(&bytes)?;
            f.sync_all()
        });
        result.map_err(io_err(&target, "write"))?;
    }
    Ok(())
}

/// The bytes of file `name`.
fn encode(name: &str, target: &Path, out: &RenderOutputs) -> Result<Vec<u8>, OutputError> {
    let (w, h, ds) = (out.width, out.height, out.dbuffer_size);
    let alpha = |i: usize| if out.hit[i] { 1.0 } else { 0.0 };
    let encoded = match name {
        IMAGE_PNG => {
            let bytes: Vec<u8> = out
                .color
                .iter()
                .flat_map(|c| c.map(linear_to_srgb8))
                .collect();
            png_rgb8(w, h, &bytes)
        }
        VISIBILITY_EXR => exr_rgba32f(
            w,
            h,
            out.visibility
                .iter()
                .enumerate()
                .map(|(i, &v)| [v, v, v, alpha(i)]),
        ),
        POSITION_EXR => exr_rgba32f(
            w,
            h,
            out.position
                .iter()
                .enumerate()
                .map(|(i, p)| [p[0], p[1], p[2], alpha(i)]),
        ),
        DBUFFER_EXR => exr_rgba32f(
            ds,
            ds,
            (0..out.d_o.len()).map(|i| [out.d_o[i], out.d_u[i], out.d_p[i], out.s_u[i]]),
        ),
        DBUFFER_S_EXR => exr_rgba32f(
            ds,
            ds,
            (0..out.s_u.len()).map(|i| [out.s_u[i], out.s_p[i], 0.0, 1.0]),
        ),
        CLASSES_PNG => {
            let bytes: Vec<u8> = (0..out.class.len())
                .flat_map(|i| {
                    // Checked in `validate`: a hit pixel's class is 0, 1 or 2.
                    let class = ShadowClass::ALL.get(usize::from(out.class[i]));
                    match (out.hit[i], class) {
                        (true, Some(&c)) => class_rgb(c),
                        _ => NOT_HIT_RGB,
                    }
                })
                .collect();
            png_rgb8(w, h, &bytes)
        }
        META_JSON => {
            return out
                .meta
                .to_json_pretty()
                .map(String::into_bytes)
                .map_err(|source| OutputError::Json {
                    path: target.to_path_buf(),
                    source,
                })
        }
        other => {
            let msg = format!("{other} is not a render output file");
            return Err(io_err(target, "encode")(io::Error::other(msg)));
        }
    };
    encoded.map_err(|source| OutputError::Encode {
        path: target.to_path_buf(),
        source,
    })
}

/// A PNG of 8-bit RGB `bytes` (`3·w·h` of them, checked by `validate`).
pub fn png_rgb8(w: u32, h: u32, bytes: &[u8]) -> image::ImageResult<Vec<u8>> {
    let mut png = Vec::new();
    PngEncoder::new(&mut png).write_image(bytes, w, h, ExtendedColorType::Rgb8)?;
    Ok(png)
}

/// An uncompressed RGBA f32 EXR of `w·h` pixels (the count is checked by `validate`).
pub fn exr_rgba32f(
    w: u32,
    h: u32,
    pixels: impl Iterator<Item = [f32; 4]>,
) -> image::ImageResult<Vec<u8>> {
    let raw: Vec<u8> = pixels.flatten().flat_map(f32::to_ne_bytes).collect();
    let mut exr = Cursor::new(Vec::new());
    OpenExrEncoder::new(&mut exr).write_image(&raw, w, h, ExtendedColorType::Rgba32F)?;
    Ok(exr.into_inner())
}

enum InstallError {
    /// Failed; the output folder is as it was.
    RolledBack(OutputError),
    /// Failed, and putting the previous files back failed too.
    Stuck(OutputError, io::Error),
}

/// Back up the previous files into `temp`, then rename the new ones over them and remove the
/// `stale` ones; on failure, put the previous files back. Step indices count `names` first,
/// then `stale`.
fn install(
    dir: &Path,
    temp: &Path,
    names: &[String],
    stale: &[String],
    fault: &mut Fault<'_>,
) -> Result<Vec<PathBuf>, InstallError> {
    let backup_of = |name: &str| temp.join(format!("{name}.previous"));
    let all: Vec<&String> = names.iter().chain(stale).collect();
    let mut had_previous = vec![false; all.len()];
    for (i, name) in all.iter().enumerate() {
        let target = dir.join(name);
        match fs::symlink_metadata(&target) {
            Ok(_) => {
                let backup = backup_of(name);
                fault(Step::Backup(i))
                    .and_then(|()| {
                        fs::hard_link(&target, &backup)
                            .or_else(|_| fs::copy(&target, &backup).map(drop))
                    })
                    .map_err(|e| InstallError::RolledBack(io_err(&target, "back up")(e)))?;
                had_previous[i] = true;
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(InstallError::RolledBack(io_err(&target, "read")(e))),
        }
    }
    let mut paths = Vec::with_capacity(names.len());
    for (i, name) in all.iter().enumerate() {
        let target = dir.join(name);
        let installing = i < names.len();
        let moved = fault(Step::Install(i)).and_then(|()| {
            if installing {
                fs::rename(temp.join(name), &target)
            } else {
                fs::remove_file(&target)
            }
        });
        if let Err(e) = moved {
            let action = if installing {
                "move into place"
            } else {
                "remove"
            };
            let cause = io_err(&target, action)(e);
            // Undo steps 0..i, last first.
            let mut undo = Ok(());
            for (j, name) in all.iter().enumerate().take(i).rev() {
                let target = dir.join(name);
                let step = if had_previous[j] {
                    fs::rename(backup_of(name), &target)
                } else {
                    fs::remove_file(&target)
                };
                if undo.is_ok() {
                    undo = step;
                }
            }
            return Err(match undo {
                Ok(()) => InstallError::RolledBack(cause),
                Err(rollback) => InstallError::Stuck(cause, rollback),
            });
        }
        if installing {
            paths.push(target);
        }
    }
    Ok(paths)
}

/// Read an RGBA (or RGB: A = 1) 32-bit float EXR: width, height and the pixels, row-major, row 0
/// at the top, exactly as stored.
pub fn read_exr_rgba(path: &Path) -> Result<(u32, u32, Vec<[f32; 4]>), OutputError> {
    let decode_err = |source| OutputError::Decode {
        path: path.to_path_buf(),
        source,
    };
    let file = File::open(path).map_err(io_err(path, "open"))?;
    let decoder = OpenExrDecoder::with_alpha_preference(BufReader::new(file), Some(true))
        .map_err(decode_err)?;
    let (w, h) = decoder.dimensions();
    let too_large = || {
        decode_err(image::ImageError::Limits(
            image::error::LimitError::from_kind(image::error::LimitErrorKind::InsufficientMemory),
        ))
    };
    let len = usize::try_from(decoder.total_bytes()).map_err(|_| too_large())?;
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(len).map_err(|_| too_large())?;
    bytes.resize(len, 0);
    decoder.read_image(&mut bytes).map_err(decode_err)?;
    let pixels = bytes
        .chunks_exact(16)
        .map(|p| {
            let mut px = [0.0f32; 4];
            for (c, b) in px.iter_mut().zip(p.chunks_exact(4)) {
                *c = f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
            }
            px
        })
        .collect();
    Ok((w, h, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_through_the_writer() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(c)), c);
        }
    }

    fn temp_dir(tag: &str) -> PathBuf {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let dir = std::env::temp_dir().join(format!(
            "dbuffer-output-unit-{}-{}-{tag}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn meta(w: u32, h: u32, ds: u32) -> RenderMeta {
        RenderMeta {
            scene: "unit".into(),
            method: "dbuffer".into(),
            variant: "smoothstep".into(),
            width: w,
            height: h,
            dbuffer_size: ds,
            adapter: "none".into(),
            backend: "none".into(),
            cpu_ms: vec![("geometry".into(), 0.5)],
            gpu_ms: vec![],
            triangles: 1,
            caster_triangles: 1,
            umbra_silhouette_edges: 0,
            penumbra_silhouette_edges: 0,
            umbra_volume_triangles: 0,
            penumbra_volume_triangles: 0,
            warnings: vec![],
        }
    }

    fn outputs(w: u32, h: u32, ds: u32, value: f32) -> RenderOutputs {
        let n = (w * h) as usize;
        let nd = (ds * ds) as usize;
        RenderOutputs {
            width: w,
            height: h,
            color: vec![[value; 3]; n],
            visibility: vec![value; n],
            hit: vec![true; n],
            position: vec![[value; 3]; n],
            class: vec![1; n],
            dbuffer_size: ds,
            d_o: vec![value; nd],
            d_u: vec![value; nd],
            d_p: vec![value; nd],
            s_u: vec![value; nd],
            s_p: vec![value; nd],
            meta: meta(w, h, ds),
        }
    }

    /// Every file name → its bytes, plus the names of anything else in `dir`.
    fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
        let mut entries: Vec<(String, Vec<u8>)> = fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let bytes = fs::read(e.path()).unwrap_or_default();
                (e.file_name().to_string_lossy().into_owned(), bytes)
            })
            .collect();
        entries.sort();
        entries
    }

    #[test]
    fn srgb_known_values() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(0.5), 188);
        assert_eq!(linear_to_srgb8(1.0), 255);
        // The linear segment: 0.002 · 12.92 · 255 = 6.59.
        assert_eq!(linear_to_srgb8(0.002), 7);
        // 0.18 (mid gray) is 118 in sRGB; gamma 2.2 would give 117.
        assert_eq!(linear_to_srgb8(0.18), 118);
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(2.0), 255);
        assert_eq!(linear_to_srgb8(f32::INFINITY), 255);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        // Monotone over the whole range.
        let mut last = 0;
        for i in 0..=1000 {
            let s = linear_to_srgb8(i as f32 / 1000.0);
            assert!(s >= last);
            last = s;
        }
    }

    #[test]
    fn timings_are_objects_in_order_and_repeats_are_kept() {
        let mut m = meta(1, 1, 1);
        m.cpu_ms = vec![
            ("load".into(), 1.0),
            ("geometry".into(), 2.5),
            ("load".into(), 3.0),
            ("nan".into(), f64::NAN),
        ];
        let text = m.to_json_pretty().unwrap();
        let load = text.find("\"load\": 1.0").unwrap();
        let geometry = text.find("\"geometry\": 2.5").unwrap();
        let again = text.find("\"load #2\": 3.0").unwrap();
        assert!(load < geometry && geometry < again, "{text}");
        assert!(text.contains("\"nan\": null"), "{text}");
        assert!(text.contains("\"gpu_ms\": {}"), "{text}");
        assert!(text.ends_with("}\n"));
    }

    /// `Staged`: nothing changes before the commit; the commit replaces, adds and removes the
    /// stale files; a stale file failing to go puts everything back.
    #[test]
    fn staged_files_are_all_or_nothing() {
        let dir = temp_dir("staged");
        for name in [
            "frame-0000.png",
            "frame-0001.png",
            "frame-0002.png",
            "notes.txt",
        ] {
            fs::write(dir.join(name), b"old").unwrap();
        }
        let before = snapshot(&dir);
        let mut staged = Staged::new(&dir).unwrap();
        staged.add("frame-0000.png", b"new0").unwrap();
        staged.add("frame-0001.png", b"new1").unwrap();
        assert!(
            staged.add("frame-0001.png", b"again").is_err(),
            "a name twice"
        );
        assert!(
            staged.add("../escape.png", b"x").is_err(),
            "a path, not a name"
        );
        staged.remove_on_commit("frame-0002.png");
        assert_eq!(
            snapshot(&dir).len(),
            before.len() + 1,
            "only the hidden folder is new"
        );
        drop(staged);
        assert_eq!(snapshot(&dir), before, "dropped without commit: untouched");

        let mut staged = Staged::new(&dir).unwrap();
        staged.add("frame-0000.png", b"new0").unwrap();
        staged.add("frame-0001.png", b"new1").unwrap();
        staged.add("loop.png", b"anim").unwrap();
        staged.remove_on_commit("frame-0002.png");
        staged.remove_on_commit("frame-0009.png");
        let paths = staged.commit().unwrap();
        assert_eq!(paths.len(), 3);
        let after = snapshot(&dir);
        let names: Vec<&str> = after.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            ["frame-0000.png", "frame-0001.png", "loop.png", "notes.txt"]
        );
        assert_eq!(fs::read(dir.join("frame-0001.png")).unwrap(), b"new1");

        // A failing removal of a stale file undoes the installs (the generic install with a
        // fault at the last step).
        let before = snapshot(&dir);
        let temp = create_temp_dir(&dir).unwrap();
        fs::write(temp.join("frame-0000.png"), b"newer").unwrap();
        let names = vec!["frame-0000.png".to_string()];
        let stale = vec!["frame-0001.png".to_string()];
        let err = finish(&dir, temp, &names, &stale, &mut |step| {
            if step == Step::Install(1) {
                Err(io::Error::other("injected"))
            } else {
                Ok(())
            }
        })
        .unwrap_err();
        assert!(err.to_string().contains("frame-0001.png"), "{err}");
        assert_eq!(snapshot(&dir), before);
        let _ = fs::remove_dir_all(&dir);
    }

    /// A failure at any point of writing leaves the folder as it was, with no temporary folder,
    /// both when the folder held a previous render and when it held only unrelated files.
    #[test]
    fn a_failure_at_any_step_leaves_the_folder_as_it_was() {
        let steps: Vec<Step> = (0..FILE_NAMES.len())
            .flat_map(|i| [Step::Stage(i), Step::Backup(i), Step::Install(i)])
            .collect();
        for previous in [true, false] {
            let dir = temp_dir("fault");
            fs::write(dir.join("notes.txt"), b"keep me").unwrap();
            if previous {
                write_render(&dir, &outputs(3, 2, 2, 0.25)).unwrap();
            }
            let before = snapshot(&dir);
            for &fail_at in &steps {
                let mut seen = false;
                let result = write_render_with(&dir, &outputs(3, 2, 2, 0.75), &mut |step| {
                    if step == fail_at {
                        seen = true;
                        Err(io::Error::other("injected"))
                    } else {
                        Ok(())
                    }
                });
                // Backups happen only when there is a previous file.
                let reachable = previous || !matches!(fail_at, Step::Backup(_));
                assert_eq!(seen, reachable, "{fail_at:?}");
                if !reachable {
                    result.unwrap();
                    for name in FILE_NAMES {
                        fs::remove_file(dir.join(name)).unwrap();
                    }
                    continue;
                }
                let err = result.unwrap_err();
                let msg = err.to_string();
                assert!(msg.contains("injected"), "{fail_at:?}: {msg}");
                let i = match fail_at {
                    Step::Stage(i) | Step::Backup(i) | Step::Install(i) => i,
                };
                assert!(msg.contains(FILE_NAMES[i]), "{fail_at:?}: {msg}");
                assert!(
                    matches!(err, OutputError::Io { .. }),
                    "{fail_at:?}: {err:?}"
                );
                assert_eq!(snapshot(&dir), before, "{fail_at:?}, previous {previous}");
            }
            // And with no failure the new render replaces the old one completely.
            write_render(&dir, &outputs(3, 2, 2, 0.75)).unwrap();
            let after = snapshot(&dir);
            let names: Vec<&str> = after.iter().map(|(n, _)| n.as_str()).collect();
            let mut expected: Vec<&str> = FILE_NAMES.to_vec();
            expected.push("notes.txt");
            expected.sort();
            assert_eq!(names, expected);
            let (_, _, v) = read_exr_rgba(&dir.join(VISIBILITY_EXR)).unwrap();
            assert!(v.iter().all(|p| p[0] == 0.75));
            let _ = fs::remove_dir_all(&dir);
        }
    }
}
