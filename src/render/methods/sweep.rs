//! What `dbuffer study` sweeps for a method: its quality knobs and the settings the default study
//! tries (docs/guide/study.md). Every method of the registry states one or the other in its
//! module — a [`Sweep`] over its quality knobs, or why it has none ([`Sweep::fixed`]) — so a new
//! method cannot join the registry without saying where it sits on the cost/error plane
//! (`tests/cli/registry.rs`).

use super::Knob;

/// One axis of a sweep: a knob of the method, or the size of its light-space maps (the
/// D-buffer's, the shadow maps': `--dbuffer-size`, not a knob of any one method).
#[derive(Clone, Copy, Debug)]
pub enum Quality {
    Knob(&'static Knob),
    MapSize,
}

/// The name a study file and the reports use for the map-size axis.
pub const MAP_SIZE_NAME: &str = "dbuffer-size";

/// The map sizes a sweep may set (the budget's `MAX_DBUFFER_SIZE`).
pub const MAP_SIZES: std::ops::RangeInclusive<u32> = 1..=crate::budget::MAX_DBUFFER_SIZE;

/// Two axes are the same when they name the same flag.
impl PartialEq for Quality {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Quality {
    /// The flag's name without dashes (`blocker-taps`, `dbuffer-size`).
    pub fn name(&self) -> &'static str {
        match self {
            Quality::Knob(k) => k.name,
            Quality::MapSize => MAP_SIZE_NAME,
        }
    }

    /// Why `value` is out of the axis's range, naming the flag; `None` when it is in range.
    pub fn check(&self, value: u32) -> Option<String> {
        match self {
            Quality::Knob(k) => k.check(value),
            Quality::MapSize if MAP_SIZES.contains(&value) => None,
            Quality::MapSize => Some(format!(
                "--{MAP_SIZE_NAME} expects {} to {} (MAX_DBUFFER_SIZE), found {value}",
                MAP_SIZES.start(),
                MAP_SIZES.end()
            )),
        }
    }
}

/// A method's place in `dbuffer study`: its quality axes and the settings of the default study
/// (each a value per axis, cheapest first), or why it has no quality knob.
#[derive(Clone, Copy, Debug)]
pub struct Sweep {
    pub axes: &'static [Quality],
    pub settings: &'static [&'static [u32]],
    /// Why the method has no setting that trades cost for quality (its one cell: its defaults).
    pub fixed: Option<&'static str>,
}

impl Sweep {
    /// Not stated: what [`super::MethodSpec::new`] starts with, refused by the registry test.
    pub const UNSTATED: Sweep = Sweep {
        axes: &[],
        settings: &[],
        fixed: None,
    };

    /// Settings over `axes`, cheapest first.
    pub const fn over(axes: &'static [Quality], settings: &'static [&'static [u32]]) -> Sweep {
        Sweep {
            axes,
            settings,
            fixed: None,
        }
    }

    /// No quality knob, for the reason `why`.
    pub const fn fixed(why: &'static str) -> Sweep {
        Sweep {
            axes: &[],
            settings: &[],
            fixed: Some(why),
        }
    }

    /// Whether the method states a sweep or why it has none.
    pub fn is_stated(&self) -> bool {
        self.fixed.is_some() || !self.settings.is_empty()
    }

    /// At most `n` of the settings, evenly spread from the cheapest to the dearest (the quick
    /// study's three).
    pub fn spread(&self, n: usize) -> Vec<&'static [u32]> {
        let all = self.settings;
        if all.len() <= n || n == 0 {
            return all.to_vec();
        }
        if n == 1 {
            return vec![all[all.len() / 2]];
        }
        (0..n)
            .map(|i| all[(i * (all.len() - 1) + (n - 1) / 2) / (n - 1)])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static AXES: [Quality; 1] = [Quality::MapSize];

    #[test]
    fn spread_keeps_both_ends_and_the_middle() {
        let sweep = Sweep::over(&AXES, &[&[1], &[2], &[3], &[4], &[5]]);
        let picked: Vec<u32> = sweep.spread(3).iter().map(|s| s[0]).collect();
        assert_eq!(picked, vec![1, 3, 5]);
        assert_eq!(sweep.spread(9).len(), 5);
        let four = Sweep::over(&AXES, &[&[1], &[2], &[3], &[4]]);
        let picked: Vec<u32> = four.spread(3).iter().map(|s| s[0]).collect();
        assert_eq!(picked, vec![1, 3, 4]);
    }

    #[test]
    fn map_size_is_checked_against_the_budget() {
        assert!(Quality::MapSize.check(1024).is_none());
        let e = Quality::MapSize.check(0).unwrap();
        assert!(e.starts_with("--dbuffer-size expects 1 to"), "{e}");
    }
}
