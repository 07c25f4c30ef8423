//! `extensionsRequired`: what dbuffer decodes, what it may ignore (materials, textures,
//! animation), and what it must refuse (geometry it cannot decode), by name.

use super::json::Doc;
use serde_json::Value;

/// Geometry extensions dbuffer decodes.
pub(super) const DECODED: &[&str] = &[
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_lights_punctual",
];

/// Extensions that change the geometry, so that without them the triangles are not the
/// author's: refused when required.
const GEOMETRY: &[&str] = &[
    "KHR_draco_mesh_compression",
    "EXT_mesh_gpu_instancing",
    "KHR_gaussian_splatting",
    "EXT_mesh_manifold",
    "MSFT_lod",
    "FB_geometry_metadata",
    "CESIUM_primitive_outline",
    "EXT_primitive_voxels",
];

/// Why a required extension not in [`GEOMETRY`] or [`DECODED`] can be ignored: it only changes
/// how surfaces look or move, or carries data dbuffer does not show.
fn ignorable(name: &str) -> Option<&'static str> {
    let lower = name.to_ascii_lowercase();
    if lower.contains("texture") || lower.contains("image") || lower.contains("basisu") {
        Some("textures are not used")
    } else if lower.contains("material") || lower.contains("shading") || lower.contains("unlit") {
        Some("materials are not used")
    } else if lower.contains("animation") || lower.contains("skin") {
        Some("animations are not played")
    } else if lower.contains("xmp") || lower.contains("metadata") || lower.contains("audio") {
        Some("it carries data dbuffer does not show")
    } else if lower.contains("camera") {
        Some("cameras are not used")
    } else {
        None
    }
}

/// Whether `name` looks like a glTF extension name (`VENDOR_name`: an upper-case prefix of 2 to
/// 16 letters or digits, `_`, then letters, digits and `_`, 64 characters at most): such a
/// name is said back in messages; anything else in `extensionsRequired` is file content and is
/// referred to by its index only.
pub(super) fn is_extension_name(name: &str) -> bool {
    let Some((prefix, rest)) = name.split_once('_') else {
        return false;
    };
    name.len() <= 64
        && (2..=16).contains(&prefix.len())
        && prefix
            .bytes()
            .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit())
        && prefix
            .bytes()
            .next()
            .is_some_and(|b| b.is_ascii_uppercase())
        && !rest.is_empty()
        && rest.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

/// Checks `extensionsRequired`: refuses a geometry extension dbuffer cannot decode, naming it;
/// returns one note per ignored one. `extensionsRequired` that is not a list of strings is
/// ignored (it is only advice to loaders).
pub(super) fn check_required(doc: &Doc) -> Result<Vec<String>, String> {
    let mut notes = Vec::new();
    let Some(Value::Array(list)) = doc.root().get("extensionsRequired") else {
        return Ok(notes);
    };
    let mut ignored: Vec<(&str, &'static str)> = Vec::new();
    for (i, v) in list.iter().enumerate() {
        let Some(name) = v.as_str() else {
            continue;
        };
        if DECODED.contains(&name) {
            continue;
        }
        if !is_extension_name(name) {
            return Err(format!(
                "invalid glTF: extensionsRequired[{i}] is not a glTF extension name \
                 (VENDOR_name), so dbuffer cannot tell what it needs (the name is not repeated)"
            ));
        }
        if GEOMETRY.contains(&name) {
            return Err(format!(
                "requires {name}, which dbuffer cannot decode{}",
                if name == "KHR_draco_mesh_compression" {
                    " (no maintained Draco decoder in Rust yet): re-export it without Draco, \
                     e.g. with meshopt compression (`gltf-transform meshopt`, `gltfpack -cc`)"
                } else {
                    ""
                }
            ));
        }
        match ignorable(name) {
            Some(why) => {
                if !ignored.iter().any(|(n, _)| *n == name) {
                    ignored.push((name, why));
                }
            }
            None => {
                return Err(format!(
                    "requires {name}, which dbuffer cannot decode (an extension it does not \
                     know, which may change the geometry)"
                ))
            }
        }
    }
    for (name, why) in ignored {
        notes.push(format!("requires {name}: ignored, {why} (geometry only)"));
    }
    Ok(notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extension_names_are_recognised_by_shape() {
        assert!(is_extension_name("KHR_draco_mesh_compression"));
        assert!(is_extension_name("EXT_texture_webp"));
        assert!(is_extension_name("ADOBE_materials_thin_transparency"));
        assert!(!is_extension_name("CANARYx7q"));
        assert!(!is_extension_name("SECRET\nline"));
        assert!(!is_extension_name("lower_case"));
        assert!(!is_extension_name("K_x"));
        assert!(!is_extension_name("KHR_"));
        assert!(!is_extension_name("KHR_a b"));
    }

    fn required(list: &str) -> Result<Vec<String>, String> {
        let json = format!("{{\"extensionsRequired\": {list}}}");
        check_required(&super::super::json::parse(json.as_bytes()).unwrap())
    }

    #[test]
    fn required_extensions_are_decoded_ignored_or_refused_by_name() {
        assert_eq!(
            required(r#"["KHR_mesh_quantization", "EXT_meshopt_compression"]"#).unwrap(),
            Vec::<String>::new()
        );
        let notes =
            required(r#"["EXT_texture_webp", "KHR_materials_unlit", "EXT_texture_webp"]"#).unwrap();
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(notes[0].contains("EXT_texture_webp") && notes[0].contains("textures"));
        assert!(notes[1].contains("KHR_materials_unlit") && notes[1].contains("materials"));
        let e = required(r#"["KHR_draco_mesh_compression"]"#).unwrap_err();
        assert!(
            e.starts_with("requires KHR_draco_mesh_compression, which dbuffer cannot decode"),
            "{e}"
        );
        let e = required(r#"["EXT_unknown_geometry"]"#).unwrap_err();
        assert!(e.contains("requires EXT_unknown_geometry, which dbuffer cannot decode"));
        let e = required(r#"["KHR_texture_basisu", "CANARYx7q"]"#).unwrap_err();
        assert!(
            e.contains("extensionsRequired[1]") && !e.contains("CANARY"),
            "{e}"
        );
        assert!(required("3").unwrap().is_empty());
    }
}
