//! The schema of a scene file: what `[camera]`, `[light]` and each `[[object]]` hold, with their
//! defaults, and how they read and write.

use crate::scene::{AreaLight, Camera, Light, LightKind, LineLight, Outline};
use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::{de, Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// A parsed scene file, before meshes are loaded. Numbers are kept as `f64` so a file written
/// back by [`SceneFile::to_toml`] reads `0.1`, not `0.10000000149011612`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[camera]` is optional: without it the scene is seen by [`crate::scene::framed_camera`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraSpec>,
    pub light: LightSpec,
    #[serde(rename = "object", default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectSpec>,
}

/// `[camera]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub fov_y_deg: f64,
}

/// `[light]`: a disk (`center`, `normal`, `radius`), with `kind = "rect"` a rectangle
/// (`center`, `normal`, `size`, optional `tangent`), with `kind = "polygon"` a convex polygon
/// (`vertices`), or with `kind = "line"` a segment (`a`, `b`). One flat table rather than a
/// tagged enum, so `kind` can default to a disk (old files load unchanged), unknown keys stay
/// errors, and the keys of another kind get the house's messages ([`SceneFile::validate`]). A
/// disk writes back exactly the keys it always had.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<LightKind>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangent: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Vec<[f64; 3]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<[f64; 3]>,
    #[serde(default = "one")]
    pub intensity: f64,
}

impl LightSpec {
    /// A disk light's keys.
    pub fn disk(center: [f64; 3], normal: [f64; 3], radius: f64) -> LightSpec {
        LightSpec {
            center: Some(center),
            normal: Some(normal),
            radius: Some(radius),
            intensity: 1.0,
            ..LightSpec::default()
        }
    }

    /// A rectangle light's keys.
    pub fn rect(
        center: [f64; 3],
        normal: [f64; 3],
        size: [f64; 2],
        tangent: Option<[f64; 3]>,
    ) -> LightSpec {
        LightSpec {
            kind: Some(LightKind::Rect),
            center: Some(center),
            normal: Some(normal),
            size: Some(size),
            tangent,
            intensity: 1.0,
            ..LightSpec::default()
        }
    }

    /// A polygon light's keys.
    pub fn polygon(vertices: Vec<[f64; 3]>) -> LightSpec {
        LightSpec {
            kind: Some(LightKind::Polygon),
            vertices: Some(vertices),
            intensity: 1.0,
            ..LightSpec::default()
        }
    }

    /// A line light's keys.
    pub fn line(a: [f64; 3], b: [f64; 3]) -> LightSpec {
        LightSpec {
            kind: Some(LightKind::Line),
            a: Some(a),
            b: Some(b),
            intensity: 1.0,
            ..LightSpec::default()
        }
    }

    /// The keys of `light` (in `f64`; a rectangle keeps its tangent).
    pub fn of(light: &Light) -> LightSpec {
        let f = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        let mut out = match light {
            Light::Area(d) => match d.outline {
                Outline::Disk => LightSpec::disk(f(d.center), f(d.normal), f64::from(d.radius)),
                Outline::Rect { tangent, size } => LightSpec::rect(
                    f(d.center),
                    f(d.normal),
                    size.map(f64::from),
                    Some(f(tangent)),
                ),
                Outline::Polygon(p) => {
                    LightSpec::polygon(p.vertices().iter().map(|v| f(*v)).collect())
                }
            },
            Light::Line(l) => LightSpec::line(f(l.a), f(l.b)),
        };
        out.intensity = f64::from(light.intensity());
        out
    }

    pub fn kind(&self) -> LightKind {
        self.kind.unwrap_or_default()
    }

    /// The light, in `f32`, for a spec that [`SceneFile::validate`] accepted; missing keys of
    /// an unchecked spec read as zero (a zero normal becomes straight down).
    pub fn light(&self) -> Light {
        let v = |a: Option<[f64; 3]>| a.map_or(Vec3::ZERO, v3);
        let normal = || v(self.normal).try_normalize().unwrap_or(Vec3::NEG_Y);
        let intensity = self.intensity as f32;
        match self.kind() {
            LightKind::Disk => Light::Area(
                AreaLight::disk(v(self.center), normal(), self.radius.unwrap_or(0.0) as f32)
                    .with_intensity(intensity),
            ),
            LightKind::Rect => {
                let size = self.size.unwrap_or([0.0; 2]).map(|x| x as f32);
                let tangent = self.tangent.map(v3);
                Light::Area(
                    AreaLight::rect(v(self.center), normal(), size, tangent)
                        .with_intensity(intensity),
                )
            }
            LightKind::Polygon => {
                let points: Vec<Vec3> = self.vertices.iter().flatten().map(|p| v3(*p)).collect();
                Light::Area(AreaLight::polygon(&points).with_intensity(intensity))
            }
            LightKind::Line => Light::Line(LineLight {
                a: v(self.a),
                b: v(self.b),
                intensity,
            }),
        }
    }

    /// The light's centre as written in the file: a disk's or rectangle's `center`, a
    /// polygon's centroid, a segment's midpoint.
    pub fn center_f64(&self) -> [f64; 3] {
        match (self.kind(), self.center, self.a, self.b) {
            (LightKind::Disk | LightKind::Rect, Some(c), _, _) => c,
            (LightKind::Line, _, Some(a), Some(b)) => std::array::from_fn(|i| 0.5 * (a[i] + b[i])),
            (LightKind::Polygon, ..) => {
                let c = self.light().center();
                [c.x as f64, c.y as f64, c.z as f64]
            }
            _ => [0.0; 3],
        }
    }

