//! How much of `dbuffer-fused`'s lists a pixel needs: per listed receiver pixel of
//! each scene (256² camera rays, the CPU twin's lists at the default 1024² D-buffer and 256² list
//! grid), what each listed edge is as seen from the pixel's point — not a silhouette from it,
//! a silhouette beyond its height (or degenerate), a silhouette whose chord misses the disk, or
//! one that cuts the disk (the only ones V needs). The camera pass pays for every listed edge.
//!
//!     cargo run --release --example list_slack -- table1-960 table1-1440 fusion-cross

use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::fused::{edge_chord, FusedParams, FusedTwin, MaskEval};
use dbuffer::geometry::{view, PreparedCasters, VolumeParams, VtVariant};

const CAMERA: u32 = 256;

/// Listed edges by what they are from a pixel's point.
#[derive(Default)]
struct Tally {
    pixels: usize,
    not_silhouette: usize,
    beyond: usize,
    misses: usize,
    cuts: usize,
}

impl Tally {
    fn edges(&self) -> usize {
        self.not_silhouette + self.beyond + self.misses + self.cuts
    }
}

fn main() -> anyhow::Result<()> {
    let names: Vec<String> = std::env::args().skip(1).collect();
    if names.is_empty() {
        anyhow::bail!("usage: list_slack SCENE…");
    }
    for name in names {
        let scene = dbuffer::scene::load(&name)?;
        let light = scene.light.area_or_centre();
        let prepared = PreparedCasters::new(&scene);
        let geometry = prepared.build(&light, &VolumeParams::for_scene(&scene));
        let params = FusedParams {
            size: 1024,
            list_size: 256,
            eval: MaskEval::Lut,
            vt: VtVariant::Exact,
            ..FusedParams::default()
        };
        let twin = FusedTwin::new(&scene, &prepared, &geometry, params);
        let bvh = Bvh::build(scene.all_triangles());
        let mut t = Tally::default();
        for r in view::receivers(&scene, &bvh, CAMERA, CAMERA)
            .iter()
            .flatten()
            .filter(|r| r.faces_light)
        {
            let x = r.position;
            let Some(texel) = twin.texel_of(x, params.list_size) else {
                continue;
            };
            let list = twin.texel_list(texel);
            if list.edges.is_empty() {
                continue;
            }
            t.pixels += 1;
            for edge in list
                .edges
                .iter()
                .filter_map(|&i| twin.edges().get(i as usize))
            {
                if !edge.is_silhouette_from(x) {
                    t.not_silhouette += 1;
                    continue;
                }
                match edge_chord(edge, x, &light) {
                    None => t.beyond += 1,
                    Some(ch) if ch.area > 0.0 => t.cuts += 1,
                    Some(_) => t.misses += 1,
                }
            }
        }
        let share = |n: usize| 100.0 * n as f64 / t.edges().max(1) as f64;
        println!(
            "{name}: {} listed px, {:.1} edges a px; not a silhouette {:.1} %, beyond or degenerate \
             {:.1} %, chord misses the disk {:.1} %, cuts it {:.1} %",
            t.pixels,
            t.edges() as f64 / t.pixels.max(1) as f64,
            share(t.not_silhouette),
            share(t.beyond),
            share(t.misses),
            share(t.cuts)
        );
    }
    Ok(())
}
