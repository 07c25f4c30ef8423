//! What a study runs: its scenes, sizes, reference K, timing protocol and, per method, the
//! settings to sweep — from the registry's default sweeps ([`StudySpec::full`],
//! [`StudySpec::quick`]) or a study file (TOML, docs/guide/study.md), checked key by key before
//! any work.

use std::path::Path;

use crate::budget::{check_image_size, MAX_COMPARE_PIXELS, MAX_STUDY_CELLS, MAX_STUDY_PIXELS};
use crate::geometry::VtVariant;
use crate::render::methods::{Quality, MAP_SIZE_NAME};
use crate::render::{Knobs, Method};

/// The default study's scenes: Table 1 of the paper, the paper's figures where Assumption 1
/// fails, the fusion and polygon-light scenes, and the many-caster ones.
pub const FULL_SCENES: &[&str] = &[
    "table1-224",
    "table1-960",
    "table1-1440",
    "table1-5760",
    "fig1-large-light",
    "fig7-concave",
    "fig8c-complex",
    "overlap",
    "bunny",
    "fusion-cross",
    "rect-strip",
    "pergola",
    "cluster",
    "blinds",
];

/// `--quick`'s scenes: two of the paper's and two of many casters (not `pergola`, whose thin
/// slats cost `bitmask` a minute a frame).
pub const QUICK_SCENES: &[&str] = &["table1-960", "fig1-large-light", "cluster", "fusion-many"];

/// Settings `--quick` takes of a method's default sweep (cheapest, middle, dearest).
pub const QUICK_SETTINGS: usize = 3;

/// One setting of a method: the quality axes it sets (knobs over their defaults, or the map
/// size); empty for the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    pub values: Vec<(Quality, u32)>,
}

impl Setting {
    /// The method's defaults.
    pub fn defaults() -> Setting {
        Setting { values: Vec::new() }
    }

    /// The knobs it sets, the others at their defaults.
    pub fn knobs(&self) -> Knobs {
        self.values
            .iter()
            .fold(Knobs::default(), |k, (q, v)| match q {
                Quality::Knob(knob) => k.with(*knob, *v),
                Quality::MapSize => k,
            })
    }

    /// The light-space maps' size it sets, else `default`.
    pub fn map_size(&self, default: u32) -> u32 {
        self.values
            .iter()
            .find_map(|(q, v)| matches!(q, Quality::MapSize).then_some(*v))
            .unwrap_or(default)
    }

    /// How the reports name it: `blocker-taps 16, filter-taps 32`, or `defaults`.
    pub fn label(&self) -> String {
        if self.values.is_empty() {
            return "defaults".into();
        }
        let parts: Vec<String> = self
            .values
            .iter()
            .map(|(q, v)| format!("{} {v}", q.name()))
            .collect();
        parts.join(", ")
    }
}

/// A method and the settings the study measures it at.
#[derive(Clone, Debug)]
pub struct MethodSweep {
    pub method: Method,
    pub settings: Vec<Setting>,
}

impl MethodSweep {
    /// The registry's default sweep of `method` (all of it, or `quick`'s spread), or its
    /// defaults for a method without a quality knob.
    pub fn default_for(method: Method, quick: bool) -> MethodSweep {
        let sweep = method.sweep();
        let picked = if quick {
            sweep.spread(QUICK_SETTINGS)
        } else {
            sweep.settings.to_vec()
        };
        let mut settings: Vec<Setting> = picked
            .iter()
            .map(|values| Setting {
                values: sweep
                    .axes
                    .iter()
                    .copied()
                    .zip(values.iter().copied())
                    .collect(),
            })
            .collect();
        if settings.is_empty() {
            settings.push(Setting::defaults());
        }
        MethodSweep { method, settings }
    }
}

