//! Wavefront OBJ loading: a strict, streaming line scanner with clear errors and a budget.
//!
//! Only geometry is read: `v` positions and `f` faces (polygons are fan-triangulated: corners
//! `0, i, i+1`). Texture coordinates, normals, lines, points, groups and materials are ignored;
//! `vt`/`vn` lines and the `/vt/vn` parts of face references are checked for syntax only. Every
//! problem is reported as `FILE:LINE: what was expected`, and never quotes the file: a file that
//! is not an OBJ at all (a mesh path pointing at `/etc/passwd`) gets the line and what was
//! expected, not its content.
//!
//! All models of the file are merged into one [`Mesh`] and exactly equal positions (bitwise,
//! with `-0.0 == 0.0`) are welded into one vertex, so adjacency works downstream. Vertices are
//! numbered in the order faces first use them; vertices no face uses are dropped. Triangles that
//! become degenerate after welding (a repeated vertex) are dropped. Open boundaries (holes) are
//! kept as they are. A UTF-8 byte-order mark at the start of the file is skipped.
//!
//! **Budget** (`crate::budget`). The file is streamed line by line, never held whole: at most
//! `MAX_MESH_FILE_BYTES` bytes (checked from its metadata before reading), lines of at most
//! `MAX_OBJ_LINE_BYTES`, at most `MAX_MESH_VERTICES` `v` lines, and at most the triangles the
//! scene's `MAX_SCENE_TRIANGLES` leaves for it, counted face by face as they are read. Memory
//! while loading is about 16 bytes per `v` line plus 12 per triangle.

use super::{Mesh, SceneError};
use crate::budget::{
    MAX_MESH_FILE_BYTES, MAX_MESH_VERTICES, MAX_OBJ_LINE_BYTES, MAX_SCENE_TRIANGLES,
    MAX_SCENE_VERTICES,
};
use crate::fsutil::{self, ByteBudget};
use glam::Vec3;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// The byte budget of one mesh file.
pub const MESH_FILE_BUDGET: ByteBudget = ByteBudget {
    limit: MAX_MESH_FILE_BYTES,
    name: "MAX_MESH_FILE_BYTES",
    what: "a mesh file",
};

/// What a scene's other objects already use of its budget: a mesh may have what is left of
/// `MAX_SCENE_TRIANGLES` and `MAX_SCENE_VERTICES`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Others {
    pub triangles: u64,
    pub vertices: u64,
}

impl Others {
    /// Adds what built-in shape `shape` will use.
    pub fn add(&mut self, shape: &super::shapes::Shape) {
        self.triangles += shape.triangles();
        self.vertices += shape.vertices();
    }
}

/// Loads the OBJ file at `path`; errors name the file as `path` displays. The mesh may have the
/// whole scene budget of triangles and vertices.
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    load_obj_within(path, Others::default())
}

/// Like [`load_obj`] in a scene whose other objects already use `others` of its budget.
pub fn load_obj_within(path: &Path, others: Others) -> Result<Mesh, SceneError> {
    let label = super::shown(&path.display().to_string());
    let (file, _size) =
        fsutil::open_regular(path, MESH_FILE_BUDGET).map_err(|e| super::read_error(&label, e))?;
    let limit = MESH_FILE_BUDGET.limit;
    let reader = BufReader::with_capacity(1 << 16, file.take(limit.saturating_add(1)));
    let mesh = parse(reader, &label, others)?;
    Ok(mesh)
}

/// Parses OBJ text; `label` names it in errors.
pub fn parse_obj_str(text: &str, label: &str) -> Result<Mesh, SceneError> {
    parse(text.as_bytes(), label, Others::default())
}

/// Parses OBJ bytes (not necessarily UTF-8: invalid bytes are an error naming the line) in a
/// scene whose other objects already use `others` of its budget.
pub fn parse_obj_bytes(bytes: &[u8], label: &str, others: Others) -> Result<Mesh, SceneError> {
    parse(bytes, label, others)
}

/// Where a face's largest positive vertex index was first seen, to check once every `v` line
/// has been read (faces may refer to vertices defined after them).
#[derive(Clone, Copy)]
struct Forward {
    line: usize,
    index: u64,
}

