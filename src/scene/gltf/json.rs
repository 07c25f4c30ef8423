//! The glTF JSON, read leniently: parsed once into `serde_json`'s tree, then each object dbuffer
//! uses (a scene, a node, a mesh, an accessor, a buffer view, a buffer, a light) is read from
//! it when it is reached, field by field, so a material, a texture or an animation that is
//! missing, partial or extended never stops a load. Errors name the JSON path of the field
//! (`nodes[3].mesh`) and what was expected, never quoting the file.

use serde_json::{Map, Value};

/// The parsed document: its top-level object.
#[derive(Debug)]
pub(super) struct Doc {
    root: Map<String, Value>,
}

/// An object of the document with the JSON path that names it in errors (`accessors[2]`).
#[derive(Clone, Debug)]
pub(super) struct Obj<'a> {
    pub(super) map: &'a Map<String, Value>,
    pub(super) path: String,
}

/// Parses the JSON text of a `.gltf` or of a GLB's JSON chunk (a UTF-8 byte-order mark is
/// allowed). The message says where the JSON breaks, never what it holds.
pub(super) fn parse(json: &[u8]) -> Result<Doc, String> {
    let json = json.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(json);
    match serde_json::from_slice::<Value>(json) {
        Ok(Value::Object(root)) => Ok(Doc { root }),
        Ok(_) => Err("not glTF JSON: the document is not a JSON object".into()),
        Err(e) => Err(format!(
            "not glTF JSON: {} at line {}, column {}",
            match e.classify() {
                serde_json::error::Category::Io => "cannot read",
                serde_json::error::Category::Syntax => "a JSON syntax error",
                serde_json::error::Category::Data =>
                    "a value of the wrong type or nesting too deep",
                serde_json::error::Category::Eof => "the JSON ends early (truncated?)",
            },
            e.line(),
            e.column()
        )),
    }
}

/// `s`, `"s"`, as a key in a path: standard attribute names are shown, others not.
fn shown_key(key: &str) -> &str {
    let standard = ["POSITION", "NORMAL", "TANGENT"].contains(&key)
        || ["TEXCOORD_", "COLOR_", "JOINTS_", "WEIGHTS_"]
            .iter()
            .any(|p| {
                key.strip_prefix(p).is_some_and(|n| {
                    !n.is_empty() && n.len() <= 3 && n.bytes().all(|b| b.is_ascii_digit())
                })
            });
    if standard {
        key
    } else {
        "…"
    }
}

/// `path["key"]`, the key shown only if it is a standard attribute name.
pub(super) fn key_path(path: &str, key: &str) -> String {
    format!("{path}[\"{}\"]", shown_key(key))
}

/// A JSON number that is a whole number, 0 or more: `3`, or `3.0` (JSON writers sometimes give
/// one so, and glTF's schema counts it as an integer).
fn whole(v: &Value) -> Option<u64> {
    v.as_u64().or_else(|| match v.as_f64() {
        Some(f) if f >= 0.0 && f.fract() == 0.0 && f < 1.8e19 => Some(f as u64),
        _ => None,
    })
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

impl Doc {
    /// The top-level object, with an empty path.
    pub(super) fn root(&self) -> Obj<'_> {
        Obj {
            map: &self.root,
            path: String::new(),
        }
    }

    /// How many entries the top-level array `name` has (0 if it is missing or not an array).
    pub(super) fn len(&self, name: &str) -> usize {
        self.root
            .get(name)
            .and_then(Value::as_array)
            .map_or(0, Vec::len)
    }

    /// Entry `i` of the top-level array `name` as an object. `from` (e.g. `nodes[0].mesh`)
    /// says who pointed there.
    pub(super) fn element(&self, name: &str, i: usize, from: &str) -> Result<Obj<'_>, String> {
        let n = self.len(name);
        let Some(v) = self
            .root
            .get(name)
            .and_then(Value::as_array)
            .and_then(|a| a.get(i))
        else {
            return Err(format!(
                "invalid glTF: {from} is {i}, but the file has {n} {name}{}",
                if self.root.get(name).is_some_and(|v| !v.is_array()) {
                    format!(" (`{name}` is not an array)")
                } else {
                    String::new()
                }
            ));
        };
        let path = format!("{name}[{i}]");
        match v {
            Value::Object(map) => Ok(Obj { map, path }),
            other => Err(format!(
                "invalid glTF: {path} is {}: expected an object",
                kind(other)
            )),
        }
    }
}

impl<'a> Obj<'a> {
    /// `path.field`.
    pub(super) fn at(&self, field: &str) -> String {
        if self.path.is_empty() {
            field.to_string()
        } else {
            format!("{}.{field}", self.path)
        }
    }