/// A whole study, before any work.
#[derive(Clone, Debug)]
pub struct StudySpec {
    /// Built-in names or scene files (resolved against the study file's folder).
    pub scenes: Vec<String>,
    pub width: u32,
    pub height: u32,
    /// The light-space maps' size where a setting does not say.
    pub dbuffer_size: u32,
    /// The reference's samples per pixel (K).
    pub samples: u32,
    pub vt: VtVariant,
    /// The bench's protocol: frames thrown away, then frames timed (medians).
    pub warmup: usize,
    pub frames: usize,
    pub methods: Vec<MethodSweep>,
    /// Made by `--quick`.
    pub quick: bool,
}

/// Why a study cannot run: a bad study file (the key named) or flags, a study over the budget.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("{file}: line {line}, column {column}: {message}")]
    Toml {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{file}: {key}: {message}")]
    Key {
        file: String,
        key: String,
        message: String,
    },
    #[error("{0}")]
    Flags(String),
    #[error("cannot read {file}: {message}")]
    Read { file: String, message: String },
}

impl StudySpec {
    /// The default study: every method over its whole default sweep on [`FULL_SCENES`], 512²,
    /// maps of 1024², K = 1024, 2 warm-up and 5 timed frames a cell.
    pub fn full() -> StudySpec {
        StudySpec {
            scenes: FULL_SCENES.iter().map(|s| s.to_string()).collect(),
            width: 512,
            height: 512,
            dbuffer_size: 1024,
            samples: 1024,
            vt: VtVariant::Exact,
            warmup: 2,
            frames: 5,
            methods: Method::all()
                .iter()
                .map(|&m| MethodSweep::default_for(m, false))
                .collect(),
            quick: false,
        }
    }

    /// `--quick`: every method at three of its default settings on [`QUICK_SCENES`], 256²,
    /// K = 256, 1 warm-up and 3 timed frames a cell.
    pub fn quick() -> StudySpec {
        StudySpec {
            scenes: QUICK_SCENES.iter().map(|s| s.to_string()).collect(),
            width: 256,
            height: 256,
            samples: 256,
            warmup: 1,
            frames: 3,
            methods: Method::all()
                .iter()
                .map(|&m| MethodSweep::default_for(m, true))
                .collect(),
            quick: true,
            ..StudySpec::full()
        }
    }

    /// The cells: scenes × every method's settings.
    pub fn cell_count(&self) -> u64 {
        let per_scene: usize = self.methods.iter().map(|m| m.settings.len()).sum();
        self.scenes.len() as u64 * per_scene as u64
    }

    /// Refuse a study over the budget ([`MAX_STUDY_CELLS`], [`MAX_STUDY_PIXELS`]) or with
    /// nothing in it, before any work.
    pub fn check_budget(&self) -> Result<(), StudyError> {
        let cells = self.cell_count();
        if self.scenes.is_empty() || self.methods.is_empty() || cells == 0 {
            return Err(StudyError::Flags(
                "the study has no cells: it needs at least one scene and one method".into(),
            ));
        }
        if cells > MAX_STUDY_CELLS {
            return Err(StudyError::Flags(format!(
                "the study has {cells} cells ({} scenes × {} settings); the budget is \
                 {MAX_STUDY_CELLS} cells (MAX_STUDY_CELLS): narrow it with --scenes or --methods",
                self.scenes.len(),
                cells / self.scenes.len() as u64
            )));
        }
        // `--size` as well as a file's size: a cell is drawn and scored as `compare` does it.
        check_image_size(
            self.width,
            self.height,
            MAX_COMPARE_PIXELS,
            "MAX_COMPARE_PIXELS",
        )
        .map_err(|m| StudyError::Flags(format!("--size {m}")))?;
        let pixels = cells * u64::from(self.width) * u64::from(self.height);
        if pixels > MAX_STUDY_PIXELS {
            return Err(StudyError::Flags(format!(
                "the study renders {pixels} pixels ({cells} cells at {}x{}); the budget is \
                 {MAX_STUDY_PIXELS} (MAX_STUDY_PIXELS): a smaller --size or fewer cells",
                self.width, self.height
            )));
        }
        Ok(())
    }

