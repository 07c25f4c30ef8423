//! Running the `dbuffer` binary from integration tests: on lavapipe unless the caller's
//! environment names another backend, in a fresh temporary folder per case.

use std::path::{Path, PathBuf};
use std::process::Command;

/// `dbuffer`, built by cargo for this test run (or the binary `DBUFFER_TEST_BIN` names, to
/// check that a test fails on an older build), on the CPU Vulkan adapter by default.
pub fn dbuffer() -> Command {
    let bin = std::env::var_os("DBUFFER_TEST_BIN")
        .unwrap_or_else(|| env!("CARGO_BIN_EXE_dbuffer").into());
    let mut c = Command::new(bin);
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

/// `dbuffer ARGS --out OUT`, which must succeed (its stderr in the failure): its output.
pub fn run_ok(args: &[&str], out: &Path) -> std::process::Output {
    let o = dbuffer()
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("the binary runs");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}