fn parse(mut reader: impl BufRead, label: &str, others: Others) -> Result<Mesh, SceneError> {
    let budget = MAX_SCENE_TRIANGLES.saturating_sub(others.triangles);
    let whole = |problem: String| SceneError::Obj {
        file: label.to_string(),
        problem,
    };
    // Every `v` line's position (-0.0 made 0.0), and every face corner's 0-based raw index.
    let mut raw: Vec<Vec3> = Vec::new();
    let mut corners: Vec<[u32; 3]> = Vec::new();
    let (mut n_vt, mut n_vn) = (0u64, 0u64);
    let mut forward: Option<Forward> = None;
    let mut line = Vec::new();
    let mut bytes_read = 0u64;
    let mut number = 0usize;
    let mut face: Vec<u32> = Vec::new();

    loop {
        line.clear();
        let ended = read_line(&mut reader, &mut line).map_err(|e| match e {
            LineError::Io(error) => SceneError::Io {
                file: label.to_string(),
                error,
            },
            LineError::TooLong => SceneError::ObjLine {
                file: label.to_string(),
                line: number + 1,
                expected: format!(
                    "expected a line of at most {} (MAX_OBJ_LINE_BYTES), found a longer one",
                    crate::budget::bytes(MAX_OBJ_LINE_BYTES as u64)
                ),
            },
        })?;
        let Some(ended_with_newline) = ended else {
            break;
        };
        number += 1;
        bytes_read += line.len() as u64;
        if bytes_read > MESH_FILE_BUDGET.limit {
            return Err(whole(format!(
                "more than {} (MAX_MESH_FILE_BYTES): the file grew while it was read",
                crate::budget::bytes(MESH_FILE_BUDGET.limit)
            )));
        }
        let err = |expected: String| {
            let truncated = if ended_with_newline {
                ""
            } else {
                " (the file ends in the middle of this line: truncated?)"
            };
            SceneError::ObjLine {
                file: label.to_string(),
                line: number,
                expected: format!("{expected}{truncated}"),
            }
        };
        let text = match std::str::from_utf8(&line) {
            Ok(t) => t,
            Err(e) => {
                return Err(err(format!(
                    "expected UTF-8 (or ASCII) text, found invalid bytes at column {}",
                    e.valid_up_to() + 1
                )))
            }
        };
        let text = if number == 1 {
            text.strip_prefix('\u{feff}').unwrap_or(text)
        } else {
            text
        };
        let content = text.split('#').next().unwrap_or("");
        let mut words = content.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let mut nums = [0f32; 6];
                let mut n = 0usize;
                for (k, w) in words.enumerate() {
                    let x = number_word(w).map_err(|found| {
                        err(format!(
                            "expected a vertex `v x y z` of finite numbers, found {found} \
                             (number {})",
                            k + 1
                        ))
                    })?;
                    if n < nums.len() {
                        nums[n] = x;
                    }
                    n += 1;
                }
                let p = match n {
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
                if raw.len() as u64 >= MAX_MESH_VERTICES {
                    return Err(err(format!(
                        "expected at most {MAX_MESH_VERTICES} vertices in one mesh file \
                         (MAX_MESH_VERTICES), found more"
                    )));
                }
                // `+ 0.0` turns -0.0 into 0.0 so both weld together.
                raw.push(p + Vec3::ZERO);
            }
            "vt" | "vn" => {
                let (min, what) = if keyword == "vt" {
                    (1, "a texture coordinate `vt u [v [w]]`")
                } else {
                    (3, "a normal `vn x y z`")
                };
                let mut n = 0usize;
                for (k, w) in words.enumerate() {
                    number_word(w).map_err(|found| {
                        err(format!(
                            "expected {what} of finite numbers, found {found} (number {})",
                            k + 1
                        ))
                    })?;
                    n += 1;
                }
                if n < min || n > 3 {
                    return Err(err(format!("expected {what}, found {n} numbers")));
                }
                if keyword == "vt" {
                    n_vt += 1;
                } else {
                    n_vn += 1;
                }
            }
            "f" => {
                face.clear();
                let n_v = raw.len() as u64;
                for (k, word) in words.enumerate() {
                    let v = face_ref(word, n_v, n_vt, n_vn)
                        .map_err(|e| err(format!("{e} (vertex {} of the face)", k + 1)))?;
                    let index = match v {
                        Ref::Absolute(x) => {
                            if x > n_v && forward.is_none_or(|f| x > f.index) {
                                forward = Some(Forward {
                                    line: number,
                                    index: x,
                                });
                            }
                            x - 1
                        }
                        Ref::Relative(back) => n_v - back,
                    };
                    // At most MAX_MESH_VERTICES (checked in `face_ref`), so it fits.
                    face.push(u32::try_from(index).unwrap_or(u32::MAX));
                }
                if face.len() < 3 {
                    return Err(err(format!(
                        "expected a face with at least 3 vertices, found {}",
                        face.len()
                    )));
                }
                let added = face.len() as u64 - 2;
                if corners.len() as u64 + added > budget {
                    return Err(err(over_triangle_budget(others.triangles)));
                }
                corners.reserve(face.len() - 2);
                for i in 1..face.len() - 1 {
                    corners.push([face[0], face[i], face[i + 1]]);
                }
            }
            // Everything else is either harmless structure or something we ignore on purpose.
            "l" | "p" | "o" | "g" | "s" | "mtllib" | "usemtl" | "vp" | "cstype" | "deg"
            | "curv" | "curv2" | "surf" | "parm" | "trim" | "hole" | "end" | "mg" | "lod"
            | "bevel" | "c_interp" | "d_interp" | "shadow_obj" | "trace_obj" | "ctech"
            | "stech" | "call" | "csh" => {}
            _ => {
                return Err(err(
                    "expected an OBJ statement (`v`, `vt`, `vn`, `f`, `o`, `g`, ...) at the \
                     start of the line, found something else"
                        .into(),
                ))
            }
        }
    }

    let n_v = raw.len() as u64;
    if let Some(f) = forward.filter(|f| f.index > n_v) {
        return Err(SceneError::ObjLine {
            file: label.to_string(),
            line: f.line,
            expected: format!(
                "face vertex index {} is out of range: expected 1..={n_v} (the file has {n_v} \
                 vertices)",
                f.index
            ),
        });
    }
    let mesh = weld(&raw, corners);
    let vertices_left = MAX_SCENE_VERTICES.saturating_sub(others.vertices);
    if mesh.positions.len() as u64 > vertices_left {
        let of = if others.vertices == 0 {
            String::new()
        } else {
            format!(" after the {} of its other objects", others.vertices)
        };
        return Err(whole(format!(
            "its faces use {} distinct vertices, more than the {vertices_left} the scene's \
             budget of {MAX_SCENE_VERTICES} vertices (MAX_SCENE_VERTICES) leaves{of}",
            mesh.positions.len()
        )));
    }
    if mesh.triangles.is_empty() {
        return Err(whole(
            "contains no triangles: expected at least one `f` line with 3 or more distinct \
             vertices"
                .into(),
        ));
    }
    Ok(mesh)
}

