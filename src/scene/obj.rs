//! Wavefront OBJ loading: a strict line scanner for clear errors, then `tobj` to triangulate.
//!
//! Only geometry is read: `v` positions and `f` faces (polygons are fan-triangulated by tobj).
//! Texture coordinates, normals, lines, points, groups and materials are ignored; `vt`/`vn`
//! lines and the `/vt/vn` parts of face references are checked for syntax only. Every problem
//! is reported as `FILE:LINE: what was expected`.
//!
//! All models of the file are merged into one [`Mesh`] and exactly equal positions (bitwise,
//! with `-0.0 == 0.0`) are welded into one vertex, so adjacency works downstream. Triangles that
//! become degenerate after welding (a repeated vertex) are dropped. Open boundaries (holes) are
//! kept as they are.

use super::{Mesh, SceneError};
use glam::Vec3;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// Loads the OBJ file at `path`; errors name the file as `path` displays.
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    let label = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        file: label.clone(),
        source,
    })?;
    let text = match std::str::from_utf8(&bytes) {
        Ok(t) => t,
        Err(e) => {
            let line = 1 + bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            return Err(SceneError::ObjLine {
                file: label,
                line,
                expected: "expected UTF-8 (or ASCII) text, found invalid bytes".into(),
            });
        }
    };
    parse_obj_str(text, &label)
}

/// Parses OBJ text; `label` names it in errors.
pub fn parse_obj_str(text: &str, label: &str) -> Result<Mesh, SceneError> {
    let clean = scan(text, label)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut clean.as_bytes(), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| SceneError::Obj {
        file: label.to_string(),
        problem: format!("tobj could not load it: {e}"),
    })?;

    let mut positions: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    for model in &models {
        let m = &model.mesh;
        let mut remap = Vec::with_capacity(m.positions.len() / 3);
        for p in m.positions.chunks_exact(3) {
            // `+ 0.0` turns -0.0 into 0.0 so both weld together.
            let p = Vec3::new(p[0] + 0.0, p[1] + 0.0, p[2] + 0.0);
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let next = positions.len() as u32;
            let id = *welded.entry(key).or_insert_with(|| {
                positions.push(p);
                next
            });
            remap.push(id);
        }
        for t in m.indices.chunks_exact(3) {
            let get = |i: u32| remap.get(i as usize).copied();
            let (Some(a), Some(b), Some(c)) = (get(t[0]), get(t[1]), get(t[2])) else {
                return Err(SceneError::Obj {
                    file: label.to_string(),
                    problem: "tobj produced an index out of range".into(),
                });
            };
            if a != b && b != c && a != c {
                triangles.push([a, b, c]);
            }
        }
    }
    if triangles.is_empty() {
        return Err(SceneError::Obj {
            file: label.to_string(),
            problem: "contains no triangles: expected at least one `f` line with 3 or more \
                      distinct vertices"
                .into(),
        });
    }
    Ok(Mesh::new(positions, triangles))
}

/// Checks every line and returns a simplified OBJ (only `v x y z` and `f i j k ...` lines, one
/// per input line so tobj sees the same vertex numbering) for tobj.
fn scan(text: &str, label: &str) -> Result<String, SceneError> {
    let ends_cleanly = text.is_empty() || text.ends_with('\n');
    let lines: Vec<&str> = text.split('\n').collect();
    let last = lines.len();
    let mut out = String::with_capacity(text.len());
    let mut n_v = 0usize;
    let mut n_vt = 0usize;
    let mut n_vn = 0usize;
    // (line, largest positive vertex index) of faces, checked once all vertices are known.
    let mut forward: Vec<(usize, i64)> = Vec::new();

    for (i, raw) in lines.iter().enumerate() {
        let number = i + 1;
        let err = |expected: String| {
            let truncated = if number == last && !ends_cleanly {
                " (the file ends in the middle of this line: truncated?)"
            } else {
                ""
            };
            SceneError::ObjLine {
                file: label.to_string(),
                line: number,
                expected: format!("{expected}{truncated}"),
            }
        };
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let args: Vec<&str> = words.collect();
        match keyword {
            "v" => {
                let nums = numbers(&args).map_err(|w| {
                    err(format!(
                        "expected a vertex `v x y z` of finite numbers, found `{w}`"
                    ))
                })?;
                let p = match nums.len() {
                    3 | 6 => Vec3::new(nums[0], nums[1], nums[2]),
                    4 if nums[3] != 0.0 => Vec3::new(nums[0], nums[1], nums[2]) / nums[3],
                    4 => return Err(err("expected a non-zero w in `v x y z w`, found 0".into())),
                    n => {
                        return Err(err(format!(
                            "expected a vertex `v x y z` (optionally `w` or `r g b`), \
                             found {n} number{}",
                            if n == 1 { "" } else { "s" }
                        )))
                    }
                };
                if !p.is_finite() {
                    return Err(err(
                        "expected finite coordinates, found x/w overflowing".into()
                    ));
                }
                n_v += 1;
                let _ = writeln!(out, "v {:?} {:?} {:?}", p.x, p.y, p.z);
                continue;
            }
            "vt" | "vn" => {
                let (min, what) = if keyword == "vt" {
                    (1, "a texture coordinate `vt u [v [w]]`")
                } else {
                    (3, "a normal `vn x y z`")
                };
                let nums = numbers(&args)
                    .map_err(|w| err(format!("expected {what} of finite numbers, found `{w}`")))?;
                if nums.len() < min || nums.len() > 3 {
                    return Err(err(format!(
                        "expected {what}, found {} numbers",
                        nums.len()
                    )));
                }
                if keyword == "vt" {
                    n_vt += 1;
                } else {
                    n_vn += 1;
                }
            }
            "f" => {
                if args.len() < 3 {
                    return Err(err(format!(
                        "expected a face with at least 3 vertices, found {}",
                        args.len()
                    )));
                }
                out.push('f');
                let mut max_positive = 0i64;
                for word in &args {
                    let v = face_ref(word, n_v, n_vt, n_vn).map_err(err)?;
                    max_positive = max_positive.max(v);
                    let _ = write!(out, " {v}");
                }
                out.push('\n');
                if max_positive > 0 {
                    forward.push((number, max_positive));
                }
                continue;
            }
            // Everything else is either harmless structure or something we ignore on purpose.
            "l" | "p" | "o" | "g" | "s" | "mtllib" | "usemtl" | "vp" | "cstype" | "deg"
            | "curv" | "curv2" | "surf" | "parm" | "trim" | "hole" | "end" | "mg" | "lod"
            | "bevel" | "c_interp" | "d_interp" | "shadow_obj" | "trace_obj" | "ctech"
            | "stech" | "call" | "csh" => {}
            other => {
                return Err(err(format!(
                    "expected an OBJ statement (`v`, `vt`, `vn`, `f`, `o`, `g`, ...), \
                     found `{other}`"
                )))
            }
        }
        out.push('\n');
    }

    for (line, index) in forward {
        if index as usize > n_v {
            return Err(SceneError::ObjLine {
                file: label.to_string(),
                line,
                expected: format!(
                    "face vertex index {index} is out of range: expected 1..={n_v} \
                     (the file has {n_v} vertices)"
                ),
            });
        }
    }
    Ok(out)
}

