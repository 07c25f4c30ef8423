//! Frame tags: a target that each frame draws over only part of itself, and is never cleared.
//!
//! The D-buffer's volume channels are drawn only where a volume reaches, and "no crossing" (0)
//! everywhere else. Clearing what the last frame drew cost 35–45 % of their pass on lavapipe
//! (docs/results/performance.md). Instead, every texel a frame draws carries that frame's tag
//! in the low [`FrameTag::BITS`] bits of its first component (a positive distance, rounded to
//! the nearest multiple of 2⁸ ulps: at most 7.7 × 10⁻⁶ of it, 0.03 mm at 4 m), and a reader
//! takes a texel of any other frame for a cleared one. Tag 0 is never drawn, so a cleared
//! texel (all 0) is no frame's; the tags run 1 … 255 and the target is cleared whole when they
//! start over. The GPU twin is `shaders/shared/frame_tag.wgsl`.

/// A target's tag: the frame that drew its live texels, or [`FrameTag::NONE`] for a target
/// read as it is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct FrameTag(u32);

impl FrameTag {
    /// An untagged target: every texel is read as stored.
    pub const NONE: FrameTag = FrameTag(0);
    /// Bits of the first component that hold the tag.
    pub const BITS: u32 = 8;
    const MASK: u32 = (1 << Self::BITS) - 1;

    /// The tag of the next frame, and whether the target must be cleared whole first: the
    /// first frame (from [`FrameTag::NONE`]) and every time the tags start over.
    pub fn next(self) -> (FrameTag, bool) {
        if self.0 == 0 || self.0 >= Self::MASK {
            (FrameTag(1), true)
        } else {
            (FrameTag(self.0 + 1), false)
        }
    }

    /// As the shaders take it (0: untagged).
    pub fn bits(self) -> u32 {
        self.0
    }

    /// `d` rounded to what a tagged texel can hold (`frame_quantized` in the shader).
    pub fn quantized(d: f32) -> f32 {
        f32::from_bits(d.to_bits().wrapping_add(1 << (Self::BITS - 1)) & !Self::MASK)
    }

    /// `d` as a texel of this frame stores it (`frame_tagged`).
    pub fn tagged(self, d: f32) -> f32 {
        f32::from_bits(Self::quantized(d).to_bits() | self.0)
    }

    /// One texel's components as stored, made what an untagged target would hold: all 0 where
    /// another frame drew it, its first component without the tag where this one did
    /// (`frame_untagged`).
    pub fn untag(self, texel: &mut [f32]) {
        let Some(first) = texel.first_mut() else {
            return;
        };
        if self.0 == 0 {
            return;
        }
        let bits = first.to_bits();
        if bits & Self::MASK == self.0 {
            *first = f32::from_bits(bits & !Self::MASK);
        } else {
            texel.iter_mut().for_each(|v| *v = 0.0);
        }
    }

    /// Every texel of `values` (`components` floats each).
    pub fn untag_all(self, values: &mut [f32], components: usize) {
        if self.0 != 0 && components > 0 {
            values
                .chunks_exact_mut(components)
                .for_each(|t| self.untag(t));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::FrameTag;

    #[test]
    fn a_texel_of_this_frame_reads_back_within_the_rounding_and_any_other_as_cleared() {
        let (tag, clear) = FrameTag::NONE.next();
        assert!(clear, "a new target is cleared whole");
        let (later, clear_later) = tag.next();
        assert!(!clear_later);
        for d in [1e-3f32, 0.5, 1.0, 3.999_99, 4.0, 123.456, 2.9e38] {
            let mut texel = [tag.tagged(d), 0.25, -0.5, 1.0];
            let mut stale = texel;
            tag.untag(&mut texel);
            assert_eq!(texel[1..], [0.25, -0.5, 1.0]);
            assert_eq!(texel[0], FrameTag::quantized(d));
            let rel = ((texel[0] - d) / d).abs();
            assert!(rel <= 128.0 * f32::EPSILON, "{d}: {rel}");
            later.untag(&mut stale);
            assert_eq!(stale, [0.0; 4], "{d}: another frame's texel is no crossing");
        }
        let mut cleared = [0.0f32; 2];
        tag.untag(&mut cleared);
        assert_eq!(cleared, [0.0; 2]);
        let mut plain = [0.75f32, 2.0];
        FrameTag::NONE.untag(&mut plain);
        assert_eq!(plain, [0.75, 2.0], "an untagged target reads as stored");
    }

    #[test]
    fn the_tags_run_through_255_and_start_over_with_a_clear() {
        let mut tag = FrameTag::NONE;
        let mut seen = std::collections::HashSet::new();
        let mut clears = 0;
        for _ in 0..255 * 2 {
            let (next, clear) = tag.next();
            clears += usize::from(clear);
            assert!((1..=255).contains(&next.bits()));
            seen.insert(next);
            tag = next;
        }
        assert_eq!(seen.len(), 255);
        assert_eq!(clears, 2, "one clear per cycle of 255 frames");
    }

    #[test]
    fn texels_are_decoded_whole_by_the_components() {
        let (tag, _) = FrameTag::NONE.next();
        let (other, _) = tag.next();
        let mut values = vec![tag.tagged(2.0), 1.5, other.tagged(3.0), 1.25, 0.0, 0.0];
        tag.untag_all(&mut values, 2);
        assert_eq!(values, [2.0, 1.5, 0.0, 0.0, 0.0, 0.0]);
    }
}
