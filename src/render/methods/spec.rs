//! What a method is, for the registry ([`MethodSpec`]): its name, shader, knobs, lights, adapter
//! needs, bench row, cost view and study sweep, built with `const` calls that say only where a
//! method differs from the defaults.

use glam::Vec3;

use super::{AdapterNeeds, Knob, Knobs, MethodState, Quality, Sweep};
use crate::render::GpuContext;
use crate::scene::{LightKind, LineLight};

/// What a method is, for the registry: everything the rest of the program needs to know about
/// it, so that nothing outside its module matches on its name.
pub struct MethodSpec {
    /// The command-line name (`--method`, pickers, `report.json`).
    pub name: &'static str,
    /// One line for menus and `--help`.
    pub description: &'static str,
    /// Its camera shader under `shaders/` (`methods/NAME.wgsl`: its `method_visibility`).
    pub shader: &'static str,
    /// Its knobs (command-line flags, lab controls); a [`Switch`](super::Switch),
    /// [`Choice`](super::Choice) or [`Scaled`](super::Scaled) is listed by the [`Knob`] it wraps
    /// (`&OPEN.0`).
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
    /// A temporal method's knob of the frames of history a still view is shown after (`render`
    /// draws them first; `compare` scores its first frame and the one after them); `None` for a
    /// method whose frame depends on nothing before it.
    pub history: Option<&'static Knob>,
    /// Its per-scene GPU state.
    pub new: fn(&GpuContext) -> Box<dyn MethodState>,
    /// A method made at run time (a user's file, `--method file:PATH.wgsl`): what makes its
    /// state instead of `new` ([`MethodSpec::state`]).
    pub user: Option<&'static dyn MakeState>,
}

/// What makes the state of a method known only at run time (a user's file, whose state holds
/// its shader and knobs): `new` is a plain `fn` and cannot carry them.
pub trait MakeState: Send + Sync {
    fn state(&'static self, ctx: &GpuContext, spec: &'static MethodSpec) -> Box<dyn MethodState>;
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
            history: None,
            new,
            user: None,
        }
    }

    /// Its per-scene GPU state: `new`'s, or for a method made at run time its maker's.
    pub fn state(&'static self, ctx: &GpuContext) -> Box<dyn MethodState> {
        match self.user {
            Some(user) => user.state(ctx, self),
            None => (self.new)(ctx),
        }
    }

    /// A method made at run time, `user` making its state.
    pub const fn user(mut self, user: &'static dyn MakeState) -> Self {
        self.user = Some(user);
        self
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

    /// A temporal method: its image depends on the frames before it, and a still view is shown
    /// after `frames` (a knob) of them.
    pub const fn history(mut self, frames: &'static Knob) -> Self {
        self.history = Some(frames);
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

    /// What it needs of the adapter beyond the camera pass's ([`AdapterNeeds`]).
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
