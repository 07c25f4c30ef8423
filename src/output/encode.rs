//! The file formats: each render file encoded straight to disk (PNG rows, EXR blocks as the
//! encoder asks for them), the in-memory PNG and EXR encoders, the sRGB transfer function, and
//! reading an EXR back.

use std::fs::File;
use std::io::{self, BufReader, Cursor, Write};
use std::path::Path;

use image::codecs::openexr::{OpenExrDecoder, OpenExrEncoder};
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageDecoder, ImageEncoder};

use super::names::{
    class_rgb, RenderMeta, CLASSES_PNG, DBUFFER_EXR, DBUFFER_S_EXR, IMAGE_PNG, META_JSON,
    NOT_HIT_RGB, POSITION_EXR, VISIBILITY_EXR,
};
use super::sources::{DBufferRows, PixelSource};
use super::{io_err, OutputError};
use crate::geometry::metrics::ShadowClass;

/// The sRGB transfer function, inverted: [`linear_to_srgb8`] takes it back to the same byte.
pub fn srgb8_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
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

/// Encode file `name` into `out`, streaming: PNG rows as they are made, EXR blocks as the
/// encoder asks for pixels.
pub(super) fn encode_into(
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

/// [`png_rows`] into `out`, its error naming `target`.
pub fn png_file(
    out: &mut io::BufWriter<File>,
    target: &Path,
    w: u32,
    h: u32,
    row: impl FnMut(usize, &mut [u8]),
) -> Result<(), OutputError> {
    png_rows(out, w, h, row).map_err(|e| encode_error(target, e.to_string()))
}

/// An RGB image as a PNG into `out`, its error naming `target`.
pub fn png_image(
    out: &mut io::BufWriter<File>,
    target: &Path,
    img: &image::RgbImage,
) -> Result<(), OutputError> {
    let width = 3 * img.width() as usize;
    let raw = img.as_raw();
    png_file(out, target, img.width(), img.height(), |y, row| {
        row.copy_from_slice(&raw[y * width..(y + 1) * width]);
    })
}

/// [`exr_rows`] into `out`, from several threads, its error naming `target`.
pub fn exr_file(
    out: &mut io::BufWriter<File>,
    target: &Path,
    w: u32,
    h: u32,
    pixel: impl Fn(usize, usize) -> [f32; 4] + Sync,
) -> Result<(), OutputError> {
    exr_rows(out, w, h, true, pixel).map_err(|e| encode_error(target, e.to_string()))
}

fn encode_error(target: &Path, message: String) -> OutputError {
    OutputError::Encode {
        path: target.to_path_buf(),
        error: image::ImageError::IoError(io::Error::other(message)),
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
