//! The glTF JSON parsed and validated by the `gltf` crate, and its errors told without quoting
//! anything of the file.

/// The JSON parsed and validated by the `gltf` crate, except that a POSITION accessor without
/// `min`/`max` (required by the spec, left out by some exporters, and not used here) is let
/// through.
pub(super) fn document(json: &[u8]) -> Result<::gltf::Document, ::gltf::Error> {
    use ::gltf::json::validation::{Error, Validate};
    let root: ::gltf::json::Root =
        ::gltf::json::deserialize::from_slice(json).map_err(::gltf::Error::Deserialize)?;
    // gltf-json 1.4.1 validates a primitive by indexing `accessors` with its POSITION before
    // checking that index (a 300-byte file with `"POSITION": 3` and two accessors panics in
    // `validate`): those indices are checked here first.
    let mut errors = Vec::new();
    let position = ::gltf::json::validation::Checked::Valid(::gltf::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            match primitive.attributes.get(&position) {
                Some(i) if i.value() >= root.accessors.len() => errors.push((
                    ::gltf::json::Path::new()
                        .field("meshes")
                        .index(m)
                        .field("primitives")
                        .index(p)
                        .field("attributes")
                        .key("POSITION"),
                    Error::IndexOutOfBounds,
                )),
                _ => {}
            }
        }
    }
    if !errors.is_empty() {
        return Err(::gltf::Error::Validation(errors));
    }
    root.validate(&root, ::gltf::json::Path::new, &mut |path, error| {
        let path = path();
        let bounds = path.0.ends_with(".min") || path.0.ends_with(".max");
        if !(bounds && matches!(error, Error::Missing)) {
            errors.push((path, error));
        }
    });
    if errors.is_empty() {
        Ok(::gltf::Document::from_json_without_validation(root))
    } else {
        Err(::gltf::Error::Validation(errors))
    }
}

/// The `gltf` crate's error, without quoting the file.
pub(super) fn describe_gltf_error(e: &::gltf::Error) -> String {
    match e {
        ::gltf::Error::Validation(list) => {
            let shown: Vec<String> = list
                .iter()
                .take(3)
                .map(|(path, err)| format!("{}: {err}", path_shown(path.as_str())))
                .collect();
            let more = if list.len() > 3 {
                format!(" (and {} more)", list.len() - 3)
            } else {
                String::new()
            };
            format!("invalid glTF: {}{more}", shown.join("; "))
        }
        ::gltf::Error::Deserialize(e) => format!(
            "not glTF JSON: {} at line {}, column {}",
            match e.classify() {
                serde_json::error::Category::Io => "cannot read",
                serde_json::error::Category::Syntax => "a JSON syntax error",
                serde_json::error::Category::Data => "a value of the wrong type or a missing field",
                serde_json::error::Category::Eof => "the JSON ends early (truncated?)",
            },
            e.line(),
            e.column()
        ),
        other => format!("invalid glTF: {other}"),
    }
}

/// A validation error's JSON path without what it quotes of the file: gltf-json appends the
/// value (`extensionsRequired[0] = "NAME"`) and names keys (`attributes["NAME"]`); a value is
/// dropped, a key kept only if it is a standard attribute name.
fn path_shown(path: &str) -> String {
    let path = path.split_once(" = ").map_or(path, |(p, _)| p);
    let standard = |key: &str| {
        ["POSITION", "NORMAL", "TANGENT"].contains(&key)
            || ["TEXCOORD_", "COLOR_", "JOINTS_", "WEIGHTS_"]
                .iter()
                .any(|p| {
                    key.strip_prefix(p).is_some_and(|n| {
                        !n.is_empty() && n.len() <= 3 && n.bytes().all(|b| b.is_ascii_digit())
                    })
                })
    };
    let mut out = String::new();
    let mut rest = path;
    while let Some(at) = rest.find("[\"") {
        out.push_str(&rest[..at]);
        let after = &rest[at + 2..];
        match after.find("\"]") {
            Some(end) => {
                let key = &after[..end];
                out.push_str(if standard(key) { "[\"" } else { "[\"…" });
                if standard(key) {
                    out.push_str(key);
                }
                out.push_str("\"]");
                rest = &after[end + 2..];
            }
            None => {
                out.push_str("[\"…");
                rest = "";
            }
        }
    }
    out.push_str(rest);
    crate::scene::shown(&out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_paths_quote_nothing_of_the_file() {
        assert_eq!(
            path_shown("extensionsRequired[0] = \"SECRET\""),
            "extensionsRequired[0]"
        );
        assert_eq!(
            path_shown("meshes[0].primitives[1].attributes[\"POSITION\"]"),
            "meshes[0].primitives[1].attributes[\"POSITION\"]"
        );
        assert_eq!(
            path_shown("meshes[0].primitives[0].attributes[\"_SECRET\"].x"),
            "meshes[0].primitives[0].attributes[\"…\"].x"
        );
        assert_eq!(path_shown("a[\"TEXCOORD_1\"]"), "a[\"TEXCOORD_1\"]");
        assert_eq!(path_shown("a[\"TEXCOORD_\"]"), "a[\"…\"]");
        assert_eq!(path_shown("a[\"SEC\nRET"), "a[\"…");
    }
}
