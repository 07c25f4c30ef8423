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

pub mod on_shadow_map;

mod knobs;
pub use knobs::{all_knobs, Choice, Knob, KnobKind, KnobType, Knobs, Scaled, Switch, MAX_KNOBS};
mod sweep;
pub use sweep::{Quality, Sweep, MAP_SIZES, MAP_SIZE_NAME};

use std::any::Any;
use std::cell::OnceCell;
use std::fmt;
use std::str::FromStr;
use std::sync::{Arc, OnceLock};

use glam::{Mat4, Vec3};

use super::adapter::{Capabilities, FormatNeed, Usage, Verdict};
use super::frame_tag::FrameTag;
use super::gpu_scene::GpuScene;
use super::passes::camera::ScreenView;
use super::passes::shadow_map::ShadowMap;
use super::timer::Recorder;
use super::{GpuContext, RenderError};
use crate::geometry::light_view::LightView;
use crate::geometry::{PreparedCasters, SceneGeometry, VtVariant};
use crate::scene::{AreaLight, LightKind, LineLight, Scene};

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
    reference: REFERENCE;
    reference_hard: REFERENCE_HARD;
}

/// What a method is, for the registry: everything the rest of the program needs to know about
/// it, so that nothing outside its module matches on its name.
pub struct MethodSpec {
    /// The command-line name (`--method`, pickers, `report.json`).
    pub name: &'static str,
    /// One line for menus and `--help`.
    pub description: &'static str,
    /// Its camera shader under `shaders/` (`methods/NAME.wgsl`: its `method_visibility`).
    pub shader: &'static str,
    /// Its knobs (command-line flags, lab controls); a [`Switch`], [`Choice`] or [`Scaled`] is
    /// listed by the [`Knob`] it wraps (`&OPEN.0`).
    pub knobs: &'static [&'static Knob],
    /// V is computed on the CPU (the ray-cast reference): only wall time measures it.
    pub cpu_side: bool,
    /// A hard shadow from the light's centre as a point light: `compare` scores it against
    /// `reference-hard` too.
    pub hard: bool,
    /// The kinds of light it takes, if not every kind (docs/method/README.md).
    pub lights: Option<&'static [LightKind]>,
    /// What it needs of the adapter beyond what every method needs.
    pub adapter: AdapterNeeds,
    /// How `dbuffer bench` times it.
    pub bench: Bench,
    /// What the lab's volume and silhouette overlays mean under it, one line for the overlay
    /// notes; `None` for the D-buffer's own meaning.
    pub overlay_note: Option<&'static str>,
    /// The points on a line light it samples (its shadow maps' origins), which the lab draws on
    /// the segment; `None` for a method that samples none.
    pub line_samples: Option<fn(&LineLight, &Knobs) -> Vec<Vec3>>,
    /// What its cost view counts (`count_work`, `took_path` in its WGSL).
    pub cost: Cost,
    /// What `dbuffer study` sweeps: its quality knobs and the default study's settings, or why
    /// it has none ([`Sweep`]).
    pub sweep: Sweep,
    /// Its per-scene GPU state.
    pub new: fn(&GpuContext) -> Box<dyn MethodState>,
}

/// What a method's cost view shows: the work its camera shader counted at each pixel with
/// `count_work(n)` and the path it took with `took_path(code)` (`shaders/shared/camera.wgsl`,
/// written to the camera pass's cost target). A method adds its counting in its own WGSL; this
/// only names what it counts for the lab's legend, the inspector and `compare`'s heatmaps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cost {
    /// The unit of `count_work`: "shadow-map taps", "listed edges", …
    pub unit: &'static str,
    /// The names of the paths by `took_path` code (0 first); empty for a method with one path.
    pub paths: &'static [&'static str],
    /// `Some(why)`: the same work at every pixel it shades, and why (what its view then says).
    pub constant: Option<&'static str>,
}

impl Cost {
    /// A method that names nothing: its counts in plain units.
    pub const DEFAULT: Cost = Cost {
        unit: "units of work",
        paths: &[],
        constant: None,
    };

    /// Work counted in `unit`, by a method with one path.
    pub const fn counted(unit: &'static str) -> Cost {
        Cost {
            unit,
            paths: &[],
            constant: None,
        }
    }

    /// The same work at every pixel it shades, for the reason `why`.
    pub const fn constant(mut self, why: &'static str) -> Cost {
        self.constant = Some(why);
        self
    }

