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
//!
//! One file per job: [`names`] (the file names, the class colours, `meta.json`), [`sources`]
//! (where the pixels and the D-buffer's rows come from, and the check of a render held in
//! memory), [`encode`] (PNG and EXR, streamed or in memory, and reading an EXR back) and
//! [`staged`] (the all-or-nothing move into place, and the checks of `--out` made before any
//! work). This file ties them together: [`write_render`] and [`write_render_parts`].

mod encode;
mod names;
mod sources;
mod staged;
#[cfg(test)]
mod tests;

use std::fs::{self, File};
use std::io;
use std::path::{Path, PathBuf};

pub use encode::{
    exr_file, exr_rgba32f, linear_to_srgb8, png_file, png_image, png_rgb8, read_exr_rgba,
    srgb8_to_linear,
};
pub use names::{
    class_rgb, render_meta, RenderMeta, CLASSES_PNG, DBUFFER_EXR, DBUFFER_S_EXR, FILE_NAMES,
    IMAGE_PNG, LIT_RGB, META_JSON, NOT_HIT_RGB, PENUMBRA_RGB, POSITION_EXR, TEMP_PREFIX, UMBRA_RGB,
    VISIBILITY_EXR,
};
pub use sources::{
    dbuffer_texels, BandedRows, DBufferRows, DBufferTexel, FramePixels, PixelSource, RenderOutputs,
};
pub use staged::{check_out_dir, check_out_file, NewDirs, Staged};

use encode::encode_into;
use sources::{validate, VecRows};
use staged::{create_temp_dir, finish};

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
