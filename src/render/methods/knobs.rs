//! Method knobs: typed settings a method declares in its module, which become a command-line
//! flag `--NAME`, a control in the lab and a value the method reads in [`Knobs`].
//!
//! A knob is one of four kinds ([`KnobKind`]): a whole number (a slider), an on/off switch (a
//! checkbox), a choice among named options (a picker), or a share such as a percentage (a slider
//! showing the fraction). Whatever the kind, its value is held in one form from the command line
//! to the GPU: the whole number the flag takes (`--sv-open 1`, `--planar-opacity 50`), in
//! [`Knobs`]. The method reads it back typed through its static ([`Knobs::get`]): a `u32` from a
//! [`Knob`], a `bool` from a [`Switch`], the option's number from a [`Choice`], the fraction
//! from a [`Scaled`] — so a ‰ or % is divided out in one place, not by each method.

use std::fmt;
use std::ops::RangeInclusive;
use std::sync::OnceLock;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::ALL;

/// A method's knob: a command-line flag `--NAME` taking a whole number, and a control in the lab.
/// An integer knob is a `Knob` itself; the other kinds wrap one ([`Switch`], [`Choice`],
/// [`Scaled`]) so that reading it gives the right type.
#[derive(Debug)]
pub struct Knob {
    /// The flag without its dashes, e.g. `pcf-radius`.
    pub name: &'static str,
    pub help: &'static str,
    pub kind: KnobKind,
    /// The default, as the flag writes it.
    pub default: u32,
}

/// What a knob's whole number means, and so how the lab shows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KnobKind {
    /// A count or a size from `min` to `max`: a slider. `max_name` is the resource-budget
    /// constant (`crate::budget`) `max` is, named in the error when a value is over it.
    Int {
        min: u32,
        max: u32,
        max_name: Option<&'static str>,
    },
    /// On (1) or off (0); the command line also takes `true` and `false`. A checkbox.
    Switch,
    /// One of `choices`, by its number from 0. A picker.
    Choice { choices: &'static [&'static str] },
    /// A share counted in `1/per` (‰ with `per` = 1000, % with 100) from `min` to `max`; the
    /// method reads the fraction. A slider showing the fraction.
    Scaled { min: u32, max: u32, per: u32 },
}

impl Knob {
    /// A whole-number knob from `range`'s start to its end.
    pub const fn int(
        name: &'static str,
        help: &'static str,
        range: RangeInclusive<u32>,
        default: u32,
    ) -> Knob {
        Knob {
            name,
            help,
            kind: KnobKind::Int {
                min: *range.start(),
                max: *range.end(),
                max_name: None,
            },
            default,
        }
    }

    /// The same knob, its maximum being the budget constant called `max_name`.
    pub const fn budget(self, max_name: &'static str) -> Knob {
        match self.kind {
            KnobKind::Int { min, max, .. } => Knob {
                kind: KnobKind::Int {
                    min,
                    max,
                    max_name: Some(max_name),
                },
                ..self
            },
            _ => self,
        }
    }

    /// The smallest and largest value the flag takes.
    pub const fn range(&self) -> (u32, u32) {
        match self.kind {
            KnobKind::Int { min, max, .. } | KnobKind::Scaled { min, max, .. } => (min, max),
            KnobKind::Switch => (0, 1),
            KnobKind::Choice { choices } => (0, choices.len().saturating_sub(1) as u32),
        }
    }

    /// Whether the flag takes `value`.
    pub fn accepts(&self, value: u32) -> bool {
        let (min, max) = self.range();
        (min..=max).contains(&value)
    }

    /// Why `value` is refused, naming the flag; `None` when it is in range.
    pub fn check(&self, value: u32) -> Option<String> {
        if self.accepts(value) {
            return None;
        }
        let (min, max) = self.range();
        let budget = match self.kind {
            KnobKind::Int {
                max_name: Some(n), ..
            } => format!(" ({n})"),
            _ => String::new(),
        };
        Some(format!(
            "--{} expects {min} to {max}{budget}, found {value}",
            self.name
        ))
    }
}

/// An on/off knob: reads as a `bool`.
#[derive(Debug)]
pub struct Switch(pub Knob);

impl Switch {
    pub const fn new(name: &'static str, help: &'static str, default: bool) -> Switch {
        Switch(Knob {
            name,
            help,
            kind: KnobKind::Switch,
            default: default as u32,
        })
    }
}

/// A knob that picks one of named options: reads as the option's number.
#[derive(Debug)]
pub struct Choice(pub Knob);

