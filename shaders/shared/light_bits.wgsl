// The half-plane look-up tables of the light's samples (geometry::fused::DiskMask, Schwarz &
// Stamminger 2007): LUT_ANGLES masks of the samples beyond a line through the light's centre,
// then LUT_ANGLES × LUT_OFFSETS masks of those beyond a chord, by the chord's normal (its angle
// bin) and its distance from the centre (over the bound radius). `dbuffer-fused` reads them 128
// bits a mask, `bitmask` 256; both find the bin here.

// geometry::fused::LUT_ANGLES and LUT_OFFSETS.
const LUT_ANGLES: u32 = 256u;
const LUT_OFFSETS: u32 = 128u;

// The position along the diamond |u| + |v| = 1 of the ray through n, in [0, 4): a monotone
// stand-in for its angle (geometry::fused::diamond_angle).
fn diamond_angle(n: vec2<f32>) -> f32 {
    let s = abs(n.x) + abs(n.y);
    if !(s > 0.0) {
        return 0.0;
    }
    let x = n.x / s;
    let y = n.y / s;
    if y >= 0.0 {
        return select(1.0 - x, y, x >= 0.0);
    }
    return select(3.0 + x, 2.0 - y, x < 0.0);
}

// The angle bin of the normal n, rounded to the nearest (geometry::fused::lut_bin).
fn lut_bin(n: vec2<f32>) -> u32 {
    return u32(round(diamond_angle(n) * (f32(LUT_ANGLES) / 4.0))) % LUT_ANGLES;
}
