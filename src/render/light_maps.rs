//! Light-space maps ([`LightMaps`]): the textures a method keeps in light space (the D-buffer,
//! its shadow maps) and which component of which texture each named [`Channel`] is. The view
//! pass, the probe and the read-back draw them without knowing the method.

use glam::Mat4;

use super::frame_tag::FrameTag;
use super::Texture;

/// Light-space maps a method keeps (the D-buffer view, the inspector, `dbuffer.exr`): up to
/// three textures, and which component of which texture each named channel is.
pub struct LightMaps<'a> {
    pub size: u32,
    /// The light view's world → clip transform (to find the texel under a world point).
    pub view_proj: Mat4,
    /// One to three `textureLoad`-able float textures (unused slots repeat the first).
    pub textures: [&'a wgpu::TextureView; 3],
    /// The same textures, to read back.
    pub raw: [&'a wgpu::Texture; 3],
    pub channels: &'static [Channel],
    /// Changes whenever the textures are made again (whoever binds them binds again).
    pub generation: u64,
    /// Per texture, the frame tag its live texels carry ([`FrameTag::NONE`]: read as stored).
    pub tags: [FrameTag; 3],
}

impl<'a> LightMaps<'a> {
    /// The maps of `textures` (a slot may repeat another), `size`² texels seen through
    /// `view_proj`.
    pub fn new(
        size: u32,
        view_proj: Mat4,
        textures: [&'a Texture; 3],
        channels: &'static [Channel],
        generation: u64,
    ) -> LightMaps<'a> {
        LightMaps {
            size,
            view_proj,
            textures: textures.map(|t| &t.view),
            raw: textures.map(|t| &t.texture),
            channels,
            generation,
            tags: [FrameTag::NONE; 3],
        }
    }

    /// The same maps, whose textures carry frame tags (the D-buffer's volume channels).
    pub fn tagged(self, tags: [FrameTag; 3]) -> LightMaps<'a> {
        LightMaps { tags, ..self }
    }

    /// The maps of one texture whose components are all the channels.
    pub fn single(
        size: u32,
        view_proj: Mat4,
        texture: &'a Texture,
        channels: &'static [Channel],
        generation: u64,
    ) -> LightMaps<'a> {
        LightMaps::new(size, view_proj, [texture; 3], channels, generation)
    }
}

/// One channel of [`LightMaps`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Channel {
    pub name: &'static str,
    /// Which of the (up to) three textures.
    pub texture: u32,
    /// Which component (0 = R … 3 = A).
    pub component: u32,
    /// How "nothing here" is stored: values at or above it (a distance for no surface), or zero
    /// and below (no volume crossing), read as "no data".
    pub empty: Empty,
    /// Where this one has no data: the value of another `(texture, component)` instead.
    pub or: Option<(u32, u32)>,
}

impl Channel {
    /// Component `component` of texture `texture`, named `name`, marking "nothing here" as
    /// `empty`.
    pub const fn new(name: &'static str, texture: u32, component: u32, empty: Empty) -> Channel {
        Channel {
            name,
            texture,
            component,
            empty,
            or: None,
        }
    }

    /// The same, with the value of `(texture, component)` where this one has no data.
    pub const fn or(self, texture: u32, component: u32) -> Channel {
        Channel {
            or: Some((texture, component)),
            ..self
        }
    }

    /// Whether `v` is data (not the "nothing here" mark).
    pub fn has_value(&self, v: f32) -> bool {
        match self.empty {
            Empty::Far => v < 1.5e38,
            Empty::NonPositive => v > 0.0 && v < 1.5e38,
        }
    }

    /// The channel's value in a texel given as the three textures' RGBA, `None` where it has
    /// none (the GPU twin is `channel_at` in `shaders/shared/view_inputs.wgsl`).
    pub fn value(&self, texel: &[[f32; 4]; 3]) -> Option<f32> {
        let at = |t: u32, c: u32| texel[(t as usize).min(2)][(c as usize).min(3)];
        let v = at(self.texture, self.component);
        if self.has_value(v) {
            return Some(v);
        }
        let (t, c) = self.or?;
        let w = at(t, c);
        self.has_value(w).then_some(w)
    }
}

/// How a light-map channel marks texels without data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Empty {
    /// Values ≥ 1.5e38 (the "no surface" distance).
    Far,
    /// Values ≤ 0 (no volume crossing).
    NonPositive,
}

/// Light-space maps read back: per texture slot its components per texel and its values
/// (row-major, `size`²); slots that name the same texture share one copy.
#[derive(Clone, Debug)]
pub struct LightMapsData {
    pub size: u32,
    pub channels: &'static [Channel],
    /// The rows held: all of them, or a band ([`read_light_map_rows`](super::frame::read_light_map_rows)).
    pub rows: std::ops::Range<u32>,
    slots: [usize; 3],
    data: Vec<(usize, Vec<f32>)>,
}

impl LightMapsData {
    /// The maps' texels as read back (`values` per distinct texture, which `slots` maps the
    /// three slots to), frame tags taken off: what untagged textures would hold.
    pub(crate) fn read(
        maps: &LightMaps<'_>,
        rows: std::ops::Range<u32>,
        slots: [usize; 3],
        distinct: &[&wgpu::Texture],
        values: Vec<Vec<f32>>,
    ) -> LightMapsData {
        let data = distinct
            .iter()
            .zip(values)
            .enumerate()
            .map(|(k, (t, mut v))| {
                let n = components(t.format());
                let tag = slots
                    .iter()
                    .zip(maps.tags)
                    .find_map(|(s, tag)| (*s == k).then_some(tag));
                tag.unwrap_or(FrameTag::NONE).untag_all(&mut v, n);
                (n, v)
            })
            .collect();
        LightMapsData {
            size: maps.size,
            channels: maps.channels,
            rows,
            slots,
            data,
        }
    }

    /// The three textures' RGBA at texel (`x`, `y`) (missing components 0).
    pub fn texel(&self, x: u32, y: u32) -> Option<[[f32; 4]; 3]> {
        if x >= self.size || !self.rows.contains(&y) {
            return None;
        }
        let i = ((y - self.rows.start) * self.size + x) as usize;
        // As textureLoad reads a texture with fewer channels: missing G and B are 0, A is 1.
        let mut out = [[0.0, 0.0, 0.0, 1.0f32]; 3];
        for (slot, &d) in out.iter_mut().zip(&self.slots) {
            let (n, values) = self.data.get(d)?;
            for (c, v) in slot.iter_mut().take(*n).enumerate() {
                *v = *values.get(i * n + c)?;
            }
        }
        Some(out)
    }

    /// Channel `c` at texel (`x`, `y`); `None` where it has no data.
    pub fn channel(&self, c: usize, x: u32, y: u32) -> Option<f32> {
        self.channels.get(c)?.value(&self.texel(x, y)?)
    }

    /// Component `component` of texture slot `slot` over every texel held, as stored.
    pub fn raw(&self, slot: usize, component: usize) -> Vec<f32> {
        let Some((n, values)) = self.slots.get(slot).and_then(|&d| self.data.get(d)) else {
            return Vec::new();
        };
        if component >= *n {
            return vec![0.0; values.len() / (*n).max(1)];
        }
        values.iter().skip(component).step_by(*n).copied().collect()
    }
}

/// Components per texel of the light-map formats.
pub(crate) fn components(format: wgpu::TextureFormat) -> usize {
    match format {
        wgpu::TextureFormat::Rg32Float => 2,
        wgpu::TextureFormat::Rgba32Float => 4,
        _ => 1,
    }
}
