//! Writing one render's files (docs/guide/outputs.md), all or nothing.
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
//! Every EXR is 32-bit float, losslessly compressed (RLE, as the `image` crate writes them), row
//! 0 at the top, and holds exactly the values given:
//! they read back bit for bit ([`read_exr_rgba`]), infinity and NaN included. In particular a
//! missing |cx_o| stays `+inf` in `dbuffer.exr` (the EXR format and the `image` crate's encoder
//! both take it as it is; no large finite stand-in is needed).
//!
//! **Streamed.** Each file is encoded straight to disk, a PNG row or an EXR block at a time, from
//! a [`PixelSource`] and the D-buffer's [`DBufferRows`]: `dbuffer render` writes from the frame
//! it read back ([`FramePixels`], 16 bytes a pixel) and reads the D-buffer from the GPU in bands
//! ([`BandedRows`]), so an 8192² image with an 8192² D-buffer is written without a second copy
//! of either.
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
    /// Shadow class per pixel where hit: 0 lit, 1 penumbra, 2 umbra (the thresholds of docs/method/metrics.md).
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
    /// shadow classes by the thresholds of docs/method/metrics.md, the D-buffer's "no surface" as `+inf`.
    /// A frame without its D-buffer gets an empty one (0×0).
    pub fn from_frame(frame: &Frame, meta: RenderMeta) -> RenderOutputs {
        let hit: Vec<bool> = (0..frame.len()).map(|i| frame.hit(i)).collect();
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
            position: (0..frame.len())
                .map(|i| frame.position(i).map_or([0.0; 3], |p| p.to_array()))
                .collect(),
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

/// Why a render's files could not be written or read; every message names the file, on one line,
/// and includes its cause's (so no variant reports a `source()`: `{:#}` would repeat it).
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
    #[error(
        "{}: exists and is {kind}, not a directory (the output is a folder of files)",
        path.display()
    )]
    NotADirectory { path: PathBuf, kind: &'static str },
    #[error("{}: cannot write there: {error}", path.display())]
    Unwritable { path: PathBuf, error: io::Error },
    #[error("{}: is a directory; it cannot be replaced by a render output file", path.display())]
    TargetIsDirectory { path: PathBuf },
    #[error("{}: cannot {action}: {error}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        error: io::Error,
    },
    #[error("{}: cannot encode: {error}", path.display())]
    Encode {
        path: PathBuf,
        error: image::ImageError,
    },
    #[error("{}: cannot write JSON: {error}", path.display())]
    Json {
        path: PathBuf,
        error: serde_json::Error,
    },
    #[error("{}: cannot read as an RGBA float EXR: {error}", path.display())]
    Decode {
        path: PathBuf,
        error: image::ImageError,
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
    move |error| OutputError::Io {
        path,
        action,
        error,
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
    write_parts_with(dir, &out.meta, out, &mut VecRows(out), fault)
}

/// Write a render's files from its parts, all or nothing (as [`write_render`]): the pixels,
/// and the D-buffer a row at a time. Each file is streamed to disk as it is encoded, so the
/// only memory this takes beyond what `pixels` holds is a few rows (an 8192² render's files
/// are written without a second copy of the frame, and the D-buffer is never held whole when
/// `dbuffer` reads it in bands).
pub fn write_render_parts(
    dir: &Path,
    meta: &RenderMeta,
    pixels: &dyn PixelSource,
    dbuffer: &mut dyn DBufferRows,
) -> Result<Vec<PathBuf>, OutputError> {
    write_parts_with(dir, meta, pixels, dbuffer, &mut |_| Ok(()))
}

fn write_parts_with(
    dir: &Path,
    meta: &RenderMeta,
    pixels: &dyn PixelSource,
    dbuffer: &mut dyn DBufferRows,
    fault: &mut Fault<'_>,
) -> Result<Vec<PathBuf>, OutputError> {
    check_out_dir(dir, &FILE_NAMES)?;
    let created = NewDirs::create(dir).map_err(io_err(dir, "create the directory"))?;
    let result = write_into(dir, meta, pixels, dbuffer, fault);
    if result.is_err() {
        // A folder this call made is not left behind (it is empty again by now).
        created.remove_if_empty();
    }
    result
}

fn write_into(
    dir: &Path,
    meta: &RenderMeta,
    pixels: &dyn PixelSource,
    dbuffer: &mut dyn DBufferRows,
    fault: &mut Fault<'_>,
) -> Result<Vec<PathBuf>, OutputError> {
    let names: Vec<String> = FILE_NAMES.iter().map(|n| n.to_string()).collect();
    let temp = create_temp_dir(dir)?;
    if let Err(e) = stage(dir, &temp, meta, pixels, dbuffer, fault) {
        let _ = fs::remove_dir_all(&temp);
        return Err(e);
    }
    finish(dir, temp, &names, &[], fault)
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
    /// The folders `new` made: taken away again if nothing is committed.
    created: NewDirs,
}

impl Staged {
    /// Start writing into `dir` (checked first, as [`check_out_dir`] does; created with its
    /// parents if missing, and removed again if nothing is committed).
    pub fn new(dir: &Path) -> Result<Staged, OutputError> {
        check_out_dir(dir, &[])?;
        let created = NewDirs::create(dir).map_err(io_err(dir, "create the directory"))?;
        let temp = match create_temp_dir(dir) {
            Ok(t) => t,
            Err(e) => {
                created.remove_if_empty();
                return Err(e);
            }
        };
        Ok(Staged {
            dir: dir.to_path_buf(),
            temp: Some(temp),
            names: Vec::new(),
            stale: Vec::new(),
            created,
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
            self.created.remove_if_empty();
        }
    }
}

/// What `meta` describes, for messages.
fn kind_of(meta: &fs::Metadata) -> &'static str {
    if meta.is_file() {
        "a regular file"
    } else if meta.is_dir() {
        "a directory"
    } else if meta.file_type().is_symlink() {
        "a symbolic link"
    } else {
        "a device, FIFO or socket"
    }
}

/// Checks an output folder before any work is done: `dir` is a directory, or does not exist
/// and its nearest existing ancestor is a directory it can be created in; files can be
/// created there; none of `files` (names inside `dir`) is a directory. Creates nothing (a probe
/// file is made and removed to test that the place is writable).
pub fn check_out_dir(dir: &Path, files: &[&str]) -> Result<(), OutputError> {
    let mut place = dir.to_path_buf();
    loop {
        match fs::metadata(&place) {
            Ok(m) if m.is_dir() => break,
            Ok(m) => {
                return Err(OutputError::NotADirectory {
                    path: place,
                    kind: kind_of(&m),
                })
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::NotFound | io::ErrorKind::NotADirectory
                ) =>
            {
                // `dir` will be created: its parent must exist or be created too (and if a
                // file stands in the way, the walk up finds it).
                match place.parent() {
                    Some(p) if !p.as_os_str().is_empty() => place = p.to_path_buf(),
                    Some(_) if place != Path::new(".") => place = PathBuf::from("."),
                    _ => return Err(io_err(&place, "read")(e)),
                }
            }
            Err(e) => return Err(io_err(&place, "read")(e)),
        }
    }
    probe_writable(&place).map_err(|error| OutputError::Unwritable {
        path: place.clone(),
        error,
    })?;
    if place == dir {
        for name in files {
            let target = dir.join(name);
            if fs::symlink_metadata(&target).is_ok_and(|m| m.is_dir()) {
                return Err(OutputError::TargetIsDirectory { path: target });
            }
        }
    }
    Ok(())
}

/// Checks an output file before any work is done: `path` does not exist or is a regular file
/// (never a device such as `/dev/null`, a FIFO or a directory, which writing would replace),
/// and its folder exists and files can be created in it.
pub fn check_out_file(path: &Path) -> Result<(), OutputError> {
    match fs::metadata(path) {
        Ok(m) if m.is_file() => {}
        Ok(m) if m.is_dir() => {
            return Err(OutputError::TargetIsDirectory {
                path: path.to_path_buf(),
            })
        }
        Ok(m) => {
            return Err(OutputError::Unwritable {
                path: path.to_path_buf(),
                error: io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "it is {}, not a regular file; it is never replaced",
                        kind_of(&m)
                    ),
                ),
            })
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(io_err(path, "read")(e)),
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    match fs::metadata(&folder) {
        Ok(m) if m.is_dir() => {}
        Ok(m) => {
            return Err(OutputError::NotADirectory {
                path: folder,
                kind: kind_of(&m),
            })
        }
        Err(e) => return Err(io_err(&folder, "use as the output folder")(e)),
    }
    probe_writable(&folder).map_err(|error| OutputError::Unwritable {
        path: folder,
        error,
    })
}

/// Creates and removes a hidden file in `dir`: whether files can be created there (permissions,
/// a read-only file system, a full disk's inode table), whoever runs this.
fn probe_writable(dir: &Path) -> io::Result<()> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let probe = dir.join(format!(
        ".dbuffer-probe-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)?;
    fs::remove_file(&probe)
}

/// The folders one `create_dir_all` made, to take them away again after a failure.
#[derive(Debug, Default)]
pub struct NewDirs {
    /// Outermost first.
    created: Vec<PathBuf>,
}

impl NewDirs {
    /// Creates `dir` and the ancestors it lacks; remembers which it made.
    pub fn create(dir: &Path) -> io::Result<NewDirs> {
        let mut missing = Vec::new();
        let mut p = dir;
        while !p.as_os_str().is_empty() && fs::symlink_metadata(p).is_err() {
            missing.push(p.to_path_buf());
            match p.parent() {
                Some(parent) => p = parent,
                None => break,
            }
        }
        missing.reverse();
        let mut made = NewDirs::default();
        for d in missing {
            match fs::create_dir(&d) {
                Ok(()) => made.created.push(d),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && d.is_dir() => {}
                Err(e) => {
                    made.remove_if_empty();
                    return Err(e);
                }
            }
        }
        Ok(made)
    }

    /// Removes the folders made, innermost first, as long as each is empty.
    pub fn remove_if_empty(&self) {
        for d in self.created.iter().rev() {
            if fs::remove_dir(d).is_err() {
                break;
            }
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
    meta: &RenderMeta,
    pixels: &dyn PixelSource,
    dbuffer: &mut dyn DBufferRows,
    fault: &mut Fault<'_>,
) -> Result<(), OutputError> {
    for (i, name) in FILE_NAMES.iter().enumerate() {
        let target = dir.join(name);
        fault(Step::Stage(i)).map_err(io_err(&target, "write"))?;
        let file = File::create(temp.join(name)).map_err(io_err(&target, "write"))?;
        let mut out = io::BufWriter::with_capacity(1 << 20, file);
        encode_into(name, &target, &mut out, meta, pixels, dbuffer)?;
        let file = out
            .into_inner()
            .map_err(|e| io_err(&target, "write")(e.into_error()))?;
        file.sync_all().map_err(io_err(&target, "write"))?;
    }
    Ok(())
}

/// The pixels of a render, for its image files: row-major, row 0 at the top. `Sync`: the EXR
/// encoder asks for pixels from several threads.
pub trait PixelSource: Sync {
    fn size(&self) -> (u32, u32);
    /// The shaded colour, 8-bit sRGB.
    fn srgb(&self, i: usize) -> [u8; 3];
    fn visibility(&self, i: usize) -> f32;
    /// Whether the pixel saw a surface.
    fn hit(&self, i: usize) -> bool;
    /// The world position the pixel saw (meaningful where hit).
    fn position(&self, i: usize) -> [f32; 3];
    /// The shadow class where hit: 0 lit, 1 penumbra, 2 umbra.
    fn class(&self, i: usize) -> u8;
}

/// One texel of the light-view D-buffer: |cx_o| (`+inf` for no surface), |cx_uv|, |cx_pv|,
/// |cx_s| umbra, |cx_s| penumbra.
pub type DBufferTexel = [f32; 5];

/// The D-buffer a row at a time (rows are asked for in increasing order, mostly).
pub trait DBufferRows: Send {
    /// Texels on a side.
    fn size(&self) -> u32;
    /// Row `y` into `out` (`size` texels).
    fn row(&mut self, y: u32, out: &mut [DBufferTexel]) -> Result<(), OutputError>;
}

/// [`RenderOutputs`]' D-buffer, from memory.
struct VecRows<'a>(&'a RenderOutputs);

impl DBufferRows for VecRows<'_> {
    fn size(&self) -> u32 {
        self.0.dbuffer_size
    }
    fn row(&mut self, y: u32, out: &mut [DBufferTexel]) -> Result<(), OutputError> {
        let o = self.0;
        let start = y as usize * o.dbuffer_size as usize;
        for (x, texel) in out.iter_mut().enumerate() {
            let i = start + x;
            let at = |v: &[f32]| v.get(i).copied().unwrap_or(0.0);
            *texel = [at(&o.d_o), at(&o.d_u), at(&o.d_p), at(&o.s_u), at(&o.s_p)];
        }
        Ok(())
    }
}

impl PixelSource for RenderOutputs {
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
    fn srgb(&self, i: usize) -> [u8; 3] {
        self.color[i].map(linear_to_srgb8)
    }
    fn visibility(&self, i: usize) -> f32 {
        self.visibility[i]
    }
    fn hit(&self, i: usize) -> bool {
        self.hit[i]
    }
    fn position(&self, i: usize) -> [f32; 3] {
        self.position[i]
    }
    fn class(&self, i: usize) -> u8 {
        self.class[i]
    }
}

/// A frame read back, as the image files see it (no copy of it is made).
pub struct FramePixels<'a>(pub &'a Frame);

impl PixelSource for FramePixels<'_> {
    fn size(&self) -> (u32, u32) {
        (self.0.width, self.0.height)
    }
    fn srgb(&self, i: usize) -> [u8; 3] {
        let c = self.0.color[i];
        [c[0], c[1], c[2]]
    }
    fn visibility(&self, i: usize) -> f32 {
        self.0.visibility[i]
    }
    fn hit(&self, i: usize) -> bool {
        self.0.hit(i)
    }
    fn position(&self, i: usize) -> [f32; 3] {
        self.0.position(i).map_or([0.0; 3], |p| p.to_array())
    }
    fn class(&self, i: usize) -> u8 {
        class_code(self.0.visibility[i])
    }
}

