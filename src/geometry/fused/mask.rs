//! The camera pass's mask: the disk samples, the look-up tables of half-plane masks the GPU reads,
//! and the count of layers per sample over a receiver's edges (see the module docs of [`super`]:
//! "Why chords add up", "`L(c)`", "Exact where one layer deep").

use glam::{Vec2, Vec3};

use super::area::whole_segment;
use super::chord::{edge_chord, EdgeChord, FusedEdge};
use super::{
    ANCHOR_SAMPLES, ANCHOR_SHARE, CONVEX_SLACK, COUNTER_BITS, MAX_LUT_SAMPLES, MAX_SAMPLES,
};
use crate::geometry::oracle::disk_samples;
use crate::geometry::outline::area_samples;
use crate::geometry::visibility::disk_cut2_area;
use crate::scene::AreaLight;

/// How the camera pass decides which samples a half-plane holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MaskEval {
    /// Every sample tested against every line (`u A + v B + C > 0`, in `f32`).
    #[default]
    Exact,
    /// Through look-up tables of precomputed half-plane masks (Schwarz & Stamminger 2007): lines
    /// through the centre by angle (`LUT_ANGLES` bins, uniform in [`diamond_angle`]), chords by
    /// angle and distance from the centre (`LUT_ANGLES` × `LUT_OFFSETS`). What the GPU does.
    Lut,
}

/// Angle bins of the half-plane look-up tables.
pub const LUT_ANGLES: usize = 256;
/// Distance bins (over `(0, 1)`) of the chord look-up table.
pub const LUT_OFFSETS: usize = 128;

/// One bit a sample, sample `i` is bit `i % 64` of word `i / 64`.
pub type Bits = [u64; 4];

fn bit_set(bits: &mut Bits, i: usize) {
    bits[i / 64] |= 1 << (i % 64);
}

fn bit(bits: &Bits, i: usize) -> bool {
    bits[i / 64] >> (i % 64) & 1 == 1
}

fn and(a: Bits, b: Bits) -> Bits {
    [a[0] & b[0], a[1] & b[1], a[2] & b[2], a[3] & b[3]]
}

fn xor(a: Bits, b: Bits) -> Bits {
    [a[0] ^ b[0], a[1] ^ b[1], a[2] ^ b[2], a[3] ^ b[3]]
}

/// The disk samples of the camera pass's mask, and its look-up tables.
#[derive(Clone, Debug)]
pub struct DiskMask {
    /// Unit-disk coordinates, the oracle's stratified pattern for `N` samples.
    pub samples: Vec<Vec2>,
    pub eval: MaskEval,
    /// `LUT_ANGLES` masks of `{p : p·n_k > 0}` (`n_k` the direction of angle bin `k`).
    through_centre: Vec<Bits>,
    /// `LUT_ANGLES × LUT_OFFSETS` masks of `{p : p·n_k > ρ}`.
    chords: Vec<Bits>,
}

impl DiskMask {
    /// `samples` is clamped to `1..=MAX_SAMPLES` (`1..=MAX_LUT_SAMPLES` with look-up tables).
    pub fn new(samples: usize, eval: MaskEval) -> DiskMask {
        let samples = disk_samples(Self::clamped(samples, eval));
        Self::from_samples(samples, eval)
    }

    /// The mask of `light`: for a disk [`DiskMask::new`]; for a rectangle or polygon its
    /// stratified area samples (the oracle's, `geometry::outline::area_samples`) in the same
    /// unit-disk coordinates (radii of the disk it fits in, along its basis).
    pub fn for_light(light: &AreaLight, samples: usize, eval: MaskEval) -> DiskMask {
        if light.is_disk() {
            return DiskMask::new(samples, eval);
        }
        let (e1, e2) = light.basis();
        let r = light.radius.max(f32::MIN_POSITIVE);
        let unit = area_samples(light, Self::clamped(samples, eval))
            .into_iter()
            .map(|p| Vec2::new((p - light.center).dot(e1), (p - light.center).dot(e2)) / r)
            .collect();
        Self::from_samples(unit, eval)
    }

    fn clamped(samples: usize, eval: MaskEval) -> usize {
        let max = match eval {
            MaskEval::Exact => MAX_SAMPLES,
            MaskEval::Lut => MAX_LUT_SAMPLES,
        };
        samples.clamp(1, max)
    }

