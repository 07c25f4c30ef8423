//! Ground truth: what every other method is measured against, asked in one place. Two methods
//! are true by construction: `reference` (the soft shadow, rays to K stratified samples of the
//! light per pixel, converging as samples are added) and `reference-hard` (the exact hard shadow,
//! one ray per pixel to the light's centre). The session, the lab's view session, `compare`,
//! `bench`, `study` and the command line ask this module which method is which truth, whether a
//! method is one, how many samples the knobs ask of it and how it is cast, instead of comparing
//! methods by identity themselves.

use super::methods::{Knobs, Method};

/// A kind of ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Truth {
    /// The soft shadow of the whole light: `reference`, K samples per pixel, progressive.
    Soft,
    /// The hard shadow from the light's centre: `reference-hard`, one ray per pixel.
    Hard,
}

/// The method that renders the soft truth.
pub const SOFT: Method = Method::REFERENCE;
/// The method that renders the hard truth.
pub const HARD: Method = Method::REFERENCE_HARD;

/// K, the light samples per pixel of the soft truth (a knob of `reference`).
pub use super::methods::reference::SAMPLES;

impl Truth {
    /// The truth `method` is, if it is one.
    pub fn of(method: Method) -> Option<Truth> {
        if method == SOFT {
            Some(Truth::Soft)
        } else if method == HARD {
            Some(Truth::Hard)
        } else {
            None
        }
    }

    /// The truth `method` is scored against: the hard one for a method that makes a hard
    /// shadow from the light's centre, else the soft one.
    pub fn against(method: Method) -> Truth {
        if method.is_hard() {
            Truth::Hard
        } else {
            Truth::Soft
        }
    }

    /// The method that renders it.
    pub fn method(self) -> Method {
        match self {
            Truth::Soft => SOFT,
            Truth::Hard => HARD,
        }
    }

    /// Whether it converges over many samples (and so is shown as it converges).
    pub fn progressive(self) -> bool {
        self == Truth::Soft
    }
}

/// Whether `method` is either truth.
pub fn is_truth(method: Method) -> bool {
    Truth::of(method).is_some()
}

/// Whether `method` is the soft truth.
pub fn is_soft(method: Method) -> bool {
    Truth::of(method) == Some(Truth::Soft)
}

/// Whether `method` is the hard truth.
pub fn is_hard(method: Method) -> bool {
    Truth::of(method) == Some(Truth::Hard)
}

/// The soft truth's samples per pixel as `knobs` ask.
pub fn samples(knobs: &Knobs) -> u32 {
    knobs.get(&SAMPLES)
}

/// `knobs` asking the soft truth for `samples` per pixel.
pub fn with_samples(knobs: Knobs, samples: u32) -> Knobs {
    knobs.with(&SAMPLES, samples)
}

/// Which engine traces the soft truth's shadow rays: the CPU's oracle (the default, the
/// independent one) or the GPU's tracer (`render::gpu_reference`), from the same points to the
/// same samples (`compare --reference cpu|gpu`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Engine {
    #[default]
    Cpu,
    Gpu,
}

impl Engine {
    /// `cpu` or `gpu`, as `--reference` takes it.
    pub fn name(self) -> &'static str {
        match self {
            Engine::Cpu => "cpu",
            Engine::Gpu => "gpu",
        }
    }
}

impl std::str::FromStr for Engine {
    type Err = String;

    fn from_str(s: &str) -> Result<Engine, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cpu" => Ok(Engine::Cpu),
            "gpu" => Ok(Engine::Gpu),
            _ => Err(format!("--reference expects cpu or gpu, found '{s}'")),
        }
    }
}

impl std::fmt::Display for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What casting the soft truth's rays for a frame cost.
pub struct Cast {
    /// Milliseconds of the whole cast (primary rays and BVH included).
    pub ms: f64,
    /// Milliseconds of shadow rays alone.
    pub rays_ms: f64,
    /// Samples per pixel.
    pub samples: u32,
    /// Pixels that show a surface (each got every sample's ray).
    pub hit_pixels: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_references_are_the_two_truths_and_nothing_else_is() {
        assert_eq!(Truth::of(SOFT), Some(Truth::Soft));
        assert_eq!(Truth::of(HARD), Some(Truth::Hard));
        assert_eq!(Truth::Soft.method(), SOFT);
        assert_eq!(Truth::Hard.method(), HARD);
        let truths = Method::all().iter().filter(|m| is_truth(**m)).count();
        assert_eq!(truths, 2);
        assert_eq!(Truth::against(Method::HARD), Truth::Hard);
        assert_eq!(Truth::against(Method::DBUFFER), Truth::Soft);
        assert_eq!(samples(&with_samples(Knobs::default(), 7)), 7);
    }

    #[test]
    fn engines_parse_by_name() {
        assert_eq!("cpu".parse(), Ok(Engine::Cpu));
        assert_eq!(" GPU".parse(), Ok(Engine::Gpu));
        assert!("rtx"
            .parse::<Engine>()
            .is_err_and(|e| e.contains("cpu or gpu")));
        assert_eq!(Engine::default(), Engine::Cpu);
        assert_eq!(Engine::Gpu.to_string(), "gpu");
    }
}