/// The class code of V (the thresholds of docs/method/metrics.md): 0 lit, 1 penumbra, 2 umbra.
fn class_code(v: f32) -> u8 {
    match ShadowClass::of(f64::from(v)) {
        ShadowClass::Lit => 0,
        ShadowClass::Penumbra => 1,
        ShadowClass::Umbra => 2,
    }
}

/// A D-buffer read in bands of rows by `fetch(first row, rows)`, a band kept at a time. Bands
/// start at multiples of their height, a multiple of 64 rows: the EXR encoder goes over a block
/// of 64 rows once per channel, so a band boundary inside a block would read both bands again
/// for every channel.
pub struct BandedRows<F> {
    size: u32,
    band: u32,
    fetch: F,
    first: u32,
    rows: Vec<DBufferTexel>,
}

impl<F> BandedRows<F>
where
    F: FnMut(u32, u32) -> Result<Vec<DBufferTexel>, String> + Send,
{
    /// `size`² texels, about `band` rows per fetch (rounded up to a multiple of 64).
    pub fn new(size: u32, band: u32, fetch: F) -> Self {
        BandedRows {
            size,
            band: band.max(1).div_ceil(64) * 64,
            fetch,
            first: 0,
            rows: Vec::new(),
        }
    }
}

impl<F> DBufferRows for BandedRows<F>
where
    F: FnMut(u32, u32) -> Result<Vec<DBufferTexel>, String> + Send,
{
    fn size(&self) -> u32 {
        self.size
    }
    fn row(&mut self, y: u32, out: &mut [DBufferTexel]) -> Result<(), OutputError> {
        let width = self.size as usize;
        let held = (self.rows.len() / width.max(1)) as u32;
        if !(self.first..self.first + held).contains(&y) {
            let first = y / self.band * self.band;
            let n = self.band.min(self.size.saturating_sub(first));
            self.rows = (self.fetch)(first, n).map_err(|e| OutputError::Encode {
                path: PathBuf::from(DBUFFER_EXR),
                error: image::ImageError::IoError(io::Error::other(e)),
            })?;
            self.first = first;
        }
        let start = (y - self.first) as usize * width;
        match self.rows.get(start..start + width) {
            Some(row) => {
                out.copy_from_slice(row);
                Ok(())
            }
            None => Err(OutputError::Length {
                file: DBUFFER_EXR,
                field: "row",
                found: self.rows.len(),
                expected: start + width,
                width: self.size,
                height: self.size,
            }),
        }
    }
}

