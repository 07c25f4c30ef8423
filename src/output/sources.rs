//! Where a render's pixels come from: a frame read back ([`FramePixels`]), or everything held in
//! memory ([`RenderOutputs`], checked by `validate` before a file is touched); and the D-buffer a
//! row at a time, from memory or read from the GPU in bands ([`BandedRows`]).

use std::io;
use std::path::PathBuf;

use super::encode::{linear_to_srgb8, srgb8_to_linear};
use super::names::{
    RenderMeta, CLASSES_PNG, DBUFFER_EXR, DBUFFER_S_EXR, IMAGE_PNG, POSITION_EXR, VISIBILITY_EXR,
};
use super::OutputError;
use crate::geometry::metrics::ShadowClass;
use crate::render::passes::shadow_map::NO_SURFACE;
use crate::render::Frame;

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

/// `n = a·b` as a count of values, or `TooLarge` naming `file`.
fn count(file: &'static str, width: u32, height: u32) -> Result<usize, OutputError> {
    usize::try_from(u64::from(width) * u64::from(height)).map_err(|_| OutputError::TooLarge {
        file,
        width,
        height,
    })
}

pub(super) fn validate(out: &RenderOutputs) -> Result<(), OutputError> {
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
pub(super) struct VecRows<'a>(pub(super) &'a RenderOutputs);

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
