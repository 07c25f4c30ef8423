//! The lab's camera controls (orbit, pan, zoom, frame all) on a [`Camera`], and the one place the
//! lab projects world points to the screen: the same `Camera::view()` and
//! `Camera::projection(..)` the render core draws with, so overlays land on the rendered pixels.

use eframe::egui::{Pos2, Rect};
use glam::{Mat4, Vec3, Vec4};

use crate::scene::Camera;

/// Pitch stays inside ±this (radians), away from straight up or down.
const MAX_PITCH: f32 = 1.45;

/// `camera` orbited about its target by `dx`, `dy` radians (yaw, pitch).
pub fn orbit(camera: &Camera, dx: f32, dy: f32) -> Camera {
    let offset = camera.eye - camera.target;
    let distance = offset.length().max(1e-4);
    let yaw = offset.x.atan2(offset.z) - dx;
    let pitch = ((offset.y / distance).clamp(-1.0, 1.0).asin() + dy).clamp(-MAX_PITCH, MAX_PITCH);
    let dir = Vec3::new(
        pitch.cos() * yaw.sin(),
        pitch.sin(),
        pitch.cos() * yaw.cos(),
    );
    Camera {
        eye: camera.target + dir * distance,
        ..*camera
    }
}

/// `camera` moved sideways so the scene follows a drag of (`dx`, `dy`) points in a viewport
/// `height` points tall.
pub fn pan(camera: &Camera, dx: f32, dy: f32, height: f32) -> Camera {
    let (right, up, _) = basis(camera);
    let distance = (camera.eye - camera.target).length();
    let per_point = 2.0 * distance * (0.5 * camera.fov_y_deg.to_radians()).tan() / height.max(1.0);
    let shift = (-right * dx + up * dy) * per_point;
    Camera {
        eye: camera.eye + shift,
        target: camera.target + shift,
        ..*camera
    }
}

/// `camera` moved toward its target (`steps` > 0) or away; the target stays.
pub fn zoom(camera: &Camera, steps: f32) -> Camera {
    let offset = camera.eye - camera.target;
    let distance = offset.length();
    let new = (distance * (-steps * 0.1).exp()).clamp(0.05, 1e4);
    Camera {
        eye: camera.target + offset * (new / distance.max(1e-6)),
        ..*camera
    }
}

/// `camera` looking at the centre of `(lo, hi)` from its current direction, far enough to see
/// the whole box.
pub fn frame_all(camera: &Camera, (lo, hi): (Vec3, Vec3)) -> Camera {
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(0.1);
    let dir = (camera.eye - camera.target)
        .try_normalize()
        .unwrap_or(Vec3::Z);
    let half = 0.5 * camera.fov_y_deg.to_radians();
    let distance = radius / half.sin().max(0.05) * 1.1;
    Camera {
        eye: centre + dir * distance,
        target: centre,
        ..*camera
    }
}

/// Right, up and forward unit vectors of the camera, as the render core uses them.
pub fn basis(camera: &Camera) -> (Vec3, Vec3, Vec3) {
    let inverse = camera.view().inverse();
    (
        inverse.x_axis.truncate().normalize_or_zero(),
        inverse.y_axis.truncate().normalize_or_zero(),
        -inverse.z_axis.truncate().normalize_or_zero(),
    )
}

/// World → screen for one camera and one viewport rectangle.
#[derive(Clone, Copy, Debug)]
pub struct Projector {
    view_proj: Mat4,
    rect: Rect,
}

/// Clip-space w below which a point counts as behind the camera.
const NEAR_W: f32 = 1e-3;

impl Projector {
    pub fn new(camera: &Camera, rect: Rect) -> Projector {
        let aspect = rect.width().max(1.0) / rect.height().max(1.0);
        // Near and far do not move x and y after the divide; only points behind are clipped.
        Projector {
            view_proj: camera.projection(aspect, 0.01, 1000.0) * camera.view(),
            rect,
        }
    }

    fn clip(&self, p: Vec3) -> Vec4 {
        self.view_proj * p.extend(1.0)
    }

    fn screen_of(&self, c: Vec4) -> Pos2 {
        let (x, y) = (c.x / c.w, c.y / c.w);
        Pos2::new(
            self.rect.left() + (x * 0.5 + 0.5) * self.rect.width(),
            self.rect.top() + (0.5 - y * 0.5) * self.rect.height(),
        )
    }

    /// The screen position of `p`, or `None` behind the camera.
    pub fn point(&self, p: Vec3) -> Option<Pos2> {
        let c = self.clip(p);
        (c.w > NEAR_W && c.is_finite()).then(|| self.screen_of(c))
    }

