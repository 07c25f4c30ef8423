//! `compare --reference gpu|cpu`: which engine traces the reference's shadow rays, said in the
//! report; a name that is neither is refused before any work.

use crate::support::{dbuffer, run_ok, temp_dir};

#[test]
fn the_reference_is_traced_on_the_engine_asked_and_the_report_says_which() {
    for engine in ["gpu", "cpu"] {
        let out = temp_dir("compare_reference", engine);
        let o = run_ok(
            &[
                "compare",
                "fig7-concave",
                "--size",
                "32x24",
                "--samples",
                "16",
                "--methods",
                "hard",
                "--reference",
                engine,
            ],
            &out,
        );
        let stdout = String::from_utf8_lossy(&o.stdout);
        let upper = engine.to_uppercase();
        assert!(
            stdout.contains(&format!("M rays/s on the {upper}")),
            "{stdout}"
        );
        let json = std::fs::read_to_string(out.join("report.json")).unwrap_or_default();
        let report: dbuffer::compare::report::Report =
            serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(report.reference, engine);
        let md = std::fs::read_to_string(out.join("report.md")).unwrap_or_default();
        assert!(md.contains(&format!("on the {upper})")), "{md}");
        let _ = std::fs::remove_dir_all(&out);
    }
}

#[test]
fn an_unknown_engine_is_refused_before_any_work() {
    let out = temp_dir("compare_reference", "unknown");
    let o = dbuffer()
        .args(["compare", "fig7-concave", "--reference", "rtx", "--out"])
        .arg(&out)
        .output()
        .expect("the binary runs");
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("--reference expects cpu or gpu, found 'rtx'"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing written");
}