impl Choice {
    pub const fn new(
        name: &'static str,
        help: &'static str,
        choices: &'static [&'static str],
        default: u32,
    ) -> Choice {
        Choice(Knob {
            name,
            help,
            kind: KnobKind::Choice { choices },
            default,
        })
    }
}

/// A share counted in `1/per` on the command line: reads as the fraction (`f32`).
#[derive(Debug)]
pub struct Scaled(pub Knob);

impl Scaled {
    pub const fn new(
        name: &'static str,
        help: &'static str,
        range: RangeInclusive<u32>,
        default: u32,
        per: u32,
    ) -> Scaled {
        Scaled(Knob {
            name,
            help,
            kind: KnobKind::Scaled {
                min: *range.start(),
                max: *range.end(),
                per,
            },
            default,
        })
    }
}

/// A knob's static, read back as its type.
pub trait KnobType {
    type Value;
    fn knob(&self) -> &Knob;
    /// The value a flag's whole number `raw` stands for.
    fn value(&self, raw: u32) -> Self::Value;
}

impl KnobType for Knob {
    type Value = u32;
    fn knob(&self) -> &Knob {
        self
    }
    fn value(&self, raw: u32) -> u32 {
        raw
    }
}

impl KnobType for Switch {
    type Value = bool;
    fn knob(&self) -> &Knob {
        &self.0
    }
    fn value(&self, raw: u32) -> bool {
        raw != 0
    }
}

impl KnobType for Choice {
    type Value = u32;
    fn knob(&self) -> &Knob {
        &self.0
    }
    fn value(&self, raw: u32) -> u32 {
        raw
    }
}

impl KnobType for Scaled {
    type Value = f32;
    fn knob(&self) -> &Knob {
        &self.0
    }
    fn value(&self, raw: u32) -> f32 {
        let per = match self.0.kind {
            KnobKind::Scaled { per, .. } => per.max(1),
            _ => 1,
        };
        raw as f32 / per as f32
    }
}

/// At most this many distinct knobs over all methods (checked by a test).
pub const MAX_KNOBS: usize = 48;

/// Every distinct knob of the registry, in registry order. Gathered once: every knob read and
/// every comparison of two [`Knobs`] (each frame the lab asks for) looks its slot up here.
pub fn all_knobs() -> &'static [&'static Knob] {
    static ALL_KNOBS: OnceLock<Vec<&'static Knob>> = OnceLock::new();
    ALL_KNOBS.get_or_init(|| {
        let mut out: Vec<&'static Knob> = Vec::new();
        for m in ALL {
            for &k in m.knobs() {
                if !out.iter().any(|o| o.name == k.name) {
                    out.push(k);
                }
            }
        }
        out
    })
}

fn knob_slot(name: &str) -> Option<usize> {
    all_knobs()
        .iter()
        .position(|k| k.name == name)
        .filter(|&i| i < MAX_KNOBS)
}

/// The value of every knob (defaults where not set), as the flags write them: what the command
/// line parses into, the lab keeps (and saves) and a frame request carries to the methods.
#[derive(Clone, Copy)]
pub struct Knobs {
    values: [Option<u32>; MAX_KNOBS],
}

/// Two sets are the same request when every knob has the same value: a knob set to its default
/// equals one left unset (the lab stores a value once its control was touched), so neither
/// renders a frame again.
impl PartialEq for Knobs {
    fn eq(&self, other: &Self) -> bool {
        all_knobs().iter().all(|k| self.raw(k) == other.raw(k))
    }
}

impl Eq for Knobs {}

impl Default for Knobs {
    fn default() -> Self {
        Knobs {
            values: [None; MAX_KNOBS],
        }
    }
}

impl fmt::Debug for Knobs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut m = f.debug_map();
        for k in all_knobs() {
            m.entry(&k.name, &self.raw(k));
        }
        m.finish()
    }
}

impl Knobs {
    /// The value of `knob` as its type, its default if not set.
    pub fn get<K: KnobType + ?Sized>(&self, knob: &K) -> K::Value {
        knob.value(self.raw(knob.knob()))
    }

    /// The whole number `knob` has (as its flag writes it), its default if not set.
    pub fn raw(&self, knob: &Knob) -> u32 {
        self.given(knob).unwrap_or(knob.default)
    }

    /// The whole number `knob` was set to, if it was.
    pub fn given(&self, knob: &Knob) -> Option<u32> {
        knob_slot(knob.name).and_then(|i| self.values[i])
    }

