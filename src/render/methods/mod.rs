//! The shadow methods. Each is one module here with its passes, its WGSL
//! (`shaders/methods/NAME.wgsl`: the method's `method_visibility`, pasted into the shared camera
//! pass), its knobs and its CPU twin where it has one. [`ALL`] is the registry: adding a method is
//! its module (with its WGSL and snapshot) and one line in the `registry!` that makes [`ALL`]. Everything
//! the rest of the program knows about a method — its shader, knobs, bench label, overlay note,
//! light sample points — is in its [`MethodSpec`], so nothing else matches on its name (the
//! shader table is built from `shaders/` by `build.rs`; `tests/cli/registry.rs` walks [`ALL`]).
//!
//! A method's per-scene GPU state is a [`MethodState`]: it brings its light-space products
//! (D-buffer, shadow maps) up to date only when the light or a caster moved, and hands the
//! camera pass its pipeline and bind group, a [`CameraGroup`] (made again only when what it
//! binds was). What every method shares — the surfaces, shading, V(t), the targets — is the
//! camera pass's ([`super::passes::camera`]).

pub mod shadow_mapped;

mod knobs;
pub use knobs::{all_knobs, Choice, Knob, KnobKind, KnobType, Knobs, Scaled, Switch, MAX_KNOBS};
mod sweep;
pub use sweep::{Quality, Sweep, MAP_SIZES, MAP_SIZE_NAME};

mod camera_group;
mod dbuffer_light;
pub use camera_group::{v_texture_entries, CameraGroup, MethodPipeline};
mod inputs;
pub use inputs::{External, FrameInputs, Prepare};
mod needs;
mod screen_volumes;
pub use needs::{AdapterNeeds, MAP_AND_SCREEN, SHADOW_MAP, SHADOW_MAPPED, STENCIL_VOLUMES};
mod spec;
pub use spec::{Bench, Cost, MakeState, MethodSpec, SCREEN_COST};
mod state;
pub use state::{MethodState, SharedMaps};
pub mod user;

// The vocabulary the passes share with the methods lives below both; the method modules name it
// through here.
pub use super::light_maps::{Channel, Empty, LightMaps};
pub use super::passes::camera::CameraBindings;
pub use super::require;

use std::fmt;
use std::str::FromStr;

use super::adapter::{Capabilities, Verdict};
use crate::scene::LightKind;

