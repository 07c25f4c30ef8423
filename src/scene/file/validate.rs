//! Every value TOML accepts but a scene cannot use, refused with the key, what was expected and
//! what was found.

use super::meshes::{check_budget, shape_error};
use super::spec::{show, v3, Scale, SceneFile};
use crate::scene::obj::Others;
use crate::scene::{check_polygon, shapes, LightKind, SceneError, MIN_LINE_LENGTH};
use glam::DVec3;

impl SceneFile {
    /// Checks every value that TOML accepts but a scene cannot use. `parse` calls it; call it
    /// again after editing a `SceneFile` in code.
    pub fn validate(&self, label: &str) -> Result<(), SceneError> {
        let invalid = |key: &str, expected: &str, found: String| SceneError::Invalid {
            file: label.to_string(),
            key: key.to_string(),
            expected: expected.to_string(),
            found,
        };
        let finite = |key: &str, v: &[f64]| {
            // Meshes and the GPU use f32: a number past f32::MAX is infinite there.
            if v.iter().all(|&x| x.is_finite() && (x as f32).is_finite()) {
                Ok(())
            } else {
                Err(invalid(
                    key,
                    "finite numbers (no nan or inf; magnitude below 3.4e38)",
                    show(v),
                ))
            }
        };

        if let Some(c) = &self.camera {
            finite("camera.eye", &c.eye)?;
            finite("camera.target", &c.target)?;
            finite("camera.fov_y_deg", &[c.fov_y_deg])?;
            if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
                return Err(invalid(
                    "camera.fov_y_deg",
                    "a vertical field of view in degrees strictly between 0 and 180",
                    show(&[c.fov_y_deg]),
                ));
            }
            if v3(c.eye) == v3(c.target) {
                return Err(invalid(
                    "camera.target",
                    "a point different from camera.eye",
                    show(&c.target),
                ));
            }
        }

