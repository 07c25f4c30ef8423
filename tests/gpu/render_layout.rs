//! Every GPU struct has the layout its WGSL declaration has, and every code both sides use (V(t)
//! variants, branches, views, colour maps, probe layout) has the same value on both sides
//! (naga's reflection), so the two cannot drift apart silently.

use crate::support::wgsl_layout::{self, assert_wgsl_layout};

use dbuffer::geometry::{Branch, VtVariant};
use dbuffer::render::passes::camera::CameraUniforms;
use dbuffer::render::passes::extended_light_map::ElmUniforms;
use dbuffer::render::passes::hybrid::HybridUniforms;
use dbuffer::render::passes::planar::{PlanarUniforms, ReceiverUniform};
use dbuffer::render::passes::probe::{
    FIT_GRID, MOTION_GRID, PIXEL_FLOATS, PROBE_FIT, PROBE_MOTION, PROBE_PIXEL,
};
use dbuffer::render::passes::sample_maps::{SampleLight, SampleLights, MAX_LIGHTS};
use dbuffer::render::passes::shadow_map::{LightUniforms, ShadowUniforms};
use dbuffer::render::passes::stencil_volumes::ScreenUniforms;
use dbuffer::render::passes::view::{ColorMap, View, ViewUniforms, NO_FALLBACK};
use dbuffer::render::{SurfaceVertex, VolumeVertex};
use dbuffer::shader_source;

