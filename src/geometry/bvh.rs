//! Stand-in until the real BVH lands: brute force with the same API.

use glam::Vec3;

use super::ray::intersect_triangle;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    tris: Vec<[Vec3; 3]>,
}

impl Bvh {
    pub fn build(triangles: Vec<[Vec3; 3]>) -> Bvh {
        Bvh { tris: triangles }
    }
    pub fn len(&self) -> usize {
        self.tris.len()
    }
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }
    pub fn triangle(&self, i: usize) -> &[Vec3; 3] {
        &self.tris[i]
    }
    pub fn for_each_hit(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32, mut f: impl FnMut(Hit)) {
        for (i, t) in self.tris.iter().enumerate() {
            if let Some(t) = intersect_triangle(o, d, t).filter(|t| *t > t_min && *t < t_max) {
                f(Hit {
                    t,
                    triangle: i as u32,
                });
            }
        }
    }
    pub fn closest_hit(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.for_each_hit(o, d, t_min, t_max, |h| {
            if best.is_none_or(|b| h.t < b.t) {
                best = Some(h);
            }
        });
        best
    }
    pub fn any_hit(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> bool {
        self.closest_hit(o, d, t_min, t_max).is_some()
    }
}
