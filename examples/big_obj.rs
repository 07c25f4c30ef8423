//! Writes the large OBJ files the README's memory table was measured with, to standard output:
//!
//!     cargo run --release --example big_obj -- torus 4096 2047 > torus16m.obj   # closed, 16.77M triangles
//!     cargo run --release --example big_obj -- strip 8388600 > strip16m.obj     # open, 3 edges per triangle
//!     /usr/bin/time -v target/release/dbuffer inspect torus16m.obj
//!
//! `torus NU NV`: a torus grid, NU·NV vertices, 2·NU·NV triangles, every edge shared by two.
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