/// The message for a mesh over what the scene's triangle budget leaves it.
fn over_triangle_budget(others: u64) -> String {
    let left = MAX_SCENE_TRIANGLES.saturating_sub(others);
    if others == 0 {
        format!(
            "expected at most {left} triangles, the scene's budget (MAX_SCENE_TRIANGLES), \
             found more"
        )
    } else {
        format!(
            "expected at most {left} triangles, what the scene's budget of \
             {MAX_SCENE_TRIANGLES} (MAX_SCENE_TRIANGLES) leaves after the {others} of its \
             other objects, found more"
        )
    }
}

/// Welds bitwise-equal positions, numbers the vertices in the order the triangles first use
/// them (unused ones are dropped), and drops triangles with a repeated vertex.
fn weld(raw: &[Vec3], mut corners: Vec<[u32; 3]>) -> Mesh {
    // (position bits, raw index), sorted: each run of equal positions welds to its first index.
    let mut sorted: Vec<([u32; 3], u32)> = raw
        .iter()
        .enumerate()
        .map(|(i, p)| ([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()], i as u32))
        .collect();
    sorted.sort_unstable();
    let mut first = vec![0u32; raw.len()];
    for run in sorted.chunk_by(|a, b| a.0 == b.0) {
        for &(_, i) in run {
            first[i as usize] = run[0].1;
        }
    }
    drop(sorted);
    // The final index of each welded vertex, in order of first use.
    let mut order = vec![u32::MAX; raw.len()];
    let mut positions = Vec::new();
    let mut kept = 0;
    for k in 0..corners.len() {
        let t = corners[k].map(|raw_index| {
            let w = first[raw_index as usize] as usize;
            if order[w] == u32::MAX {
                order[w] = positions.len() as u32;
                positions.push(raw[w]);
            }
            order[w]
        });
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            corners[kept] = t;
            kept += 1;
        }
    }
    corners.truncate(kept);
    corners.shrink_to_fit();
    Mesh::new(positions, corners)
}

enum LineError {
    Io(std::io::Error),
    TooLong,
}

