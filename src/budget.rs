//! The resource budget (design.md §7): every limit on what one input may make the program
//! allocate, as a named constant, in one place.
//!
//! Each limit is checked **before** the allocation it guards: a built-in shape's triangle count
//! from its parameters before its vertices exist, a file's size from its metadata before it is
//! read, an OBJ's triangles while its lines are counted. An input over a limit gets an error
//! that names the limit (the constant's name), its value, and the key or flag that asked for
//! more. Under the budget, `dbuffer inspect` stays within [`MEMORY_BOUND_BYTES`] (measured on
//! the worst inputs, see the README's "Limits").
//!
//! `dbuffer --help` prints [`summary`]; the README's "Limits" section lists the same values.

/// Largest scene file (`.toml`) read, in bytes: 1 MiB. The built-in scenes are under 2 KB; a
/// megabyte holds some 20 000 objects.
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 20;

/// Largest mesh file (`.obj`) read, in bytes: 2 GiB, a 16M-triangle mesh written with normals
/// and texture coordinates. The file is streamed, never held in memory whole.
pub const MAX_MESH_FILE_BYTES: u64 = 2 << 30;

/// Longest line of an OBJ file, in bytes: 1 MiB (a polygon of some 100 000 corners).
pub const MAX_OBJ_LINE_BYTES: usize = 1 << 20;

/// Triangles over all objects of one scene (built-in shapes and meshes together): 16 Mi. The
/// shapes' counts are checked from their parameters before any is built, the meshes' while
/// their files are read.
pub const MAX_SCENE_TRIANGLES: u64 = 1 << 24;

/// Vertex positions (`v` lines) of one OBJ file: 16 Mi, as many as a closed mesh of twice
/// [`MAX_SCENE_TRIANGLES`] has.
pub const MAX_MESH_VERTICES: u64 = 1 << 24;

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

/// Pixels of `inspect`'s CPU comparison view (`inspect --size`): 16 Mi, 4096×4096. The CPU twin
/// keeps some 60 bytes per pixel, on top of the scene.
pub const MAX_INSPECT_PIXELS: u64 = 1 << 24;

/// Texels on a side of the D-buffer and the shadow maps (`--dbuffer-size N`).
pub const MAX_DBUFFER_SIZE: u32 = 8192;

/// What `dbuffer inspect` may use on any input within the budget above: 2 GiB.
pub const MEMORY_BOUND_BYTES: u64 = 2 << 30;

/// The budget as the lines `dbuffer --help` prints after its commands.
pub fn summary() -> String {
    let rows: [(&str, String, &str); 11] = [
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
            "MAX_MESH_VERTICES",
            MAX_MESH_VERTICES.to_string(),
            "`v` lines of one .obj file",
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
            "MAX_DBUFFER_SIZE",
            MAX_DBUFFER_SIZE.to_string(),
            "--dbuffer-size",
        ),
        (
            "MEMORY_BOUND_BYTES",
            bytes(MEMORY_BOUND_BYTES),
            "what inspect uses at most within the budget",
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
        if n >= size && n % size == 0 {
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
        // 8192×8192 is an image the budget allows.
        const { assert!(8192 * 8192 <= MAX_IMAGE_PIXELS && 8192 <= MAX_IMAGE_SIDE) };
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
        ] {
            assert!(s.contains(name), "{name} missing from:\n{s}");
        }
        assert!(s.contains("16777216"), "{s}");
        assert_eq!(bytes(2 << 30), "2 GiB");
        assert_eq!(bytes(1 << 20), "1 MiB");
        assert_eq!(bytes(1000), "1000 bytes");
    }
}