    /// The segment `a b` cut to what is in front of the camera and near the viewport.
    pub fn segment(&self, a: Vec3, b: Vec3) -> Option<[Pos2; 2]> {
        let (mut ca, mut cb) = (self.clip(a), self.clip(b));
        if !(ca.is_finite() && cb.is_finite()) || (ca.w <= NEAR_W && cb.w <= NEAR_W) {
            return None;
        }
        if ca.w <= NEAR_W {
            ca = ca + (cb - ca) * ((NEAR_W - ca.w) / (cb.w - ca.w));
        } else if cb.w <= NEAR_W {
            cb = cb + (ca - cb) * ((NEAR_W - cb.w) / (ca.w - cb.w));
        }
        // Liang–Barsky against a box twice the viewport, in normalised device coordinates, so
        // extruded volume edges do not reach the tessellator at 1e6 points.
        let (pa, pb) = (
            ca.truncate().truncate() / ca.w,
            cb.truncate().truncate() / cb.w,
        );
        let d = pb - pa;
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for (p, q) in [
            (-d.x, pa.x + 2.0),
            (d.x, 2.0 - pa.x),
            (-d.y, pa.y + 2.0),
            (d.y, 2.0 - pa.y),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if t0 > t1 {
            return None;
        }
        let screen = |n: glam::Vec2| {
            Pos2::new(
                self.rect.left() + (n.x * 0.5 + 0.5) * self.rect.width(),
                self.rect.top() + (0.5 - n.y * 0.5) * self.rect.height(),
            )
        };
        Some([screen(pa + d * t0), screen(pa + d * t1)])
    }
}

/// The pixel of a `width`×`height` frame under screen point `pos` of a viewport `rect`.
pub fn pixel_at(rect: Rect, pos: Pos2, width: u32, height: u32) -> Option<(u32, u32)> {
    if !rect.contains(pos) || width == 0 || height == 0 {
        return None;
    }
    let u = (pos.x - rect.left()) / rect.width();
    let v = (pos.y - rect.top()) / rect.height();
    let x = ((u * width as f32) as u32).min(width - 1);
    let y = ((v * height as f32) as u32).min(height - 1);
    Some((x, y))
}

/// The ray through screen point `pos` of viewport `rect` (the render core's pixel ray, at a
/// resolution of one pixel per point).
pub fn ray_at(camera: &Camera, rect: Rect, pos: Pos2) -> Option<(Vec3, Vec3)> {
    let (w, h) = (rect.width().round() as u32, rect.height().round() as u32);
    let (x, y) = pixel_at(rect, pos, w, h)?;
    Some(camera.pixel_ray(x, y, w, h))
}

/// Where the ray `(origin, dir)` meets the plane through `point` with normal `normal`.
pub fn ray_plane(origin: Vec3, dir: Vec3, point: Vec3, normal: Vec3) -> Option<Vec3> {
    let denom = dir.dot(normal);
    if denom.abs() < 1e-6 {
        return None;
    }
    let t = (point - origin).dot(normal) / denom;
    (t > 0.0 && t.is_finite()).then(|| origin + dir * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 3.0, 6.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            fov_y_deg: 45.0,
        }
    }

    #[test]
    fn orbit_keeps_distance_and_target() {
        let c = camera();
        let o = orbit(&c, 0.7, -0.2);
        assert_eq!(o.target, c.target);
        let d = |c: &Camera| (c.eye - c.target).length();
        assert!((d(&o) - d(&c)).abs() < 1e-4);
        assert!((o.eye - c.eye).length() > 0.1);
        // Pitch is clamped short of the pole, so the view never flips.
        let top = orbit(&c, 0.0, 10.0);
        assert!(top.eye.y - top.target.y < d(&c));
    }

    #[test]
    fn zoom_and_frame_all() {
        let c = camera();
        let z = zoom(&c, 3.0);
        assert!((z.eye - z.target).length() < (c.eye - c.target).length());
        let f = frame_all(&c, (Vec3::splat(-1.0), Vec3::splat(1.0)));
        assert_eq!(f.target, Vec3::ZERO);
        // The box's bounding sphere fits in the vertical field of view.
        let p = Projector::new(&f, Rect::from_min_size(Pos2::ZERO, [100.0, 100.0].into()));
        for corner in [
            Vec3::splat(1.0),
            Vec3::splat(-1.0),
            Vec3::new(1.0, -1.0, 1.0),
        ] {
            let s = p.point(corner).unwrap();
            assert!(
                (0.0..=100.0).contains(&s.x) && (0.0..=100.0).contains(&s.y),
                "{s:?}"
            );
        }
    }

    #[test]
    fn projection_matches_the_pixel_ray() {
        let c = camera();
        let rect = Rect::from_min_size(Pos2::new(10.0, 20.0), [200.0, 100.0].into());
        let pos = Pos2::new(160.5, 45.5);
        let (o, d) = ray_at(&c, rect, pos).unwrap();
        let s = Projector::new(&c, rect).point(o + d * 5.0).unwrap();
        assert!((s - pos).length() < 1e-2, "{s:?} vs {pos:?}");
    }

    #[test]
    fn segments_behind_the_camera_are_cut() {
        let c = camera();
        let p = Projector::new(&c, Rect::from_min_size(Pos2::ZERO, [100.0, 100.0].into()));
        let behind = c.eye + (c.eye - c.target);
        assert!(p.segment(behind, behind + Vec3::X).is_none());
        let [a, b] = p.segment(c.target, behind).unwrap();
        assert!(a.x.is_finite() && b.y.is_finite());
        assert!(p.point(behind).is_none());
    }

    #[test]
    fn ray_meets_plane() {
        let hit = ray_plane(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, Vec3::ZERO, Vec3::Y).unwrap();
        assert_eq!(hit, Vec3::ZERO);
        assert!(ray_plane(Vec3::Y, Vec3::X, Vec3::ZERO, Vec3::Y).is_none());
    }
}
