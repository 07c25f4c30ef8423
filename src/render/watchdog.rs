//! A watchdog for GPU work that does not end: a shader whose loop never exits blocks the
//! thread that waits for it (in `queue.submit` on drivers that finish the previous work first,
//! as lavapipe 22.3 does, or in the wait for a readback), and a command line would hang
//! without a word. Work the render core waits for is wrapped in a [`Watch`]; a command that
//! [`start`]s the watchdog is stopped by it, with a message naming the work, once a watch is
//! older than [`gpu_timeout`]. The lab starts none: a stalled frame there ends when the driver
//! ends it, and the next frame reports a lost device.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

static STARTED: AtomicBool = AtomicBool::new(false);
static NEXT: AtomicU64 = AtomicU64::new(0);
/// The open watches: (id, since, what).
static OPEN: Mutex<Vec<(u64, Instant, String)>> = Mutex::new(Vec::new());

/// GPU work being waited for; dropped when the wait is over.
#[must_use = "a watch covers the work until it is dropped"]
pub struct Watch(Option<u64>);

/// Watch the work `what` names (made only where a watchdog runs) until the guard is dropped.
pub fn watch(what: impl FnOnce() -> String) -> Watch {
    if !STARTED.load(Ordering::Relaxed) {
        return Watch(None);
    }
    let id = NEXT.fetch_add(1, Ordering::Relaxed);
    if let Ok(mut open) = OPEN.lock() {
        open.push((id, Instant::now(), what()));
    }
    Watch(Some(id))
}

impl Drop for Watch {
    fn drop(&mut self) {
        if let (Some(id), Ok(mut open)) = (self.0, OPEN.lock()) {
            open.retain(|(i, _, _)| *i != id);
        }
    }
}

/// The oldest open watch older than `limit`, if any: what it watches and for how long.
pub fn overdue(limit: Duration) -> Option<(String, Duration)> {
    let open = OPEN.lock().ok()?;
    open.iter()
        .map(|(_, since, what)| (what, since.elapsed()))
        .filter(|(_, age)| *age > limit)
        .max_by_key(|(_, age)| *age)
        .map(|(what, age)| (what.clone(), age))
}

/// The message for work that did not end within `limit`.
pub fn stall_message(what: &str, limit: Duration) -> String {
    format!(
        "{what}: the GPU did not finish it within {} s ({GPU_TIMEOUT_ENV} sets the limit): a \
         shader that does not end, such as a loop whose exit is never taken, or work too large \
         for this device",
        limit.as_secs_f64()
    )
}

/// Start the watchdog (once; later calls do nothing): a thread that calls `stop` with
/// [`stall_message`] once a watch is older than [`gpu_timeout`]. `stop` ends the process: the
/// stalled thread cannot be woken.
pub fn start(stop: fn(&str) -> !) {
    if STARTED.swap(true, Ordering::SeqCst) {
        return;
    }
    let limit = gpu_timeout();
    let tick = (limit / 8).clamp(Duration::from_millis(10), Duration::from_millis(250));
    let spawned = std::thread::Builder::new()
        .name("gpu-watchdog".into())
        .spawn(move || loop {
            std::thread::sleep(tick);
            if let Some((what, _)) = overdue(limit) {
                stop(&stall_message(&what, limit));
            }
        });
    if spawned.is_err() {
        STARTED.store(false, Ordering::SeqCst);
    }
}

/// The variable that sets [`gpu_timeout`] in seconds.
pub const GPU_TIMEOUT_ENV: &str = "DBUFFER_GPU_TIMEOUT_S";

/// The longest a blocking wait for the GPU may take: 120 s, or [`GPU_TIMEOUT_ENV`]'s seconds
/// (a positive number; anything else keeps the default). Far above any frame dbuffer draws at
/// its largest sizes on a CPU rasteriser; a wait longer than this is a stuck device.
pub fn gpu_timeout() -> std::time::Duration {
    static TIMEOUT: std::sync::OnceLock<std::time::Duration> = std::sync::OnceLock::new();
    *TIMEOUT.get_or_init(|| {
        std::env::var(GPU_TIMEOUT_ENV)
            .ok()
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|s| s.is_finite() && *s > 0.0)
            .map_or(std::time::Duration::from_secs(120), |s| {
                std::time::Duration::from_secs_f64(s.min(86_400.0))
            })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_watch_is_overdue_past_its_limit_and_gone_when_dropped() {
        STARTED.store(true, Ordering::SeqCst);
        let w = watch(|| "a frame of user-test".into());
        assert!(overdue(Duration::from_secs(3600)).is_none());
        let (what, _) = overdue(Duration::ZERO).expect("older than nothing");
        assert_eq!(what, "a frame of user-test");
        drop(w);
        assert!(overdue(Duration::ZERO).is_none_or(|(w, _)| w != "a frame of user-test"));
        let m = stall_message("a frame of user-x", Duration::from_secs(2));
        assert!(m.starts_with("a frame of user-x: the GPU did not finish it within 2 s"));
        assert!(m.contains(GPU_TIMEOUT_ENV));
    }
}