fn source(name: &str) -> String {
    shader_source::load(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn uniforms_match_their_wgsl() {
    for shader in ["passes/shadow_map.wgsl", "passes/dbuffer_volumes.wgsl"] {
        assert_wgsl_layout!(
            LightUniforms,
            &source(shader),
            "LightUniforms",
            view_proj,
            center,
            inv_far,
            normal,
            tag
        );
    }
    // Every method's shader includes the camera pass's half; the map methods the lookup.
    for method in dbuffer::render::Method::all() {
        let shader = source(method.spec().shader);
        assert_wgsl_layout!(
            CameraUniforms,
            &shader,
            "CameraUniforms",
            view_proj,
            eye,
            ambient,
            light_center,
            light_radius,
            light_normal,
            light_intensity,
            light_kind,
            light_corner_count,
            light_area,
            light_bound,
            light_u,
            _pad1,
            light_w,
            _pad2,
            light_corners
        );
    }
    for shader in [
        "hard",
        "pcf",
        "pcss",
        "dbuffer",
        "extended_light_map",
        "bitmask",
    ] {
        assert_wgsl_layout!(
            ShadowUniforms,
            &source(&format!("methods/{shader}.wgsl")),
            "ShadowUniforms",
            light_view_proj,
            inv_light_view_proj,
            size,
            texel_slope,
            bias_constant,
            bias_slope,
            knobs
        );
    }
    for shader in [
        source("methods/sampled.wgsl"),
        source("passes/sample_maps.wgsl"),
        source("methods/linear_ssm.wgsl"),
    ] {
        assert_wgsl_layout!(SampleLight, &shader, "SampleLight", view_proj, point, _pad);
        assert_wgsl_layout!(
            SampleLights,
            &shader,
            "SampleLights",
            lights,
            count,
            size,
            texel_slope,
            bias_constant,
            bias_slope,
            _pad0,
            _pad1,
            _pad2
        );
    }
    for shader in ["passes/stencil_volumes.wgsl", "passes/wedges.wgsl"] {
        assert_wgsl_layout!(
            ScreenUniforms,
            &source(shader),
            "ScreenUniforms",
            infinite_view_proj,
            eye,
            size
        );
    }
    use dbuffer::render::methods::smrt::SmrtUniforms;
    assert_wgsl_layout!(
        SmrtUniforms,
        &source("methods/smrt.wgsl"),
        "SmrtUniforms",
        extrapolate_slope,
        cot_max_angle,
        texel_dither,
        max_slope_bias,
        screen_ray,
        normal_bias,
        tan_half_fov
    );
    use dbuffer::render::passes::moment_sat::SatUniforms;
    assert_wgsl_layout!(
        SatUniforms,
        &source("passes/moment_sat.wgsl"),
        "SatUniforms",
        inv_light_view_proj,
        light_center,
        light_normal,
        size,
        scale,
        _pad0,
        _pad1
    );
    use dbuffer::render::passes::micro_patches::PatchUniforms;
    assert_wgsl_layout!(
        PatchUniforms,
        &source("passes/micro_patches.wgsl"),
        "PatchUniforms",
        inv_light_view_proj,
        light_center,
        light_normal,
        mode,
        gap_fill,
        size,
        source_offset,
        target_offset,
        _pad0,
        _pad1,
        _pad2
    );
    use dbuffer::render::passes::ssm::{SkinVertex, SsmSample};
    use dbuffer::render::passes::wedges::WedgeDisk;
    assert_wgsl_layout!(
        WedgeDisk,
        &source("passes/wedges.wgsl"),
        "WedgeDisk",
        center,
        normal,
        u,
        w,
        polygon,
        corners
    );
    assert_wgsl_layout!(
        HybridUniforms,
        &source("passes/hybrid.wgsl"),
        "HybridUniforms",
        inv_light_view_proj,
        light_view_proj,
        infinite_view_proj,
        inv_infinite_view_proj,
        light,
        params,
        limits,
        screen
    );
    assert_wgsl_layout!(
        ElmUniforms,
        &source("passes/extended_light_map.wgsl"),
        "ElmUniforms",
        view_proj,
        light,
        axis,
        spot,
        emitter,
        size
    );
    let planar = source("passes/planar.wgsl");
    assert_wgsl_layout!(ReceiverUniform, &planar, "Receiver", projection, plane);
    assert_wgsl_layout!(
        PlanarUniforms,
        &planar,
        "PlanarUniforms",
        infinite_view_proj,
        shade,
        eye,
        receivers
    );
    for shader in ["passes/ssm_skins.wgsl", "passes/ssm_visibility.wgsl"] {
        assert_wgsl_layout!(
            SsmSample,
            &source(shader),
            "SsmSample",
            view_proj,
            inv_view_proj,
            point,
            layer,
            size,
            capacity,
            far,
            tau,
            weight,
            skin_bias,
            pitch,
            _pad1
        );
        assert_wgsl_layout!(
            SkinVertex,
            &source(shader),
            "SkinVertex",
            position,
            value,
            cell,
            corner,
            _pad0,
            _pad1
        );
    }
    for shader in [source("passes/view.wgsl"), source("passes/probe.wgsl")] {
        assert_wgsl_layout!(
            ViewUniforms,
            &shader,
            "ViewUniforms",
            kind,
            channel_mask,
            colormap,
            has_reference,
            black,
            white,
            map_size,
            channel_count,
            channels,
            tags,
            inv_view_proj,
            map_view_proj,
            probe
        );
    }
}

#[test]
fn codes_match_their_wgsl() {
    // The CPU twins' thresholds, as the GPU halves spell them.
    wgsl_layout::assert_consts(
        &source("passes/ssm_skins.wgsl"),
        "shared/ssm_sample.wgsl",
        &[(
            "SSM_NO_SURFACE_AT",
            f64::from(dbuffer::geometry::ssm::NO_SURFACE_AT),
        )],
    );
    wgsl_layout::assert_consts(
        &source("passes/wedges.wgsl"),
        "passes/wedges.wgsl",
        &[(
            "SLAB_EPS",
            dbuffer::geometry::wedges::SLAB_EPS as f32 as f64,
        )],
    );
    // dbuffer-fused's twin and camera pass: the anchor, the convex path's slack, and how many
    // candidate edges a pixel whose list overflowed walks.
    use dbuffer::geometry::fused;
    wgsl_layout::assert_consts(
        &source("methods/dbuffer_fused.wgsl"),
        "methods/dbuffer_fused.wgsl",
        &[
            ("ANCHOR_SAMPLES", fused::ANCHOR_SAMPLES as f64),
            ("ANCHOR_SHARE", fused::ANCHOR_SHARE as f32 as f64),
            ("CONVEX_SLACK", fused::CONVEX_SLACK as f32 as f64),
            ("WHOLE_WALK_EDGES", fused::WHOLE_WALK_EDGES as f64),
        ],
    );
    let camera = source("methods/hard.wgsl");
    // VT_VARIANT is a pipeline constant (render::passes::camera::CameraPass::method_pipeline
    // sets it to VtVariant::code()); the branches of v_of_t compare it with these.
    let mut pairs: Vec<(&str, f64)> = VtVariant::ALL
        .iter()
        .map(|v| {
            let name = match v {
                VtVariant::Smoothstep => "VT_SMOOTHSTEP",
                VtVariant::Sqrt => "VT_SQRT",
                VtVariant::Exact => "VT_EXACT",
                VtVariant::Linear => "VT_LINEAR",
            };
            (name, f64::from(v.code()))
        })
        .collect();
    for (name, b) in [
        ("BRANCH_UMBRA", Branch::Umbra),
        ("BRANCH_PENUMBRA_HIDDEN", Branch::PenumbraHidden),
        ("BRANCH_PENUMBRA_VISIBLE", Branch::PenumbraVisible),
        ("BRANCH_LIT", Branch::Lit),
    ] {
        pairs.push((name, f64::from(b.code())));
    }
    pairs.push((
        "CLASS_EPSILON",
        dbuffer::geometry::metrics::CLASS_EPS as f32 as f64,
    ));
    use dbuffer::render::passes::camera::{LIGHT_DISK, LIGHT_LINE};
    pairs.push(("LIGHT_DISK", f64::from(LIGHT_DISK)));
    pairs.push(("LIGHT_LINE", f64::from(LIGHT_LINE)));
    wgsl_layout::assert_consts(&camera, "shared/camera.wgsl", &pairs);
    // The D-buffer's corner texture: as many corners to a row, and texels to a corner, as the
    // geometry packs them; the corner rule's margins as the twin's.
    use dbuffer::geometry::{volume_vertices, wedges};
    wgsl_layout::assert_consts(
        &source("methods/dbuffer.wgsl"),
        "methods/dbuffer.wgsl",
        &[
            ("CORNERS_PER_ROW", volume_vertices::CORNERS_PER_ROW as f64),
            (
                "TEXELS_PER_CORNER",
                volume_vertices::TEXELS_PER_CORNER as f64,
            ),
            ("SILHOUETTE_MARGIN", wedges::SILHOUETTE_MARGIN as f32 as f64),
            ("REACH_MARGIN", wedges::REACH_MARGIN as f32 as f64),
            ("SEAM_MARGIN", wedges::SEAM_MARGIN as f32 as f64),
        ],
    );

    let view = source("passes/view.wgsl");
    let mut pairs: Vec<(&str, f64)> = View::ALL
        .iter()
        .map(|v| {
            let name = match v {
                View::Final => "VIEW_FINAL",
                View::Visibility => "VIEW_VISIBILITY",
                View::T => "VIEW_T",
                View::Classes => "VIEW_CLASSES",
                View::Error => "VIEW_ERROR",
                View::DBuffer => "VIEW_LIGHT_MAPS",
                View::Cost => "VIEW_COST",
                View::Flip => "VIEW_FLIP",
            };
            (name, f64::from(v.code()))
        })
        .collect();
    for m in ColorMap::ALL {
        let name = match m {
            ColorMap::Gray => "COLORMAP_GRAY",
            ColorMap::Heat => "COLORMAP_HEAT",
            ColorMap::Turbo => "COLORMAP_TURBO",
        };
        pairs.push((name, f64::from(m.code())));
    }
    pairs.push(("NO_FALLBACK", f64::from(NO_FALLBACK)));
    wgsl_layout::assert_consts(&view, "shared/view_inputs.wgsl", &pairs);
    wgsl_layout::assert_consts(
        &source("passes/probe.wgsl"),
        "passes/probe.wgsl",
        &[("PIXEL_FLOATS", PIXEL_FLOATS as f64)],
    );
    // The fit's samples come back in a few KiB (the lab reads back at most 4 KiB a frame).
    const { assert!(FIT_GRID * FIT_GRID * 4 <= 3 * 1024) };
    const { assert!(MOTION_GRID * MOTION_GRID * 4 <= 3 * 1024) };
    wgsl_layout::assert_consts(
        &source("passes/probe.wgsl"),
        "passes/probe.wgsl",
        &[
            ("PROBE_FIT", f64::from(PROBE_FIT)),
            ("PROBE_PIXEL", f64::from(PROBE_PIXEL)),
            ("PROBE_MOTION", f64::from(PROBE_MOTION)),
        ],
    );
    assert_eq!(MAX_LIGHTS, 64, "SampleLights holds array<SampleLight, 64>");
}

/// Vertex inputs are not laid out by WGSL; the attribute offsets in Rust must match the Rust
/// struct, and the shader locations the WGSL inputs.
#[test]
fn vertex_attributes_match_the_structs() {
    use std::mem::offset_of;
    let surface: Vec<(u32, u64)> = SurfaceVertex::ATTRIBUTES
        .iter()
        .map(|a| (a.shader_location, a.offset))
        .collect();
    assert_eq!(
        surface,
        vec![
            (0, offset_of!(SurfaceVertex, position) as u64),
            (1, offset_of!(SurfaceVertex, albedo) as u64),
        ]
    );
    let volume: Vec<(u32, u64)> = VolumeVertex::ATTRIBUTES
        .iter()
        .map(|a| (a.shader_location, a.offset))
        .collect();
    assert_eq!(
        volume,
        vec![
            (0, offset_of!(VolumeVertex, position) as u64),
            (1, offset_of!(VolumeVertex, kind) as u64),
            (2, offset_of!(VolumeVertex, base) as u64),
            (3, offset_of!(VolumeVertex, num) as u64),
            (4, offset_of!(VolumeVertex, den) as u64),
            (5, offset_of!(VolumeVertex, side) as u64),
        ]
    );
    // The WGSL inputs use those locations with the matching types.
    let surface_in = source("passes/shadow_map.wgsl");
    for decl in [
        "@location(0) position: vec3<f32>",
        "@location(1) albedo: f32",
    ] {
        assert!(surface_in.contains(decl), "SurfaceIn lacks `{decl}`");
    }
    let volumes = source("passes/dbuffer_volumes.wgsl");
    for decl in [
        "@location(0) position: vec3<f32>",
        "@location(1) kind: u32",
        "@location(2) base: f32",
        "@location(3) num: f32",
        "@location(4) den: f32",
        "@location(5) side: vec2<f32>",
    ] {
        assert!(
            volumes.contains(decl),
            "dbuffer_volumes.wgsl lacks `{decl}`"
        );
    }
}