    /// Set the knob called `name` to the whole number `value` (no range check: see
    /// [`Knobs::validate`]).
    pub fn set(&mut self, name: &str, value: u32) -> Result<(), String> {
        let i = knob_slot(name).ok_or_else(|| format!("unknown knob '{name}'"))?;
        self.values[i] = Some(value);
        Ok(())
    }

    /// `self` with `knob` set to the whole number `value`, as its flag writes it.
    pub fn with<K: KnobType + ?Sized>(mut self, knob: &K, value: u32) -> Knobs {
        if let Some(i) = knob_slot(knob.knob().name) {
            self.values[i] = Some(value);
        }
        self
    }

    /// Every knob that was set, with its value, in registry order.
    pub fn set_ones(&self) -> impl Iterator<Item = (&'static Knob, u32)> + '_ {
        all_knobs()
            .iter()
            .filter_map(|&k| Some((k, self.given(k)?)))
    }

    /// Forget the values out of their knob's range (a hand-edited or old settings file).
    pub fn drop_invalid(&mut self) {
        for k in all_knobs() {
            if let (Some(i), Some(v)) = (knob_slot(k.name), self.given(k)) {
                if !k.accepts(v) {
                    self.values[i] = None;
                }
            }
        }
    }

    /// Every knob in its range, or which one is not and what was expected (naming the flag).
    pub fn validate(&self) -> Result<(), String> {
        match all_knobs().iter().find_map(|k| k.check(self.raw(k))) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// Saved as the list of `(name, value)` pairs that were set, as the lab's settings always kept
/// them: a settings file of an older build loads, and a knob this build does not know is dropped.
impl Serialize for Knobs {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.set_ones().map(|(k, v)| (k.name, v)))
    }
}

impl<'de> Deserialize<'de> for Knobs {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let pairs = Vec::<(String, u32)>::deserialize(d)?;
        let mut knobs = Knobs::default();
        for (name, value) in pairs {
            let _ = knobs.set(&name, value);
        }
        Ok(knobs)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{hybrid, pcf, planar, sampled, shadow_volume};
    use super::*;

    #[test]
    fn a_knob_set_to_its_default_is_the_same_request_as_one_left_unset() {
        let unset = Knobs::default();
        assert_eq!(unset, unset.with(&pcf::RADIUS, pcf::RADIUS.default));
        assert_ne!(unset, unset.with(&pcf::RADIUS, pcf::RADIUS.default + 1));
    }

    #[test]
    fn knobs_fit_and_validate_by_flag() {
        assert!(all_knobs().len() <= MAX_KNOBS);
        let k = Knobs::default();
        assert_eq!(k.get(&pcf::RADIUS), pcf::RADIUS.default);
        k.validate().unwrap();
        let bad = k.with(&pcf::RADIUS, 99);
        assert_eq!(bad.get(&pcf::RADIUS), 99);
        let e = bad.validate().unwrap_err();
        assert_eq!(e, "--pcf-radius expects 0 to 8, found 99");
        let mut named = Knobs::default();
        named.set("lights", 4).unwrap();
        assert_eq!(named.get(&sampled::LIGHTS), 4);
        assert!(named.set("nope", 1).is_err());
    }

    #[test]
    fn kinds_read_as_their_type() {
        let k = Knobs::default();
        assert!(k.get(&shadow_volume::OPEN), "two-sided by default");
        assert!(!k.with(&shadow_volume::OPEN, 0).get(&shadow_volume::OPEN));
        assert_eq!(k.get(&hybrid::THRESHOLD), 20.0 / 1000.0);
        assert_eq!(k.with(&planar::OPACITY, 50).get(&planar::OPACITY), 0.5);
        let e = k.with(&shadow_volume::OPEN, 2).validate().unwrap_err();
        assert_eq!(e, "--sv-open expects 0 to 1, found 2");
        assert_eq!(
            super::super::reference::SAMPLES.check(0).unwrap(),
            format!(
                "--samples expects 1 to {} (MAX_REFERENCE_SAMPLES), found 0",
                super::super::reference::MAX_SAMPLES
            )
        );
    }

    #[test]
    fn saved_pairs_load_and_unknown_ones_are_dropped() {
        let json = r#"[["pcf-radius", 3], ["no-such-knob", 1], ["sv-open", 7]]"#;
        let mut k: Knobs = serde_json::from_str(json).unwrap();
        assert_eq!(k.get(&pcf::RADIUS), 3);
        k.drop_invalid();
        assert_eq!(k.given(&shadow_volume::OPEN.0), None);
        assert_eq!(serde_json::to_string(&k).unwrap(), r#"[["pcf-radius",3]]"#);
    }
}