    /// The names of its paths by code.
    pub const fn paths(mut self, paths: &'static [&'static str]) -> Cost {
        self.paths = paths;
        self
    }

    /// The name of path `code` ("path N" for a code it does not name).
    pub fn path_name(&self, code: f32) -> String {
        let k = code.round();
        if k >= 0.0 && (k as usize) < self.paths.len() {
            self.paths[k as usize].to_string()
        } else {
            format!("path {k}")
        }
    }
}

impl MethodSpec {
    /// The method `name` with its camera `shader` and per-scene state `new`: no knobs, every
    /// kind of light, a soft shadow computed on the GPU, timed by the bench under its name. The
    /// calls below say where a method differs, so a spec reads as what is particular to it.
    pub const fn new(
        name: &'static str,
        shader: &'static str,
        new: fn(&GpuContext) -> Box<dyn MethodState>,
    ) -> MethodSpec {
        MethodSpec {
            name,
            description: "",
            shader,
            knobs: &[],
            cpu_side: false,
            hard: false,
            lights: None,
            adapter: AdapterNeeds::NONE,
            bench: Bench::DEFAULTS,
            overlay_note: None,
            line_samples: None,
            cost: Cost::DEFAULT,
            sweep: Sweep::UNSTATED,
            new,
        }
    }

    /// `dbuffer study` sweeps its quality `axes` over `settings` (a value per axis each,
    /// cheapest first).
    pub const fn sweep(
        mut self,
        axes: &'static [Quality],
        settings: &'static [&'static [u32]],
    ) -> Self {
        self.sweep = Sweep::over(axes, settings);
        self
    }

    /// It has no setting that trades cost for quality, for the reason `why`: `dbuffer study`
    /// measures its defaults alone.
    pub const fn fixed_quality(mut self, why: &'static str) -> Self {
        self.sweep = Sweep::fixed(why);
        self
    }

    /// What its cost view counts ([`Cost`]).
    pub const fn cost(mut self, cost: Cost) -> Self {
        self.cost = cost;
        self
    }

    /// Its one line for menus and `--help`.
    pub const fn about(mut self, description: &'static str) -> Self {
        self.description = description;
        self
    }

    pub const fn knobs(mut self, knobs: &'static [&'static Knob]) -> Self {
        self.knobs = knobs;
        self
    }

    /// V comes from the CPU (the ray-cast references).
    pub const fn cpu_side(mut self) -> Self {
        self.cpu_side = true;
        self
    }

    /// A hard shadow from the light's centre (scored against `reference-hard` too).
    pub const fn hard(mut self) -> Self {
        self.hard = true;
        self
    }

    /// It takes these kinds of light only (the first is the one the bench converts to).
    pub const fn lights(mut self, kinds: &'static [LightKind]) -> Self {
        self.lights = Some(kinds);
        self
    }

    /// What it needs of the adapter beyond the camera pass's (an entry of [`needs`]).
    pub const fn adapter(mut self, needs: AdapterNeeds) -> Self {
        self.adapter = needs;
        self
    }

    /// The bench times it under `label` with `knobs` set.
    pub const fn bench(
        mut self,
        label: &'static str,
        knobs: &'static [(&'static Knob, u32)],
    ) -> Self {
        self.bench = Bench {
            label: Some(label),
            knobs,
        };
        self
    }

    pub const fn overlay_note(mut self, note: &'static str) -> Self {
        self.overlay_note = Some(note);
        self
    }

    pub const fn line_samples(mut self, points: fn(&LineLight, &Knobs) -> Vec<Vec3>) -> Self {
        self.line_samples = Some(points);
        self
    }
}

/// The cost view of the methods whose V was made over the screen before the camera pass
/// (`shadow-volume`, `planar`, `hybrid`): the camera pass reads one texel of it.
pub const SCREEN_COST: Cost = Cost::counted("screen texels read").constant(
    "one texel of the V its screen passes made; their work is the volumes' fill before the \
     camera pass (bench's stencil fill)",
);

/// What a method needs of the adapter beyond what every method needs ([`AdapterNeeds::BASE`],
/// the camera pass's), checked before any work ([`Method::on`]): a device without it refuses the
/// method in one line instead of failing in one of its pipelines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdapterNeeds {
    /// Optional features it cannot do without.
    pub features: wgpu::Features,
    /// The formats it renders to, blends into, filters or binds as storage (each with its
    /// fallback, if it has one).
    pub formats: &'static [FormatNeed],
    /// Downlevel capabilities it uses (compute shaders, storage written from fragment shaders,
    /// storage read in vertex shaders).
    pub downlevel: wgpu::DownlevelFlags,
    /// Storage buffers one of its shader stages binds at most.
    pub storage_buffers_per_stage: u32,
    /// Storage textures one of its shader stages binds at most.
    pub storage_textures_per_stage: u32,
}

