//! The resource budget (docs/guide/limits.md): every limit on what one input may make the program
//! allocate, as a named constant, in one place.
//!
//! Each limit is checked **before** the allocation it guards: a built-in shape's triangle count
//! from its parameters before its vertices exist, a file's size from its metadata before it is
//! read, an OBJ's triangles while its lines are counted. An input over a limit gets an error
//! that names the limit (the constant's name), its value, and the key or flag that asked for
//! more. Under the budget, `dbuffer inspect` stays within [`MEMORY_BOUND_BYTES`] (measured on
//! the worst inputs, see docs/guide/limits.md).
//!
//! `dbuffer --help` prints [`summary`]; docs/guide/limits.md lists the same values.

/// Largest scene file (`.toml`) read, in bytes: 1 MiB. The built-in scenes are under 2 KB; a
/// megabyte holds some 20 000 objects.
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 20;

/// Largest mesh file (`.obj`) read, in bytes: 2 GiB, a 16M-triangle mesh written with normals
/// and texture coordinates. The file is streamed, never held in memory whole.
pub const MAX_MESH_FILE_BYTES: u64 = 2 << 30;

/// Largest glTF model file (`.gltf`/`.glb`) read, and each buffer file beside it, and all of a
/// model's buffers together, in bytes: 1 GiB. A model is held in memory while it is read (its
/// accessors index into it), so this bounds what reading it can take.
pub const MAX_MODEL_FILE_BYTES: u64 = 1 << 30;

/// Longest line of an OBJ file, in bytes: 1 MiB (a polygon of some 100 000 corners).
pub const MAX_OBJ_LINE_BYTES: usize = 1 << 20;

/// Triangles over all objects of one scene (built-in shapes and meshes together): 16 Mi. The
/// shapes' counts are checked from their parameters before any is built, the meshes' while
/// their files are read.
pub const MAX_SCENE_TRIANGLES: u64 = 1 << 24;

/// Vertices over all objects of one scene, after welding: 8 Mi, what a closed mesh of
/// [`MAX_SCENE_TRIANGLES`] has. It bounds memory where triangles share few vertices (a
/// triangle soup has three per triangle). Built-in shapes have about one per two triangles.
pub const MAX_SCENE_VERTICES: u64 = 1 << 23;

/// Vertex positions (`v` lines) of one OBJ file before welding: 16 Mi (files that repeat
/// positions weld down to [`MAX_SCENE_VERTICES`]). Loading keeps 16 bytes per `v` line.
pub const MAX_MESH_VERTICES: u64 = 1 << 24;

/// Triangles of the umbra and penumbra volumes over all casters of a scene, for one light:
/// 2 Mi, some 350 MB on the CPU. Known after classification, before a volume is built (every
/// silhouette face, two per silhouette edge, then the fans as they are made); a caster whose
/// volumes would pass what its scene has left casts no shadow, with a warning. Four
/// 4M-triangle spheres under a 0.5 m light need 1.7 Mi; a light much larger than the casters
/// makes nearly every face a silhouette face.
pub const MAX_VOLUME_TRIANGLES: u64 = 1 << 21;

/// Segments of one parameter of a built-in shape (`sphere:SxK`, `cylinder:S`, ...).
pub const MAX_SHAPE_SEGMENTS: u32 = 4096;

/// Largest product `A·B` of a two-parameter built-in shape (`sphere:AxB`, `torus:AxB`, ...):
/// about 4 million triangles for one shape.
pub const MAX_SHAPE_QUADS: u64 = 2_000_000;

/// Largest icosphere subdivision level (7 gives 327 680 triangles).
pub const MAX_ICOSPHERE_LEVEL: u32 = 7;

/// Disk samples per pixel of the ray-cast reference (`--samples` of `render`, `compare` and
/// `inspect`).
pub const MAX_REFERENCE_SAMPLES: u32 = 65536;

/// Pixels of a rendered image (`--size WxH` of `render` and `compare`): 64 Mi, 8192×8192.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 26;

/// Longest side of a rendered image, in pixels (`--size`).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Pixels of `inspect`'s CPU comparison view (`inspect --size`): 4 Mi, 2048×2048. The CPU twin
/// keeps some 55 bytes per pixel, on top of the scene.
pub const MAX_INSPECT_PIXELS: u64 = 1 << 22;

/// Triangles of a scene `inspect --samples` compares on the CPU: 4 Mi. The ray-cast reference
/// and the CPU twin each build a BVH over every triangle of the scene, some 350 bytes per
/// triangle in all (1.5 GB at 4 Mi).
pub const MAX_ORACLE_TRIANGLES: u64 = 1 << 22;

/// Texels on a side of the D-buffer and the shadow maps (`--dbuffer-size N`).
pub const MAX_DBUFFER_SIZE: u32 = 8192;

/// GPU storage of `dbuffer-fused`'s edge lists (`--list-size`² texels × (`--list-cap` + 1)
/// `u32`: the ids and a counter per texel): 128 MiB, WebGPU's default largest storage binding
/// (and lavapipe's). The defaults (256², 256) take 64 MiB; a combination over it is refused,
/// naming both flags.
pub const MAX_FUSED_LIST_BYTES: u64 = 128 << 20;