    /// The same place as a light of `kind` ([`Light::converted`]).
    pub fn converted(&self, kind: LightKind) -> LightSpec {
        if kind == self.kind() {
            return self.clone();
        }
        let mut out = LightSpec::of(&self.light().converted(kind));
        out.intensity = self.intensity;
        out
    }

    /// Handle `k` of the light moved to `to`: a line's end (0: `a`, else `b`); a rectangle's
    /// corner, which resizes it about its centre (the corner's offsets along its tangent and its
    /// height's direction, doubled, at least 1 mm); a polygon's vertex `k`, projected onto the
    /// polygon's plane, kept only if the polygon stays a light ([`crate::scene::check_polygon`]).
    /// A disk has no handles.
    pub fn set_corner(&mut self, k: usize, to: [f64; 3]) {
        match self.kind() {
            LightKind::Disk => {}
            LightKind::Line => {
                if k == 0 {
                    self.a = Some(to);
                } else {
                    self.b = Some(to);
                }
            }
            LightKind::Rect => {
                let Some(a) = self.light().as_area().copied() else {
                    return;
                };
                let (t, b) = a.basis();
                let d = v3(to) - a.center;
                let size = [
                    f64::from(2.0 * d.dot(t).abs()).max(1e-3),
                    f64::from(2.0 * d.dot(b).abs()).max(1e-3),
                ];
                self.size = Some(size);
                self.tangent = Some([t.x as f64, t.y as f64, t.z as f64]);
            }
            LightKind::Polygon => {
                let Some(a) = self.light().as_area().copied() else {
                    return;
                };
                let Some(vertices) = self.vertices.as_ref() else {
                    return;
                };
                if k >= vertices.len() {
                    return;
                }
                let n = a.normal.as_dvec3();
                let p = glam::DVec3::from(to);
                let on_plane = p - n * n.dot(p - a.center.as_dvec3());
                let mut moved = vertices.clone();
                moved[k] = on_plane.to_array();
                let points: Vec<glam::DVec3> =
                    moved.iter().map(|v| glam::DVec3::from(*v)).collect();
                if crate::scene::check_polygon(&points).is_none() {
                    self.vertices = Some(moved);
                }
            }
        }
    }

    /// The light moved so its centre is at `to`; a line or polygon keeps its shape.
    pub fn set_center(&mut self, to: [f64; 3]) {
        let c = self.center_f64();
        let shift = |p: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| p[i] + to[i] - c[i]) };
        match self.kind() {
            LightKind::Disk | LightKind::Rect => self.center = Some(to),
            LightKind::Polygon => {
                if let Some(vs) = &mut self.vertices {
                    for p in vs.iter_mut() {
                        *p = shift(*p);
                    }
                }
            }
            LightKind::Line => {
                self.a = self.a.map(shift);
                self.b = self.b.map(shift);
            }
        }
    }
}

/// One `[[object]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub mesh: String,
    #[serde(default)]
    pub translate: [f64; 3],
    #[serde(default)]
    pub rotate_deg: [f64; 3],
    #[serde(default)]
    pub scale: Scale,
    #[serde(default = "yes")]
    pub casts_shadow: bool,
    /// Which scene of a glTF model (`.gltf`/`.glb` mesh) to draw; default: the model's default
    /// scene (its `scene`, else its first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gltf_scene: Option<usize>,
}

/// `scale`: one number for all axes, or `[x, y, z]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

impl Scale {
    /// The three per-axis factors.
    pub fn xyz(&self) -> [f64; 3] {
        match *self {
            Scale::Uniform(s) => [s; 3],
            Scale::PerAxis(v) => v,
        }
    }
}

impl Serialize for Scale {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Scale::Uniform(x) => s.serialize_f64(*x),
            Scale::PerAxis(v) => v.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> de::Visitor<'de> for V {
            type Value = Scale;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of three numbers [x, y, z]")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<Scale, E> {
                Ok(Scale::Uniform(x))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<Scale, E> {
                Ok(Scale::Uniform(x as f64))
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<Scale, E> {
                Ok(Scale::Uniform(x as f64))
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Scale, A::Error> {
                let mut v = [0.0; 3];
                for (i, slot) in v.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<f64>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Scale::PerAxis(v))
            }
        }
        d.deserialize_any(V)
    }
}

fn one() -> f64 {
    1.0
}

fn yes() -> bool {
    true
}

pub(super) fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

pub(super) fn show(a: &[f64]) -> String {
    let parts: Vec<String> = a.iter().map(|x| format!("{x}")).collect();
    if parts.len() == 1 {
        parts[0].clone()
    } else {
        format!("[{}]", parts.join(", "))
    }
}

impl CameraSpec {
    /// The camera, in `f32`.
    pub fn camera(&self) -> Camera {
        Camera {
            eye: v3(self.eye),
            target: v3(self.target),
            fov_y_deg: self.fov_y_deg as f32,
        }
    }
}

impl ObjectSpec {
    /// The object's name: `name`, or else the mesh name.
    pub fn display_name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.mesh)
    }

    /// The object-to-world transform `T · R · S` (see the module documentation).
    pub fn transform(&self) -> Affine3A {
        let r = self.rotate_deg;
        let rotation = Quat::from_euler(
            EulerRot::XYZ,
            (r[0] as f32).to_radians(),
            (r[1] as f32).to_radians(),
            (r[2] as f32).to_radians(),
        );
        Affine3A::from_scale_rotation_translation(
            v3(self.scale.xyz()),
            rotation,
            v3(self.translate),
        )
    }
}