impl Default for AdapterNeeds {
    fn default() -> Self {
        AdapterNeeds::NONE
    }
}

/// The centre shadow map (`passes::shadow_map`): distances in `R32Float`, a `Depth32Float` test.
pub const SHADOW_MAP: [FormatNeed; 2] = [
    FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::R32Float]),
    FormatNeed::new(Usage::Depth, &[wgpu::TextureFormat::Depth32Float]),
];

/// What a method drawn with the centre shadow map alone needs: `hard`, `pcf`, `pcss`, `sampled`
/// and the D-buffer's `|cx_o|` (a method whose needs are its own states them in its module, a
/// `const NEEDS`; `reference` and `reference-hard` draw V from the CPU with the camera pass and
/// need only [`AdapterNeeds::BASE`]).
pub const SHADOW_MAPPED: AdapterNeeds = AdapterNeeds::formats(&SHADOW_MAP);

/// The stencil shadow volumes (`passes::stencil_volumes`): positions and visibility as floats, a
/// half-float fill count, and a stencil (with 24-bit depth where 32-bit float depth with stencil
/// is missing: the volumes' depth test is coarser, and `tests/gpu/hard_methods.rs` holds
/// `shadow-volume` on it to at most 0.05 % of pixels off the exact hard shadow).
pub const STENCIL_VOLUMES: [FormatNeed; 4] = [
    FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::Rgba32Float]),
    FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::R32Float]),
    FormatNeed::new(Usage::Blend, &[wgpu::TextureFormat::R16Float]),
    FormatNeed {
        usage: Usage::Depth,
        formats: &[
            wgpu::TextureFormat::Depth32FloatStencil8,
            wgpu::TextureFormat::Depth24PlusStencil8,
        ],
        fallback: "24-bit depth under the stencil: at most 0.05 % of pixels change class",
    },
];

/// The centre's shadow map and the camera's prepass of the stencil methods (its positions):
/// `hybrid`'s walls read both, `smrt` its screen ray.
pub const MAP_AND_SCREEN: [FormatNeed; 6] = [
    SHADOW_MAP[0],
    SHADOW_MAP[1],
    STENCIL_VOLUMES[0],
    STENCIL_VOLUMES[1],
    STENCIL_VOLUMES[2],
    STENCIL_VOLUMES[3],
];

impl AdapterNeeds {
    /// Nothing beyond what every method needs.
    pub const NONE: AdapterNeeds = AdapterNeeds {
        features: wgpu::Features::empty(),
        formats: &[],
        downlevel: wgpu::DownlevelFlags::empty(),
        storage_buffers_per_stage: 0,
        storage_textures_per_stage: 0,
    };

