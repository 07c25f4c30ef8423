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

    /// Whether pixel `i` shows a surface whose V or t is out of range ([`out_of_range`]): what
    /// the range view marks (`range_flag` of `shaders/shared/view_inputs.wgsl`). The camera pass
    /// writes a t out of [0, 1] so that it reads back out of it (`encode_t` of
    /// `shaders/shared/camera.wgsl`).
    pub fn out_of_range(&self, i: usize) -> bool {
        self.hit(i)
            && (self.visibility.get(i).is_none_or(|&v| out_of_range(v)) || out_of_range(self.t(i)))
    }

    /// How many pixels [`Frame::out_of_range`] holds: `compare`'s `invalid_px`, the lab's count
    /// under the range view.
    pub fn out_of_range_pixels(&self) -> usize {
        (0..self.len()).filter(|&i| self.out_of_range(i)).count()
    }
}

/// Whether a V or a t is NaN, infinite, below 0 or above 1: no method may return one.
pub fn out_of_range(v: f32) -> bool {
    !(0.0..=1.0).contains(&v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×1 frame of surfaces with V and t + 2 × branch as given.
    fn frame(visibility: [f32; 4], t_branch: [f32; 4]) -> Frame {
        Frame {
            width: 4,
            height: 1,
            visibility: visibility.to_vec(),
            t_branch: t_branch.to_vec(),
            depth: vec![0.5; 4],
            ..Frame::default()
        }
    }

    #[test]
    fn nan_infinite_and_out_of_range_values_are_counted() {
        assert!(out_of_range(f32::NAN) && out_of_range(f32::INFINITY));
        assert!(out_of_range(-1e-7) && out_of_range(1.0 + 1e-6));
        assert!(!out_of_range(0.0) && !out_of_range(1.0));
        // V: valid, NaN, 1.5, −∞; t valid everywhere (branch lit: 7 = t 1 + 2 × 3).
        let f = frame([0.5, f32::NAN, 1.5, f32::NEG_INFINITY], [7.0; 4]);
        let marked: Vec<bool> = (0..4).map(|i| f.out_of_range(i)).collect();
        assert_eq!(marked, [false, true, true, true]);
        assert_eq!(f.out_of_range_pixels(), 3);
    }

    #[test]
    fn t_is_checked_after_taking_the_branch_off() {
        // t 0.25 on the visible penumbra (4.25), t 1 lit (7): valid although above 1 as sums;
        // t 1.25 on the hidden penumbra (3.25, camera.wgsl's stand-in for a t above 1), t NaN.
        let f = frame([0.5; 4], [4.25, 7.0, 3.25, f32::NAN]);
        assert_eq!(f.t(2), 1.25);
        let marked: Vec<bool> = (0..4).map(|i| f.out_of_range(i)).collect();
        assert_eq!(marked, [false, false, true, true]);
    }

    #[test]
    fn pixels_without_a_surface_are_not_counted() {
        let mut f = frame([f32::NAN; 4], [f32::NAN; 4]);
        f.depth = vec![0.0, 0.0, 0.5, 0.0];
        assert_eq!(f.out_of_range_pixels(), 1);
    }
}