/// The D-buffer texels of light-space maps read back (all rows held, or a band): |cx_o| from
/// slot 0 (`+inf` where no surface), |cx_uv| and its |cx_s| from slot 1, |cx_pv| and its
/// |cx_s| from slot 2 — what [`RenderOutputs::from_frame`] takes apart.
pub fn dbuffer_texels(maps: &crate::render::frame::LightMapsData) -> Vec<DBufferTexel> {
    let (d_o, d_u, d_p, s_u, s_p) = (
        maps.raw(0, 0),
        maps.raw(1, 0),
        maps.raw(2, 0),
        maps.raw(1, 1),
        maps.raw(2, 1),
    );
    let at = |v: &[f32], i: usize| v.get(i).copied().unwrap_or(0.0);
    (0..d_o.len())
        .map(|i| {
            let o = at(&d_o, i);
            let o = if f64::from(o) >= NO_SURFACE * 0.5 {
                f32::INFINITY
            } else {
                o
            };
            [o, at(&d_u, i), at(&d_p, i), at(&s_u, i), at(&s_p, i)]
        })
        .collect()
}

/// Encode file `name` into `out`, streaming: PNG rows as they are made, EXR blocks as the
/// encoder asks for pixels.
fn encode_into(
    name: &str,
    target: &Path,
    out: &mut io::BufWriter<File>,
    meta: &RenderMeta,
    pixels: &dyn PixelSource,
    dbuffer: &mut dyn DBufferRows,
) -> Result<(), OutputError> {
    let (w, h) = pixels.size();
    let ds = dbuffer.size();
    let encode_err = |error: image::ImageError| OutputError::Encode {
        path: target.to_path_buf(),
        error,
    };
    let exr_err = |e: exr::error::Error| {
        encode_err(image::ImageError::IoError(io::Error::other(e.to_string())))
    };
    let png_err = |e: png::EncodingError| {
        encode_err(image::ImageError::IoError(io::Error::other(e.to_string())))
    };
    let alpha = |i: usize| if pixels.hit(i) { 1.0 } else { 0.0 };
    let width = w as usize;
    match name {
        IMAGE_PNG => png_rows(out, w, h, |y, row| {
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                px.copy_from_slice(&pixels.srgb(y * width + x));
            }
        })
        .map_err(png_err),
        CLASSES_PNG => png_rows(out, w, h, |y, row| {
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                let i = y * width + x;
                let class = ShadowClass::ALL.get(usize::from(pixels.class(i)));
                px.copy_from_slice(&match (pixels.hit(i), class) {
                    (true, Some(&c)) => class_rgb(c),
                    _ => NOT_HIT_RGB,
                });
            }
        })
        .map_err(png_err),
        VISIBILITY_EXR => exr_rows(out, w, h, true, |x, y| {
            let i = y * width + x;
            let v = pixels.visibility(i);
            [v, v, v, alpha(i)]
        })
        .map_err(exr_err),
        POSITION_EXR => exr_rows(out, w, h, true, |x, y| {
            let i = y * width + x;
            let p = pixels.position(i);
            [p[0], p[1], p[2], alpha(i)]
        })
        .map_err(exr_err),
        DBUFFER_EXR | DBUFFER_S_EXR => {
            // One row at a time from `dbuffer`, which may be reading the GPU in bands: the
            // encoder runs on this thread, rows in order.
            let cursor = std::sync::Mutex::new((u32::MAX, vec![[0.0f32; 5]; ds as usize], None));
            let rows = std::sync::Mutex::new(dbuffer);
            let s_only = name == DBUFFER_S_EXR;
            let result = exr_rows(out, ds, ds, false, |x, y| {
                let Ok(mut c) = cursor.lock() else {
                    return [f32::NAN; 4];
                };
                let (held, row, error) = &mut *c;
                if *held != y as u32 {
                    match rows.lock() {
                        Ok(mut r) => {
                            if let Err(e) = r.row(y as u32, row) {
                                error.get_or_insert(e);
                            }
                        }
                        Err(_) => {
                            error.get_or_insert(OutputError::Length {
                                file: DBUFFER_EXR,
                                field: "row",
                                found: 0,
                                expected: ds as usize,
                                width: ds,
                                height: ds,
                            });
                        }
                    }
                    *held = y as u32;
                }
                let t = row.get(x).copied().unwrap_or([0.0; 5]);
                if s_only {
                    [t[3], t[4], 0.0, 1.0]
                } else {
                    [t[0], t[1], t[2], t[3]]
                }
            });
            let failed = cursor.into_inner().ok().and_then(|c| c.2);
            if let Some(e) = failed {
                return Err(e);
            }
            result.map_err(exr_err)
        }
        META_JSON => {
            let json = meta.to_json_pretty().map_err(|error| OutputError::Json {
                path: target.to_path_buf(),
                error,
            })?;
            out.write_all(json.as_bytes())
                .map_err(io_err(target, "write"))
        }
        other => {
            let msg = format!("{other} is not a render output file");
            Err(io_err(target, "encode")(io::Error::other(msg)))
        }
    }
}

