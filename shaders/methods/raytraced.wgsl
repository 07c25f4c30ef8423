// `raytraced`: shadow rays traced on the GPU and denoised (src/render/methods/raytraced.rs). V per
// pixel is made before the camera pass by passes/raytraced.wgsl — rays against the scene's BVH,
// then temporal accumulation and a penumbra-sized spatial filter — and read here at the pixel:
// the denoised V, or this frame's raw rays when the denoiser is off.
// #include shared/camera.wgsl

// RaytracedParams of src/render/methods/raytraced.rs.
struct RaytracedParams {
    // 1: the denoised V; 0: this frame's raw rays.
    denoise: u32,
    // The image's width in pixels (the buffers are row-major).
    width: u32,
    _pad0: u32,
    _pad1: u32,
};

// This frame's rays, one vec4 a pixel: (V, mean hit distance, rays blocked, BVH nodes visited).
@group(1) @binding(0) var<storage, read> rt_raw: array<vec4<f32>>;
// The denoiser's output: (V, BVH nodes visited, spatial radius, frames accumulated).
@group(1) @binding(1) var<storage, read> rt_denoised: array<vec4<f32>>;
@group(1) @binding(2) var<uniform> params: RaytracedParams;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    // No ray leaves a point behind the one-sided light (the reference casts none either).
    if !in_front_of_light(x) {
        return plain(0.0);
    }
    let p = vec2<u32>(floor(pixel));
    let i = min(p.y * params.width + p.x, arrayLength(&rt_raw) - 1u);
    let raw = rt_raw[i];
    count_work(raw.w);
    if params.denoise == 0u {
        took_path(0.0);
        return plain(raw.x);
    }
    let d = rt_denoised[i];
    took_path(select(1.0, 2.0, d.z > 0.0));
    return plain(d.x);
}
