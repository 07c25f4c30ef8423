//! What the lab remembers between runs (eframe persistence): the method, V(t), view, display
//! mappings, overlays and recent files. The scene itself is not restored: `dbuffer` opens the
//! default scene, `dbuffer gui SCENE` the one named.

use crate::render::truth;
use serde::{Deserialize, Serialize};

use crate::geometry::VtVariant;
use crate::render::passes::view::{Mapping, View};
use crate::render::{Knobs, Method};

/// The scene `dbuffer` opens with no arguments.
pub const DEFAULT_SCENE: &str = "fig7-concave";

/// [`Settings::reference_engine`] leaving the choice to the adapter.
pub const AUTO_ENGINE: &str = "auto";

/// How many recent files the File menu keeps.
pub const MAX_RECENT: usize = 8;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Method name (kept as text so a renamed method does not lose the other settings).
    pub method: String,
    /// The right-hand method of the split view.
    pub split_method: String,
    pub split: bool,
    /// Where the split divider is, 0..1 of the viewport width.
    pub split_at: f32,
    pub vt: String,
    pub view: View,
    /// Channel isolation of the D-buffer view: `|cx_o|`, `|cx_uv|`, `|cx_pv|`, `|cx_s|`.
    pub channels: [bool; 4],
    pub v_map: Mapping,
    pub t_map: Mapping,
    pub error_map: Mapping,
    pub dbuffer_map: Mapping,
    /// The cost view's range (auto-fitted by default: each method counts its own unit).
    pub cost_map: Mapping,
    /// The FLIP view's range: FLIP's own 0 … 1.
    pub flip_map: Mapping,
    pub overlays: Overlays,
    /// D-buffer (and shadow map) size in texels.
    pub dbuffer_size: u32,
    /// Render at this fraction of the viewport's physical pixels (speed on slow adapters).
    pub render_scale: f32,
    /// Reference samples per pixel (K).
    pub reference_samples: u32,
    /// Where the reference's rays are traced: `auto` (the GPU where the adapter can, else the
    /// CPU's threads), `gpu` or `cpu`; anything else reads as `auto`.
    pub reference_engine: String,
    /// The methods' knobs the user set (the others keep their defaults), saved as the
    /// `(name, value)` pairs they always were.
    pub knobs: Knobs,
    pub recent: Vec<String>,
}

/// Overlays drawn over the viewport, each toggled on its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct Overlays {
    pub classes: bool,
    pub umbra_volume: bool,
    pub penumbra_volume: bool,
    pub silhouettes: bool,
    /// The light drawn as its shape: a disk, a rectangle, a polygon or a segment (settings
    /// saved before the rectangle and polygon lights call it `light_disk`).
    #[serde(alias = "light_disk")]
    pub light_outline: bool,
}

impl Default for Overlays {
    fn default() -> Self {
        Self {
            classes: false,
            umbra_volume: false,
            penumbra_volume: false,
            silhouettes: false,
            light_outline: true,
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            method: Method::DBUFFER.name().into(),
            split_method: truth::SOFT.name().into(),
            split: false,
            split_at: 0.5,
            vt: VtVariant::Smoothstep.name().into(),
            view: View::Final,
            channels: [true, false, false, false],
            v_map: Mapping::unit(),
            t_map: Mapping::unit(),
            error_map: Mapping::error(),
            dbuffer_map: Mapping::auto(),
            cost_map: Mapping::auto(),
            flip_map: Mapping {
                black: 0.0,
                white: 1.0,
                map: crate::render::passes::view::ColorMap::Heat,
                auto: false,
            },
            overlays: Overlays::default(),
            dbuffer_size: 1024,
            render_scale: 1.0,
            reference_samples: 256,
            reference_engine: AUTO_ENGINE.into(),
            knobs: Knobs::default(),
            recent: Vec::new(),
        }
    }
}

impl Settings {
    /// The method, falling back to the D-buffer for a name this build does not know.
    pub fn method(&self) -> Method {
        self.method.parse().unwrap_or_default()
    }

    pub fn split_method(&self) -> Method {
        self.split_method.parse().unwrap_or(truth::SOFT)
    }

    /// The reference engine asked for (`None`: the GPU where the adapter can, else the CPU).
    pub fn reference_engine(&self) -> Option<truth::Engine> {
        self.reference_engine.parse().ok()
    }

    /// Whether the reference is one of the methods on screen (either side of a split).
    pub fn shows_reference(&self) -> bool {
        truth::is_soft(self.method()) || (self.split && truth::is_soft(self.split_method()))
    }

    /// Whether what is shown needs the reference: it is a shown method, or the error view
    /// measures against it. Only then does it converge (and the status bar show its progress).
    pub fn needs_reference(&self) -> bool {
        self.shows_reference() || self.view == View::Error || self.view == View::Flip
    }

    pub fn vt(&self) -> VtVariant {
        self.vt.parse().unwrap_or(VtVariant::Smoothstep)
    }