        let l = &self.light;
        let kind = l.kind();
        // The keys of another kind are mistakes, not options: say which kind reads them.
        let present: [(&str, Option<String>); 8] = [
            ("center", l.center.map(|v| show(&v))),
            ("normal", l.normal.map(|v| show(&v))),
            ("radius", l.radius.map(|v| show(&[v]))),
            ("size", l.size.map(|v| show(&v))),
            ("tangent", l.tangent.map(|v| show(&v))),
            (
                "vertices",
                l.vertices.as_ref().map(|v| format!("{} vertices", v.len())),
            ),
            ("a", l.a.map(|v| show(&v))),
            ("b", l.b.map(|v| show(&v))),
        ];
        for (key, found) in present {
            let Some(found) = found else { continue };
            if !light_keys(kind).contains(&key) {
                let owner = LightKind::ALL
                    .into_iter()
                    .find(|k| light_keys(*k).contains(&key))
                    .unwrap_or_default();
                let expected = format!(
                    "no such key for a {kind} light (kind = \"{kind}\" reads {} and intensity; \
                     {key} belongs to kind = \"{owner}\")",
                    light_keys(kind).join(", ")
                );
                return Err(invalid(&format!("light.{key}"), &expected, found));
            }
        }
        let missing = |key: &str, expected: &str| invalid(key, expected, "nothing".into());
        let normal_of = |what: &str| -> Result<[f64; 3], SceneError> {
            let normal = l.normal.ok_or_else(|| {
                missing(
                    "light.normal",
                    &format!("the {what}'s normal [x, y, z] (it emits toward it)"),
                )
            })?;
            finite("light.normal", &normal)?;
            let n = v3(normal);
            if n.length() <= 1e-6 || n.try_normalize().is_none() {
                return Err(invalid(
                    "light.normal",
                    "a non-zero direction (it is normalised)",
                    show(&normal),
                ));
            }
            Ok(normal)
        };
        match kind {
            LightKind::Disk | LightKind::Rect => {
                let what = if kind == LightKind::Disk {
                    "disk"
                } else {
                    "rectangle"
                };
                let center = l.center.ok_or_else(|| {
                    missing("light.center", &format!("the {what}'s centre [x, y, z]"))
                })?;
                finite("light.center", &center)?;
                let normal = normal_of(what)?;
                if kind == LightKind::Disk {
                    let radius = l
                        .radius
                        .ok_or_else(|| missing("light.radius", "the disk's radius"))?;
                    finite("light.radius", &[radius])?;
                    if radius <= 0.0 {
                        return Err(invalid(
                            "light.radius",
                            "a positive disk radius",
                            show(&[radius]),
                        ));
                    }
                } else {
                    let size = l.size.ok_or_else(|| {
                        missing("light.size", "the rectangle's [width, height] in metres")
                    })?;
                    finite("light.size", &size)?;
                    if size.iter().any(|&x| x <= 0.0 || (x as f32) <= 0.0) {
                        return Err(invalid(
                            "light.size",
                            "a positive width and height [w, h] in metres",
                            show(&size),
                        ));
                    }
                    if let Some(t) = l.tangent {
                        finite("light.tangent", &t)?;
                        let (t, n) = (DVec3::from(t), DVec3::from(normal).normalize());
                        let projected = t - n * n.dot(t);
                        if projected.length() <= 1e-6 * t.length().max(1e-30) || t.length() == 0.0 {
                            return Err(invalid(
                                "light.tangent",
                                "a direction not parallel to light.normal (the width's \
                                 direction, projected onto the light's plane)",
                                show(&l.tangent.unwrap_or_default()),
                            ));
                        }
                    }
                }
            }
            LightKind::Polygon => {
                let vertices = l.vertices.as_ref().ok_or_else(|| {
                    missing(
                        "light.vertices",
                        "the polygon's vertices [[x, y, z], ...], counter-clockwise seen from \
                         the side it emits to",
                    )
                })?;
                for v in vertices {
                    finite("light.vertices", v)?;
                }
                let points: Vec<DVec3> = vertices.iter().map(|v| DVec3::from(*v)).collect();
                if let Some((expected, found)) = check_polygon(&points) {
                    let found = if found.is_empty() {
                        format!("{} vertices", vertices.len())
                    } else {
                        found
                    };
                    return Err(invalid("light.vertices", &expected, found));
                }
            }
            LightKind::Line => {
                let a = l.a.ok_or_else(|| {
                    missing("light.a", "the first end point [x, y, z] of the line light")
                })?;
                let b = l.b.ok_or_else(|| {
                    missing(
                        "light.b",
                        "the second end point [x, y, z] of the line light",
                    )
                })?;
                finite("light.a", &a)?;
                finite("light.b", &b)?;
                // In f32, as the light is used: a and b must stay apart there too.
                if (v3(b) - v3(a)).length() < MIN_LINE_LENGTH as f32 {
                    return Err(invalid(
                        "light.b",
                        &format!(
                            "an end point at least {MIN_LINE_LENGTH} m from light.a (the line \
                             light has zero length)"
                        ),
                        show(&b),
                    ));
                }
            }
        }
        finite("light.intensity", &[l.intensity])?;
        if l.intensity < 0.0 {
            return Err(invalid(
                "light.intensity",
                "a non-negative number",
                show(&[l.intensity]),
            ));
        }

        let mut shapes_use = Others::default();
        for (i, o) in self.objects.iter().enumerate() {
            let key = |k: &str| format!("object[{i}].{k}");
            if o.mesh.trim().is_empty() {
                return Err(invalid(
                    &key("mesh"),
                    "a built-in shape name or a path to an .obj, .gltf or .glb file",
                    "an empty string".into(),
                ));
            }
            if shapes::is_shape_name(&o.mesh) {
                // Parameters and size are known before anything is built.
                let shape = shapes::Shape::parse(&o.mesh)
                    .map_err(|e| shape_error(e, label, &key("mesh")))?;
                check_budget(label, &key("mesh"), &o.mesh, &shape, shapes_use)?;
                shapes_use.add(&shape);
            }
            finite(&key("translate"), &o.translate)?;
            finite(&key("rotate_deg"), &o.rotate_deg)?;
            let s = o.scale.xyz();
            finite(&key("scale"), &s)?;
            // f32 is what the mesh gets: a scale that underflows to 0 there is zero too.
            if s.iter().any(|&x| x as f32 == 0.0) {
                return Err(invalid(
                    &key("scale"),
                    "non-zero scale factors (negative ones mirror)",
                    match o.scale {
                        Scale::Uniform(x) => show(&[x]),
                        Scale::PerAxis(v) => show(&v),
                    },
                ));
            }
        }
        Ok(())
    }
}

/// The keys of `[light]` a light of `kind` reads, besides `kind` and `intensity`.
pub fn light_keys(kind: LightKind) -> &'static [&'static str] {
    match kind {
        LightKind::Disk => &["center", "normal", "radius"],
        LightKind::Rect => &["center", "normal", "size", "tangent"],
        LightKind::Polygon => &["vertices"],
        LightKind::Line => &["a", "b"],
    }
}
