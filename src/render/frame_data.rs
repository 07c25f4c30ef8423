//! A rendered frame read back into memory ([`Frame`]): what the camera pass wrote per pixel, and
//! what is derived from it on request (t, the branch, the world position). `render`, `compare`,
//! `bench`, the view pass's CPU twin and the tests read it.

use super::light_maps::LightMapsData;

/// A rendered frame, read back. Images are row-major, row 0 at the top. Per pixel it keeps what
/// the camera pass wrote — 16 bytes, 1 GiB at 8192² — and derives the rest when asked: t and
/// the branch from their packed sum, the world position from the depth.
#[derive(Clone, Debug, Default)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// Shaded colour, sRGB 8-bit RGBA.
    pub color: Vec<[u8; 4]>,
    /// V per pixel.
    pub visibility: Vec<f32>,
    /// t + 2 × branch code per pixel, as the camera pass stores them ([`Frame::t`],
    /// [`Frame::branch`]).
    pub t_branch: Vec<f32>,
    /// Reversed depth per pixel: 0 where no surface was hit ([`Frame::position`]).
    pub depth: Vec<f32>,
    /// Per pixel the method's units of work and the path it took (`count_work`, `took_path` of
    /// `shaders/shared/camera.wgsl`); empty unless the request asked for it
    /// ([`FrameRequest::read_cost`](super::FrameRequest::read_cost)).
    pub cost: Vec<[f32; 2]>,
    /// The camera's clip → world transform, to place a pixel from its depth.
    pub inverse_view_proj: glam::Mat4,
    pub dbuffer_size: u32,
    /// The light-space maps, when they were asked for.
    pub maps: Option<LightMapsData>,
    /// GPU milliseconds per pass from timestamp queries; empty without them.
    pub gpu_ms: Vec<(String, f64)>,
}

impl Frame {
    /// Pixels in the frame.
    pub fn len(&self) -> usize {
        self.visibility.len()
    }

    pub fn is_empty(&self) -> bool {
        self.visibility.is_empty()
    }

    /// Whether pixel `i` shows a surface.
    pub fn hit(&self, i: usize) -> bool {
        self.depth.get(i).is_some_and(|&z| z > 0.0)
    }

    /// The branch code of pixel `i` ([`crate::geometry::Branch::code`]).
    pub fn branch(&self, i: usize) -> u8 {
        // Umbra 0, hidden [2, 2.5], visible [4.5, 5], lit 7: round((x − ½)/2) is the branch
        // and the rest is t, both exact.
        let x = self.t_branch.get(i).copied().unwrap_or(0.0);
        ((x - 0.5) / 2.0).round().clamp(0.0, 3.0) as u8
    }

    /// t of pixel `i`.
    pub fn t(&self, i: usize) -> f32 {
        let x = self.t_branch.get(i).copied().unwrap_or(0.0);
        x - 2.0 * f32::from(self.branch(i))
    }

    /// The world position pixel `i` shows, `None` where it shows no surface.
    pub fn position(&self, i: usize) -> Option<glam::Vec3> {
        let z = *self.depth.get(i)?;
        if z <= 0.0 || self.width == 0 {
            return None;
        }
        let (w, h) = (self.width as usize, self.height.max(1) as f32);
        let (x, y) = ((i % w) as f32, (i / w) as f32);
        let ndc = glam::Vec4::new(
            (x + 0.5) / w as f32 * 2.0 - 1.0,
            1.0 - (y + 0.5) / h * 2.0,
            z,
            1.0,
        );
        let p = self.inverse_view_proj * ndc;
        Some(p.truncate() / p.w)
    }
}