    /// The display mapping of a scalar view (V, t, error, D-buffer); `None` for the others.
    pub fn mapping(&self, view: View) -> Option<&Mapping> {
        match view {
            View::Visibility => Some(&self.v_map),
            View::T => Some(&self.t_map),
            View::Error => Some(&self.error_map),
            View::DBuffer => Some(&self.dbuffer_map),
            View::Cost => Some(&self.cost_map),
            View::Flip => Some(&self.flip_map),
            View::Final | View::Classes | View::Range => None,
        }
    }

    pub fn mapping_mut(&mut self, view: View) -> Option<&mut Mapping> {
        match view {
            View::Visibility => Some(&mut self.v_map),
            View::T => Some(&mut self.t_map),
            View::Error => Some(&mut self.error_map),
            View::DBuffer => Some(&mut self.dbuffer_map),
            View::Cost => Some(&mut self.cost_map),
            View::Flip => Some(&mut self.flip_map),
            View::Final | View::Classes | View::Range => None,
        }
    }

    /// Put `entry` first in the recent files, without duplicates.
    pub fn push_recent(&mut self, entry: &str) {
        self.recent.retain(|r| r != entry);
        self.recent.insert(0, entry.to_string());
        self.recent.truncate(MAX_RECENT);
    }

    /// Values a hand-edited or old settings file may have put out of range, brought back in.
    pub fn sanitize(&mut self) {
        self.dbuffer_size = self.dbuffer_size.clamp(64, 4096);
        if !(self.render_scale.is_finite() && (0.1..=2.0).contains(&self.render_scale)) {
            self.render_scale = 1.0;
        }
        if !(self.split_at.is_finite() && (0.0..=1.0).contains(&self.split_at)) {
            self.split_at = 0.5;
        }
        self.reference_samples = self
            .reference_samples
            .clamp(1, crate::render::methods::reference::MAX_SAMPLES);
        // Knobs this build does not know were dropped as the file loaded; out of range, here.
        self.knobs.drop_invalid();
        self.recent.truncate(MAX_RECENT);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recent_files_are_unique_most_recent_first_and_capped() {
        let mut s = Settings::default();
        for i in 0..12 {
            s.push_recent(&format!("scene{i}.toml"));
        }
        s.push_recent("scene5.toml");
        assert_eq!(s.recent.len(), MAX_RECENT);
        assert_eq!(s.recent[0], "scene5.toml");
        assert_eq!(s.recent.iter().filter(|r| *r == "scene5.toml").count(), 1);
    }

    #[test]
    fn unknown_names_and_bad_numbers_fall_back() {
        let mut s = Settings {
            method: "no-such-method".into(),
            vt: "cubic".into(),
            render_scale: f32::NAN,
            dbuffer_size: 0,
            ..Settings::default()
        };
        s.sanitize();
        assert_eq!(s.method(), Method::DBUFFER);
        assert_eq!(s.vt(), VtVariant::Smoothstep);
        assert_eq!(s.render_scale, 1.0);
        assert_eq!(s.dbuffer_size, 64);
    }

    #[test]
    fn the_reference_engine_is_auto_unless_named() {
        assert_eq!(Settings::default().reference_engine(), None);
        let named = |e: &str| Settings {
            reference_engine: e.into(),
            ..Settings::default()
        };
        assert_eq!(named("gpu").reference_engine(), Some(truth::Engine::Gpu));
        assert_eq!(named("cpu").reference_engine(), Some(truth::Engine::Cpu));
        assert_eq!(named("rtx").reference_engine(), None);
        // Settings saved before the choice existed load with it on auto.
        let s: Settings = serde_json::from_str(r#"{"reference_samples": 64}"#).unwrap();
        assert_eq!(s.reference_engine, AUTO_ENGINE);
    }

    #[test]
    fn the_light_overlay_of_older_settings_keeps_its_state() {
        // Saved before the overlay was renamed from the disk to any light's outline.
        let text = r#"{"overlays": {"light_disk": false, "classes": true}}"#;
        let s: Settings = serde_json::from_str(text).unwrap();
        assert!(!s.overlays.light_outline && s.overlays.classes);
        let saved = serde_json::to_value(&s).unwrap();
        assert_eq!(saved["overlays"]["light_outline"], serde_json::json!(false));
    }

    #[test]
    fn saved_knobs_load_as_they_were_written() {
        // The pairs an older build saved (and this one saves): unknown names and values out of
        // range are dropped, the others kept.
        let text = r#"{"knobs": [["pcf-radius", 4], ["gone-knob", 1], ["sv-open", 9]]}"#;
        let mut s: Settings = serde_json::from_str(text).unwrap();
        s.sanitize();
        let pcf = &crate::render::methods::pcf::RADIUS;
        assert_eq!(s.knobs.get(pcf), 4);
        assert_eq!(s.knobs.set_ones().count(), 1);
        let saved = serde_json::to_value(&s).unwrap();
        assert_eq!(saved["knobs"], serde_json::json!([["pcf-radius", 4]]));
    }
}
