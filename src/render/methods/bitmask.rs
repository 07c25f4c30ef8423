//! `bitmask`: bitmask soft shadows (Schwarz & Stamminger, Computer Graphics Forum 26(3), 2007) on
//! the centre's shadow map. Each texel of the map is a micro-patch; seen from the shaded point
//! it is back-projected onto the light and sets the bits of the light samples it covers (up to
//! 256, through the half-plane look-up tables `dbuffer-fused` reads too), so overlapping
//! occluders combine as in the world: occluder fusion in image space. The texels searched lie in
//! a region sized by the light, found through a min-max pyramid; the micro-patches' corners are
//! gap-filled so that one surface's patches tile the light without gaps ("Microquad soft shadow
//! mapping revisited", EG 2008). `shaders/methods/bitmask.wgsl`; the corners and the pyramid are
//! `passes::micro_patches`; the arithmetic's CPU twin is `geometry::bitmask`.

use super::{
    require, AdapterNeeds, CameraGroup, Cost, FrameInputs, Knob, LightMaps, MethodSpec,
    MethodState, Prepare, Quality, Scaled, SharedMaps, Switch, SHADOW_MAP,
};
use crate::geometry::fused::{DiskMask, MaskEval};
use crate::render::adapter::{FormatNeed, Usage};
use crate::render::passes::micro_patches::{pyramid_shape, MicroPatches};
use crate::render::passes::shadow_map::{lookup_entries, MapFrame, ShadowUniforms};
use crate::render::{
    buffer_entry, storage_entry, texture_entry, uniform_buffer, view_entry, GpuContext, RenderError,
};
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
    Box::new(Bitmask::new(ctx))
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

fn bitmask_knobs(f: &FrameInputs<'_>, levels: u32) -> [f32; 4] {
    let flags = if f.knobs.get(&COARSE) { FLAG_COARSE } else { 0 };
    [
        super::pcss::lowest_caster(f.scene),
        f.knobs.get(&SAMPLES) as f32,
        flags as f32 + f.knobs.get(&DETAIL),
        levels as f32,
    ]
}

/// What the corners and the pyramid were made from.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Made {
    revision: u64,
    map: u64,
    gap_fill: bool,
}

/// What the bind group binds.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bound {
    map: u64,
    patches: u64,
    lut: u64,
}

/// The look-up tables and what they were made for.
struct Lut {
    buffer: wgpu::Buffer,
    samples: u32,
    light: AreaLight,
    generation: u64,
}

pub struct Bitmask {
    patches: MicroPatches,
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    lut: Option<Lut>,
    made: Option<Made>,
}

impl Bitmask {
    fn new(ctx: &GpuContext) -> Bitmask {
        let mut entries = lookup_entries().to_vec();
        let texture = wgpu::TextureViewDimension::D2;
        entries.push(texture_entry(2, wgpu::ShaderStages::FRAGMENT, texture));
        entries.push(texture_entry(3, wgpu::ShaderStages::FRAGMENT, texture));
        entries.push(storage_entry(4, wgpu::ShaderStages::FRAGMENT, true));
        entries.push(texture_entry(5, wgpu::ShaderStages::FRAGMENT, texture));
        Bitmask {
            patches: MicroPatches::default(),
            camera: CameraGroup::new(ctx, SHADER, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "Bitmask::uniforms"),
            lut: None,
            made: None,
        }
    }

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

impl MethodState for Bitmask {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let ctx = inputs.ctx;
        let map = shared.shadow_map.update(inputs, rec)?;
        let made = Made {
            revision: inputs.revision,
            map: map.generation,
            gap_fill: inputs.knobs.get(&GAP_FILL),
        };
        let light = *inputs.area(BITMASK.name)?;
        if self.made != Some(made) {
            let frame = MapFrame::new(inputs.light_view, &inputs.scene.light);
            self.patches.record(
                ctx,
                rec,
                &map.distance.view,
                map.size,
                made.gap_fill,
                &frame,
            );
            self.made = Some(made);
        }
        let (_, levels) = pyramid_shape(map.size);
        let uniforms =
            ShadowUniforms::new(inputs.light_view, map.size, bitmask_knobs(inputs, levels));
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let samples = inputs.knobs.get(&SAMPLES);
        self.update_lut(&ctx.device, light, samples);
        let patches = require(self.patches.maps(), "the micro-patch maps were not made")?;
        let lut = require(
            self.lut.as_ref(),
            "the bitmask look-up tables were not made",
        )?;
        let bound = Bound {
            map: map.generation,
            patches: patches.generation,
            lut: lut.generation,
        };
        let entries = [
            buffer_entry(0, &self.uniforms),
            view_entry(1, &map.distance.view),
            view_entry(2, &patches.corners.view),
            view_entry(3, &patches.pyramid[0].view),
            buffer_entry(4, &lut.buffer),
            view_entry(5, &patches.pyramid[1].view),
        ];
        self.camera.bind(&ctx.device, bound, &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        shared.shadow_map.light_maps()
    }

    fn invalidate(&mut self) {
        self.made = None;
    }
}