/// Candidate silhouette edges `dbuffer-fused` keeps for one light: 512 Ki (112 bytes of record
/// and 128 of proxy each on the GPU, 120 MiB). A scene with more (millions of caster triangles
/// under a large light) gets the paper's `dbuffer` V everywhere: every list counts as
/// overflowing (the method's `overflow` light-map channel shows 1 everywhere).
pub const MAX_FUSED_EDGES: u64 = 1 << 19;

/// Frames of `compare --orbit` (`--frames`): 720, a half-degree step round the orbit.
pub const MAX_ORBIT_FRAMES: usize = 720;

/// Pixels of a `compare` image, still or `--orbit` (`--size WxH`): 16 Mi, 4096×4096. A
/// comparison holds the reference's V and image, the pixels that count and one method's frame
/// with its FLIP map at a time (about 60 bytes a pixel), and on a CPU adapter its GPU targets
/// are host memory too (about 30 more): checked from the flags before any work.
pub const MAX_COMPARE_PIXELS: u64 = 1 << 24;

/// Cells of one `dbuffer study` (scenes × methods × settings).
pub const MAX_STUDY_CELLS: u64 = 1 << 16;

/// Pixels a `dbuffer study` renders over its cells, counting each cell's image once (cells ×
/// `--size`): 4 Gi, about 4,000 cells at 1024² (the default study is 870 at 512², 0.23 Gi).
pub const MAX_STUDY_PIXELS: u64 = 1 << 32;

/// Pixels of an `animate` frame (`--size WxH`): 16 Mi, 4096×4096. A frame is read back (16
/// bytes a pixel) and encoded while its GPU targets (24 bytes a pixel, host memory on a CPU
/// adapter) are held: checked from the flags before any work.
pub const MAX_ANIMATE_PIXELS: u64 = 1 << 24;

/// What `dbuffer inspect` and `dbuffer compare` may use on any input within the budget above:
/// 2 GiB.
pub const MEMORY_BOUND_BYTES: u64 = 2 << 30;

/// `WxH` (or `WXH`) with both sides positive: the image size of `--size` and of a study file.
pub fn parse_wxh(text: &str) -> Option<(u32, u32)> {
    let (w, h) = text.split_once(['x', 'X'])?;
    let (w, h) = (w.trim().parse().ok()?, h.trim().parse().ok()?);
    (w > 0 && h > 0).then_some((w, h))
}

/// Why a `w`×`h` image is over the limits, if it is: sides of at most [`MAX_IMAGE_SIDE`], at
/// most `max_pixels` pixels (the constant called `name`).
pub fn check_image_size(w: u32, h: u32, max_pixels: u64, name: &str) -> Result<(), String> {
    if w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(format!(
            "{w}x{h}: expected sides of at most {MAX_IMAGE_SIDE} pixels (MAX_IMAGE_SIDE)"
        ));
    }
    let pixels = u64::from(w) * u64::from(h);
    if pixels > max_pixels {
        return Err(format!(
            "{w}x{h} is {pixels} pixels: expected at most {max_pixels} ({name}, {} Mpixels)",
            max_pixels >> 20
        ));
    }
    Ok(())
}

