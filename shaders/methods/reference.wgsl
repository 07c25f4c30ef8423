// `reference`: V computed elsewhere — by rays to K stratified disk samples per pixel on the CPU
// (src/render/reference.rs) — uploaded as a texture and shaded like every other method
// (src/render/methods/reference.rs).
// #include shared/camera.wgsl

@group(1) @binding(0) var external_v: texture_2d<f32>;

// ReferenceParams of src/render/methods/reference.rs.
struct ReferenceParams {
    // The rays each pixel in front of the light has cast so far (the cost view).
    rays: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(1) @binding(1) var<uniform> params: ReferenceParams;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    let size = vec2<i32>(textureDimensions(external_v));
    let p = clamp(vec2<i32>(floor(pixel)), vec2<i32>(0), size - 1);
    // The oracle casts no ray from behind the one-sided light (geometry::oracle).
    if in_front_of_light(x) {
        count_work(f32(params.rays));
    }
    return plain(textureLoad(external_v, p, 0).x);
}
