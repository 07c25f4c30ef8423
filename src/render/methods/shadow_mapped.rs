//! What the methods drawn from the centre's shadow map share (`hard`, `pcf`, `pcss`, `vsm`,
//! `msm`, `msm-soft`, `bitmask`): the map itself is the session's ([`super::SharedMaps`]), made
//! once per light or caster move; a method adds the products it makes from the map (moments, a
//! summed-area table, micro-patches: its [`MapProducts`]), its camera shader and its parameters.
//! [`ShadowMapped`] is such a method's state, one `prepare` for all of them: update the map,
//! remake the products when what they were made from changed, write the uniforms, bind.
//!
//! Group 1 of such a method's camera shader: the map's `ShadowUniforms` (0) and the map (1)
//! (`shaders/shared/shadow_lookup.wgsl`), the method's own parameters as `params` (2: a
//! `#[repr(C)]` struct declared in its module and in its WGSL; a method without parameters,
//! `()`, binds none), then the products' bindings (3 on).

use bytemuck::Pod;

use super::{
    AdapterNeeds, CameraGroup, FrameInputs, LightMaps, MethodState, Prepare, Scaled, SharedMaps,
    SHADOW_MAP,
};
use crate::render::passes::moment_sat::MomentSat;
use crate::render::passes::shadow_map::{
    lookup_entries, MapFrame, ShadowMapTargets, ShadowUniforms, PARAMS_BINDING,
};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, storage_entry, uniform_buffer, uniform_entry, view_entry, GpuContext, RenderError,
};
use crate::scene::Scene;

/// What a method binds beside the map and its parameters: what it makes from the map (moments, a
/// table, micro-patches), or holds for good (`pcss`'s Poisson disk).
pub trait MapProducts: Send + 'static {
    /// What the products are made from besides the scene's revision and the map (a knob that
    /// shapes them).
    type Key: Copy + PartialEq + Send + 'static;

    /// Their layout entries in group 1, numbered from 3 on.
    fn layout(&self) -> Vec<wgpu::BindGroupLayoutEntry>;

    /// Their key for this frame.
    fn key(&self, inputs: &FrameInputs<'_>) -> Self::Key;

    /// Make them from `map`: called when the scene's revision, the map or the key changed since
    /// they were last made.
    fn record(
        &mut self,
        inputs: &FrameInputs<'_>,
        rec: &mut Recorder<'_>,
        map: &ShadowMapTargets,
        key: Self::Key,
    );

    /// Their group 1 entries (numbered as [`MapProducts::layout`] says), and the generations of
    /// what they bind (the group is made again when one changes).
    fn entries(&mut self, inputs: &FrameInputs<'_>) -> Result<Bound<'_>, RenderError>;
}

/// What [`MapProducts::entries`] binds.
pub struct Bound<'a> {
    pub generations: Vec<u64>,
    pub entries: Vec<wgpu::BindGroupEntry<'a>>,
}

/// A method that makes nothing of its own from the map (`hard`, `pcf`).
impl MapProducts for () {
    type Key = ();

    fn layout(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        Vec::new()
    }