    /// What every method needs: the camera pass's targets (V and the receiver distance as
    /// `Rg32Float`, the picture as `Rgba8UnormSrgb`, a `Depth32Float` test).
    pub const BASE: AdapterNeeds = AdapterNeeds {
        formats: &[
            FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::Rg32Float]),
            FormatNeed::new(Usage::Render, &[wgpu::TextureFormat::Rgba8UnormSrgb]),
            FormatNeed::new(Usage::Depth, &[wgpu::TextureFormat::Depth32Float]),
        ],
        ..AdapterNeeds::NONE
    };

    /// `formats` and nothing else.
    pub const fn formats(formats: &'static [FormatNeed]) -> AdapterNeeds {
        AdapterNeeds {
            formats,
            ..AdapterNeeds::NONE
        }
    }

    /// Whether an adapter with `features` has the features the method needs.
    pub fn met_by(&self, features: wgpu::Features) -> bool {
        features.contains(self.features)
    }

    /// What the method gets on `caps`: runs, runs with fallbacks, or what is missing.
    pub fn check(&self, caps: &Capabilities) -> Verdict {
        let mut missing = Vec::new();
        let mut fallbacks = Vec::new();
        let lacking = self.features - caps.features;
        if !lacking.is_empty() {
            missing.push(format!("the feature {lacking:?}"));
        }
        for need in AdapterNeeds::BASE.formats.iter().chain(self.formats) {
            match caps.pick(need) {
                None => {
                    let names: Vec<String> =
                        need.formats.iter().map(|f| format!("{f:?}")).collect();
                    let item = format!("{} {}", need.usage.verb(), names.join(" or "));
                    if !missing.contains(&item) {
                        missing.push(item);
                    }
                }
                Some(f) if Some(&f) != need.formats.first() => {
                    let item =
                        format!("{f:?} instead of {:?} ({})", need.formats[0], need.fallback);
                    if !fallbacks.contains(&item) {
                        fallbacks.push(item);
                    }
                }
                Some(_) => {}
            }
        }
        let flags = self.downlevel - caps.downlevel;
        if !flags.is_empty() {
            missing.push(format!("the downlevel capability {flags:?}"));
        }
        let l = &caps.limits;
        if self.storage_buffers_per_stage > l.max_storage_buffers_per_shader_stage {
            missing.push(format!(
                "{} storage buffers per shader stage (the device has {})",
                self.storage_buffers_per_stage, l.max_storage_buffers_per_shader_stage
            ));
        }
        if self.storage_textures_per_stage > l.max_storage_textures_per_shader_stage {
            missing.push(format!(
                "{} storage textures per shader stage (the device has {})",
                self.storage_textures_per_stage, l.max_storage_textures_per_shader_stage
            ));
        }
        if !missing.is_empty() {
            Verdict::Cannot(missing)
        } else if !fallbacks.is_empty() {
            Verdict::Fallback(fallbacks)
        } else {
            Verdict::Runs
        }
    }
}

/// How `dbuffer bench` times a method: the label of its rows and the knobs it sets.
pub struct Bench {
    /// The rows' label; `None`: the method's name.
    pub label: Option<&'static str>,
    /// Knobs set for the run (as their flags write them); the others keep their defaults.
    pub knobs: &'static [(&'static Knob, u32)],
}

impl Bench {
    /// Under its name, with the default knobs.
    pub const DEFAULTS: Bench = Bench {
        label: None,
        knobs: &[],
    };
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

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ALL.iter().copied().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<&str> = ALL.iter().map(|m| m.name()).collect();
            format!("unknown method '{s}': expected one of {}", names.join(", "))
        })
    }
}

/// What a method sees of the session while it records a frame.
pub struct FrameInputs<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a Scene,
    pub surfaces: &'a GpuScene,
    /// The casters welded with their adjacency, prepared on first use ([`FrameInputs::prepared`]).
    pub prepared: &'a OnceCell<PreparedCasters>,
    pub light_view: &'a LightView,
    /// Bumped whenever the light or a caster changed: light-space products made for an older
    /// revision are stale.
    pub revision: u64,
    /// The D-buffer and shadow maps are this many texels square.
    pub map_size: u32,
    pub vt: VtVariant,
    pub knobs: &'a Knobs,
    /// V per pixel handed in from outside (the ray-cast reference), if any.
    pub external: Option<External<'a>>,
    /// The camera of this frame and its image size (screen-space methods draw before the camera
    /// pass; a light-space method ignores it).
    pub view: ScreenView,
}

impl FrameInputs<'_> {
    /// The casters welded with their adjacency (built once per mesh, on first use: methods
    /// without volumes never pay for it).
    pub fn prepared(&self) -> &PreparedCasters {
        self.prepared
            .get_or_init(|| PreparedCasters::new(self.scene))
    }

    /// The scene's disk light, for a method that needs one; an error naming `method` for a
    /// line light (the session refuses such a frame before it gets here).
    pub fn area(&self, method: &str) -> Result<&AreaLight, RenderError> {
        self.scene.light.as_area().ok_or_else(|| {
            RenderError::Request(format!(
                "method '{method}' needs a planar light (disk, rect or polygon), and this \
                 scene's light is a line"
            ))
        })
    }
}

/// What [`MethodState::prepare`] works with: the frame's inputs, the light-space maps the
/// session shares between methods, and the frame's encoder (a method takes them apart with
/// `let Prepare(inputs, shared, rec) = p;`).
pub struct Prepare<'p, 'r>(
    pub &'p FrameInputs<'p>,
    pub &'p mut SharedMaps,
    pub &'p mut Recorder<'r>,
);