    fn from_samples(samples: Vec<Vec2>, eval: MaskEval) -> DiskMask {
        let (mut through_centre, mut chords) = (Vec::new(), Vec::new());
        if eval == MaskEval::Lut {
            for k in 0..LUT_ANGLES {
                let n = lut_direction(k);
                let mut m = Bits::default();
                for (i, p) in samples.iter().enumerate() {
                    if p.dot(n) > 0.0 {
                        bit_set(&mut m, i);
                    }
                }
                through_centre.push(m);
                for j in 0..LUT_OFFSETS {
                    let rho = (j as f32 + 0.5) / LUT_OFFSETS as f32;
                    let mut m = Bits::default();
                    for (i, p) in samples.iter().enumerate() {
                        if p.dot(n) > rho {
                            bit_set(&mut m, i);
                        }
                    }
                    chords.push(m);
                }
            }
        }
        DiskMask {
            samples,
            eval,
            through_centre,
            chords,
        }
    }

    pub fn len(&self) -> usize {
        self.samples.len()
    }

    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The look-up tables as the GPU reads them, 128 bits (four `u32`, sample `i` is bit `i % 32`
    /// of word `i / 32`) per mask: the [`LUT_ANGLES`] masks through the centre, then the
    /// [`LUT_ANGLES`] × [`LUT_OFFSETS`] chord masks (angle-major). Empty unless the mask was made
    /// with [`MaskEval::Lut`] and at most 128 samples (what the GPU's counter holds).
    pub fn lut_words(&self) -> Vec<[u32; 4]> {
        if self.eval != MaskEval::Lut || self.samples.len() > 128 {
            return Vec::new();
        }
        let words = |b: &Bits| {
            [
                b[0] as u32,
                (b[0] >> 32) as u32,
                b[1] as u32,
                (b[1] >> 32) as u32,
            ]
        };
        self.through_centre
            .iter()
            .chain(&self.chords)
            .map(words)
            .collect()
    }

    /// The same tables with all 256 bits a mask (eight `u32`, sample `i` is bit `i % 32` of word
    /// `i / 32`): what `bitmask` reads, for up to [`MAX_LUT_SAMPLES`] samples. Empty unless made
    /// with [`MaskEval::Lut`].
    pub fn lut_words_wide(&self) -> Vec<[u32; 8]> {
        if self.eval != MaskEval::Lut {
            return Vec::new();
        }
        let words = |b: &Bits| std::array::from_fn(|i| (b[i / 2] >> (32 * (i % 2))) as u32);
        self.through_centre
            .iter()
            .chain(&self.chords)
            .map(words)
            .collect()
    }

    /// The samples `p` with `p·n ≤ ρ` (a half-plane of the light's unit-disk coordinates, `n`
    /// any non-zero normal, `ρ` relative to `|n|`) through the chord table, as `bitmask`'s
    /// camera pass reads it: the chord of the angle bin nearest `n` (`-n` where `ρ < 0`) and the
    /// distance bin below `|ρ|`. Every sample for `ρ ≥ 1`, none for `ρ ≤ -1`. Exact samples
    /// (no table) where the mask was made with [`MaskEval::Exact`].
    pub fn half_plane(&self, n: Vec2, rho: f32) -> Bits {
        let len = n.length();
        let all = self.all();
        if len.is_nan() || len <= 0.0 || rho.is_nan() {
            return Bits::default();
        }
        let rho = rho / len;
        if rho >= 1.0 {
            return all;
        }
        if rho <= -1.0 {
            return Bits::default();
        }
        if self.eval == MaskEval::Exact || self.chords.is_empty() {
            let mut m = Bits::default();
            for (i, p) in self.samples.iter().enumerate() {
                if p.dot(n) <= rho * len {
                    bit_set(&mut m, i);
                }
            }
            return m;
        }
        let j = ((rho.abs() * LUT_OFFSETS as f32) as usize).min(LUT_OFFSETS - 1);
        if rho >= 0.0 {
            // Not beyond the chord at ρ along n.
            let beyond = self.chords[lut_bin(n.x, n.y) * LUT_OFFSETS + j];
            xor(beyond, all)
        } else {
            // Beyond the chord at |ρ| along -n.
            self.chords[lut_bin(-n.x, -n.y) * LUT_OFFSETS + j]
        }
    }

    /// Every sample's bit.
    pub fn all(&self) -> Bits {
        let mut m = Bits::default();
        for i in 0..self.samples.len().min(MAX_LUT_SAMPLES) {
            bit_set(&mut m, i);
        }
        m
    }

    /// Adds `ch.delta` to the counter of every sample in the edge's region; returns whether any
    /// sample was in it.
    pub fn add_region(&self, ch: &EdgeChord, count: &mut [i32]) -> bool {
        match self.eval {
            MaskEval::Exact => {
                let mut any = false;
                for (k, &p) in count.iter_mut().zip(&self.samples) {
                    if ch.contains(p) {
                        *k += ch.delta;
                        any = true;
                    }
                }
                any
            }
            MaskEval::Lut => {
                let bits = self.lut_region(ch);
                for (i, k) in count.iter_mut().enumerate() {
                    if bit(&bits, i) {
                        *k += ch.delta;
                    }
                }
                bits != Bits::default()
            }
        }
    }

    /// The samples in an edge's region, through the look-up tables.
    fn lut_region(&self, ch: &EdgeChord) -> Bits {
        let [a, b, c] = ch.chord;
        let len = (a * a + b * b).sqrt();
        // C < 0: the chord lies at ρ = −C/|(A, B)| > 0 from the centre.
        let rho = -c / len;
        if len.is_nan() || len <= 0.0 || rho.is_nan() || rho >= 1.0 || self.chords.is_empty() {
            return Bits::default();
        }
        let j = ((rho * LUT_OFFSETS as f32) as usize).min(LUT_OFFSETS - 1);
        let beyond = self.chords[lut_bin(a, b) * LUT_OFFSETS + j];
        let sa = self.through_centre[lut_bin(ch.end_a[0], ch.end_a[1])];
        let sb = self.through_centre[lut_bin(ch.end_b[0], ch.end_b[1])];
        and(beyond, xor(sa, sb))
    }
}

/// The unit direction of angle bin `k`: the bins are uniform in the "diamond angle"
/// ([`diamond_angle`]), which a GPU computes with one division where an angle takes an arc
/// tangent.
fn lut_direction(k: usize) -> Vec2 {
    let d = k as f32 / LUT_ANGLES as f32 * 4.0;
    let v = if d < 1.0 {
        Vec2::new(1.0 - d, d)
    } else if d < 2.0 {
        Vec2::new(1.0 - d, 2.0 - d)
    } else if d < 3.0 {
        Vec2::new(d - 3.0, 2.0 - d)
    } else {
        Vec2::new(d - 3.0, d - 4.0)
    };
    v.normalize()
}

/// A monotone stand-in for the angle of `(a, b)`, in `[0, 4)`: the position along the diamond
/// `|u| + |v| = 1` where the ray through `(a, b)` meets it, counter-clockwise from `(1, 0)`.
/// `shaders/methods/dbuffer_fused.wgsl` computes it the same way.
pub fn diamond_angle(a: f32, b: f32) -> f32 {
    let s = a.abs() + b.abs();
    if s.is_nan() || s <= 0.0 {
        return 0.0;
    }
    let (x, y) = (a / s, b / s);
    if y >= 0.0 {
        if x >= 0.0 {
            y
        } else {
            1.0 - x
        }
    } else if x < 0.0 {
        2.0 - y
    } else {
        3.0 + x
    }
}

/// The angle bin of the normal `(a, b)`, rounded to the nearest.
fn lut_bin(a: f32, b: f32) -> usize {
    ((diamond_angle(a, b) * (LUT_ANGLES as f32 / 4.0)).round() as usize) % LUT_ANGLES
}

/// Wraps a layer count to the camera pass's `COUNTER_BITS`-bit two's complement.
pub(super) fn wrap(v: i32) -> i32 {
    let span = 1 << COUNTER_BITS;
    (v + span / 2).rem_euclid(span) - span / 2
}

/// How the camera pass reached V at a receiver with a list (the cost view's paths of
/// `dbuffer-fused`, `render::methods::dbuffer_fused`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum VPath {
    /// No chord cuts the disk: all of it is as its centre is.
    NoChord,
    /// The chords that cut the disk are all one convex caster's: one layer deep, the exact area.
    Convex,
    /// One or two chords cut the disk, each a whole circular segment (a disk light): the exact
    /// area of the parts they make (Jakobsen et al. 2004, §6.3).
    Chords,
    /// The samples' counts showed the disk one layer deep: the exact area.
    OneLayer,
    /// The samples' count.
    #[default]
    Samples,
}

