//! Orbits for animations (`dbuffer animate`, and the lab recording the same): the light or the
//! camera once around a vertical axis, frame by frame.
//!
//! **Light**: the disk's centre turns about the vertical axis through the centre of the
//! casters' bounding box, at its own height and distance from that axis, and its normal turns
//! with it (a light tilted toward the casters stays tilted toward them). A light (nearly)
//! straight above that axis would hardly move its shadow, so one closer to the axis than a
//! quarter of its height above the casters' centre orbits at half that height from the axis
//! instead ([`Poses::note`] says so). **Camera**: the eye turns about the vertical axis through
//! its target. Frame `k` of `n` is at `360° · k / n`, so the last frame leads back into the
//! first.

use glam::{Quat, Vec3};

use super::{Camera, Light, Scene};

/// What moves around the orbit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orbit {
    Light,
    Camera,
}

impl std::str::FromStr for Orbit {
    type Err = String;
    fn from_str(s: &str) -> Result<Orbit, String> {
        match s {
            "light" => Ok(Orbit::Light),
            "camera" => Ok(Orbit::Camera),
            other => Err(format!("--orbit expects light or camera, found '{other}'")),
        }
    }
}

/// The orbit: the pose at frame 0 and the axis everything turns about.
pub struct Poses {
    orbit: Orbit,
    /// The light at frame 0 (moved off the axis if it was on it).
    pub light: Light,
    camera: Camera,
    /// A point on the vertical axis of the orbit.
    axis: Vec3,
    /// Said once on stderr (a light moved off the axis to orbit at all).
    pub note: Option<String>,
}

impl Poses {
    pub fn new(scene: &Scene, orbit: Orbit) -> Poses {
        let mut light = scene.light;
        let mut note = None;
        let axis = match orbit {
            Orbit::Camera => scene.camera.target,
            Orbit::Light => {
                let centre = casters_centre(scene).unwrap_or(Vec3::ZERO);
                let offset = light.center() - centre;
                let flat = Vec3::new(offset.x, 0.0, offset.z);
                let horizontal = flat.length();
                let radius = 0.5 * offset.y.abs().max(light.half_extent());
                if horizontal < 0.5 * radius {
                    let out = flat.try_normalize().unwrap_or(Vec3::X);
                    light = light.with_center(Vec3::new(
                        centre.x + out.x * radius,
                        light.center().y,
                        centre.z + out.z * radius,
                    ));
                    note = Some(format!(
                        "the light is (nearly) straight above the casters: it orbits {radius:.2} m \
                         off their vertical axis, half its height above their centre"
                    ));
                }
                centre
            }
        };
        Poses {
            orbit,
            light,
            camera: scene.camera,
            axis,
            note,
        }
    }

    /// Where frame `k` of `n` carries a point that moves with the light (a point on it, or one
    /// of the reference's samples): turned with the light about the axis on a light orbit, left
    /// where it is on a camera orbit. The reference's samples moved this way keep their pattern
    /// on the light from frame to frame.
    pub fn carry(&self, k: usize, n: usize, p: Vec3) -> Vec3 {
        match self.orbit {
            Orbit::Light => {
                let angle = std::f32::consts::TAU * k as f32 / n.max(1) as f32;
                let axis = Vec3::new(self.axis.x, p.y, self.axis.z);
                axis + Quat::from_rotation_y(angle) * (p - axis)
            }
            Orbit::Camera => p,
        }
    }

    /// Frame `k` of `n`'s light and camera (the one that does not orbit stays as it was).
    pub fn at(&self, k: usize, n: usize) -> (Light, Camera) {
        let angle = std::f32::consts::TAU * k as f32 / n.max(1) as f32;
        let turn = Quat::from_rotation_y(angle);
        let about = |p: Vec3| {
            let axis = Vec3::new(self.axis.x, p.y, self.axis.z);
            axis + turn * (p - axis)
        };
        match self.orbit {
            Orbit::Light => (self.light.moved(about, |v| turn * v), self.camera),
            Orbit::Camera => (
                self.light,
                Camera {
                    eye: about(self.camera.eye),
                    ..self.camera
                },
            ),
        }
    }
}

/// The centre of the casters' bounding box (every object's if none casts).
fn casters_centre(scene: &Scene) -> Option<Vec3> {
    let any_caster = scene.objects.iter().any(|o| o.casts_shadow);
    let mut bounds: Option<(Vec3, Vec3)> = None;
    for o in scene
        .objects
        .iter()
        .filter(|o| o.casts_shadow || !any_caster)
    {
        if let Some((a, b)) = o.mesh.bounds() {
            bounds = Some(match bounds {
                Some((lo, hi)) => (lo.min(a), hi.max(b)),
                None => (a, b),
            });
        }
    }
    bounds.map(|(lo, hi)| (lo + hi) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_light_keeps_its_height_distance_and_relative_tilt() {
        let scene = crate::scene::load("fig7-concave").unwrap();
        let poses = Poses::new(&scene, Orbit::Light);
        let start = *scene.light.as_area().unwrap();
        let first = *poses.light.as_area().unwrap();
        let centre = casters_centre(&scene).unwrap();
        let axis_dist = |p: Vec3| Vec3::new(p.x - centre.x, 0.0, p.z - centre.z).length();
        let mut last = start.center;
        for k in 0..8 {
            let (l, _) = poses.at(k, 8);
            let l = *l.as_area().unwrap();
            assert!((l.center.y - first.center.y).abs() < 1e-5);
            assert!((axis_dist(l.center) - axis_dist(first.center)).abs() < 1e-4);
            // The normal keeps its angle to the direction toward the axis.
            let inward =
                |c: Vec3| Vec3::new(centre.x - c.x, 0.0, centre.z - c.z).normalize_or_zero();
            let a0 = first.normal.dot(inward(first.center));
            assert!((l.normal.dot(inward(l.center)) - a0).abs() < 1e-4);
            assert!((l.normal.y - first.normal.y).abs() < 1e-5);
            if k > 0 {
                assert!((l.center - last).length() > 1e-3, "frame {k} moved");
            }
            last = l.center;
        }
        assert!((poses.at(0, 8).0.center() - first.center).length() < 1e-6);
    }

    #[test]
    fn a_light_on_the_axis_is_moved_off_it_and_the_camera_orbits_its_target() {
        let mut scene = crate::scene::load("fig7-concave").unwrap();
        let centre = casters_centre(&scene).unwrap();
        scene.light = scene
            .light
            .with_center(Vec3::new(centre.x, centre.y + 4.0, centre.z));
        let poses = Poses::new(&scene, Orbit::Light);
        assert!(poses.note.is_some());
        assert!((poses.light.center().x - centre.x - 2.0).abs() < 1e-4);

        let poses = Poses::new(&scene, Orbit::Camera);
        let target = scene.camera.target;
        let d0 = (scene.camera.eye - target).length();
        let (light, camera) = poses.at(3, 12);
        assert_eq!(camera.target, target);
        assert!(((camera.eye - target).length() - d0).abs() < 1e-4);
        assert!(
            (camera.eye - scene.camera.eye).length() > 1e-3,
            "the camera moved"
        );
        assert_eq!(light, scene.light, "the light stays");
    }
}
