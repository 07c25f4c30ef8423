//! The GPU render core against its CPU twin, on the CPU adapter (lavapipe) the test command
//! installs. Per pixel, the GPU's V is compared with the twin evaluated exactly at the world
//! position the GPU shaded: mean |ΔV| < 0.01, and any larger disagreement must sit within two
//! D-buffer texels of a boundary (where the twin's branch changes), since the GPU looks the
//! channels up per texel and the twin per exact ray.

use dbuffer::geometry::light_view::LightView;
use dbuffer::geometry::{
    Branch, DBufferTwin, PreparedCasters, SceneGeometry, VolumeParams, VtVariant,
};
use dbuffer::render::{Frame, FrameRequest, GpuContext, Method, Session};
use dbuffer::scene::{self, Scene};

const SIZE: u32 = 96;
const DBUFFER: u32 = 1024;

fn context() -> GpuContext {
    match GpuContext::headless() {
        Ok(ctx) => ctx,
        Err(e) => {
            panic!("the render tests need a wgpu adapter (./scripts/test.sh installs Mesa's): {e}")
        }
    }
}

/// A frame of `method` with the geometry the D-buffer was drawn from (the paper's, for a method
/// that builds none) and the light view.
fn render(
    ctx: &GpuContext,
    name: &str,
    method: Method,
) -> (Scene, SceneGeometry, LightView, Frame) {
    let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut session = Session::new(ctx, scene.clone());
    let request = FrameRequest {
        width: SIZE,
        height: SIZE,
        dbuffer_size: DBUFFER,
        method,
        vt: VtVariant::Exact,
        read_dbuffer: true,
        ..FrameRequest::default()
    };
    let frame = session
        .frame(ctx, &request)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    // The CPU stage's geometry: the session's where its stage ran on the CPU, else made here
    // (the GPU stage gives the same, tests/gpu/geometry_gpu.rs), for the twin.
    let geometry = match session.geometry(Method::DBUFFER) {
        Some(g) => g.clone(),
        None => {
            assert!(
                method != Method::DBUFFER || session.gpu_geometry(Method::DBUFFER).is_some(),
                "the D-buffer was made"
            );
            let light = scene.light.area_or_centre();
            PreparedCasters::new(&scene).build(&light, &VolumeParams::for_scene(&scene))
        }
    };
    (scene, geometry, *session.light_view(), frame)
}

#[test]
fn gpu_agrees_with_the_cpu_twin() {
    let ctx = context();
    println!("adapter: {}", ctx.adapter_description());
    for name in [
        "table1-224",
        "fig7-concave",
        "fig8b-light-size",
        "overlap",
        "acute-corner",
        "fig8c-complex",
    ] {
        let (scene, geometry, view, frame) = render(&ctx, name, Method::DBUFFER);
        let twin = DBufferTwin::new(&scene, &geometry.casters);
        // Compare where the surface faces the light (the pixels every metric uses), the twin
        // given the receiver's normal for its horizon; a surface turned away from the light
        // must read V = 0.
        let receivers = dbuffer::geometry::view::receivers(
            &scene,
            &dbuffer::geometry::bvh::Bvh::build(scene.all_triangles()),
            SIZE,
            SIZE,
        );
        let slope = 2.0
            / view
                .projection
                .x_axis
                .x
                .abs()
                .min(view.projection.y_axis.y.abs())
            / DBUFFER as f32;
        let (mut n, mut sum, mut far_from_boundary, mut shadowed) =
            (0usize, 0.0f64, Vec::new(), 0usize);
        for (i, v_gpu) in frame.visibility.iter().enumerate() {
            let Some(x) = frame.position(i) else {
                continue;
            };
            let Some(receiver) = receivers[i] else {
                continue;
            };
            if !receiver.faces_light {
                assert_eq!(*v_gpu, 0.0, "{name}: pixel {i} faces away from the light");
                continue;
            }
            let s = twin.sample(x);
            let v_twin = twin.visibility_on(x, receiver.normal, VtVariant::Exact);
            let dv = (f64::from(*v_gpu) - v_twin).abs();
            n += 1;
            sum += dv;
            shadowed += usize::from(s.branch != Branch::Lit);
            if dv > 0.1 {
                // Near a boundary or a seam? Probe the twin two texel footprints around x.
                let w = (x - scene.light.center()).normalize();
                let (a, b) = w.any_orthonormal_pair();
                let reach = 2.0 * slope * s.d;
                let near_boundary = [a, -a, b, -b, a + b, a - b, -a + b, -a - b]
                    .iter()
                    .any(|o| {
                        // A class boundary, or a seam between a fan (V from its corner) and
                        // another volume triangle (V from its chord): the texel's winner changes.
                        let n = twin.sample(x + *o * reach);
                        n.branch != s.branch || n.corner() != s.corner()
                    });
                if !near_boundary {
                    far_from_boundary.push((i % SIZE as usize, i / SIZE as usize, *v_gpu, v_twin));
                }
            }
        }
        let mean = sum / n.max(1) as f64;
        println!(
            "{name:<18} {n} px, {shadowed} in shadow, mean |dV| {mean:.4}, {} far from a boundary",
            far_from_boundary.len()
        );
        assert!(
            n > 2000 && shadowed > 100,
            "{name}: the view must show the shadow"
        );
        assert!(mean < 0.01, "{name}: mean |dV| {mean}");
        assert!(
            far_from_boundary.is_empty(),
            "{name}: GPU and twin disagree away from boundaries at {:?}",
            &far_from_boundary[..far_from_boundary.len().min(5)]
        );
    }
}

#[test]
fn hard_shadow_is_the_centre_test_alone() {
    let ctx = context();
    let (scene, geometry, _, frame) = render(&ctx, "table1-960", Method::HARD);
    let twin = DBufferTwin::new(&scene, &geometry.casters);
    let (mut agree, mut n) = (0, 0);
    for (i, &v) in frame.visibility.iter().enumerate() {
        let Some(p) = frame.position(i) else {
            continue;
        };
        assert!(v == 0.0 || v == 1.0, "hard shadows are binary, got {v}");
        let s = twin.sample(p);
        n += 1;
        agree += usize::from((v == 0.0) == s.hidden);
    }
    assert!(
        agree as f64 >= 0.99 * n as f64,
        "{agree}/{n} pixels agree with the twin's hidden test"
    );
}