/// The result of the mask for one receiver.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaskResult {
    /// Samples visible.
    pub visible: u32,
    pub samples: u32,
    /// `L(c)` as anchored.
    pub anchor: i32,
    /// Edges that changed some sample.
    pub active_edges: u32,
    /// Layers of a crossing (2 for closed casters; 0 when no chord crosses the disk).
    pub layers: u32,
    /// Where V is known in closed form (every path but [`VPath::Samples`]), the exact visible
    /// fraction.
    pub exact: Option<f64>,
    pub path: VPath,
}

impl MaskResult {
    /// The visible fraction of the samples.
    pub fn v_samples(&self) -> f64 {
        f64::from(self.visible) / f64::from(self.samples.max(1))
    }

    /// V: exact one layer deep, else the samples' fraction.
    pub fn v(&self) -> f64 {
        self.exact.unwrap_or_else(|| self.v_samples())
    }
}

/// What the camera pass knows of `L(c)`, the layers between `x` and the disk centre.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CentreLayers {
    /// Exactly (the light pass counted the caster surfaces along the ray, and `x` lies beyond
    /// them all).
    Known(i32),
    /// Only whether `x` is hidden from `c` (the D-buffer's `|cx_o|` test).
    Hidden(bool),
}

/// The camera pass's mask over `edges` (any superset of the edges that matter) at `x`.
pub fn mask_visibility<'a>(
    edges: impl IntoIterator<Item = &'a FusedEdge>,
    x: Vec3,
    centre: CentreLayers,
    light: &AreaLight,
    mask: &DiskMask,
) -> MaskResult {
    mask_details(edges, x, centre, light, mask).result
}