/// The budget as the lines `dbuffer --help` prints after its commands.
pub fn summary() -> String {
    let rows: [(&str, String, &str); 22] = [
        (
            "MAX_SCENE_FILE_BYTES",
            bytes(MAX_SCENE_FILE_BYTES),
            "a .toml scene file",
        ),
        (
            "MAX_MESH_FILE_BYTES",
            bytes(MAX_MESH_FILE_BYTES),
            "an .obj mesh file",
        ),
        (
            "MAX_MODEL_FILE_BYTES",
            bytes(MAX_MODEL_FILE_BYTES),
            "a .gltf/.glb model, each of its buffer files, and all its buffers together",
        ),
        (
            "MAX_OBJ_LINE_BYTES",
            bytes(MAX_OBJ_LINE_BYTES as u64),
            "one line of an .obj file",
        ),
        (
            "MAX_SCENE_TRIANGLES",
            MAX_SCENE_TRIANGLES.to_string(),
            "triangles over all objects of a scene",
        ),
        (
            "MAX_SCENE_VERTICES",
            MAX_SCENE_VERTICES.to_string(),
            "vertices over all objects of a scene, after welding",
        ),
        (
            "MAX_MESH_VERTICES",
            MAX_MESH_VERTICES.to_string(),
            "`v` lines of one .obj file",
        ),
        (
            "MAX_VOLUME_TRIANGLES",
            MAX_VOLUME_TRIANGLES.to_string(),
            "shadow-volume triangles of a scene (over it: no shadow, a warning)",
        ),
        (
            "MAX_SHAPE_QUADS",
            MAX_SHAPE_QUADS.to_string(),
            "A·B of one built-in shape NAME:AxB (segments up to 4096)",
        ),
        (
            "MAX_REFERENCE_SAMPLES",
            MAX_REFERENCE_SAMPLES.to_string(),
            "--samples",
        ),
        (
            "MAX_IMAGE_PIXELS",
            format!("{MAX_IMAGE_PIXELS} (side {MAX_IMAGE_SIDE})"),
            "--size of render and compare",
        ),
        (
            "MAX_INSPECT_PIXELS",
            MAX_INSPECT_PIXELS.to_string(),
            "--size of inspect",
        ),
        (
            "MAX_ORACLE_TRIANGLES",
            MAX_ORACLE_TRIANGLES.to_string(),
            "triangles of a scene inspect --samples ray-casts on the CPU",
        ),
        (
            "MAX_DBUFFER_SIZE",
            MAX_DBUFFER_SIZE.to_string(),
            "--dbuffer-size",
        ),
        (
            "MAX_FUSED_LIST_BYTES",
            bytes(MAX_FUSED_LIST_BYTES),
            "dbuffer-fused's lists: --list-size² × (--list-cap + 1) × 4 bytes",
        ),
        (
            "MAX_FUSED_EDGES",
            MAX_FUSED_EDGES.to_string(),
            "dbuffer-fused's candidate edges (over it: dbuffer's V everywhere)",
        ),
        (
            "MAX_ORBIT_FRAMES",
            MAX_ORBIT_FRAMES.to_string(),
            "--frames of compare --orbit",
        ),
        (
            "MAX_COMPARE_PIXELS",
            MAX_COMPARE_PIXELS.to_string(),
            "--size of compare (still and --orbit)",
        ),
        (
            "MAX_ANIMATE_PIXELS",
            MAX_ANIMATE_PIXELS.to_string(),
            "--size of animate",
        ),
        (
            "MAX_STUDY_CELLS",
            MAX_STUDY_CELLS.to_string(),
            "cells of dbuffer study (scenes × methods × settings)",
        ),
        (
            "MAX_STUDY_PIXELS",
            MAX_STUDY_PIXELS.to_string(),
            "dbuffer study: cells × --size pixels",
        ),
        (
            "MEMORY_BOUND_BYTES",
            bytes(MEMORY_BOUND_BYTES),
            "what inspect and compare use at most within the budget",
        ),
    ];
    let mut text =
        String::from("Limits (src/budget.rs; an input over one is refused, naming it):\n");
    for (name, value, what) in rows {
        text.push_str(&format!("  {name:<22} {value:<22} {what}\n"));
    }
    text
}

/// `n` bytes as KiB, MiB or GiB when it is a whole number of them.
pub fn bytes(n: u64) -> String {
    for (unit, size) in [("GiB", 1u64 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)] {
        if n >= size && n.is_multiple_of(size) {
            return format!("{} {unit}", n / size);
        }
    }
    format!("{n} bytes")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_budget_covers_what_the_render_core_renders() {
        // The render core renders 16M triangles; the budget must let a scene have them.
        const { assert!(MAX_SCENE_TRIANGLES >= 16 * 1024 * 1024) };
        // One shape never exceeds the scene budget alone.
        const { assert!(2 * MAX_SHAPE_QUADS <= MAX_SCENE_TRIANGLES) };
        // A closed mesh of half the triangle budget fits the vertex budget.
        const { assert!(MAX_SCENE_TRIANGLES / 4 + 2 <= MAX_SCENE_VERTICES) };
        // 8192×8192 is an image the budget allows.
        const { assert!(8192 * 8192 <= MAX_IMAGE_PIXELS && 8192 <= MAX_IMAGE_SIDE) };
        // The commands with a smaller image of their own still take 3000×3000.
        const { assert!(3000 * 3000 <= MAX_COMPARE_PIXELS && MAX_COMPARE_PIXELS <= MAX_IMAGE_PIXELS) };
        const { assert!(3000 * 3000 <= MAX_ANIMATE_PIXELS && MAX_ANIMATE_PIXELS <= MAX_IMAGE_PIXELS) };
    }

    #[test]
    fn the_summary_names_every_limit() {
        let s = summary();
        for name in [
            "MAX_SCENE_FILE_BYTES",
            "MAX_MESH_FILE_BYTES",
            "MAX_SCENE_TRIANGLES",
            "MAX_REFERENCE_SAMPLES",
            "MAX_IMAGE_PIXELS",
            "MAX_DBUFFER_SIZE",
            "MAX_FUSED_LIST_BYTES",
            "MAX_FUSED_EDGES",
            "MAX_COMPARE_PIXELS",
            "MAX_ANIMATE_PIXELS",
        ] {
            assert!(s.contains(name), "{name} missing from:\n{s}");
        }
        assert!(s.contains("16777216"), "{s}");
        assert_eq!(bytes(2 << 30), "2 GiB");
        assert_eq!(bytes(1 << 20), "1 MiB");
        assert_eq!(bytes(1000), "1000 bytes");
    }
}