/// V per pixel handed in from outside, and a number that changes when its texture does.
#[derive(Clone, Copy)]
pub struct External<'a> {
    pub view: &'a wgpu::TextureView,
    pub generation: u64,
    /// The rays each pixel in front of the light has cast for it (the reference's samples so
    /// far; its cost view).
    pub rays: u32,
}

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
        textures: [&'a super::Texture; 3],
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
        texture: &'a super::Texture,
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

/// A method's camera pipelines (one per V(t) variant, made on first use) and the layout of its
/// group 1, built once per device.
pub struct MethodPipeline {
    shader: &'static str,
    module: wgpu::ShaderModule,
    pub layout: wgpu::BindGroupLayout,
    /// By V(t) variant, light shape (disk or line, rectangle or polygon) and targets (all, or
    /// the colour only: [`FrameRequest::colour_only`](crate::render::FrameRequest)): the
    /// pipeline, and for a method drawn in two draws ([`CameraGroup::two_draws`]) the second's.
    pipelines: [OnceLock<(wgpu::RenderPipeline, Option<wgpu::RenderPipeline>)>; 16],
    two_draws: bool,
    camera: Arc<super::passes::camera::CameraPass>,
}

impl MethodPipeline {
    /// The pipelines of `shader` (`methods/NAME.wgsl`) whose group 1 has `entries`, drawn in
    /// two draws or one (`two_draws`, the same for every user of `shader`).
    pub fn get(
        ctx: &GpuContext,
        shader: &'static str,
        entries: &[wgpu::BindGroupLayoutEntry],
        two_draws: bool,
    ) -> Arc<MethodPipeline> {
        ctx.shared_named(shader, |device| MethodPipeline {
            shader,
            module: super::shader_module(device, shader),
            layout: device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(shader),
                entries,
            }),
            pipelines: Default::default(),
            two_draws,
            camera: super::passes::camera::CameraPass::get(ctx),
        })
    }

    /// The pipeline for V(t) variant `vt` under a rectangle or polygon light (`polygon`) or
    /// not, writing the colour target only or every one, and the second draw's for a method
    /// drawn in two.
    pub fn pipeline(
        &self,
        device: &wgpu::Device,
        vt: VtVariant,
        polygon: bool,
        colour_only: bool,
    ) -> (&wgpu::RenderPipeline, Option<&wgpu::RenderPipeline>) {
        use super::passes::camera::Draw;
        let slot = &self.pipelines
            [4 * (vt.code() as usize).min(3) + 2 * usize::from(polygon) + usize::from(colour_only)];
        let (first, second) = slot.get_or_init(|| {
            let make = |draw| {
                self.camera.method_pipeline(
                    device,
                    self.shader,
                    &self.module,
                    &self.layout,
                    (vt, polygon, colour_only),
                    draw,
                )
            };
            if self.two_draws {
                (make(Draw::First), Some(make(Draw::Refine)))
            } else {
                (make(Draw::Only), None)
            }
        });
        (first, second.as_ref())
    }
}

/// The camera pass's view of a method: its pipeline (and a second draw's, for a method drawn in
/// two: [`CameraGroup::two_draws`]) and its bind group (group 1).
pub struct CameraBindings<'a> {
    pub pipeline: &'a wgpu::RenderPipeline,
    pub refine: Option<&'a wgpu::RenderPipeline>,
    pub bind_group: &'a wgpu::BindGroup,
    /// The pipelines write the colour target only.
    pub colour_only: bool,
}

/// What every method's camera pass is made of: its pipelines ([`MethodPipeline`], shared by
/// the device) and its bind group (group 1), made again only when what it binds was made again.
///
/// [`CameraGroup::bind`] takes the entries and a key that says what they are made of — the
/// generation of each texture or buffer bound that can be replaced, as a named struct where
/// there are several (a bind group made from a comparable description, as rerun's
/// `BindGroupDesc`). A key equal to the last one keeps the group: no bind group per frame, and
/// none that binds a texture since replaced.
pub struct CameraGroup {
    pipeline: Arc<MethodPipeline>,
    /// The group and the key it was made for.
    bound: Option<(wgpu::BindGroup, Box<dyn Any + Send>)>,
}

impl CameraGroup {
    /// The camera pipelines of `shader` (`methods/NAME.wgsl`) whose group 1 has `layout`.
    pub fn new(
        ctx: &GpuContext,
        shader: &'static str,
        layout: &[wgpu::BindGroupLayoutEntry],
    ) -> CameraGroup {
        CameraGroup {
            pipeline: MethodPipeline::get(ctx, shader, layout, false),
            bound: None,
        }
    }