/// Parses every word as a finite `f32`; on failure returns the offending word.
fn numbers(words: &[&str]) -> Result<Vec<f32>, String> {
    words
        .iter()
        .map(|w| match w.parse::<f32>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err((*w).to_string()),
        })
        .collect()
}

/// Checks one face reference `v`, `v/vt`, `v//vn` or `v/vt/vn` and returns the vertex index as
/// written (positive absolute, negative relative, already checked against `n_v`).
fn face_ref(word: &str, n_v: usize, n_vt: usize, n_vn: usize) -> Result<i64, String> {
    let syntax =
        || format!("expected a face vertex like `7`, `7/2`, `7//3` or `7/2/3`, found `{word}`");
    let parts: Vec<&str> = word.split('/').collect();
    if parts.len() > 3 {
        return Err(syntax());
    }
    let mut v = 0i64;
    for (k, part) in parts.iter().enumerate() {
        if part.is_empty() {
            if k == 0 || (k == 2) || (k == 1 && parts.len() == 2) {
                return Err(syntax());
            }
            continue;
        }
        let x: i64 = part.parse().map_err(|_| syntax())?;
        let (count, what) = match k {
            0 => (n_v, "vertex"),
            1 => (n_vt, "texture coordinate"),
            _ => (n_vn, "normal"),
        };
        if x == 0 {
            return Err(format!(
                "face {what} index 0 is out of range: OBJ indices start at 1 (or are negative, \
                 relative)"
            ));
        }
        if x < 0 && x.unsigned_abs() as usize > count {
            return Err(format!(
                "face {what} index {x} is out of range: a relative index must be in -{count}..=-1 \
                 ({count} defined so far)"
            ));
        }
        if k > 0 && x > 0 && x as usize > count {
            return Err(format!(
                "face {what} index {x} is out of range: expected 1..={count} ({count} defined so \
                 far)"
            ));
        }
        if k == 0 {
            v = x;
        }
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        parse_obj_str(text, "t.obj").unwrap_err().to_string()
    }

    #[test]
    fn quad_is_triangulated_and_welded() {
        let m = parse_obj_str(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -0.0 0 0\nf 1 2 3 4\nf 5 2 -3\n",
            "t.obj",
        )
        .unwrap();
        assert_eq!(m.triangles.len(), 3);
        assert_eq!(m.positions.len(), 4, "-0.0 welds with 0.0");
    }

    #[test]
    fn relative_indices_and_slashes() {
        let m = parse_obj_str(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf -3/1/1 -2//1 -1/1\n",
            "t.obj",
        )
        .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn errors_name_the_line() {
        assert!(err("v 0 0 0\nv 1 0\n").starts_with("t.obj:2: "));
        assert!(err("v 0 0 0\nv 1 0 nan\n").contains("t.obj:2:"));
        assert!(err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n").contains("t.obj:4: expected a face"));
        assert!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").contains("t.obj:4: face vertex index 4")
        );
        assert!(err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n").contains("t.obj:4:"));
        assert!(err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n").contains("t.obj:4:"));
        assert!(err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/x\n").contains("t.obj:4:"));
        assert!(err("v 0 0 0\nv 1 0 0\nv 0").contains("t.obj:3: expected a vertex"));
        assert!(err("v 0 0 0\nv 1 0 0\nv 0").contains("truncated"));
        assert!(err("v 0 0 0\n").contains("contains no triangles"));
        assert!(err("").contains("contains no triangles"));
        assert!(err("v 0 0 0\nv 1 0 0\nf 1 2 2\n").contains("contains no triangles"));
        assert!(err("hello world\n").contains("t.obj:1:"));
    }
}
