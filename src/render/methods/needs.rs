//! What each method needs of the adapter beyond [`AdapterNeeds::BASE`], by the passes it runs
//! (each method's [`MethodSpec`](super::MethodSpec) names its entry; a pass's formats are
//! its own constants, repeated here as the adapter is asked about them).

use wgpu::DownlevelFlags as D;
use wgpu::TextureFormat as F;

use super::{AdapterNeeds, SHADOW_MAP, STENCIL_VOLUMES};
use crate::render::adapter::{FormatNeed, Usage};

/// The centre shadow map alone: `hard`, `pcf`, `pcss`, and the D-buffer's `|cx_o|`.
pub const SHADOW_MAPPED: AdapterNeeds = AdapterNeeds::formats(&SHADOW_MAP);

/// `dbuffer`, `dbuffer-center`: the shadow map and the volumes' `Rg32Float` crossings (in BASE).
pub const DBUFFER: AdapterNeeds = SHADOW_MAPPED;

/// `dbuffer-fused`: the layers (half-float counts, float receivers, the first layer's depth), the
/// edge lists built by compute and read back in fragment shaders (4 storage buffers a stage),
/// the maps written as a storage texture.
pub const DBUFFER_FUSED: AdapterNeeds = AdapterNeeds {
    formats: &[
        SHADOW_MAP[0],
        SHADOW_MAP[1],
        FormatNeed::new(Usage::Render, &[F::R16Float]),
        FormatNeed::new(Usage::Render, &[F::Rgba32Float]),
        FormatNeed::new(Usage::Render, &[F::R8Unorm]),
        FormatNeed::new(Usage::Storage, &[F::Rgba32Float]),
    ],
    downlevel: D::COMPUTE_SHADERS
        .union(D::FRAGMENT_WRITABLE_STORAGE)
        .union(D::VERTEX_STORAGE),
    storage_buffers_per_stage: 4,
    storage_textures_per_stage: 1,
    ..AdapterNeeds::NONE
};

/// `sampled`: shadow maps from sample points on the light.
pub const SAMPLED: AdapterNeeds = SHADOW_MAPPED;

/// `linear-ssm`: the sample maps and the skins found by compute passes (six storage buffers in
/// the size-extract pipeline's compute stage).
pub const LINEAR_SSM: AdapterNeeds = AdapterNeeds {
    formats: &SHADOW_MAP,
    downlevel: D::COMPUTE_SHADERS,
    storage_buffers_per_stage: 6,
    ..AdapterNeeds::NONE
};

/// `shadow-volume`: the stencil volumes.
pub const SHADOW_VOLUME: AdapterNeeds = AdapterNeeds::formats(&STENCIL_VOLUMES);

/// `planar`: the stencil volumes and a half-float shade it blends.
pub const PLANAR: AdapterNeeds = AdapterNeeds::formats(&[
    STENCIL_VOLUMES[0],
    STENCIL_VOLUMES[1],
    STENCIL_VOLUMES[2],
    STENCIL_VOLUMES[3],
    FormatNeed::new(Usage::Blend, &[F::R16Float]),
]);

/// `hybrid`: the shadow map, the stencil volumes and its walls found by a compute pass (six
/// storage buffers in its compute stage).
pub const HYBRID: AdapterNeeds = AdapterNeeds {
    formats: &[
        SHADOW_MAP[0],
        SHADOW_MAP[1],
        STENCIL_VOLUMES[0],
        STENCIL_VOLUMES[1],
        STENCIL_VOLUMES[2],
        STENCIL_VOLUMES[3],
    ],
    downlevel: D::COMPUTE_SHADERS,
    storage_buffers_per_stage: 6,
    ..AdapterNeeds::NONE
};

/// `extended-light-map`: float maps and the light's gobo, filtered.
pub const EXTENDED_LIGHT_MAP: AdapterNeeds = AdapterNeeds::formats(&[
    SHADOW_MAP[0],
    SHADOW_MAP[1],
    FormatNeed::new(Usage::Render, &[F::Rgba32Float]),
    FormatNeed::new(Usage::Filter, &[F::Rgba8UnormSrgb]),
]);

/// `wedges`: the stencil volumes and the wedges' coverage summed by blending, in 32-bit floats
/// or, where they do not blend, 16-bit ones.
pub const WEDGES: AdapterNeeds = AdapterNeeds::formats(&[
    STENCIL_VOLUMES[0],
    STENCIL_VOLUMES[1],
    STENCIL_VOLUMES[2],
    STENCIL_VOLUMES[3],
    FormatNeed {
        usage: Usage::Blend,
        formats: &[F::R32Float, F::R16Float],
        fallback: "coverage summed in half floats: V within 1/64 of the 32-bit sum, within 1/256 at 99.5 % of pixels",
    },
]);

// `reference` and `reference-hard` draw V from the CPU with the camera pass alone: they need
// only `AdapterNeeds::BASE`, and state nothing.