    /// Read a study file over `base` (what its keys leave unsaid), naming the key of any error.
    pub fn from_file(path: &Path, base: StudySpec) -> Result<StudySpec, StudyError> {
        let label = path.display().to_string();
        let bytes = crate::fsutil::read_regular(path, crate::scene::file::SCENE_FILE_BUDGET)
            .map_err(|e| StudyError::Read {
                file: label.clone(),
                message: e.to_string(),
            })?;
        let text =
            crate::scene::file::decode_utf8(&bytes, &label).map_err(|e| StudyError::Read {
                file: label.clone(),
                message: e.to_string(),
            })?;
        let mut spec = StudySpec::parse(text, &label, base)?;
        // Scene files name their place against the study file's folder.
        let folder = path.parent().unwrap_or(Path::new("."));
        for scene in &mut spec.scenes {
            if crate::scene::builtin::source(scene).is_none() && Path::new(scene).is_relative() {
                *scene = folder.join(&*scene).display().to_string();
            }
        }
        Ok(spec)
    }

    /// Parse a study file's text over `base`; `file` names it in errors.
    pub fn parse(text: &str, file: &str, base: StudySpec) -> Result<StudySpec, StudyError> {
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let (line, column) = e
                .span()
                .map_or((1, 1), |s| crate::scene::file::line_column(text, s.start));
            StudyError::Toml {
                file: file.to_string(),
                line,
                column,
                message: e.message().trim().to_string(),
            }
        })?;
        let key_error = |key: &str, message: String| StudyError::Key {
            file: file.to_string(),
            key: key.to_string(),
            message,
        };
        let mut spec = base;
        for (key, value) in &table {
            match key.as_str() {
                "scenes" => {
                    let list = value.as_array().ok_or_else(|| {
                        key_error(key, "expected a list of scene names or files".into())
                    })?;
                    if list.is_empty() {
                        return Err(key_error(key, "an empty list studies nothing".into()));
                    }
                    spec.scenes = list
                        .iter()
                        .enumerate()
                        .map(|(i, v)| {
                            v.as_str().map(str::to_string).ok_or_else(|| {
                                key_error(
                                    &format!("scenes[{i}]"),
                                    "expected a scene name or file".into(),
                                )
                            })
                        })
                        .collect::<Result<_, _>>()?;
                }
                "size" => {
                    let (w, h) = match value {
                        toml::Value::String(s) => crate::budget::parse_wxh(s),
                        toml::Value::Array(a) if a.len() == 2 => {
                            match (positive(&a[0]), positive(&a[1])) {
                                (Some(w), Some(h)) => Some((w, h)),
                                _ => None,
                            }
                        }
                        _ => None,
                    }
                    .ok_or_else(|| {
                        key_error(key, "expected \"WxH\" or [W, H], e.g. \"512x512\"".into())
                    })?;
                    // Each cell is drawn and scored as `compare` does it: its limit.
                    check_image_size(w, h, MAX_COMPARE_PIXELS, "MAX_COMPARE_PIXELS")
                        .map_err(|m| key_error(key, m))?;
                    spec.width = w;
                    spec.height = h;
                }
                "dbuffer_size" | "dbuffer-size" => {
                    spec.dbuffer_size =
                        int_in(value, Quality::MapSize).map_err(|m| key_error(key, m))?;
                }
                "samples" => {
                    spec.samples = int_in(value, Quality::Knob(&crate::render::truth::SAMPLES))
                        .map_err(|m| key_error(key, m))?;
                }
                "vt" => {
                    spec.vt = value
                        .as_str()
                        .ok_or_else(|| {
                            key_error(key, "expected smoothstep, sqrt, exact or linear".into())
                        })?
                        .parse()
                        .map_err(|e: String| key_error(key, e))?;
                }
                "warmup" => {
                    spec.warmup = positive(value)
                        .filter(|&n| n <= 100)
                        .or_else(|| value.as_integer().filter(|&n| n == 0).map(|_| 0))
                        .ok_or_else(|| key_error(key, "expected 0 to 100 frames".into()))?
                        as usize;
                }
                "frames" => {
                    spec.frames = positive(value)
                        .filter(|&n| n <= 100)
                        .ok_or_else(|| key_error(key, "expected 1 to 100 timed frames".into()))?
                        as usize;
                }
                "methods" => {
                    let methods = value
                        .as_table()
                        .ok_or_else(|| key_error(key, "expected a table of methods".into()))?;
                    if methods.is_empty() {
                        return Err(key_error(key, "an empty table studies no method".into()));
                    }
                    let mut sweeps = Vec::new();
                    for (name, sweep) in methods {
                        let key = format!("methods.{name}");
                        let method: Method =
                            name.parse().map_err(|e: String| key_error(&key, e))?;
                        sweeps.push(method_sweep(method, sweep, spec.quick).map_err(
                            |(k, m)| {
                                key_error(
                                    &if k.is_empty() {
                                        key.clone()
                                    } else {
                                        format!("{key}.{k}")
                                    },
                                    m,
                                )
                            },
                        )?);
                    }
                    // Registry order, as every report lists methods.
                    sweeps.sort_by_key(|s| s.method.order());
                    spec.methods = sweeps;
                }
                other => {
                    return Err(key_error(
                        other,
                        "unknown key; a study file takes scenes, size, dbuffer_size, samples, vt, \
                         warmup, frames and [methods]"
                            .into(),
                    ))
                }
            }
        }
        Ok(spec)
    }

    /// `--scenes`, `--methods` and `--size` narrow the study (the methods keep their sweeps).
    pub fn narrow(
        &mut self,
        scenes: Option<Vec<String>>,
        methods: Option<Vec<Method>>,
        size: Option<(u32, u32)>,
    ) -> Result<(), StudyError> {
        if let Some(scenes) = scenes {
            if scenes.is_empty() {
                return Err(StudyError::Flags(
                    "--scenes expects a comma-separated list of scenes".into(),
                ));
            }
            self.scenes = scenes;
        }
        if let Some(methods) = methods {
            if methods.is_empty() {
                return Err(StudyError::Flags(
                    "--methods expects a comma-separated list of methods".into(),
                ));
            }
            for &m in &methods {
                if !self.methods.iter().any(|s| s.method == m) {
                    self.methods.push(MethodSweep::default_for(m, self.quick));
                }
            }
            self.methods.retain(|s| methods.contains(&s.method));
            self.methods.sort_by_key(|s| s.method.order());
        }
        if let Some((w, h)) = size {
            self.width = w;
            self.height = h;
        }
        Ok(())
    }
}