/// Reads one line (without its `\n`) into `line`, at most [`MAX_OBJ_LINE_BYTES`] of it.
/// `Ok(None)` at the end of the input; otherwise whether the line ended with a newline.
fn read_line(reader: &mut impl BufRead, line: &mut Vec<u8>) -> Result<Option<bool>, LineError> {
    let mut any = false;
    loop {
        let buf = match reader.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(LineError::Io(e)),
        };
        if buf.is_empty() {
            return Ok(any.then_some(false));
        }
        any = true;
        let (take, done) = match buf.iter().position(|&b| b == b'\n') {
            Some(i) => (i, true),
            None => (buf.len(), false),
        };
        if line.len() + take > MAX_OBJ_LINE_BYTES {
            return Err(LineError::TooLong);
        }
        line.extend_from_slice(&buf[..take]);
        reader.consume(take + usize::from(done));
        if done {
            return Ok(Some(true));
        }
    }
}

/// One word as a finite `f32`; on failure, what was found, without quoting it.
fn number_word(w: &str) -> Result<f32, &'static str> {
    match w.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) if x.is_nan() => Err("nan"),
        Ok(_) => Err("an infinite number (inf, or beyond ±3.4e38)"),
        Err(_) => Err("a word that is not a number"),
    }
}

/// A face's vertex reference: 1-based absolute, or relative (`-back`, 1 = the last vertex).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ref {
    Absolute(u64),
    Relative(u64),
}