    pub(super) fn get(&self, field: &str) -> Option<&'a Value> {
        self.map.get(field)
    }

    fn wrong(&self, field: &str, v: &Value, expected: &str) -> String {
        format!(
            "invalid glTF: {} is {}: expected {expected}",
            self.at(field),
            kind(v)
        )
    }

    /// A non-negative whole number (an index or a count), if present.
    pub(super) fn opt_uint(&self, field: &str) -> Result<Option<u64>, String> {
        match self.map.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => whole(v)
                .map(Some)
                .ok_or_else(|| self.wrong(field, v, "a whole number, 0 or more")),
        }
    }

    /// A non-negative whole number that must be there.
    pub(super) fn uint(&self, field: &str) -> Result<u64, String> {
        self.opt_uint(field)?
            .ok_or_else(|| format!("invalid glTF: {} is missing", self.at(field)))
    }

    /// An index (a whole number that fits `usize`), if present.
    pub(super) fn opt_index(&self, field: &str) -> Result<Option<usize>, String> {
        Ok(self
            .opt_uint(field)?
            .map(|n| usize::try_from(n).unwrap_or(usize::MAX)))
    }

    pub(super) fn opt_bool(&self, field: &str) -> Result<Option<bool>, String> {
        match self.map.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Bool(b)) => Ok(Some(*b)),
            Some(v) => Err(self.wrong(field, v, "true or false")),
        }
    }

    /// A string field, if present.
    pub(super) fn opt_str(&self, field: &str) -> Result<Option<&'a str>, String> {
        match self.map.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.wrong(field, v, "a string")),
        }
    }

    /// An array of `n` numbers, if present (each as f32; a number beyond f32 is infinite, and
    /// refused by whoever needs it finite).
    pub(super) fn opt_floats(&self, field: &str, n: usize) -> Result<Option<Vec<f32>>, String> {
        match self.map.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Array(a)) if a.len() == n => a
                .iter()
                .map(|x| x.as_f64().map(|f| f as f32))
                .collect::<Option<Vec<f32>>>()
                .map(Some)
                .ok_or_else(|| {
                    format!(
                        "invalid glTF: {} has an entry that is not a number",
                        self.at(field)
                    )
                }),
            Some(v) => Err(self.wrong(field, v, &format!("an array of {n} numbers"))),
        }
    }

    /// An array of indices, if present.
    pub(super) fn opt_indices(&self, field: &str) -> Result<Option<Vec<usize>>, String> {
        match self.map.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Array(a)) => a
                .iter()
                .enumerate()
                .map(|(k, x)| {
                    whole(x)
                        .map(|n| usize::try_from(n).unwrap_or(usize::MAX))
                        .ok_or_else(|| {
                            format!(
                                "invalid glTF: {}[{k}] is {}: expected an index",
                                self.at(field),
                                kind(x)
                            )
                        })
                })
                .collect::<Result<Vec<usize>, String>>()
                .map(Some),
            Some(v) => Err(self.wrong(field, v, "an array of indices")),
        }
    }

    /// A nested object, if present.
    pub(super) fn opt_obj(&self, field: &str) -> Result<Option<Obj<'a>>, String> {
        match self.map.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Object(map)) => Ok(Some(Obj {
                map,
                path: self.at(field),
            })),
            Some(v) => Err(self.wrong(field, v, "an object")),
        }
    }

    /// `extensions.NAME` of this object, if present and an object (anything else is ignored:
    /// an extension dbuffer does not read is not its business).
    pub(super) fn extension(&self, name: &str) -> Option<Obj<'a>> {
        let map = self
            .map
            .get("extensions")?
            .as_object()?
            .get(name)?
            .as_object()?;
        Some(Obj {
            map,
            path: format!("{}.{name}", self.at("extensions")),
        })
    }

    /// Whether `extensions.NAME` is there at all.
    pub(super) fn has_extension(&self, name: &str) -> bool {
        self.map
            .get("extensions")
            .and_then(Value::as_object)
            .is_some_and(|e| e.contains_key(name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_quote_only_standard_attribute_names() {
        assert_eq!(key_path("a", "POSITION"), "a[\"POSITION\"]");
        assert_eq!(key_path("a", "TEXCOORD_1"), "a[\"TEXCOORD_1\"]");
        assert_eq!(key_path("a", "TEXCOORD_"), "a[\"…\"]");
        assert_eq!(key_path("a", "_SECRET\nx"), "a[\"…\"]");
    }

    #[test]
    fn fields_are_read_leniently_and_refused_by_path() {
        let doc = parse(br#"{"nodes": [{"mesh": 2.0, "children": [1, "x"], "scale": [1, 2]}, 7]}"#)
            .unwrap();
        let n = doc.element("nodes", 0, "scenes[0].nodes[0]").unwrap();
        assert_eq!(n.opt_index("mesh").unwrap(), Some(2));
        assert_eq!(
            n.opt_indices("children").unwrap_err(),
            "invalid glTF: nodes[0].children[1] is a string: expected an index"
        );
        assert!(n
            .opt_floats("scale", 3)
            .unwrap_err()
            .contains("nodes[0].scale"));
        assert!(doc
            .element("nodes", 1, "x")
            .unwrap_err()
            .contains("nodes[1] is a number"));
        assert!(doc
            .element("nodes", 5, "scenes[0].nodes[1]")
            .unwrap_err()
            .contains("scenes[0].nodes[1] is 5, but the file has 2 nodes"));
        assert!(parse(b"[1]").unwrap_err().contains("not a JSON object"));
        assert!(parse(b"{\"a\": SECRET}").unwrap_err().contains("line 1"));
    }
}