/// Declares each method module and [`ALL`] from one line a module: `module: ITS_SPECS;`.
macro_rules! registry {
    ($($(#[$doc:meta])* $module:ident: $($spec:ident),+;)+) => {
        $($(#[$doc])* pub mod $module;)+

        /// Every method, in the order pickers, `compare` and `bench` list them.
        pub const ALL: &[Method] = &[$($(Method(&$module::$spec)),+),+];
    };
}

// The registry: adding a method is its module and one line here.
registry! {
    dbuffer: DBUFFER, DBUFFER_CENTER;
    dbuffer_fused: DBUFFER_FUSED;
    hard: HARD;
    pcf: PCF;
    pcss: PCSS;
    smrt: SMRT;
    vsm: VSM;
    msm: MSM;
    msm_soft: MSM_SOFT;
    bitmask: BITMASK;
    sampled: SAMPLED;
    linear_ssm: LINEAR_SSM;
    shadow_volume: SHADOW_VOLUME;
    planar: PLANAR;
    hybrid: HYBRID;
    extended_light_map: EXTENDED_LIGHT_MAP;
    wedges: WEDGES;
    raytraced: RAYTRACED;
    reference: REFERENCE;
    reference_hard: REFERENCE_HARD;
}

/// A method of [`ALL`].
#[derive(Clone, Copy)]
pub struct Method(&'static MethodSpec);

impl Method {
    /// The paper's method, the default.
    pub const DBUFFER: Method = Method(&dbuffer::DBUFFER);
    /// The D-buffer with silhouettes from the light centre.
    pub const DBUFFER_CENTER: Method = Method(&dbuffer::DBUFFER_CENTER);
    /// The D-buffer with every silhouette chord a receiver needs, where occluders fuse.
    pub const DBUFFER_FUSED: Method = Method(&dbuffer_fused::DBUFFER_FUSED);
    /// The hard shadow map, the baseline of the benchmarks.
    pub const HARD: Method = Method(&hard::HARD);
    /// The ray-cast ground truth.
    pub const REFERENCE: Method = Method(&reference::REFERENCE);
    /// The exact hard shadow: one ray per pixel to the light centre.
    pub const REFERENCE_HARD: Method = Method(&reference_hard::REFERENCE_HARD);

    pub fn all() -> &'static [Method] {
        ALL
    }

    /// The registry's method made from `spec` (`None` for a spec [`ALL`] does not list).
    pub fn of(spec: &'static MethodSpec) -> Option<Method> {
        ALL.iter().copied().find(|m| std::ptr::eq(m.0, spec))
    }

    pub fn spec(self) -> &'static MethodSpec {
        self.0
    }

    pub fn name(self) -> &'static str {
        self.0.name
    }

    pub fn description(self) -> &'static str {
        self.0.description
    }

    pub fn knobs(self) -> &'static [&'static Knob] {
        self.0.knobs
    }

    /// What `dbuffer study` sweeps for it.
    pub fn sweep(self) -> &'static Sweep {
        &self.0.sweep
    }

    /// Whether V is computed on the CPU (the reference).
    pub fn cpu_side(self) -> bool {
        self.0.cpu_side
    }

    pub fn is_reference(self) -> bool {
        self == Method::REFERENCE
    }

    /// Whether it makes a hard shadow from the light's centre (scored against `reference-hard`).
    pub fn is_hard(self) -> bool {
        self.0.hard
    }

    /// The kinds of light the method takes, if not every kind (docs/method/README.md).
    pub fn needs(self) -> Option<&'static [LightKind]> {
        self.0.lights
    }

    /// The method a `light` light gets when none is named: the first of the registry made for
    /// some kinds only that takes it (the D-buffer for a disk, rectangle or polygon,
    /// `linear-ssm` for a line).
    pub fn made_for(light: LightKind) -> Method {
        ALL.iter()
            .copied()
            .find(|m| m.needs().is_some_and(|k| k.contains(&light)))
            .or_else(|| ALL.iter().copied().find(|m| m.takes(light)))
            .unwrap_or(Method::HARD)
    }

    /// Whether the method can render with a `light` light.
    pub fn takes(self, light: LightKind) -> bool {
        self.needs().is_none_or(|k| k.contains(&light))
    }

    /// The kinds it takes in words: "a disk, rect or polygon light", "any light".
    pub fn takes_in_words(self) -> String {
        match self.needs() {
            None => "any light".into(),
            Some(kinds) => format!("a {} light", LightKind::list_in_words(kinds)),
        }
    }

    /// `None` when the method can render with a `light` light; else the one-line reason it
    /// refuses, naming the method, both kinds and the methods that take this one. `render`
    /// exits with it, `compare` and `bench` list the method as not applicable, the lab greys
    /// its picker entry: a disk-only method never draws a line light's scene as something else.
    pub fn refuses(self, light: LightKind) -> Option<String> {
        if self.takes(light) {
            return None;
        }
        let needs = self.takes_in_words();
        let this = match light {
            LightKind::Disk => "a disk".to_string(),
            other => format!("a {other} (kind = \"{other}\")"),
        };
        let others: Vec<&str> = ALL
            .iter()
            .filter(|m| m.takes(light))
            .map(|m| m.name())
            .collect();
        Some(format!(
            "method '{self}' needs {needs}, and this scene's light is {this}; \
             for a {light} light use {}",
            others.join(", ")
        ))
    }
}

/// The planar lights: a method that takes a disk, a rectangle and a polygon alike.
pub const AREA_LIGHTS: &[LightKind] = &[LightKind::Disk, LightKind::Rect, LightKind::Polygon];

