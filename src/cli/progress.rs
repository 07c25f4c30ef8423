//! Progress of long command-line work (compare's reference, bench, animate) on stderr.
//!
//! On a terminal: one bar per job with its position, elapsed time and ETA (indicatif), replaced
//! by a one-line summary when done. Anywhere else (a log, a pipe, CI): no bar and no carriage
//! returns, but plain lines a log can use: the job and its size, each named stage, every quarter
//! of the way with the time left, and the summary.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// One job of `total` units; cheap to clone (the clones share it), so a callback can own one.
#[derive(Clone)]
pub struct Progress {
    inner: Arc<Inner>,
}

struct Inner {
    bar: Option<ProgressBar>,
    what: String,
    unit: &'static str,
    total: u64,
    start: Instant,
    /// Quarters already reported on the plain-line path (0 to 4).
    quarters: AtomicU64,
}

impl Progress {
    /// A job called `what` of `total` `unit`s (e.g. "frames"); a bar if stderr is a terminal.
    pub fn new(what: &str, total: u64, unit: &'static str) -> Progress {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
            let style = ProgressStyle::with_template(
                "{prefix:>9} [{bar:30}] {pos}/{len} {elapsed}, ETA {eta} {wide_msg:.dim}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
            bar.set_style(style);
            bar.set_prefix(what.to_string());
            bar
        });
        if bar.is_none() {
            errln!("{what}: {total} {unit}");
        }
        Progress {
            inner: Arc::new(Inner {
                bar,
                what: what.to_string(),
                unit,
                total,
                start: Instant::now(),
                quarters: AtomicU64::new(0),
            }),
        }
    }

    /// `done` of the total are done.
    pub fn set(&self, done: u64) {
        let p = &self.inner;
        match &p.bar {
            Some(bar) => bar.set_position(done),
            None => {
                let quarter = (done.min(p.total) * 4)
                    .checked_div(p.total)
                    .unwrap_or(4)
                    .min(4);
                let before = p.quarters.fetch_max(quarter, Ordering::Relaxed);
                if quarter > before && quarter < 4 {
                    let s = p.start.elapsed().as_secs_f64();
                    let left = s / done.max(1) as f64 * (p.total - done.min(p.total)) as f64;
                    errln!(
                        "{}: {}/{} {} ({} %), {s:.1} s, about {left:.0} s left",
                        p.what,
                        done,
                        p.total,
                        p.unit,
                        quarter * 25
                    );
                }
            }
        }
    }

    /// A named stage of the job: the bar's message, or a line of its own.
    pub fn stage(&self, line: &str) {
        match &self.inner.bar {
            Some(bar) => bar.set_message(line.to_string()),
            None => errln!("{}  {line}", self.inner.what),
        }
    }

    /// The job is over: the bar gives way to one summary line.
    pub fn finish(&self) {
        let p = &self.inner;
        if let Some(bar) = &p.bar {
            bar.finish_and_clear();
        }
        errln!(
            "{}: {} {} in {:.1} s",
            p.what,
            p.total,
            p.unit,
            p.start.elapsed().as_secs_f64()
        );
    }
}

/// A callback for [`dbuffer::render::offline::Offline::progress`]: the reference's samples per
/// pixel as a job of its own, started on the first report.
pub fn reference_samples() -> Box<dyn FnMut(usize, usize)> {
    let mut job: Option<Progress> = None;
    Box::new(move |done, total| {
        let p = job.get_or_insert_with(|| {
            Progress::new(
                dbuffer::render::truth::SOFT.name(),
                total as u64,
                "samples per pixel",
            )
        });
        p.set(done as u64);
        if done >= total {
            p.finish();
            job = None;
        }
    })
}
