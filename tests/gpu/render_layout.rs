//! Every GPU struct has the layout its WGSL declaration has, and every code both sides use (V(t)
//! variants, branches, views, colour maps, probe layout) has the same value on both sides
//! (naga's reflection), so the two cannot drift apart silently.

use crate::support::wgsl_layout::{self, assert_wgsl_layout, assert_wgsl_params};

use dbuffer::geometry::{Branch, VtVariant};
use dbuffer::render::passes::camera::CameraUniforms;
use dbuffer::render::passes::extended_light_map::ElmUniforms;
use dbuffer::render::passes::hybrid::HybridUniforms;
use dbuffer::render::passes::planar::{PlanarUniforms, ReceiverUniform};
use dbuffer::render::passes::probe::{
    COUNT_GROUPS, FIT_GRID, MOTION_GRID, PIXEL_FLOATS, PROBE_COUNT, PROBE_FIT, PROBE_MOTION,
    PROBE_PIXEL,
};
use dbuffer::render::passes::raytraced::RtUniforms;
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
    // Every method that looks up the centre's map (its shader includes shared/shadow_lookup.wgsl).
    let mut lookups = 0;
    for method in dbuffer::render::Method::all() {
        let shader = source(method.spec().shader);
        if wgsl_layout::struct_layout(&shader, "ShadowUniforms").is_none() {
            continue;
        }
        lookups += 1;
        assert_wgsl_layout!(
            ShadowUniforms,
            &shader,
            "ShadowUniforms",
            light_view_proj,
            inv_light_view_proj,
            size,
            texel_slope,
            bias_constant,
            bias_slope
        );
    }
    assert!(
        lookups >= 10,
        "only {lookups} methods look up the shadow map"
    );
    // pcss's Poisson disk: two points a vec4, as the buffer it binds holds them.
    use dbuffer::render::methods::pcss::POISSON_POINTS;
    let disk = wgsl_layout::struct_layout(&source("methods/pcss.wgsl"), "PoissonDisk");
    assert_eq!(
        disk.map(|(size, _)| size as usize),
        Some(POISSON_POINTS * 8)
    );
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
    assert_wgsl_layout!(
        RtUniforms,
        &source("passes/raytraced.wgsl"),
        "RtUniforms",
        view_proj,
        prev_view_proj,
        eye,
        frame,
        light_center,
        light_kind,
        light_normal,
        light_corner_count,
        light_u,
        light_area,
        light_w,
        light_radius,
        line_a,
        rays,
        line_b,
        history,
        width,
        height,
        tan_half_fov,
        radius,
        node_count,
        triangle_count,
        flags,
        light_size,
        light_corners
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

/// Every method's parameters — the `params` uniform of its shader, declared in its module — have
/// the layout and the member types (u32 or f32) of their WGSL struct, in group 1 (at
/// `PARAMS_BINDING` for the methods that look up the shadow map). The test walks the registry:
/// a method whose shader binds `params` of a struct this table does not check fails it, and so
/// does an entry no method binds, or a uniform of a method's own that is not its `params` (a
/// bare `vec4<f32>` of numbers each shader reads its own way).
#[test]
fn every_methods_params_match_their_wgsl() {
    use dbuffer::render::methods::{
        bitmask::BitmaskParams, dbuffer::DBufferParams, dbuffer_fused::DBufferFusedParams,
        extended_light_map::ExtendedLightMapParams, msm::MsmParams, msm_soft::MsmSoftParams,
        pcf::PcfParams, pcss::PcssParams, raytraced::RaytracedParams, reference::ReferenceParams,
        smrt::SmrtParams, vsm::VsmParams, wedges::WedgesParams,
    };
    use dbuffer::render::passes::shadow_map::PARAMS_BINDING;
    /// A WGSL struct's name, and the check of it against its Rust struct in a shader.
    type Check = (&'static str, fn(&str));
    let checks: &[Check] = &[
        ("PcfParams", |w| {
            assert_wgsl_params!(PcfParams, w, "PcfParams", radius, _pad0, _pad1, _pad2)
        }),
        ("PcssParams", |w| {
            assert_wgsl_params!(
                PcssParams,
                w,
                "PcssParams",
                blocker_taps,
                filter_taps,
                nearest_caster,
                _pad0
            )
        }),
        ("VsmParams", |w| {
            assert_wgsl_params!(VsmParams, w, "VsmParams", bleed, min_variance, _pad0, _pad1)
        }),
        ("MsmParams", |w| {
            assert_wgsl_params!(MsmParams, w, "MsmParams", radius, bias, _pad0, _pad1)
        }),
        ("MsmSoftParams", |w| {
            assert_wgsl_params!(
                MsmSoftParams,
                w,
                "MsmSoftParams",
                lowest_caster,
                bias,
                least_blocker,
                _pad0
            )
        }),
        ("BitmaskParams", |w| {
            assert_wgsl_params!(
                BitmaskParams,
                w,
                "BitmaskParams",
                lowest_caster,
                samples,
                flags,
                detail,
                levels,
                _pad0,
                _pad1,
                _pad2
            )
        }),
        ("SmrtParams", |w| {
            assert_wgsl_params!(
                SmrtParams,
                w,
                "SmrtParams",
                extrapolate_slope,
                cot_max_angle,
                texel_dither,
                max_slope_bias,
                screen_ray,
                normal_bias,
                tan_half_fov,
                rays,
                steps,
                adaptive,
                _pad0
            )
        }),
        ("DBufferParams", |w| {
            assert_wgsl_params!(
                DBufferParams,
                w,
                "DBufferParams",
                horizon,
                corners,
                tag,
                _pad0
            )
        }),
        ("DBufferFusedParams", |w| {
            assert_wgsl_params!(
                DBufferFusedParams,
                w,
                "DBufferFusedParams",
                tag,
                _pad0,
                _pad1,
                _pad2
            )
        }),
        ("WedgesParams", |w| {
            assert_wgsl_params!(
                WedgesParams,
                w,
                "WedgesParams",
                horizon,
                _pad0,
                _pad1,
                _pad2
            )
        }),
        ("ReferenceParams", |w| {
            assert_wgsl_params!(
                ReferenceParams,
                w,
                "ReferenceParams",
                rays,
                _pad0,
                _pad1,
                _pad2
            )
        }),
        ("RaytracedParams", |w| {
            assert_wgsl_params!(
                RaytracedParams,
                w,
                "RaytracedParams",
                denoise,
                width,
                _pad0,
                _pad1
            )
        }),
        ("ExtendedLightMapParams", |w| {
            assert_wgsl_params!(
                ExtendedLightMapParams,
                w,
                "ExtendedLightMapParams",
                inv_far,
                levels,
                _pad0,
                _pad1
            )
        }),
    ];
    let mut bound = std::collections::BTreeSet::new();
    for method in dbuffer::render::Method::all() {
        let spec = method.spec();
        let shader = source(spec.shader);
        let uniforms = wgsl_layout::uniforms(&shader);
        // The shared uniforms (checked above) and constant tables; anything else is `params`.
        let shared = ["camera", "shadow", "sampled", "ssm", "fused", "disk"];
        for u in &uniforms {
            assert!(
                u.var == "params" || shared.contains(&u.var.as_str()),
                "{}: the uniform `{}` is neither its `params` nor a shared one",
                spec.name,
                u.var
            );
        }
        let Some(params) = uniforms.iter().find(|u| u.var == "params") else {
            continue;
        };
        let Some(ty) = params.ty.clone() else {
            panic!("{}: `params` is not a named struct", spec.name);
        };
        let lookup = wgsl_layout::struct_layout(&shader, "ShadowUniforms").is_some();
        assert!(
            params.group == 1 && (!lookup || params.binding == PARAMS_BINDING),
            "{}: `params` is bound at group {}, binding {}",
            spec.name,
            params.group,
            params.binding
        );
        let Some((_, check)) = checks.iter().find(|(name, _)| *name == ty) else {
            panic!(
                "{}: its shader binds `params: {ty}`, which this test does not check",
                spec.name
            );
        };
        check(&shader);
        bound.insert(ty);
    }
    for (name, _) in checks {
        assert!(
            bound.contains(*name),
            "no method's shader binds `params: {name}`"
        );
    }
}

/// The type check of [`assert_wgsl_params!`] fires on a count declared `f32` on one side and
/// `u32` on the other, and on two fields swapped.
#[test]
fn a_params_type_or_order_mismatch_fires() {
    #[repr(C)]
    struct Swapped {
        taps: u32,
        near: f32,
    }
    let wgsl = "struct P { near: f32, taps: u32, }";
    let swapped = std::panic::catch_unwind(|| {
        assert_wgsl_params!(Swapped, wgsl, "P", taps, near);
    });
    assert!(swapped.is_err(), "two fields swapped must fail");
    #[repr(C)]
    struct FloatCount {
        near: f32,
        taps: f32,
    }
    let float_count = std::panic::catch_unwind(|| {
        assert_wgsl_params!(FloatCount, wgsl, "P", near, taps);
    });
    assert!(float_count.is_err(), "a count as f32 against u32 must fail");
    #[repr(C)]
    struct Right {
        near: f32,
        taps: u32,
    }
    assert_wgsl_params!(Right, wgsl, "P", near, taps);
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
                View::Range => "VIEW_RANGE",
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
    const { assert!(COUNT_GROUPS * 4 <= 3 * 1024) };
    wgsl_layout::assert_consts(
        &source("passes/probe.wgsl"),
        "passes/probe.wgsl",
        &[
            ("PROBE_FIT", f64::from(PROBE_FIT)),
            ("PROBE_PIXEL", f64::from(PROBE_PIXEL)),
            ("PROBE_MOTION", f64::from(PROBE_MOTION)),
            ("PROBE_COUNT", f64::from(PROBE_COUNT)),
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