/// What the mask saw at one receiver: the result, the chord of every edge that is one there
/// (with its position in the edges given), and each sample's `Δ` (the layers the path from the
/// centre to it crosses, wrapped to the GPU counter's `COUNTER_BITS` bits).
#[derive(Clone, Debug, PartialEq)]
pub struct MaskDetails {
    pub result: MaskResult,
    pub chords: Vec<(usize, EdgeChord)>,
    pub delta: Vec<i32>,
}

/// [`mask_visibility`] with what it saw ([`MaskDetails`]).
pub fn mask_details<'a>(
    edges: impl IntoIterator<Item = &'a FusedEdge>,
    x: Vec3,
    centre: CentreLayers,
    light: &AreaLight,
    mask: &DiskMask,
) -> MaskDetails {
    let n = mask.len();
    let mut count = vec![0i32; n];
    let mut active = 0;
    // ∫Δ over the disk, exactly, and the layers of a crossing.
    let mut integral = 0.0f64;
    let mut layers = 0;
    let mut chords = Vec::new();
    // The chords that cut the disk, with their edges' casters and convexity.
    let mut cutting: Vec<(EdgeChord, u32, bool)> = Vec::new();
    for (k, e) in edges.into_iter().enumerate() {
        let Some(ch) = edge_chord(e, x, light) else {
            continue;
        };
        if mask.add_region(&ch, &mut count) {
            active += 1;
        }
        // A chord that misses the disk has no area (the GPU leaves it out before its area).
        let [a, b, c] = ch.chord;
        if c * c < a * a + b * b {
            if ch.area > 0.0 {
                integral += f64::from(ch.delta) * ch.area;
                layers = layers.max(ch.delta.abs());
            }
            cutting.push((ch, e.caster, e.convex));
        }
        chords.push((k, ch));
    }
    let count: Vec<i32> = count.into_iter().map(wrap).collect();
    // The smallest Δ, ignoring up to ANCHOR_SAMPLES − 1 samples below it (the ANCHOR_SAMPLES-th
    // smallest): a sample that a look-up table's quantised line put on the wrong side of one edge
    // of a silhouette and not of its neighbour reads ±layers off, and must not shift every
    // sample's count.
    let min = {
        let mut sorted = count.clone();
        sorted.sort_unstable();
        sorted
            .get(ANCHOR_SAMPLES.min(sorted.len()).max(1) - 1)
            .copied()
            .unwrap_or(0)
    };
    let (floor, hidden) = match centre {
        CentreLayers::Known(k) => (k, k > 0),
        CentreLayers::Hidden(h) => (i32::from(h), h),
    };
    let anchor = (-min).max(floor);
    let visible = count.iter().filter(|&&k| k + anchor <= 0).count() as u32;
    // L(c) of the closed forms that take the disk as one layer deep.
    let lc = match centre {
        CentreLayers::Known(k) => k,
        CentreLayers::Hidden(h) => {
            if h {
                layers
            } else {
                0
            }
        }
    };
    let one_layer = 1.0 - (f64::from(lc) + integral) / f64::from(layers.max(1));
    let one_convex = cutting
        .iter()
        .all(|&(_, caster, convex)| convex && caster == cutting[0].1);
    let whole = cutting
        .iter()
        .all(|(ch, ..)| whole_segment(ch.ends[0], ch.ends[1]));
    let (exact, path) = if layers == 0 {
        (Some(if hidden { 0.0 } else { 1.0 }), VPath::NoChord)
    } else if one_convex
        && (lc == 0 || lc == layers)
        && (-CONVEX_SLACK..=1.0 + CONVEX_SLACK).contains(&one_layer)
    {
        // One convex caster's chords: seen from x it covers one convex region, so every part of
        // the disk is 0 or `layers` deeper than the rest, and the chords' areas give V.
        (Some(one_layer.clamp(0.0, 1.0)), VPath::Convex)
    } else if light.is_disk() && cutting.len() <= 2 && whole {
        (Some(two_chords(&cutting, floor)), VPath::Chords)
    } else if count.iter().all(|&k| k + lc == 0 || k + lc == layers) {
        // One layer deep: where every sample sees 0 or `layers` layers (L(c) = `layers` if
        // hidden), the hidden fraction is the mean of L / layers, which the chords give exactly.
        (Some(one_layer.clamp(0.0, 1.0)), VPath::OneLayer)
    } else {
        (None, VPath::Samples)
    };
    MaskDetails {
        result: MaskResult {
            visible,
            samples: n as u32,
            anchor,
            active_edges: active,
            layers: layers as u32,
            exact,
            path,
        },
        chords,
        delta: count,
    }
}

