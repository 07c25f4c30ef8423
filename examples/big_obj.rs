//! Writes the large OBJ files the memory table of docs/guide/limits.md was measured with, to standard output:
//!
//!     cargo run --release --example big_obj -- torus 4096 2047 > torus16m.obj   # closed, 16.77M triangles
//!     cargo run --release --example big_obj -- strip 8388600 > strip16m.obj     # open, 3 edges per triangle
//!     /usr/bin/time -v target/release/dbuffer inspect torus16m.obj
//!
//!     cargo run --release --example big_obj -- torus-glb 4096 2047 > torus16m.glb  # the same as glTF
//!
//! `torus NU NV`: a torus grid, NU·NV vertices, 2·NU·NV triangles, every edge shared by two;
//! `torus-glb NU NV` writes it as a binary glTF (one mesh, f32 positions, u32 indices).
//! `strip V`: V vertices on a helix and about 2·V triangles `(k, k+1, k+3)` and
//! `(k, k+4, k+9)`, which share no edge: every edge is a boundary, the most edges (three per
//! triangle) and silhouette edges a mesh of that size can have.

use std::f64::consts::TAU;
use std::io::{BufWriter, Write};

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: u64| {
        args.get(i)
            .and_then(|a| a.parse::<u64>().ok())
            .unwrap_or(default)
    };
    let mut out = BufWriter::with_capacity(1 << 20, std::io::stdout().lock());
    match args.first().map(String::as_str) {
        Some("torus") => {
            let (nu, nv) = (arg(1, 4096), arg(2, 2047));
            for i in 0..nu {
                for j in 0..nv {
                    let (u, v) = (TAU * i as f64 / nu as f64, TAU * j as f64 / nv as f64);
                    let w = 0.35 + 0.15 * v.cos();
                    writeln!(
                        out,
                        "v {:.7} {:.7} {:.7}",
                        w * u.cos(),
                        0.15 * v.sin(),
                        w * u.sin()
                    )?;
                }
            }
            for i in 0..nu {
                for j in 0..nv {
                    let at = |i: u64, j: u64| (i % nu) * nv + j % nv + 1;
                    let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                    writeln!(out, "f {a} {b} {c}\nf {a} {c} {d}")?;
                }
            }
        }
        Some("torus-glb") => {
            let (nu, nv) = (arg(1, 4096), arg(2, 2047));
            let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
            let mut positions = Vec::with_capacity((nu * nv * 12) as usize);
            for i in 0..nu {
                for j in 0..nv {
                    let (u, v) = (TAU * i as f64 / nu as f64, TAU * j as f64 / nv as f64);
                    let w = 0.35 + 0.15 * v.cos();
                    let p = [
                        (w * u.cos()) as f32,
                        (0.15 * v.sin()) as f32,
                        (w * u.sin()) as f32,
                    ];
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                        positions.extend_from_slice(&p[k].to_le_bytes());
                    }
                }
            }
            let mut indices = Vec::with_capacity((nu * nv * 24) as usize);
            for i in 0..nu {
                for j in 0..nv {
                    let at = |i: u64, j: u64| ((i % nu) * nv + j % nv) as u32;
                    let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                    for k in [a, b, c, a, c, d] {
                        indices.extend_from_slice(&k.to_le_bytes());
                    }
                }
            }
            let json = format!(
                r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],"buffers":[{{"byteLength":{}}}],"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{}}},{{"buffer":0,"byteOffset":{},"byteLength":{}}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
                positions.len() + indices.len(),
                positions.len(),
                positions.len(),
                indices.len(),
                nu * nv,
                lo[0],
                lo[1],
                lo[2],
                hi[0],
                hi[1],
                hi[2],
                nu * nv * 6
            );
            let mut json = json.into_bytes();
            while json.len() % 4 != 0 {
                json.push(b' ');
            }
            let bin = positions.len() + indices.len(); // both multiples of 4
            let total = 12 + 8 + json.len() + 8 + bin;
            out.write_all(b"glTF")?;
            out.write_all(&2u32.to_le_bytes())?;
            out.write_all(&(total as u32).to_le_bytes())?;
            out.write_all(&(json.len() as u32).to_le_bytes())?;
            out.write_all(b"JSON")?;
            out.write_all(&json)?;
            out.write_all(&(bin as u32).to_le_bytes())?;
            out.write_all(b"BIN\0")?;
            out.write_all(&positions)?;
            out.write_all(&indices)?;
        }
        Some("strip") => {
            let v = arg(1, 8_388_600);
            for k in 0..v {
                let a = 0.37 * k as f64;
                let r = 1.0 + 0.3 * (0.001 * k as f64).sin();
                writeln!(
                    out,
                    "v {:.7} {:.7} {:.7}",
                    a.cos() * r,
                    1e-4 * k as f64,
                    a.sin()
                )?;
            }
            for k in 0..v.saturating_sub(3) {
                writeln!(out, "f {} {} {}", k + 1, k + 2, k + 4)?;
            }
            for k in 0..v.saturating_sub(9) {
                writeln!(out, "f {} {} {}", k + 1, k + 5, k + 10)?;
            }
        }
        _ => eprintln!("usage: big_obj torus NU NV | strip V"),
    }
    out.flush()
}
