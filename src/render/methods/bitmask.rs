//! `bitmask`: bitmask soft shadows (Schwarz & Stamminger, Computer Graphics Forum 26(3), 2007) on
//! the centre's shadow map. Each texel of the map is a micro-patch; seen from the shaded point
//! it is back-projected onto the light and sets the bits of the light samples it covers (up to
//! 256, through the half-plane look-up tables `dbuffer-fused` reads too), so overlapping
//! occluders combine as in the world: occluder fusion in image space. The texels searched lie in
//! a region sized by the light, found through a min-max pyramid; the micro-patches' corners are
//! gap-filled so that one surface's patches tile the light without gaps ("Microquad soft shadow
//! mapping revisited", EG 2008). `shaders/methods/bitmask.wgsl`; the corners and the pyramid are
//! `passes::micro_patches`; the arithmetic's CPU twin is `geometry::bitmask`.

use super::shadow_mapped::{lowest_caster, Bound, MapProducts, ShadowMapped};
use super::{
    require, AdapterNeeds, Cost, FrameInputs, Knob, MethodSpec, Quality, Scaled, Switch, SHADOW_MAP,
};
use crate::geometry::fused::{DiskMask, MaskEval};
use crate::render::adapter::{FormatNeed, Usage};
use crate::render::passes::micro_patches::{pyramid_shape, MicroPatches};
use crate::render::passes::shadow_map::{MapFrame, ShadowMapTargets};
use crate::render::timer::Recorder;
use crate::render::{buffer_entry, storage_entry, texture_entry, view_entry, RenderError};
use crate::scene::AreaLight;

pub static SAMPLES: Knob = Knob::int(
    "bitmask-samples",
    "bitmask: light samples, one bit each",
    64..=256,
    256,
);

pub static GAP_FILL: Switch = Switch::new(
    "bitmask-gap-fill",
    "bitmask: move each micro-patch's corners to the distance its surface's texels agree on, so neighbouring patches meet (off: each texel flat at its own distance)",
    true,
);

pub static COARSE: Switch = Switch::new(
    "bitmask-coarse",
    "bitmask: back-project a pyramid node wholly in front of the receiver and nearly flat as one patch (off: every texel)",
    true,
);

/// The level of detail: a pyramid node whose diagonal, back-projected from the point onto the
/// light, is at most this share of the samples' spacing is read as one patch.
pub static DETAIL: Scaled = Scaled::new(
    "bitmask-detail",
    "bitmask: read a pyramid node as one patch where its diagonal, seen from the point on the light, is at most this share of the light samples' spacing, in 1/100 (0: every texel)",
    0..=99,
    50,
    100,
);

pub static BITMASK: MethodSpec = MethodSpec::new("bitmask", SHADER, |ctx| {
    Box::new(ShadowMapped::new(ctx, SHADER, Patches::default(), BitmaskParams::new))
})
.adapter(NEEDS)
.about("bitmask soft shadows (Schwarz & Stamminger 2007): micro-patches back-projected onto light samples")
.knobs(&[&SAMPLES, &GAP_FILL.0, &COARSE.0, &DETAIL.0])
.cost(Cost::counted("pyramid nodes and texels visited"))
.lights(super::AREA_LIGHTS)
.sweep(&[Quality::Knob(&SAMPLES)], &[&[64], &[128], &[256]]);

const SHADER: &str = "methods/bitmask.wgsl";

/// The shadow map, the patch corners and pyramid (`Rgba32Float` render targets read with
/// `textureLoad`), the look-up tables as a storage buffer read by the fragment shader.
const NEEDS: AdapterNeeds = AdapterNeeds {
    formats: &[
        SHADOW_MAP[0],
        SHADOW_MAP[1],
        FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::Rgba32Float]),
    ],
    downlevel: wgpu::DownlevelFlags::FRAGMENT_STORAGE,
    storage_buffers_per_stage: 1,
    ..AdapterNeeds::NONE
};

/// `FLAG_COARSE` of the shader.
const FLAG_COARSE: u32 = 1;

