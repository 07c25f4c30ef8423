// The point of the light at u in [0, 1)², uniform over its area, from the camera pass's light
// uniforms: a disk by the concentric map (Shirley and Chiu), a rectangle or a convex polygon by
// its fan from corner 0 (u.x picks a triangle by area and is spread again within it), so
// neighbouring u stay near and a stratified u is a stratified light. passes/raytraced.wgsl
// samples its own uniforms the same way. A line light (whose points the camera uniforms do
// not hold) gives its centre.
// #include shared/camera.wgsl

fn light_sample(u: vec2<f32>) -> vec3<f32> {
    var p = vec2<f32>(0.0);
    if camera.light_kind == LIGHT_POLYGON {
        let c0 = light_corner(0u);
        let n = camera.light_corner_count;
        var target_area = u.x * camera.light_area;
        for (var i = 1u; i + 1u < n; i++) {
            let a = light_corner(i);
            let b = light_corner(i + 1u);
            let ea = a - c0;
            let eb = b - c0;
            let area = 0.5 * abs(ea.x * eb.y - ea.y * eb.x);
            if target_area <= area || i + 2u == n {
                let s = clamp(target_area / max(area, 1e-30), 0.0, 1.0);
                let r = sqrt(s);
                p = c0 * (1.0 - r) + a * (r * (1.0 - u.y)) + b * (r * u.y);
                break;
            }
            target_area -= area;
        }
    } else if camera.light_kind == LIGHT_DISK {
        let a = 2.0 * u - 1.0;
        var r = 0.0;
        var phi = 0.0;
        if abs(a.x) > abs(a.y) {
            r = a.x;
            phi = 0.78539816 * (a.y / a.x);
        } else if a.y != 0.0 {
            r = a.y;
            phi = 1.5707963 - 0.78539816 * (a.x / a.y);
        }
        p = camera.light_radius * r * vec2<f32>(cos(phi), sin(phi));
    }
    return camera.light_center + p.x * camera.light_u + p.y * camera.light_w;
}
