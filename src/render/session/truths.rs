//! The session's ground truths: which engine casts the soft truth's rays, the rays a frame
//! needs cast before it is drawn, the progressive reference's state and the truths' images the
//! lab's workers hand over.

use super::*;

impl Session {
    /// Trace the soft truth's rays in [`Session::cast_truth`] with `engine` (the CPU's oracle
    /// unless told).
    pub fn set_truth_engine(&mut self, engine: truth::Engine) {
        self.truth_engine = engine;
    }

    /// The engine [`Session::cast_truth`] traces the soft truth's rays with.
    pub fn truth_engine(&self) -> truth::Engine {
        self.truth_engine
    }

    /// Cast the rays a frame of `request` needs before it is drawn, here on this thread (on the
    /// CPU, or on the GPU as [`Session::set_truth_engine`] said), and hand them to the GPU: for
    /// the soft truth every sample per pixel at once (`progress` hears samples done and total);
    /// `None` for any other method (the hard truth casts its own in the frame).
    pub fn cast_truth(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Option<truth::Cast>, RenderError> {
        if !truth::is_soft(request.method) {
            return Ok(None);
        }
        let key = self.reference_key(request);
        let t = Instant::now();
        let r = match self.truth_engine {
            truth::Engine::Cpu => crate::render::reference::compute(
                self.scene(),
                key.width,
                key.height,
                key.samples,
                progress,
            ),
            truth::Engine::Gpu => {
                crate::render::gpu_reference::compute(
                    ctx,
                    self.scene(),
                    key.width,
                    key.height,
                    key.samples,
                    progress,
                )?
                .0
            }
        };
        let ms = t.elapsed().as_secs_f64() * 1e3;
        self.set_reference(ctx, key, &r.visibility, (key.samples, key.samples))?;
        Ok(Some(truth::Cast {
            ms,
            rays_ms: r.rays_ms,
            samples: key.samples,
            hit_pixels: r.hit_pixels,
        }))
    }

    /// What the reference for `request` depends on.
    pub fn reference_key(&self, request: &FrameRequest) -> ReferenceKey {
        ReferenceKey {
            light: self.scene.light,
            camera: self.scene.camera,
            width: request.width,
            height: request.height,
            samples: request.knobs.get(&truth::SAMPLES),
            meshes: self.meshes,
        }
    }

    /// Hand the GPU reference V for `key` (row-major, `key.width`×`key.height`), holding `done`
    /// of `total` samples per pixel.
    pub fn set_reference(
        &mut self,
        ctx: &GpuContext,
        key: ReferenceKey,
        visibility: &[f32],
        progress: (u32, u32),
    ) -> Result<(), RenderError> {
        upload(&mut self.reference, ctx, key, visibility, progress)
    }

    /// What the exact hard shadow for `request` depends on (the area reference's key with one
    /// sample: the light's centre).
    pub fn reference_hard_key(&self, request: &FrameRequest) -> ReferenceKey {
        ReferenceKey {
            samples: 1,
            ..self.reference_key(request)
        }
    }

    /// Hand the GPU the exact hard shadow V for `key` (row-major, `key.width`×`key.height`,
    /// made off this thread: the lab's worker); a frame of `reference-hard` for that key shades
    /// it instead of casting its rays in the frame.
    pub fn set_reference_hard(
        &mut self,
        ctx: &GpuContext,
        key: ReferenceKey,
        visibility: &[f32],
    ) -> Result<(), RenderError> {
        upload(&mut self.reference_hard, ctx, key, visibility, (1, 1))
    }

    /// Hand the GPU a FLIP map (row-major, `key.width`×`key.height`) of a frame against the
    /// reference of `key`: the view pass's FLIP view shows it while the reference is that one.
    pub fn set_flip(
        &mut self,
        ctx: &GpuContext,
        key: ReferenceKey,
        map: &[f32],
    ) -> Result<(), RenderError> {
        upload(&mut self.flip, ctx, key, map, (1, 1))
    }

    /// Whether the GPU holds the exact hard shadow for `request`, handed in by
    /// [`Session::set_reference_hard`].
    pub fn has_reference_hard(&self, request: &FrameRequest) -> bool {
        let key = self.reference_hard_key(request);
        self.reference_hard.as_ref().is_some_and(|r| r.key == key)
    }

    /// Whether the GPU holds the reference for `request` (some samples of it).
    pub fn has_reference(&self, request: &FrameRequest) -> bool {
        let key = self.reference_key(request);
        self.reference.as_ref().is_some_and(|r| r.key == key)
    }

    /// Samples per pixel of the reference on the GPU, and how many it will hold when complete.
    pub fn reference_progress(&self) -> Option<(u32, u32)> {
        self.reference.as_ref().map(|r| (r.done, r.total))
    }

    /// Take `step` more reference samples per pixel for `request` here, on this thread (starting
    /// over when what it depends on changed), and hand them to the GPU. Returns (done, total).
    pub fn advance_reference(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
        step: u32,
    ) -> Result<(u32, u32), RenderError> {
        request.validate(ctx)?;
        let key = self.reference_key(request);
        if self.progressive.as_ref().is_none_or(|(k, _)| *k != key) {
            let r = reference::start(&self.scene, key.width, key.height, key.samples);
            self.progressive = Some((key, r));
        }
        let Some((_, r)) = self.progressive.as_mut() else {
            return Ok((0, 0));
        };
        r.step(step as usize);
        let progress = (r.samples_done() as u32, r.samples_total() as u32);
        let v = r.visibility().to_vec();
        self.set_reference(ctx, key, &v, progress)?;
        Ok(progress)
    }

    /// The reference V of the synchronous reference so far, if one was advanced for `request`.
    pub fn reference_visibility(&self, request: &FrameRequest) -> Option<&[f32]> {
        let key = self.reference_key(request);
        self.progressive
            .as_ref()
            .filter(|(k, _)| *k == key)
            .map(|(_, r)| r.visibility())
    }

    /// Whether the synchronous reference still has samples to take.
    pub fn converging(&self) -> bool {
        self.progressive
            .as_ref()
            .is_some_and(|(_, r)| !r.is_complete())
    }
}