fn positive(v: &toml::Value) -> Option<u32> {
    v.as_integer()
        .filter(|&n| n > 0 && n <= i64::from(u32::MAX))
        .map(|n| n as u32)
}

/// A whole number in `axis`'s range, or why not (naming the flag and its range).
fn int_in(v: &toml::Value, axis: Quality) -> Result<u32, String> {
    let n = v
        .as_integer()
        .ok_or_else(|| format!("expected a whole number for --{}", axis.name()))?;
    let value = u32::try_from(n).map_err(|_| {
        axis.check(u32::MAX)
            .unwrap_or_else(|| format!("--{} takes no {n}", axis.name()))
            .replace(&u32::MAX.to_string(), &n.to_string())
    })?;
    match axis.check(value) {
        Some(why) => Err(why),
        None => Ok(value),
    }
}

/// The axis a study file's key names for `method`: one of its knobs (`blocker_taps` or
/// `blocker-taps`), or the map size (`dbuffer_size`).
fn axis_of(method: Method, key: &str) -> Result<Quality, String> {
    let name = key.replace('_', "-");
    if name == MAP_SIZE_NAME {
        return Ok(Quality::MapSize);
    }
    match method.knobs().iter().find(|k| k.name == name) {
        Some(k) => Ok(Quality::Knob(k)),
        None => {
            let mut own: Vec<&str> = method.knobs().iter().map(|k| k.name).collect();
            own.push(MAP_SIZE_NAME);
            Err(format!(
                "{method} has no knob '{name}' (it takes {})",
                own.join(", ")
            ))
        }
    }
}