/// A method made for the disk alone (its closed forms are the disk's).
pub const DISK_ONLY: &[LightKind] = &[LightKind::Disk];

impl Method {
    /// What the method gets on a device with `caps` (its needs and [`AdapterNeeds::BASE`]).
    pub fn on(self, caps: &Capabilities) -> Verdict {
        self.0.adapter.check(caps)
    }

    /// Why the method cannot draw here — a light it does not take ([`Method::refuses`]), else a
    /// device without what it needs ([`Method::refuses_on`], when the device is known) — or
    /// `None`: what the session and the lab check before every frame.
    pub fn refusal(self, light: LightKind, caps: Option<&Capabilities>) -> Option<String> {
        self.refuses(light)
            .or_else(|| caps.and_then(|c| self.refuses_on(c)))
    }

    /// `None` when the method can run on a device with `caps`; else the one-line reason it
    /// refuses, naming the method, what is missing and the adapter. Checked before any work,
    /// beside [`Method::refuses`]: `render` exits with it, `compare` and `bench` list the method
    /// as not applicable, the lab greys its picker entry.
    pub fn refuses_on(self, caps: &Capabilities) -> Option<String> {
        match self.on(caps) {
            Verdict::Cannot(missing) => Some(format!(
                "method '{self}' needs {}, which the adapter {} does not have; try another \
                 adapter with --backend (see `dbuffer adapters`)",
                missing.join(", "),
                caps.adapter
            )),
            _ => None,
        }
    }
}

impl Default for Method {
    fn default() -> Self {
        Method::DBUFFER
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Self) -> bool {
        self.0.name == other.0.name
    }
}

impl Eq for Method {}

impl std::hash::Hash for Method {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.0.name.hash(state);
    }
}

impl fmt::Debug for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Method({})", self.0.name)
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.0.name)
    }
}

impl Method {
    /// `s` as `--method` takes it: a method of [`ALL`] by name, or a user's file
    /// (`file:PATH.wgsl`, [`user::load`]) with its knobs set by `user_knobs` (`NAME=VALUE`).
    pub fn parse_with(s: &str, user_knobs: &[String]) -> Result<Method, String> {
        match user::path_of(s) {
            Some(path) => user::load(path, user_knobs),
            None => s.parse(),
        }
    }

    /// Whether it is a user's method (`file:PATH.wgsl`), made at run time.
    pub fn is_user(self) -> bool {
        self.0.user.is_some()
    }

    /// Its place in reports and plots: its index in [`ALL`]; a user's method comes after all
    /// of them.
    pub fn order(self) -> usize {
        ALL.iter().position(|&m| m == self).unwrap_or(ALL.len())
    }

    /// A user's method's file, as given; `None` for the registry's.
    pub fn user_path(self) -> Option<&'static str> {
        user::of(self).map(|u| u.path.as_str())
    }

    /// A user's method's expanded shader and knob values (what decides its images beyond its
    /// name, for caches keyed by the method); `None` for the registry's.
    pub fn user_shader(self) -> Option<(String, [f32; user::MAX_USER_KNOBS])> {
        user::of(self).map(|u| (u.source(), u.values()))
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if let Some(path) = user::path_of(s) {
            return user::load(path, &[]);
        }
        if let Some(m) = user::by_name(s) {
            return Ok(m);
        }
        ALL.iter().copied().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<&str> = ALL.iter().map(|m| m.name()).collect();
            format!(
                "unknown method '{s}': expected one of {}, or file:PATH.wgsl",
                names.join(", ")
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_parse_back() {
        for (i, m) in ALL.iter().enumerate() {
            assert_eq!(m.name().parse::<Method>(), Ok(*m));
            assert!(ALL[..i].iter().all(|o| o.name() != m.name()), "{m} twice");
        }
        assert!("nope".parse::<Method>().unwrap_err().contains("dbuffer, "));
    }
}
