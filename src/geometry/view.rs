//! What the camera sees, on the CPU: the surface point and normal behind every pixel. The CPU
//! twin, the oracle and the metrics use it to evaluate a whole frame the way the camera pass does.

use glam::Vec3;
use rayon::prelude::*;

use super::bvh::Bvh;
use crate::scene::Scene;

/// The surface behind one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    pub position: Vec3,
    /// Unit normal of the hit triangle, turned toward the camera.
    pub normal: Vec3,
    /// The normal faces the light centre (a line's midpoint) and the light reaches the point
    /// (in front of a one-sided disk): the pixels the metrics of docs/method/metrics.md are taken over.
    pub faces_light: bool,
}

/// The receiver behind each pixel of a `width`×`height` view (row-major, row 0 at the top);
/// `None` where the ray hits nothing.
pub fn receivers(scene: &Scene, surfaces: &Bvh, width: u32, height: u32) -> Vec<Option<Receiver>> {
    per_pixel(width, height, |i| {
        receiver_at(scene, surfaces, i, width, height)
    })
}

/// [`receivers`]' surface points alone (16 bytes a pixel instead of 32).
pub fn points(scene: &Scene, surfaces: &Bvh, width: u32, height: u32) -> Vec<Option<Vec3>> {
    per_pixel(width, height, |i| {
        receiver_at(scene, surfaces, i, width, height).map(|r| r.position)
    })
}

/// Whether each pixel's receiver faces the light ([`Receiver::faces_light`]; false where the
/// ray hits nothing): a byte a pixel, what the metrics' mask needs of [`receivers`].
pub fn facing_light(scene: &Scene, surfaces: &Bvh, width: u32, height: u32) -> Vec<bool> {
    per_pixel(width, height, |i| {
        receiver_at(scene, surfaces, i, width, height).is_some_and(|r| r.faces_light)
    })
}

fn per_pixel<T: Send>(width: u32, height: u32, f: impl Fn(u32) -> T + Sync + Send) -> Vec<T> {
    (0..width * height).into_par_iter().map(f).collect()
}

/// The receiver behind pixel `i` of a `width`×`height` view.
pub fn receiver_at(
    scene: &Scene,
    surfaces: &Bvh,
    i: u32,
    width: u32,
    height: u32,
) -> Option<Receiver> {
    let light = scene.light;
    let (origin, dir) = scene.camera.pixel_ray(i % width, i / width, width, height);
    let hit = surfaces.closest_hit(origin, dir, 0.0, f32::INFINITY)?;
    let [a, b, c] = *surfaces.triangle(hit.triangle as usize);
    let mut normal = (b - a).cross(c - a).normalize_or_zero();
    if normal.dot(dir) > 0.0 {
        normal = -normal;
    }
    let position = origin + dir * hit.t;
    let faces_light = normal.dot(light.center() - position) > 0.0 && light.reaches(position);
    Some(Receiver {
        position,
        normal,
        faces_light,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{AreaLight, Camera, Mesh, Object};

    #[test]
    fn pixel_rays_match_the_view_projection_and_hit_the_ground() {
        let camera = Camera {
            eye: Vec3::new(0.5, 3.0, 6.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            fov_y_deg: 45.0,
        };
        let (w, h) = (40, 30);
        let clip = camera.projection(w as f32 / h as f32, 0.1, 100.0) * camera.view();
        for (px, py) in [(0, 0), (39, 29), (20, 15), (7, 22)] {
            let (o, d) = camera.pixel_ray(px, py, w, h);
            let p = clip.project_point3(o + 5.0 * d);
            let expect_x = 2.0 * (px as f32 + 0.5) / w as f32 - 1.0;
            let expect_y = 1.0 - 2.0 * (py as f32 + 0.5) / h as f32;
            assert!(
                (p.x - expect_x).abs() < 1e-4 && (p.y - expect_y).abs() < 1e-4,
                "{px},{py}: {p}"
            );
        }
        let ground = Mesh::new(
            vec![
                Vec3::new(-10.0, 0.0, -10.0),
                Vec3::new(10.0, 0.0, -10.0),
                Vec3::new(10.0, 0.0, 10.0),
                Vec3::new(-10.0, 0.0, 10.0),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        );
        let scene = Scene {
            name: "ground".into(),
            camera,
            light: AreaLight {
                center: Vec3::new(0.0, 4.0, 0.0),
                normal: Vec3::NEG_Y,
                radius: 0.5,
                intensity: 1.0,
                outline: crate::scene::Outline::Disk,
            }
            .into(),
            objects: vec![Object {
                name: "ground".into(),
                mesh: ground,
                casts_shadow: false,
            }],
        };
        let bvh = Bvh::build(scene.all_triangles());
        let r = receivers(&scene, &bvh, w, h);
        let centre = r[(15 * w + 20) as usize].expect("the centre pixel sees the ground");
        assert!(centre.position.y.abs() < 1e-4 && centre.normal == Vec3::Y && centre.faces_light);
        assert!(r[0].is_none(), "the top-left pixel looks above the horizon");
    }
}