    fn key(&self, _: &FrameInputs<'_>) {}

    fn record(&mut self, _: &FrameInputs<'_>, _: &mut Recorder<'_>, _: &ShadowMapTargets, _: ()) {}

    fn entries(&mut self, _: &FrameInputs<'_>) -> Result<Bound<'_>, RenderError> {
        Ok(Bound {
            generations: Vec::new(),
            entries: Vec::new(),
        })
    }
}

/// A method's parameters for this frame, from its knobs and the scene (the map is
/// `inputs.map_size` texels on a side).
pub type ParamsOf<P> = fn(&FrameInputs<'_>) -> P;

/// What the products were made from.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Made<K> {
    revision: u64,
    map: u64,
    key: K,
}

/// The state of a method drawn from the centre's shadow map: its products `X` and its
/// parameters `P` (`params` of its shader).
pub struct ShadowMapped<X: MapProducts, P: Pod> {
    products: X,
    params_of: ParamsOf<P>,
    camera: CameraGroup,
    shadow: wgpu::Buffer,
    /// `None` for a method without parameters.
    params: Option<wgpu::Buffer>,
    made: Option<Made<X::Key>>,
}

impl<X: MapProducts, P: Pod> ShadowMapped<X, P> {
    /// The method of camera shader `shader` (`methods/NAME.wgsl`).
    pub fn new(
        ctx: &GpuContext,
        shader: &'static str,
        products: X,
        params_of: ParamsOf<P>,
    ) -> ShadowMapped<X, P> {
        let mut entries = lookup_entries().to_vec();
        let params = (std::mem::size_of::<P>() > 0).then(|| {
            entries.push(uniform_entry(PARAMS_BINDING, wgpu::ShaderStages::FRAGMENT));
            uniform_buffer::<P>(&ctx.device, "ShadowMapped::params")
        });
        entries.extend(products.layout());
        ShadowMapped {
            products,
            params_of,
            camera: CameraGroup::new(ctx, shader, &entries),
            shadow: uniform_buffer::<ShadowUniforms>(&ctx.device, "ShadowMapped::shadow"),
            params,
            made: None,
        }
    }
}

impl<X: MapProducts, P: Pod + Send> MethodState for ShadowMapped<X, P> {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let ctx = inputs.ctx;
        let map = shared.shadow_map.update(inputs, rec)?;
        let made = Made {
            revision: inputs.revision,
            map: map.generation,
            key: self.products.key(inputs),
        };
        if self.made != Some(made) {
            self.products.record(inputs, rec, map, made.key);
            self.made = Some(made);
        }
        let shadow = ShadowUniforms::new(inputs.light_view, map.size);
        ctx.queue
            .write_buffer(&self.shadow, 0, bytemuck::bytes_of(&shadow));
        if let Some(buffer) = &self.params {
            let params = (self.params_of)(inputs);
            ctx.queue
                .write_buffer(buffer, 0, bytemuck::bytes_of(&params));
        }
        let own = self.products.entries(inputs)?;
        let mut entries = vec![
            buffer_entry(0, &self.shadow),
            view_entry(1, &map.distance.view),
        ];
        if let Some(buffer) = &self.params {
            entries.push(buffer_entry(PARAMS_BINDING, buffer));
        }
        entries.extend(own.entries);
        self.camera
            .bind(&ctx.device, (map.generation, own.generations), &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        shared.shadow_map.light_maps()
    }

    fn invalidate(&mut self) {
        self.made = None;
    }
}

/// What `msm` and `msm-soft` need of the adapter: the shadow map; the moment table built by
/// compute and read in fragment shaders (2 storage buffers).
pub const MOMENT_TABLE_NEEDS: AdapterNeeds = AdapterNeeds {
    formats: &SHADOW_MAP,
    downlevel: wgpu::DownlevelFlags::COMPUTE_SHADERS.union(wgpu::DownlevelFlags::FRAGMENT_STORAGE),
    storage_buffers_per_stage: 2,
    ..AdapterNeeds::NONE
};

/// A method's knob `name` for the moment bias α of the moment table, in millionths, 1 to 5000:
/// Peters & Klein's 3·10⁻⁵ by default, for moments quantized to 16 bits each (64 bits a texel),
/// as the table's fixed point holds them.
pub const fn moment_bias(name: &'static str, help: &'static str) -> Scaled {
    Scaled::new(name, help, 1..=5000, 30, 1_000_000)
}

/// `msm`'s and `msm-soft`'s product: the map as four moments a texel in a summed-area table,
/// bound as the table (3) and its depth range (4) (`shaders/shared/msm.wgsl`).
impl MapProducts for MomentSat {
    type Key = ();

    fn layout(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        vec![
            storage_entry(3, wgpu::ShaderStages::FRAGMENT, true),
            storage_entry(4, wgpu::ShaderStages::FRAGMENT, true),
        ]
    }

    fn key(&self, _: &FrameInputs<'_>) {}

    fn record(
        &mut self,
        inputs: &FrameInputs<'_>,
        rec: &mut Recorder<'_>,
        map: &ShadowMapTargets,
        _: (),
    ) {
        let frame = MapFrame::new(inputs.light_view, &inputs.scene.light);
        MomentSat::record(self, inputs.ctx, rec, &map.distance.view, map.size, &frame);
    }

    fn entries(&mut self, _: &FrameInputs<'_>) -> Result<Bound<'_>, RenderError> {
        let table = super::require(self.table(), "the moment table was not made")?;
        Ok(Bound {
            generations: vec![table.generation],
            entries: vec![
                buffer_entry(3, &table.buffer),
                buffer_entry(4, &table.range),
            ],
        })
    }
}

/// The least height above the light's plane of a caster vertex in front of it: where the
/// searches of `msm-soft` and `bitmask` start (the light's reach in the map is widest there).
pub fn lowest_caster(scene: &Scene) -> f32 {
    let Some(light) = scene.light.as_area() else {
        return 1e30;
    };
    scene
        .casters()
        .flat_map(|o| o.mesh.positions.iter())
        .map(|v| light.normal.dot(*v - light.center))
        .filter(|h| h.is_finite() && *h > 0.0)
        .fold(f32::MAX, f32::min)
        .min(1e30)
}
