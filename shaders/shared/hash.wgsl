// A hash of two words to one (lowbias32 of their mix, Chris Wellons' integer hash): decorrelated
// bits per pixel for the methods that scramble their samples (smrt, raytraced).
fn hash2(a: u32, b: u32) -> u32 {
    var x = (a * 0x9e3779b9u) ^ (b + 0x7f4a7c15u);
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}
