//! Running the `dbuffer` binary from integration tests: on lavapipe unless the caller's
//! environment names another backend, in a fresh temporary folder per case.

use std::path::PathBuf;
use std::process::Command;

/// `dbuffer`, built by cargo for this test run, on the CPU Vulkan adapter by default.
pub fn dbuffer() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dbuffer"));
    c.env(
        "WGPU_BACKEND",
        std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "vulkan".into()),
    );
    c.env("NODEVICE_SELECT", "1");
    c
}

/// An empty (not yet created) folder for one case: `suite` names the test file, `name` the case.
pub fn temp_dir(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dbuffer-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}
