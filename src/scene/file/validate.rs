//! Every value TOML accepts but a scene cannot use, refused with the key, what was expected and
//! what was found.

use super::meshes::{check_budget, shape_error};
use super::spec::{show, v3, Scale, SceneFile};
use crate::scene::obj::Others;
use crate::scene::{shapes, LightKind, SceneError, MIN_LINE_LENGTH};

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
        // The keys of the other kind are mistakes, not options: say which kind reads them.
        let foreign = |key: &str, found: String, kind: LightKind| {
            let expected = match kind {
                LightKind::Line => {
                    "no such key for a line light (kind = \"line\" reads a, b and intensity)"
                }
                LightKind::Disk => {
                    "no such key for a disk light (a disk reads center, normal, radius and \
                     intensity; end points a and b need kind = \"line\")"
                }
            };
            invalid(key, expected, found)
        };
        let missing = |key: &str, expected: &str| invalid(key, expected, "nothing".into());
        match l.kind() {
            LightKind::Disk => {
                for (key, value) in [("light.a", l.a), ("light.b", l.b)] {
                    if let Some(v) = value {
                        return Err(foreign(key, show(&v), LightKind::Disk));
                    }
                }
                let center = l
                    .center
                    .ok_or_else(|| missing("light.center", "the disk's centre [x, y, z]"))?;
                let normal = l.normal.ok_or_else(|| {
                    missing(
                        "light.normal",
                        "the disk's normal [x, y, z] (it emits toward it)",
                    )
                })?;
                let radius = l
                    .radius
                    .ok_or_else(|| missing("light.radius", "the disk's radius"))?;
                finite("light.center", &center)?;
                finite("light.normal", &normal)?;
                finite("light.radius", &[radius])?;
                let n = v3(normal);
                if n.length() <= 1e-6 || n.try_normalize().is_none() {
                    return Err(invalid(
                        "light.normal",
                        "a non-zero direction (it is normalised)",
                        show(&normal),
                    ));
                }
                if radius <= 0.0 {
                    return Err(invalid(
                        "light.radius",
                        "a positive disk radius",
                        show(&[radius]),
                    ));
                }
            }
            LightKind::Line => {
                for (key, value) in [("light.center", l.center), ("light.normal", l.normal)] {
                    if let Some(v) = value {
                        return Err(foreign(key, show(&v), LightKind::Line));
                    }
                }
                if let Some(r) = l.radius {
                    return Err(foreign("light.radius", show(&[r]), LightKind::Line));
                }
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
