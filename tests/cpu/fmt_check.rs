//! `scripts/fmt-check.sh`, which `scripts/test.sh` runs: rustfmt over every `.rs` file, not only
//! those `cargo fmt` reaches through `mod` lines (a module only a macro declares, like the method
//! registry's, is invisible to it).

use std::path::{Path, PathBuf};
use std::process::Command;

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/fmt-check.sh")
}

fn check(dir: &Path) -> std::process::Output {
    Command::new("bash")
        .arg(script())
        .arg(dir)
        .output()
        .expect("bash runs the script")
}

/// A module that only a macro declares, formatted and then not: the check passes on the first and
/// fails on the second, naming the file; `cargo fmt --check` on the crate would pass both.
#[test]
fn the_fmt_check_fails_on_an_unformatted_file_a_macro_declares() {
    let dir = std::env::temp_dir().join(format!("dbuffer-fmt-check-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("src")).unwrap();
    std::fs::write(
        dir.join("src/lib.rs"),
        "macro_rules! registry {\n    ($($m:ident),+) => { $(pub mod $m;)+ };\n}\n\nregistry!(hidden);\n",
    )
    .unwrap();
    let hidden = dir.join("src/hidden.rs");
    std::fs::write(&hidden, "pub fn f() -> u32 {\n    1\n}\n").unwrap();
    let clean = check(&dir);
    assert!(
        clean.status.success(),
        "{}",
        String::from_utf8_lossy(&clean.stderr)
    );

    std::fs::write(&hidden, "pub fn f()->u32{1}\n").unwrap();
    let dirty = check(&dir);
    let stderr = String::from_utf8_lossy(&dirty.stderr);
    assert!(!dirty.status.success(), "an unformatted file passed");
    assert!(stderr.contains("hidden.rs"), "{stderr}");
    assert!(!stderr.contains("lib.rs"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The repository itself passes (what `scripts/test.sh` asserts on every run).
#[test]
fn the_repository_is_formatted_everywhere() {
    let out = Command::new("bash")
        .arg(script())
        .output()
        .expect("bash runs the script");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