/// An 8-bit RGB PNG written a row at a time: `row(y, bytes)` fills row `y`.
fn png_rows(
    out: &mut io::BufWriter<File>,
    w: u32,
    h: u32,
    mut row: impl FnMut(usize, &mut [u8]),
) -> Result<(), png::EncodingError> {
    let mut encoder = png::Encoder::new(out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    let mut stream = writer.stream_writer()?;
    let mut bytes = vec![0u8; 3 * w as usize];
    for y in 0..h as usize {
        row(y, &mut bytes);
        stream.write_all(&bytes)?;
    }
    stream.finish()?;
    writer.finish()
}

/// An RGBA f32 EXR (the `image` crate's encoding: RLE, lossless) written block by block as the
/// encoder asks `pixel(x, y)`; `parallel`: from several threads, in any order.
fn exr_rows(
    out: &mut io::BufWriter<File>,
    w: u32,
    h: u32,
    parallel: bool,
    pixel: impl Fn(usize, usize) -> [f32; 4] + Sync,
) -> Result<(), exr::error::Error> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let image = Image::from_channels(
        (w as usize, h as usize),
        SpecificChannels::rgba(|p: Vec2<usize>| {
            let [r, g, b, a] = pixel(p.x(), p.y());
            (r, g, b, a)
        }),
    );
    let write = image.write();
    if parallel {
        write.to_buffered(out)
    } else {
        write.non_parallel().to_buffered(out)
    }
}

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
    let decode_err = |error| OutputError::Decode {
        path: path.to_path_buf(),
        error,
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
    fn a_dbuffer_read_in_bands_writes_the_same_files_and_reads_each_band_once_per_file() {
        // 150 texels a side: bands of 64 rows cross the 64-row blocks of the EXR encoder only
        // at their edges; values differ per texel so a misplaced row shows.
        let (w, h, ds) = (5, 3, 150u32);
        let mut out = outputs(w, h, ds, 0.5);
        let nd = (ds * ds) as usize;
        for i in 0..nd {
            let f = i as f32;
            out.d_o[i] = if i % 7 == 0 { f32::INFINITY } else { f };
            out.d_u[i] = f + 0.25;
            out.d_p[i] = f + 0.5;
            out.s_u[i] = -f;
            out.s_p[i] = f * 2.0;
        }
        let whole = temp_dir("whole");
        write_render(&whole, &out).unwrap();
        let banded = temp_dir("banded");
        let fetches = std::sync::atomic::AtomicUsize::new(0);
        let mut rows = BandedRows::new(ds, 1, |first, n| {
            fetches.fetch_add(1, Ordering::Relaxed);
            let texels = (first * ds..(first + n).min(ds) * ds)
                .map(|i| {
                    let i = i as usize;
                    [out.d_o[i], out.d_u[i], out.d_p[i], out.s_u[i], out.s_p[i]]
                })
                .collect();
            Ok(texels)
        });
        write_render_parts(&banded, &out.meta, &out, &mut rows).unwrap();
        for name in [DBUFFER_EXR, DBUFFER_S_EXR, VISIBILITY_EXR, POSITION_EXR] {
            let a = read_exr_rgba(&whole.join(name)).unwrap();
            let b = read_exr_rgba(&banded.join(name)).unwrap();
            assert_eq!((a.0, a.1), (b.0, b.1), "{name}");
            let same =
                a.2.iter()
                    .zip(&b.2)
                    .all(|(p, q)| p.iter().zip(q).all(|(x, y)| x.to_bits() == y.to_bits()));
            assert!(same, "{name} differs");
        }
        for name in [IMAGE_PNG, CLASSES_PNG, META_JSON] {
            assert_eq!(
                image_or_bytes(&whole.join(name)),
                image_or_bytes(&banded.join(name)),
                "{name}"
            );
        }
        // Three bands of 64 rows, once for each of the two D-buffer files.
        assert_eq!(fetches.load(Ordering::Relaxed), 2 * 3);
        let _ = fs::remove_dir_all(&whole);
        let _ = fs::remove_dir_all(&banded);
    }

    /// A PNG's pixels, or a file's bytes.
    fn image_or_bytes(path: &Path) -> Vec<u8> {
        match image::open(path) {
            Ok(img) => img.into_bytes(),
            Err(_) => fs::read(path).unwrap(),
        }
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

    /// A folder made for the render (with its missing parents) is taken away again when
    /// writing fails at any step, and made only once the outputs are checked.
    #[test]
    fn a_new_folder_is_not_left_behind_after_a_failure() {
        let base = temp_dir("new-dir");
        let dir = base.join("a").join("b");
        for fail_at in [Step::Stage(0), Step::Stage(6), Step::Install(3)] {
            let result = write_render_with(&dir, &outputs(3, 2, 2, 0.5), &mut |step| {
                if step == fail_at {
                    Err(io::Error::other("injected"))
                } else {
                    Ok(())
                }
            });
            assert!(result.is_err(), "{fail_at:?}");
            assert!(
                !base.join("a").exists(),
                "{fail_at:?} left {}",
                dir.display()
            );
        }
        // Outputs that fail their checks create nothing at all.
        let mut bad = outputs(3, 2, 2, 0.5);
        bad.visibility.pop();
        assert!(write_render(&dir, &bad).is_err());
        assert!(!base.join("a").exists());
        // A folder that was there before stays.
        fs::create_dir_all(&dir).unwrap();
        let result = write_render_with(&dir, &outputs(3, 2, 2, 0.5), &mut |step| match step {
            Step::Stage(0) => Err(io::Error::other("injected")),
            _ => Ok(()),
        });
        assert!(result.is_err() && dir.is_dir());
        let _ = fs::remove_dir_all(&base);
    }

    /// Output targets are checked before any work: a file where the folder should be, a
    /// folder under a file, a place nothing can be created in, a device or FIFO as a file.
    #[test]
    fn output_targets_are_checked_up_front() {
        let base = temp_dir("targets");
        let file = base.join("file.txt");
        fs::write(&file, b"x").unwrap();
        let e = check_out_dir(&file, &FILE_NAMES).unwrap_err();
        assert!(matches!(e, OutputError::NotADirectory { .. }), "{e:?}");
        assert!(e.to_string().contains("a regular file"), "{e}");
        let e = check_out_dir(&file.join("sub"), &FILE_NAMES).unwrap_err();
        assert!(e.to_string().contains("file.txt"), "{e}");
        check_out_dir(&base.join("new").join("deeper"), &FILE_NAMES).unwrap();
        assert!(!base.join("new").exists(), "checking creates nothing");
        #[cfg(target_os = "linux")]
        {
            // /proc takes no new entries, whoever asks (root included).
            let e = check_out_dir(Path::new("/proc/dbuffer-out"), &FILE_NAMES).unwrap_err();
            assert!(matches!(e, OutputError::Unwritable { .. }), "{e:?}");
            let e = check_out_file(Path::new("/dev/null")).unwrap_err();
            assert!(e.to_string().contains("never replaced"), "{e}");
        }
        check_out_file(&file).unwrap();
        check_out_file(&base.join("new.png")).unwrap();
        let e = check_out_file(&base.join("missing").join("x.png")).unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
        let e = check_out_file(&base).unwrap_err();
        assert!(matches!(e, OutputError::TargetIsDirectory { .. }), "{e:?}");
        let leftovers: Vec<_> = fs::read_dir(&base)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains("probe"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
        let _ = fs::remove_dir_all(&base);
    }
}
