//! `render::shaders` without a GPU: a shader folder's saves are accepted only whole and valid.
//! A good save reports the files it changed; a broken one is an error at the file, line and
//! column of its source with the offending line, and changes nothing; saving back what was
//! accepted is no change at all.

use std::collections::BTreeSet;
use std::path::Path;

use dbuffer::render::shaders;

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("temp folder");
    for entry in std::fs::read_dir(from).expect("shaders/") {
        let entry = entry.expect("entry");
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).expect("copy");
        }
    }
}

#[test]
fn a_folder_is_accepted_only_whole_and_valid() {
    let dir = std::env::temp_dir().join(format!("dbuffer-reload-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders"), &dir);
    shaders::set_dir(Some(&dir)).expect("a copy of shaders/ validates");
    assert_eq!(shaders::reload(), Ok(None), "nothing saved yet");

    let vsm = dir.join("methods/vsm.wgsl");
    let text = std::fs::read_to_string(&vsm).expect("vsm");
    std::fs::write(&vsm, format!("{text}// an edit\n")).expect("save");
    let reloaded = shaders::reload().expect("valid").expect("a change");
    assert_eq!(
        reloaded.changed,
        BTreeSet::from(["methods/vsm.wgsl".to_string()])
    );
    assert_eq!(reloaded.generation, shaders::generation());

    // A shared file broken: found through a shader that includes it, named at its own line.
    let hash = dir.join("shared/hash.wgsl");
    let good = std::fs::read_to_string(&hash).expect("hash");
    let broken = format!("{good}fn broken() -> f32 {{\n    return 1.0 +;\n}}\n");
    let line = broken.lines().count() as u32 - 1;
    std::fs::write(&hash, &broken).expect("save");
    let e = shaders::reload().expect_err("broken");
    assert_eq!(
        (e.file.as_str(), e.line),
        (hash.display().to_string().as_str(), line),
        "{e}"
    );
    assert_eq!(e.text.as_deref(), Some("    return 1.0 +;"), "{e}");
    assert!(e.column > 0, "{e}");
    let generation = shaders::generation();
    assert_eq!(shaders::reload(), Err(e), "still broken, still the error");
    assert_eq!(shaders::generation(), generation, "nothing accepted");

    // Saved back as it was accepted: no change, no error.
    std::fs::write(&hash, &good).expect("save");
    assert_eq!(shaders::reload(), Ok(None));

    shaders::set_dir(None).expect("the embedded shaders");
    assert_eq!(shaders::dir(), None);
    let _ = std::fs::remove_dir_all(&dir);
}