    /// The same for a method whose V costs much at few pixels: the camera pass draws the
    /// surfaces twice. The first draw (`fs_first` of its shader) shades every pixel it can
    /// cheaply and marks the others by writing their depth one float step farther (reversed
    /// depth: smaller); the second (`fs_refine`), depth test greater, passes only there and
    /// writes the surface's depth back. A CPU rasteriser runs every branch of a shader for a
    /// whole group of pixels, but none of it for a group the depth test rejects: the expensive
    /// code runs only for groups with a marked pixel.
    pub fn two_draws(
        ctx: &GpuContext,
        shader: &'static str,
        layout: &[wgpu::BindGroupLayoutEntry],
    ) -> CameraGroup {
        CameraGroup {
            pipeline: MethodPipeline::get(ctx, shader, layout, true),
            bound: None,
        }
    }

    /// Make the bind group of `entries` unless the one held was made for `key`.
    pub fn bind<K: PartialEq + Send + 'static>(
        &mut self,
        device: &wgpu::Device,
        key: K,
        entries: &[wgpu::BindGroupEntry<'_>],
    ) {
        let current = self.bound.as_ref().and_then(|(_, k)| k.downcast_ref::<K>());
        if current == Some(&key) {
            return;
        }
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.pipeline.shader),
            layout: &self.pipeline.layout,
            entries,
        });
        self.bound = Some((group, Box::new(key)));
    }

    /// The pipeline for V(t) variant `vt` and the light's shape, and the group; `None` before
    /// the first [`CameraGroup::bind`] (a method returns its group from
    /// [`MethodState::prepare`] once it has bound it).
    pub fn bindings(
        &self,
        device: &wgpu::Device,
        vt: VtVariant,
        polygon: bool,
        colour_only: bool,
    ) -> Option<CameraBindings<'_>> {
        self.bound.as_ref().map(|(group, _)| {
            let (pipeline, refine) = self.pipeline.pipeline(device, vt, polygon, colour_only);
            CameraBindings {
                pipeline,
                refine,
                bind_group: group,
                colour_only,
            }
        })
    }
}

/// Group 1 of a method whose V per pixel is a texture: the screen passes' visibility
/// (`shaders/shared/screen_v.wgsl`) or the reference's V handed in (`methods/reference.wgsl`).
pub fn v_texture_entries() -> [wgpu::BindGroupLayoutEntry; 1] {
    [super::texture_entry(
        0,
        wgpu::ShaderStages::FRAGMENT,
        wgpu::TextureViewDimension::D2,
    )]
}

/// `value`, or the GPU error `missing` (a pass that should have made it did not).
pub fn require<T>(value: Option<T>, missing: &str) -> Result<T, RenderError> {
    value.ok_or_else(|| RenderError::Gpu(missing.into()))
}

/// The session's light-space products several methods share (the centre shadow map of `hard`,
/// `pcf`, `pcss` and the D-buffer's `|cx_o|`), each made once per revision.
pub struct SharedMaps {
    pub shadow_map: ShadowMap,
}

/// A method's GPU state for one scene.
pub trait MethodState: Send {
    /// Bring the light-space products up to date for `inputs`, recording the passes that make
    /// them only when they are stale, and write this frame's uniforms; what the camera pass
    /// draws the frame with (its [`CameraGroup`], bound for this frame).
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError>;

    /// Its light-space maps, if it has any.
    fn light_maps<'a>(&'a self, _shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        None
    }

    /// The geometry stage's output its light pass was built from (overlays, stats).
    fn geometry(&self) -> Option<&SceneGeometry> {
        None
    }

    /// CPU milliseconds of its last geometry build, and how many builds it has made.
    fn geometry_builds(&self) -> (u64, f64) {
        (0, 0.0)
    }

    /// Forget the light-space products: the next frame remakes them (to time them).
    fn invalidate(&mut self) {}

    /// For a method that counts shadow volumes over the screen: the mean number of volume
    /// fragments per pixel of its last frame (the fill it pays), measured with a pass of its
    /// own; `None` for every other method.
    fn stencil_fill(&self, _ctx: &GpuContext) -> Option<Result<f64, RenderError>> {
        None
    }

    /// Pick up what the GPU hands back a frame or more later for the overlays (`hybrid`'s
    /// walls), without waiting; `true` while something is on its way or has just arrived (a
    /// window repaints then).
    fn poll_geometry(&mut self) -> bool {
        false
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
