//! Tests of `support/wgsl_layout.rs` on small Rust/WGSL struct pairs.

use crate::support::wgsl_layout;

use std::mem::offset_of;
use std::panic::{catch_unwind, AssertUnwindSafe};

use wgsl_layout::{assert_layout, struct_layout};

const WGSL: &str = "
struct Light {
    position: vec3<f32>,
    radius: f32,
    color: vec3<f32>,
    count: u32,
}

struct Params {
    origin: vec3<f32>,
    scale: vec2<f32>,
    flags: u32,
}
";

/// vec3 is 16-aligned but 12 bytes: a scalar packs into its tail, no padding needed.
#[repr(C)]
struct Light {
    position: [f32; 3],
    radius: f32,
    color: [f32; 3],
    count: u32,
}

/// vec2 is 8-aligned: `scale` starts at 16, and the struct rounds up to 32 (16-aligned).
#[repr(C)]
struct Params {
    origin: [f32; 3],
    _pad0: f32,
    scale: [f32; 2],
    flags: u32,
    _pad1: u32,
}

/// `Params` without the explicit padding: `scale` lands at 12 and the size is 24.
#[repr(C)]
struct ParamsUnpadded {
    origin: [f32; 3],
    scale: [f32; 2],
    flags: u32,
}

fn panic_message(result: std::thread::Result<()>) -> String {
    let payload = result.expect_err("the assertion must fire");
    payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| (*s).to_owned()))
        .unwrap_or_default()
}

#[test]
fn reads_naga_offsets_and_size() {
    let (size, members) = struct_layout(WGSL, "Params").expect("Params is declared");
    assert_eq!(size, 32);
    let members: Vec<(&str, u32)> = members.iter().map(|(n, o)| (n.as_str(), *o)).collect();
    assert_eq!(members, [("origin", 0), ("scale", 16), ("flags", 24)]);
    assert_eq!(struct_layout(WGSL, "Light").map(|(s, _)| s), Some(32));
    assert_eq!(struct_layout(WGSL, "Nope"), None);
}

#[test]
fn matching_structs_pass() {
    assert_layout::<Light>(
        WGSL,
        "Light",
        &[
            ("position", offset_of!(Light, position)),
            ("radius", offset_of!(Light, radius)),
            ("color", offset_of!(Light, color)),
            ("count", offset_of!(Light, count)),
        ],
    );
    wgsl_layout::assert_wgsl_layout!(Params, WGSL, "Params", origin, scale, flags);
}

#[test]
fn a_mismatch_fires_and_lists_both_layouts() {
    let message = panic_message(catch_unwind(AssertUnwindSafe(|| {
        wgsl_layout::assert_wgsl_layout!(ParamsUnpadded, WGSL, "Params", origin, scale, flags);
    })));
    assert!(message.contains("layout mismatch"), "{message}");
    // Both sides of the differing row, and the sizes.
    assert!(
        message.contains(
            "scale                        16   scale                        12   <-- differs"
        ),
        "{message}"
    );
    assert!(
        message.contains(
            "(size)                       32   (size_of)                    24   <-- differs"
        ),
        "{message}"
    );
}

#[test]
fn a_renamed_or_missing_member_fires() {
    let message = panic_message(catch_unwind(AssertUnwindSafe(|| {
        assert_layout::<Light>(
            WGSL,
            "Light",
            &[
                ("position", offset_of!(Light, position)),
                ("radius", offset_of!(Light, radius)),
                ("color", offset_of!(Light, color)),
            ],
        );
    })));
    assert!(message.contains("count"), "{message}");
    let message = panic_message(catch_unwind(|| assert_layout::<Light>(WGSL, "Lamp", &[])));
    assert!(message.contains("no struct `Lamp`"), "{message}");
}