/// Checks one face reference `v`, `v/vt`, `v//vn` or `v/vt/vn` and returns the vertex part
/// (relative ones already checked against `n_v`; positive ones are checked at the end).
fn face_ref(word: &str, n_v: u64, n_vt: u64, n_vn: u64) -> Result<Ref, String> {
    let syntax = || {
        "expected a face vertex like `7`, `7/2`, `7//3` or `7/2/3`, found something else"
            .to_string()
    };
    let slashes = word.bytes().filter(|&b| b == b'/').count();
    if slashes > 2 {
        return Err(syntax());
    }
    let mut parts = word.split('/');
    let mut vertex = None;
    for k in 0..3 {
        let Some(part) = parts.next() else {
            break;
        };
        if part.is_empty() {
            // Only `v//vn` may leave a part empty: the texture coordinate of three parts.
            if k == 1 && slashes == 2 {
                continue;
            }
            return Err(syntax());
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
        let magnitude = x.unsigned_abs();
        if x < 0 && magnitude > count {
            return Err(format!(
                "face {what} index {x} is out of range: a relative index must be in -{count}..=-1 \
                 ({count} defined so far)"
            ));
        }
        if k > 0 && x > 0 && magnitude > count {
            return Err(format!(
                "face {what} index {x} is out of range: expected 1..={count} ({count} defined so \
                 far)"
            ));
        }
        if k == 0 {
            if x > 0 && magnitude > MAX_MESH_VERTICES {
                return Err(format!(
                    "face vertex index {x} is out of range: a mesh file has at most \
                     {MAX_MESH_VERTICES} vertices (MAX_MESH_VERTICES)"
                ));
            }
            vertex = Some(if x > 0 {
                Ref::Absolute(magnitude)
            } else {
                Ref::Relative(magnitude)
            });
        }
    }
    vertex.ok_or_else(syntax)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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

    #[test]
    fn errors_never_quote_the_file() {
        for text in [
            "root:x:0:0:root:/root:/bin/bash\n",
            "v 0 0 s3cr3t\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 s3cr3t\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/s3cr3t\n",
            "vt s3cr3t\n",
            "s3cr3t 1 2 3\n",
        ] {
            let msg = err(text);
            assert!(
                !msg.contains("s3cr3t") && !msg.contains("root:"),
                "{text:?} gave {msg}"
            );
            assert!(msg.starts_with("t.obj:1:") || msg.contains(":4:"), "{msg}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let m = parse_obj_str("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj").unwrap();
        assert_eq!(m.triangles.len(), 1);
        // Only at the start of the file.
        assert!(err("v 0 0 0\n\u{feff}v 1 0 0\n").contains("t.obj:2:"));
    }

    #[test]
    fn crlf_line_ends() {
        let m = parse_obj_str("v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n", "t.obj").unwrap();
        assert_eq!(m.triangles.len(), 1);
    }

    #[test]
    fn the_triangle_budget_is_counted_while_reading() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4\nf 1 2 3\n";
        let others = |triangles, vertices| Others {
            triangles,
            vertices,
        };
        let full =
            parse_obj_bytes(text.as_bytes(), "t.obj", others(MAX_SCENE_TRIANGLES - 3, 0)).unwrap();
        assert_eq!(full.triangles.len(), 3);
        let msg = parse_obj_bytes(text.as_bytes(), "t.obj", others(MAX_SCENE_TRIANGLES - 2, 0))
            .unwrap_err()
            .to_string();
        assert!(
            msg.starts_with("t.obj:6:") && msg.contains("MAX_SCENE_TRIANGLES"),
            "{msg}"
        );
        // Four distinct vertices; the budget of vertices is checked after welding.
        assert!(
            parse_obj_bytes(text.as_bytes(), "t.obj", others(0, MAX_SCENE_VERTICES - 4)).is_ok()
        );
        let msg = parse_obj_bytes(text.as_bytes(), "t.obj", others(0, MAX_SCENE_VERTICES - 3))
            .unwrap_err()
            .to_string();
        assert!(msg.contains("MAX_SCENE_VERTICES"), "{msg}");
    }

    #[test]
    fn an_endless_line_is_refused() {
        let text = vec![b'v'; MAX_OBJ_LINE_BYTES + 1];
        let msg = parse_obj_bytes(&text, "t.obj", Others::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("MAX_OBJ_LINE_BYTES"), "{msg}");
    }

    #[test]
    fn unused_vertices_are_dropped_and_order_follows_first_use() {
        let m = parse_obj_str(
            "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nf 4 3 5\n",
            "t.obj",
        )
        .unwrap();
        assert_eq!(
            m.positions,
            vec![Vec3::new(0.0, 1.0, 0.0), Vec3::X, Vec3::ZERO]
        );
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    /// What the loader did before it streamed: tobj (fan triangulation, single index), then a
    /// weld in the order of tobj's positions. The streaming loader must give the same mesh.
    fn with_tobj(text: &str) -> Option<Mesh> {
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ignore_points: true,
            ignore_lines: true,
        };
        let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .ok()?;
        let mut positions: Vec<Vec3> = Vec::new();
        let mut triangles = Vec::new();
        let mut welded = std::collections::HashMap::new();
        for model in &models {
            let m = &model.mesh;
            let remap: Vec<u32> = m
                .positions
                .chunks_exact(3)
                .map(|p| {
                    let p = Vec3::new(p[0] + 0.0, p[1] + 0.0, p[2] + 0.0);
                    let next = positions.len() as u32;
                    *welded
                        .entry([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
                        .or_insert_with(|| {
                            positions.push(p);
                            next
                        })
                })
                .collect();
            for t in m.indices.chunks_exact(3) {
                let [a, b, c] = [0, 1, 2].map(|k| remap[t[k] as usize]);
                if a != b && b != c && a != c {
                    triangles.push([a, b, c]);
                }
            }
        }
        Some(Mesh::new(positions, triangles))
    }

    #[test]
    fn the_bunny_is_the_mesh_tobj_made() {
        let text = include_str!("../../assets/bunny.obj");
        let ours = parse_obj_str(text, "bunny.obj").unwrap();
        assert_eq!(Some(ours), with_tobj(text));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// On valid OBJ text (vertices from a small grid so that some weld, faces of 3 to 6
        /// corners with absolute and relative references, some degenerate) the streaming loader
        /// makes exactly the mesh the tobj-based one did.
        #[test]
        fn same_mesh_as_tobj(
            verts in prop::collection::vec((0i8..3, 0i8..3, -1i8..2), 3..12),
            faces in prop::collection::vec(
                (prop::collection::vec(0usize..64, 3..7), any::<bool>()),
                1..10,
            ),
        ) {
            let mut text = String::new();
            for (x, y, z) in &verts {
                text.push_str(&format!("v {x} {y} {}\n", if *z == 0 { "-0.0".to_string() } else { z.to_string() }));
            }
            let n = verts.len();
            for (refs, relative) in &faces {
                text.push('f');
                for r in refs {
                    let i = r % n;
                    if *relative {
                        text.push_str(&format!(" -{}", n - i));
                    } else {
                        text.push_str(&format!(" {}", i + 1));
                    }
                }
                text.push('\n');
            }
            let ours = parse_obj_str(&text, "p.obj").ok();
            let theirs = with_tobj(&text).filter(|m| !m.triangles.is_empty());
            prop_assert_eq!(ours, theirs, "{}", text);
        }
    }
}