/// `BitmaskParams` of `shaders/methods/bitmask.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BitmaskParams {
    /// The lowest caster's height above the light's plane ([`lowest_caster`]).
    pub lowest_caster: f32,
    /// Light samples, one bit each.
    pub samples: u32,
    /// `FLAG_COARSE` or 0.
    pub flags: u32,
    /// The level of detail, a share of the samples' spacing (below 1).
    pub detail: f32,
    /// The pyramid's levels.
    pub levels: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl BitmaskParams {
    pub fn new(f: &FrameInputs<'_>) -> BitmaskParams {
        let (_, levels) = pyramid_shape(f.map_size);
        BitmaskParams {
            lowest_caster: lowest_caster(f.scene),
            samples: f.knobs.get(&SAMPLES),
            flags: if f.knobs.get(&COARSE) { FLAG_COARSE } else { 0 },
            detail: f.knobs.get(&DETAIL),
            levels,
            ..BitmaskParams::default()
        }
    }
}

/// The look-up tables and what they were made for.
struct Lut {
    buffer: wgpu::Buffer,
    samples: u32,
    light: AreaLight,
    generation: u64,
}

/// What the method makes from the map: the micro-patches' corners and the pyramid (made for
/// the gap filling or not), and the look-up tables of the light's samples.
#[derive(Default)]
pub struct Patches {
    patches: MicroPatches,
    lut: Option<Lut>,
}

impl Patches {
    /// Make the look-up tables of `samples` samples of `light` unless those held are (a disk's
    /// samples are the same for every disk).
    fn update_lut(&mut self, device: &wgpu::Device, light: AreaLight, samples: u32) {
        let same_shape = |l: &AreaLight| (l.is_disk() && light.is_disk()) || *l == light;
        let fresh = self
            .lut
            .as_ref()
            .is_some_and(|t| t.samples == samples && same_shape(&t.light));
        if fresh {
            return;
        }
        use wgpu::util::DeviceExt;
        let words = DiskMask::for_light(&light, samples as usize, MaskEval::Lut).lut_words_wide();
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("Bitmask::lut"),
            contents: bytemuck::cast_slice(&words),
            usage: wgpu::BufferUsages::STORAGE,
        });
        self.lut = Some(Lut {
            buffer,
            samples,
            light,
            generation: crate::render::passes::next_generation(),
        });
    }
}

impl MapProducts for Patches {
    /// The gap filling.
    type Key = bool;

    fn layout(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        let texture = wgpu::TextureViewDimension::D2;
        let stage = wgpu::ShaderStages::FRAGMENT;
        vec![
            texture_entry(3, stage, texture),
            texture_entry(4, stage, texture),
            storage_entry(5, stage, true),
            texture_entry(6, stage, texture),
        ]
    }

    fn key(&self, inputs: &FrameInputs<'_>) -> bool {
        inputs.knobs.get(&GAP_FILL)
    }

    fn record(
        &mut self,
        inputs: &FrameInputs<'_>,
        rec: &mut Recorder<'_>,
        map: &ShadowMapTargets,
        gap_fill: bool,
    ) {
        let frame = MapFrame::new(inputs.light_view, &inputs.scene.light);
        self.patches.record(
            inputs.ctx,
            rec,
            &map.distance.view,
            map.size,
            gap_fill,
            &frame,
        );
    }

    fn entries(&mut self, inputs: &FrameInputs<'_>) -> Result<Bound<'_>, RenderError> {
        let light = *inputs.area(BITMASK.name)?;
        self.update_lut(&inputs.ctx.device, light, inputs.knobs.get(&SAMPLES));
        let patches = require(self.patches.maps(), "the micro-patch maps were not made")?;
        let lut = require(
            self.lut.as_ref(),
            "the bitmask look-up tables were not made",
        )?;
        Ok(Bound {
            generations: vec![patches.generation, lut.generation],
            entries: vec![
                view_entry(3, &patches.corners.view),
                view_entry(4, &patches.pyramid[0].view),
                buffer_entry(5, &lut.buffer),
                view_entry(6, &patches.pyramid[1].view),
            ],
        })
    }
}