/// V where at most two chords cut the disk, each a whole circular segment (`cutting`, with
/// their edges' casters and convexity): the disk falls into the parts beyond neither, one or
/// both chords (Jakobsen et al. 2004, §6.3: the area beyond two chords in closed form,
/// `disk_cut2_area`), each `Δ` layers deeper than the centre. `L(c)` is anchored as over the
/// samples: at least `floor`, and no part larger than [`ANCHOR_SHARE`] below 0 layers.
fn two_chords(cutting: &[(EdgeChord, u32, bool)], floor: i32) -> f64 {
    use std::f64::consts::PI;
    // Each chord as (unit normal, distance): the region beyond it is m·p > h.
    let line = |k: usize| {
        cutting.get(k).map_or((glam::DVec2::X, 2.0, 0), |(ch, ..)| {
            let [a, b, c] = ch.chord.map(f64::from);
            let len = (a * a + b * b).sqrt();
            (glam::DVec2::new(a, b) / len, -c / len, ch.delta)
        })
    };
    let ((m1, h1, d1), (m2, h2, d2)) = (line(0), line(1));
    let segment = |h: f64| {
        let h = h.clamp(-1.0, 1.0);
        (h.acos() - h * (1.0 - h * h).max(0.0).sqrt()) / PI
    };
    let (a1, a2) = (segment(h1), segment(h2));
    let both = disk_cut2_area(m1, h1, m2, h2) / PI;
    let parts = [
        (0, 1.0 - a1 - a2 + both),
        (d1, a1 - both),
        (d2, a2 - both),
        (d1 + d2, both),
    ];
    let lowest = parts
        .iter()
        .filter(|p| p.1 > ANCHOR_SHARE)
        .map(|p| p.0)
        .min()
        .unwrap_or(0);
    let anchor = (-lowest).max(floor);
    parts
        .iter()
        .filter(|p| p.0 + anchor <= 0)
        .map(|p| p.1.max(0.0))
        .sum::<f64>()
        .clamp(0.0, 1.0)
}
