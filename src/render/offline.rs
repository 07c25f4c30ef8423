//! A whole frame without a window, as `dbuffer render` and the tests make it: geometry, upload,
//! the passes, and everything read back into [`RenderOutputs`] with its timings.

use std::time::Instant;

use super::frame::{Frame, FrameRenderer, FrameRequest, Method};
use super::gpu_scene::GpuScene;
use super::light_pass::NO_SURFACE;
use super::reference;
use super::{GpuContext, RenderError};
use crate::geometry::light_view::LightView;
use crate::geometry::metrics::ShadowClass;
use crate::geometry::{PreparedCasters, VolumeParams};
use crate::output::{RenderMeta, RenderOutputs};
use crate::scene::Scene;

/// A GPU context with its passes, kept across renders.
pub struct Offline {
    pub ctx: GpuContext,
    renderer: FrameRenderer,
    /// Called with (samples done, samples total) while the reference accumulates.
    pub progress: Option<Box<dyn FnMut(usize, usize)>>,
}

impl Offline {
    pub fn new() -> Result<Offline, RenderError> {
        let ctx = GpuContext::headless()?;
        let renderer = FrameRenderer::new(&ctx);
        Ok(Offline {
            ctx,
            renderer,
            progress: None,
        })
    }

    /// Render `scene` (called `name` in meta.json) as `request` says.
    pub fn render(
        &mut self,
        name: &str,
        scene: &Scene,
        request: &FrameRequest,
    ) -> Result<(Frame, RenderOutputs), RenderError> {
        let t0 = Instant::now();
        let prepared = PreparedCasters::new(scene);
        let prepare_ms = ms(t0);
        let t1 = Instant::now();
        let params = VolumeParams {
            center_silhouettes: request.method.center_silhouettes(),
            ..VolumeParams::for_scene(scene)
        };
        let geometry = prepared.build(&scene.light, &params);
        let volumes_ms = ms(t1);
        let t2 = Instant::now();
        let view = LightView::fit(scene);
        let gpu = GpuScene::new(&self.ctx.device, scene, &geometry);
        let upload_ms = ms(t2);
        let mut reference_ms = Vec::new();
        let t3 = Instant::now();
        let frame = if request.method == Method::Reference {
            let positions = self.renderer.render(
                &self.ctx,
                scene,
                &gpu,
                &view,
                &reference::positions_request(request),
            )?;
            let t = Instant::now();
            let mut r = reference::start(scene, &positions, request.params.reference_samples);
            let total = r.samples_total();
            // Steps of about a second's work on this machine's CPU, for the progress line.
            let step = (total / 16).max(1);
            while r.step(step) > 0 {
                if let Some(progress) = &mut self.progress {
                    progress(r.samples_done(), total);
                }
            }
            let rays_ms = ms(t);
            reference_ms.push(("reference_rays".to_string(), rays_ms));
            self.renderer.render_with(
                &self.ctx,
                scene,
                &gpu,
                &view,
                request,
                Some(r.visibility()),
            )?
        } else {
            self.renderer
                .render(&self.ctx, scene, &gpu, &view, request)?
        };
        let frame_ms = ms(t3);

        let mut warnings = geometry.warnings.clone();
        if view.clipped {
            warnings.push(format!(
                "the casters' penumbrae reach beyond {}° from the D-buffer's axis; shadows there are cut",
                crate::geometry::light_view::MAX_HALF_ANGLE_DEG
            ));
        }
        let n = (frame.width * frame.height) as usize;
        let hit: Vec<bool> = frame.position.iter().map(|p| p[3] > 0.5).collect();
        let class = frame
            .visibility
            .iter()
            .zip(&hit)
            .map(|(&v, &h)| match (h, ShadowClass::of(f64::from(v))) {
                (false, _) | (true, ShadowClass::Lit) => 0,
                (true, ShadowClass::Penumbra) => 1,
                (true, ShadowClass::Umbra) => 2,
            })
            .collect();
        let outputs = RenderOutputs {
            width: frame.width,
            height: frame.height,
            color: frame
                .color
                .iter()
                .map(|c| {
                    [
                        srgb_to_linear(c[0]),
                        srgb_to_linear(c[1]),
                        srgb_to_linear(c[2]),
                    ]
                })
                .collect(),
            visibility: frame.visibility.clone(),
            hit,
            position: frame.position.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            class,
            dbuffer_size: frame.dbuffer_size,
            d_o: frame
                .distance
                .iter()
                .map(|&d| {
                    if f64::from(d) >= NO_SURFACE * 0.5 {
                        f32::INFINITY
                    } else {
                        d
                    }
                })
                .collect(),
            d_u: frame.umbra.iter().map(|u| u[0]).collect(),
            d_p: frame.penumbra.iter().map(|p| p[0]).collect(),
            s_u: frame.umbra.iter().map(|u| u[1]).collect(),
            s_p: frame.penumbra.iter().map(|p| p[1]).collect(),
            meta: RenderMeta {
                scene: name.to_string(),
                method: request.method.name().to_string(),
                variant: request.vt.name().to_string(),
                width: frame.width,
                height: frame.height,
                dbuffer_size: frame.dbuffer_size,
                adapter: self.ctx.adapter.name.clone(),
                backend: format!("{:?}", self.ctx.adapter.backend),
                cpu_ms: [
                    ("geometry_prepare".into(), prepare_ms),
                    ("geometry_volumes".into(), volumes_ms),
                    ("upload".into(), upload_ms),
                    ("frame_and_readback".into(), frame_ms),
                ]
                .into_iter()
                .chain(reference_ms)
                .collect(),
                gpu_ms: frame.gpu_ms.clone(),
                triangles: scene.objects.iter().map(|o| o.mesh.triangles.len()).sum(),
                caster_triangles: scene.caster_triangle_count(),
                umbra_silhouette_edges: geometry.stats.umbra_edges,
                penumbra_silhouette_edges: geometry.stats.penumbra_edges,
                umbra_volume_triangles: geometry.stats.umbra_triangles,
                penumbra_volume_triangles: geometry.stats.penumbra_triangles,
                warnings,
            },
        };
        debug_assert_eq!(outputs.color.len(), n);
        Ok((frame, outputs))
    }
}

fn ms(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}

/// The sRGB transfer function, inverted.
fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn srgb_round_trips_through_the_writer() {
        for c in 0..=255u8 {
            assert_eq!(crate::output::linear_to_srgb8(super::srgb_to_linear(c)), c);
        }
    }
}
