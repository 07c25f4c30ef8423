// Frame tags (src/render/frame_tag.rs, its CPU twin, says why): a target drawn each frame over
// only part of itself, and never cleared, marks each texel it draws with the frame's tag in the
// low 8 bits of its first component (a positive distance, rounded to the nearest multiple of
// 2^8 ulps); a texel of any other frame reads as a cleared one (0). Tag 0: an untagged target.

const FRAME_TAG_MASK: u32 = 0xffu;

// d rounded to what a tagged texel holds (FrameTag::quantized).
fn frame_quantized(d: f32) -> f32 {
    return bitcast<f32>((bitcast<u32>(d) + 0x80u) & ~FRAME_TAG_MASK);
}

// d (already frame_quantized) as a texel of the frame `tag` stores it.
fn frame_tagged(d: f32, tag: u32) -> f32 {
    return bitcast<f32>(bitcast<u32>(d) | tag);
}

// A texel as stored, made what an untagged target would hold (FrameTag::untag): all 0 where
// another frame drew it, the first component without the tag where the frame `tag` did.
fn frame_untagged(texel: vec4<f32>, tag: u32) -> vec4<f32> {
    let bits = bitcast<u32>(texel.x);
    let live = vec4<f32>(bitcast<f32>(bits & ~FRAME_TAG_MASK), texel.yzw);
    return select(select(vec4<f32>(0.0), live, (bits & FRAME_TAG_MASK) == tag), texel, tag == 0u);
}
