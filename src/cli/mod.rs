//! The subcommands. Each one loads through [`dbuffer::scene`] and computes through the same
//! library code the GUI uses; nothing here renders or computes on its own.

use std::time::Instant;

use anyhow::{bail, Context, Result};
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{PreparedCasters, VolumeParams};
use dbuffer::scene;

pub fn scenes() -> Result<()> {
    for name in scene::builtin::names() {
        println!("{name}");
    }
    Ok(())
}

pub fn not_yet(what: &str, issue: u32) -> Result<()> {
    bail!("{what} is not yet available (it lands with issue #{issue}); try `dbuffer inspect SCENE`")
}

pub fn inspect(name: &str, samples: Option<usize>) -> Result<()> {
    let scene = scene::load(name).with_context(|| format!("cannot load scene '{name}'"))?;
    let t0 = Instant::now();
    let prepared = PreparedCasters::new(&scene);
    let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
    let params = VolumeParams::for_scene(&scene);
    let t1 = Instant::now();
    let geometry = prepared.build(&scene.light, &params);
    let build_ms = t1.elapsed().as_secs_f64() * 1e3;

    let l = &scene.light;
    println!("scene     {}", scene.name);
    println!(
        "light     centre {} normal {} radius {}",
        l.center, l.normal, l.radius
    );
    println!(
        "{:<16} {:>9} {:>9} {:>9} {:>6} {:>6} {:>7} {:>7} {:>5} {:>8} {:>8}",
        "caster",
        "tris",
        "all-fr",
        "none-fr",
        "sil-A",
        "sil-B",
        "umb-e",
        "pen-e",
        "fans",
        "umb-tri",
        "pen-tri"
    );
    for c in &geometry.casters {
        let s = c.stats;
        println!(
            "{:<16} {:>9} {:>9} {:>9} {:>6} {:>6} {:>7} {:>7} {:>5} {:>8} {:>8}",
            c.name,
            s.triangles,
            s.all_front,
            s.none_front,
            s.silhouette_a,
            s.silhouette_b,
            s.umbra_edges,
            s.penumbra_edges,
            s.fans,
            s.umbra_triangles,
            s.penumbra_triangles
        );
    }
    println!("geometry  prepare {prepare_ms:.3} ms (once per mesh), classes+silhouettes+volumes {build_ms:.3} ms");
    for w in &geometry.warnings {
        println!("warning   {w}");
    }

    if let Some(k) = samples {
        if k == 0 {
            bail!("--samples must be at least 1");
        }
        let oracle = Oracle::from_scene(&scene, k);
        // A grid of points on the y = 0 plane under the light, where the built-ins put the ground.
        let n = 64;
        let points: Vec<_> = (0..n * n)
            .map(|i| {
                let (x, z) = (
                    (i % n) as f32 / (n - 1) as f32,
                    (i / n) as f32 / (n - 1) as f32,
                );
                glam::Vec3::new(l.center.x - 3.0 + 6.0 * x, 0.0, l.center.z - 3.0 + 6.0 * z)
            })
            .collect();
        let t2 = Instant::now();
        let v = oracle.visibility_many(&points);
        let secs = t2.elapsed().as_secs_f64();
        let (umbra, lit) = (
            v.iter().filter(|&&v| v <= 0.004).count(),
            v.iter().filter(|&&v| v >= 0.996).count(),
        );
        println!(
            "oracle    {} points x {k} samples in {:.1} ms ({:.1} M rays/s); ground 6x6 m: {umbra} umbra, {} penumbra, {lit} lit",
            points.len(),
            secs * 1e3,
            (points.len() * k) as f64 / secs / 1e6,
            points.len() - umbra - lit
        );
    }
    Ok(())
}