/// One method's entry of `[methods]`: `"default"` (the registry's sweep), `"defaults"` (its
/// defaults alone), a table of axes to lists (every combination), or a list of tables (those
/// settings). The error's key is relative to the method's (`blocker_taps[2]`, `[1].smrt_rays`).
fn method_sweep(
    method: Method,
    value: &toml::Value,
    quick: bool,
) -> Result<MethodSweep, (String, String)> {
    let at = |k: String, m: String| (k, m);
    let settings = match value {
        toml::Value::String(s) if s == "default" => {
            return Ok(MethodSweep::default_for(method, quick))
        }
        toml::Value::String(s) if s == "defaults" => vec![Setting::defaults()],
        toml::Value::Table(axes) => {
            if axes.is_empty() {
                return Err(at(
                    String::new(),
                    "an empty sweep: name an axis, or \"default\"".into(),
                ));
            }
            let mut grid: Vec<Setting> = vec![Setting::defaults()];
            for (key, values) in axes {
                let axis = axis_of(method, key).map_err(|m| at(key.clone(), m))?;
                let list: Vec<&toml::Value> = match values {
                    toml::Value::Array(a) => a.iter().collect(),
                    one => vec![one],
                };
                if list.is_empty() {
                    return Err(at(key.clone(), "an empty list sweeps nothing".into()));
                }
                let mut parsed = Vec::new();
                for (i, v) in list.iter().enumerate() {
                    let where_ = if matches!(values, toml::Value::Array(_)) {
                        format!("{key}[{i}]")
                    } else {
                        key.clone()
                    };
                    parsed.push(int_in(v, axis).map_err(|m| at(where_, m))?);
                }
                grid = grid
                    .iter()
                    .flat_map(|s| {
                        parsed.iter().map(move |&v| {
                            let mut next = s.clone();
                            next.values.push((axis, v));
                            next
                        })
                    })
                    .collect();
            }
            grid
        }
        toml::Value::Array(list) => {
            if list.is_empty() {
                return Err(at(String::new(), "an empty list sweeps nothing".into()));
            }
            let mut settings = Vec::new();
            for (i, item) in list.iter().enumerate() {
                let table = item.as_table().ok_or_else(|| {
                    at(
                        format!("[{i}]"),
                        "expected a table of axes, e.g. { pcf_radius = 2 }".into(),
                    )
                })?;
                let mut setting = Setting::defaults();
                for (key, v) in table {
                    let axis = axis_of(method, key).map_err(|m| at(format!("[{i}].{key}"), m))?;
                    let value = int_in(v, axis).map_err(|m| at(format!("[{i}].{key}"), m))?;
                    setting.values.push((axis, value));
                }
                settings.push(setting);
            }
            settings
        }
        _ => {
            return Err(at(
                String::new(),
                "expected \"default\", \"defaults\", a table of axes to values, or a list of \
                 settings"
                    .into(),
            ))
        }
    };
    Ok(MethodSweep { method, settings })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<StudySpec, String> {
        StudySpec::parse(text, "s.toml", StudySpec::quick()).map_err(|e| e.to_string())
    }

    #[test]
    fn a_grid_is_every_combination_and_a_list_its_settings() {
        let s = parse(
            "scenes = [\"table1-224\"]\nsize = \"96x64\"\n[methods]\n\
             pcss = { blocker_taps = [8, 16], filter_taps = [16, 32, 64] }\n\
             smrt = [{ smrt_rays = 1, smrt_steps = 4 }, { smrt_rays = 7 }]\n\
             hard = { dbuffer_size = [512, 2048] }\nwedges = \"defaults\"\n",
        )
        .unwrap();
        assert_eq!((s.width, s.height), (96, 64));
        let names: Vec<&str> = s.methods.iter().map(|m| m.method.name()).collect();
        assert_eq!(names, ["hard", "pcss", "smrt", "wedges"], "registry order");
        assert_eq!(s.methods[1].settings.len(), 6);
        assert_eq!(s.methods[2].settings[1].label(), "smrt-rays 7");
        assert_eq!(s.methods[0].settings[1].map_size(1024), 2048);
        assert_eq!(s.methods[3].settings, vec![Setting::defaults()]);
        assert_eq!(s.cell_count(), 6 + 2 + 2 + 1);
    }

    #[test]
    fn bad_files_name_the_key() {
        for (text, wanted) in [
            (
                "[methods]\npcsss = \"default\"",
                "methods.pcsss: unknown method",
            ),
            (
                "[methods]\npcss = { blocker = [8] }",
                "methods.pcss.blocker: pcss has no knob 'blocker'",
            ),
            (
                "[methods]\npcss = { blocker_taps = [8, 99] }",
                "methods.pcss.blocker_taps[1]: --blocker-taps expects 1 to 64, found 99",
            ),
            (
                "[methods]\npcss = { blocker_taps = [] }",
                "methods.pcss.blocker_taps: an empty list",
            ),
            ("[methods]\npcss = []", "methods.pcss: an empty list"),
            ("[methods]\npcss = {}", "methods.pcss: an empty sweep"),
            (
                "[methods]\nhard = { dbuffer_size = 0 }",
                "methods.hard.dbuffer_size: --dbuffer-size expects 1",
            ),
            (
                "[methods]\nsmrt = [{ smrt_rays = -1 }]",
                "methods.smrt.[0].smrt_rays: --smrt-rays",
            ),
            ("scenes = []", "scenes: an empty list"),
            ("size = \"0x3\"", "size: expected"),
            (
                "size = \"8192x4096\"",
                "size: 8192x4096 is 33554432 pixels: expected at most 16777216 (MAX_COMPARE_PIXELS",
            ),
            (
                "size = [20000, 2]",
                "size: 20000x2: expected sides of at most 16384",
            ),
            ("frames = 0", "frames: expected 1 to 100"),
            ("colour = 1", "colour: unknown key"),
            ("samples = 0", "samples: --samples expects 1"),
            ("scenes = [", "s.toml: line 1, column"),
        ] {
            let e = parse(text).unwrap_err();
            assert!(e.contains(wanted), "{text:?}: {e}");
            assert!(e.starts_with("s.toml: "), "{e}");
        }
    }

    #[test]
    fn the_budget_is_checked_from_the_spec() {
        let mut s = StudySpec::quick();
        s.check_budget().unwrap();
        s.width = 16384;
        s.height = 16384;
        let e = s.check_budget().unwrap_err().to_string();
        assert!(e.contains("MAX_COMPARE_PIXELS"), "{e}");
        // The default study's cells at 4096²: each within a cell's limit, all over the study's.
        s = StudySpec::full();
        s.width = 4096;
        s.height = 4096;
        let e = s.check_budget().unwrap_err().to_string();
        assert!(e.contains("MAX_STUDY_PIXELS"), "{e}");
        s.scenes.clear();
        assert!(s
            .check_budget()
            .unwrap_err()
            .to_string()
            .contains("no cells"));
    }

    #[test]
    fn quick_takes_three_settings_of_every_swept_method() {
        let s = StudySpec::quick();
        for m in &s.methods {
            let swept = m.method.sweep().fixed.is_none();
            assert_eq!(m.settings.len(), if swept { 3 } else { 1 }, "{}", m.method);
        }
    }

    #[test]
    fn narrowing_keeps_sweeps_and_adds_a_method_at_its_defaults() {
        let mut s = parse("[methods]\npcss = { blocker_taps = [8] }").unwrap();
        let pcss: Method = "pcss".parse().unwrap();
        s.narrow(None, Some(vec![pcss, Method::HARD]), Some((64, 32)))
            .unwrap();
        assert_eq!(s.methods.len(), 2);
        assert_eq!(s.methods[0].method, Method::HARD);
        assert_eq!(s.methods[1].settings.len(), 1);
        assert_eq!((s.width, s.height), (64, 32));
    }
}
