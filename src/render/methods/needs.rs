//! What a method needs of the adapter ([`AdapterNeeds`]) and the format sets several methods
//! share (the centre shadow map, the stencil volumes).

use crate::render::adapter::{Capabilities, FormatNeed, Usage, Verdict};

/// What a method needs of the adapter beyond what every method needs ([`AdapterNeeds::BASE`],
/// the camera pass's), checked before any work ([`Method::on`](super::Method::on)): a device without it refuses the
/// method in one line instead of failing in one of its pipelines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdapterNeeds {
    /// Optional features it cannot do without.
    pub features: wgpu::Features,
    /// The formats it renders to, blends into, filters or binds as storage (each with its
    /// fallback, if it has one).
    pub formats: &'static [FormatNeed],
    /// Downlevel capabilities it uses (compute shaders, storage written from fragment shaders,
    /// storage read in vertex shaders).
    pub downlevel: wgpu::DownlevelFlags,
    /// Storage buffers one of its shader stages binds at most.
    pub storage_buffers_per_stage: u32,
    /// Storage textures one of its shader stages binds at most.
    pub storage_textures_per_stage: u32,
}

impl Default for AdapterNeeds {
    fn default() -> Self {
        AdapterNeeds::NONE
    }
}

/// The centre shadow map (`passes::shadow_map`): distances in `R32Float`, a `Depth32Float` test.
pub const SHADOW_MAP: [FormatNeed; 2] = [
    FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::R32Float]),
    FormatNeed::new(Usage::Depth, &[wgpu::TextureFormat::Depth32Float]),
];

/// What a method drawn with the centre shadow map alone needs: `hard`, `pcf`, `pcss`, `sampled`
/// and the D-buffer's `|cx_o|` (a method whose needs are its own states them in its module, a
/// `const NEEDS`; `reference` and `reference-hard` draw V from the CPU with the camera pass and
/// need only [`AdapterNeeds::BASE`]).
pub const SHADOW_MAPPED: AdapterNeeds = AdapterNeeds::formats(&SHADOW_MAP);

/// The stencil shadow volumes (`passes::stencil_volumes`): positions and visibility as floats, a
/// half-float fill count, and a stencil (with 24-bit depth where 32-bit float depth with stencil
/// is missing: the volumes' depth test is coarser, and `tests/gpu/hard_methods.rs` holds
/// `shadow-volume` on it to at most 0.05 % of pixels off the exact hard shadow).
pub const STENCIL_VOLUMES: [FormatNeed; 4] = [
    FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::Rgba32Float]),
    FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::R32Float]),
    FormatNeed::new(Usage::Blend, &[wgpu::TextureFormat::R16Float]),
    FormatNeed {
        usage: Usage::Depth,
        formats: &[
            wgpu::TextureFormat::Depth32FloatStencil8,
            wgpu::TextureFormat::Depth24PlusStencil8,
        ],
        fallback: "24-bit depth under the stencil: at most 0.05 % of pixels change class",
    },
];

/// The centre's shadow map and the camera's prepass of the stencil methods (its positions):
/// `hybrid`'s walls read both, `smrt` its screen ray.
pub const MAP_AND_SCREEN: [FormatNeed; 6] = [
    SHADOW_MAP[0],
    SHADOW_MAP[1],
    STENCIL_VOLUMES[0],
    STENCIL_VOLUMES[1],
    STENCIL_VOLUMES[2],
    STENCIL_VOLUMES[3],
];

impl AdapterNeeds {
    /// Nothing beyond what every method needs.
    pub const NONE: AdapterNeeds = AdapterNeeds {
        features: wgpu::Features::empty(),
        formats: &[],
        downlevel: wgpu::DownlevelFlags::empty(),
        storage_buffers_per_stage: 0,
        storage_textures_per_stage: 0,
    };

    /// What every method needs: the camera pass's targets (V and the receiver distance as
    /// `Rg32Float`, the picture as `Rgba8UnormSrgb`, a `Depth32Float` test).
    pub const BASE: AdapterNeeds = AdapterNeeds {
        formats: &[
            FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::Rg32Float]),
            FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::Rgba8UnormSrgb]),
            FormatNeed::new(Usage::Depth, &[wgpu::TextureFormat::Depth32Float]),
        ],
        ..AdapterNeeds::NONE
    };

    /// `formats` and nothing else.
    pub const fn formats(formats: &'static [FormatNeed]) -> AdapterNeeds {
        AdapterNeeds {
            formats,
            ..AdapterNeeds::NONE
        }
    }

    /// Whether an adapter with `features` has the features the method needs.
    pub fn met_by(&self, features: wgpu::Features) -> bool {
        features.contains(self.features)
    }

    /// What the method gets on `caps`: runs, runs with fallbacks, or what is missing.
    pub fn check(&self, caps: &Capabilities) -> Verdict {
        let mut missing = Vec::new();
        let mut fallbacks = Vec::new();
        let lacking = self.features - caps.features;
        if !lacking.is_empty() {
            missing.push(format!("the feature {lacking:?}"));
        }
        for need in AdapterNeeds::BASE.formats.iter().chain(self.formats) {
            match caps.pick(need) {
                None => {
                    let names: Vec<String> =
                        need.formats.iter().map(|f| format!("{f:?}")).collect();
                    let item = format!("{} {}", need.usage.verb(), names.join(" or "));
                    if !missing.contains(&item) {
                        missing.push(item);
                    }
                }
                Some(f) if Some(&f) != need.formats.first() => {
                    let item =
                        format!("{f:?} instead of {:?} ({})", need.formats[0], need.fallback);
                    if !fallbacks.contains(&item) {
                        fallbacks.push(item);
                    }
                }
                Some(_) => {}
            }
        }
        let flags = self.downlevel - caps.downlevel;
        if !flags.is_empty() {
            missing.push(format!("the downlevel capability {flags:?}"));
        }
        let l = &caps.limits;
        if self.storage_buffers_per_stage > l.max_storage_buffers_per_shader_stage {
            missing.push(format!(
                "{} storage buffers per shader stage (the device has {})",
                self.storage_buffers_per_stage, l.max_storage_buffers_per_shader_stage
            ));
        }
        if self.storage_textures_per_stage > l.max_storage_textures_per_shader_stage {
            missing.push(format!(
                "{} storage textures per shader stage (the device has {})",
                self.storage_textures_per_stage, l.max_storage_textures_per_shader_stage
            ));
        }
        if !missing.is_empty() {
            Verdict::Cannot(missing)
        } else if !fallbacks.is_empty() {
            Verdict::Fallback(fallbacks)
        } else {
            Verdict::Runs
        }
    }
}
