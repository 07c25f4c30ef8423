// `linear-ssm`'s visibility channels (Heidrich et al. 2000, §3.2): the skins of one sample's map drawn into a
// neighbouring sample's view, Gouraud-shaded from 0 on the occluder to 1 on the receiver,
// interpolated linearly in the image as the paper's hardware did, times the pair's share of the
// light. The nearest skin wins (a scratch depth buffer); a skin behind the sample's own nearest
// surface (its distance map) is hidden. The pipeline's write mask picks the channel: R for the
// pair with the previous sample, G for the pair with the next.
// #include shared/ssm_sample.wgsl

@group(0) @binding(0) var<uniform> sample: SsmSample;
@group(0) @binding(1) var maps: texture_2d_array<f32>;

struct SkinIn {
    @location(0) position: vec3<f32>,
    @location(1) value: f32,
};

struct SkinOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(linear) value: f32,
};

@vertex
fn vs_main(v: SkinIn) -> SkinOut {
    var out: SkinOut;
    out.clip = sample.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.value = v.value;
    return out;
}

@fragment
fn fs_main(f: SkinOut) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(f.clip.xy);
    let nearest = textureLoad(maps, texel, i32(sample.layer), 0).x;
    if distance(f.world, sample.point) > nearest * (1.0 + sample.skin_bias) {
        discard;
    }
    let w = clamp(f.value, 0.0, 1.0) * sample.weight;
    return vec4<f32>(w, w, 0.0, 0.0);
}
