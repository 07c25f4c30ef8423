use std::sync::atomic::{AtomicU64, Ordering};

use super::*;

#[test]
fn srgb_round_trips_through_the_writer() {
    for c in 0..=255u8 {
        assert_eq!(linear_to_srgb8(srgb8_to_linear(c)), c);
    }
}

fn temp_dir(tag: &str) -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let dir = std::env::temp_dir().join(format!(
        "dbuffer-output-unit-{}-{}-{tag}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn meta(w: u32, h: u32, ds: u32) -> RenderMeta {
    RenderMeta {
        scene: "unit".into(),
        method: "dbuffer".into(),
        variant: "smoothstep".into(),
        width: w,
        height: h,
        dbuffer_size: ds,
        adapter: "none".into(),
        backend: "none".into(),
        cpu_ms: vec![("geometry".into(), 0.5)],
        gpu_ms: vec![],
        triangles: 1,
        caster_triangles: 1,
        umbra_silhouette_edges: 0,
        penumbra_silhouette_edges: 0,
        umbra_volume_triangles: 0,
        penumbra_volume_triangles: 0,
        warnings: vec![],
    }
}

fn outputs(w: u32, h: u32, ds: u32, value: f32) -> RenderOutputs {
    let n = (w * h) as usize;
    let nd = (ds * ds) as usize;
    RenderOutputs {
        width: w,
        height: h,
        color: vec![[value; 3]; n],
        visibility: vec![value; n],
        hit: vec![true; n],
        position: vec![[value; 3]; n],
        class: vec![1; n],
        dbuffer_size: ds,
        d_o: vec![value; nd],
        d_u: vec![value; nd],
        d_p: vec![value; nd],
        s_u: vec![value; nd],
        s_p: vec![value; nd],
        meta: meta(w, h, ds),
    }
}

/// Every file name → its bytes, plus the names of anything else in `dir`.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut entries: Vec<(String, Vec<u8>)> = fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let bytes = fs::read(e.path()).unwrap_or_default();
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect();
    entries.sort();
    entries
}

#[test]
fn a_dbuffer_read_in_bands_writes_the_same_files_and_reads_each_band_once_per_file() {
    // 150 texels a side: bands of 64 rows cross the 64-row blocks of the EXR encoder only
    // at their edges; values differ per texel so a misplaced row shows.
    let (w, h, ds) = (5, 3, 150u32);
    let mut out = outputs(w, h, ds, 0.5);
    let nd = (ds * ds) as usize;
    for i in 0..nd {
        let f = i as f32;
        out.d_o[i] = if i % 7 == 0 { f32::INFINITY } else { f };
        out.d_u[i] = f + 0.25;
        out.d_p[i] = f + 0.5;
        out.s_u[i] = -f;
        out.s_p[i] = f * 2.0;
    }
    let whole = temp_dir("whole");
    write_render(&whole, &out).unwrap();
    let banded = temp_dir("banded");
    let fetches = std::sync::atomic::AtomicUsize::new(0);
    let mut rows = BandedRows::new(ds, 1, |first, n| {
        fetches.fetch_add(1, Ordering::Relaxed);
        let texels = (first * ds..(first + n).min(ds) * ds)
            .map(|i| {
                let i = i as usize;
                [out.d_o[i], out.d_u[i], out.d_p[i], out.s_u[i], out.s_p[i]]
            })
            .collect();
        Ok(texels)
    });
    write_render_parts(&banded, &out.meta, &out, &mut rows).unwrap();
    for name in [DBUFFER_EXR, DBUFFER_S_EXR, VISIBILITY_EXR, POSITION_EXR] {
        let a = read_exr_rgba(&whole.join(name)).unwrap();
        let b = read_exr_rgba(&banded.join(name)).unwrap();
        assert_eq!((a.0, a.1), (b.0, b.1), "{name}");
        let same =
            a.2.iter()
                .zip(&b.2)
                .all(|(p, q)| p.iter().zip(q).all(|(x, y)| x.to_bits() == y.to_bits()));
        assert!(same, "{name} differs");
    }
    for name in [IMAGE_PNG, CLASSES_PNG, META_JSON] {
        assert_eq!(
            image_or_bytes(&whole.join(name)),
            image_or_bytes(&banded.join(name)),
            "{name}"
        );
    }
    // Three bands of 64 rows, once for each of the two D-buffer files.
    assert_eq!(fetches.load(Ordering::Relaxed), 2 * 3);
    let _ = fs::remove_dir_all(&whole);
    let _ = fs::remove_dir_all(&banded);
}

/// A PNG's pixels, or a file's bytes.
fn image_or_bytes(path: &Path) -> Vec<u8> {
    match image::open(path) {
        Ok(img) => img.into_bytes(),
        Err(_) => fs::read(path).unwrap(),
    }
}

#[test]
fn srgb_known_values() {
    assert_eq!(linear_to_srgb8(0.0), 0);
    assert_eq!(linear_to_srgb8(0.5), 188);
    assert_eq!(linear_to_srgb8(1.0), 255);
    // The linear segment: 0.002 · 12.92 · 255 = 6.59.
    assert_eq!(linear_to_srgb8(0.002), 7);
    // 0.18 (mid gray) is 118 in sRGB; gamma 2.2 would give 117.
    assert_eq!(linear_to_srgb8(0.18), 118);
    assert_eq!(linear_to_srgb8(-1.0), 0);
    assert_eq!(linear_to_srgb8(2.0), 255);
    assert_eq!(linear_to_srgb8(f32::INFINITY), 255);
    assert_eq!(linear_to_srgb8(f32::NAN), 0);
    // Monotone over the whole range.
    let mut last = 0;
    for i in 0..=1000 {
        let s = linear_to_srgb8(i as f32 / 1000.0);
        assert!(s >= last);
        last = s;
    }
}

#[test]
fn timings_are_objects_in_order_and_repeats_are_kept() {
    let mut m = meta(1, 1, 1);
    m.cpu_ms = vec![
        ("load".into(), 1.0),
        ("geometry".into(), 2.5),
        ("load".into(), 3.0),
        ("nan".into(), f64::NAN),
    ];
    let text = m.to_json_pretty().unwrap();
    let load = text.find("\"load\": 1.0").unwrap();
    let geometry = text.find("\"geometry\": 2.5").unwrap();
    let again = text.find("\"load #2\": 3.0").unwrap();
    assert!(load < geometry && geometry < again, "{text}");
    assert!(text.contains("\"nan\": null"), "{text}");
    assert!(text.contains("\"gpu_ms\": {}"), "{text}");
    assert!(text.ends_with("}\n"));
}

/// `Staged`: nothing changes before the commit; the commit replaces, adds and removes the
/// stale files; a stale file failing to go puts everything back.
#[test]
fn staged_files_are_all_or_nothing() {
    let dir = temp_dir("staged");
    for name in [
        "frame-0000.png",
        "frame-0001.png",
        "frame-0002.png",
        "notes.txt",
    ] {
        fs::write(dir.join(name), b"old").unwrap();
    }
    let before = snapshot(&dir);
    let mut staged = Staged::new(&dir).unwrap();
    staged.add("frame-0000.png", b"new0").unwrap();
    staged.add("frame-0001.png", b"new1").unwrap();
    assert!(
        staged.add("frame-0001.png", b"again").is_err(),
        "a name twice"
    );
    assert!(
        staged.add("../escape.png", b"x").is_err(),
        "a path, not a name"
    );
    staged.remove_on_commit("frame-0002.png");
    assert_eq!(
        snapshot(&dir).len(),
        before.len() + 1,
        "only the hidden folder is new"
    );
    drop(staged);
    assert_eq!(snapshot(&dir), before, "dropped without commit: untouched");

    let mut staged = Staged::new(&dir).unwrap();
    staged.add("frame-0000.png", b"new0").unwrap();
    staged.add("frame-0001.png", b"new1").unwrap();
    staged.add("loop.png", b"anim").unwrap();
    staged.remove_on_commit("frame-0002.png");
    staged.remove_on_commit("frame-0009.png");
    let paths = staged.commit().unwrap();
    assert_eq!(paths.len(), 3);
    let after = snapshot(&dir);
    let names: Vec<&str> = after.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        ["frame-0000.png", "frame-0001.png", "loop.png", "notes.txt"]
    );
    assert_eq!(fs::read(dir.join("frame-0001.png")).unwrap(), b"new1");

    // A failing removal of a stale file undoes the installs (the generic install with a
    // fault at the last step).
    let before = snapshot(&dir);
    let temp = create_temp_dir(&dir).unwrap();
    fs::write(temp.join("frame-0000.png"), b"newer").unwrap();
    let names = vec!["frame-0000.png".to_string()];
    let stale = vec!["frame-0001.png".to_string()];
    let err = finish(&dir, temp, &names, &stale, &mut |step| {
        if step == Step::Install(1) {
            Err(io::Error::other("injected"))
        } else {
            Ok(())
        }
    })
    .unwrap_err();
    assert!(err.to_string().contains("frame-0001.png"), "{err}");
    assert_eq!(snapshot(&dir), before);
    let _ = fs::remove_dir_all(&dir);
}

/// A failure at any point of writing leaves the folder as it was, with no temporary folder,
/// both when the folder held a previous render and when it held only unrelated files.
#[test]
fn a_failure_at_any_step_leaves_the_folder_as_it_was() {
    let steps: Vec<Step> = (0..FILE_NAMES.len())
        .flat_map(|i| [Step::Stage(i), Step::Backup(i), Step::Install(i)])
        .collect();
    for previous in [true, false] {
        let dir = temp_dir("fault");
        fs::write(dir.join("notes.txt"), b"keep me").unwrap();
        if previous {
            write_render(&dir, &outputs(3, 2, 2, 0.25)).unwrap();
        }
        let before = snapshot(&dir);
        for &fail_at in &steps {
            let mut seen = false;
            let result = write_render_with(&dir, &outputs(3, 2, 2, 0.75), &mut |step| {
                if step == fail_at {
                    seen = true;
                    Err(io::Error::other("injected"))
                } else {
                    Ok(())
                }
            });
            // Backups happen only when there is a previous file.
            let reachable = previous || !matches!(fail_at, Step::Backup(_));
            assert_eq!(seen, reachable, "{fail_at:?}");
            if !reachable {
                result.unwrap();
                for name in FILE_NAMES {
                    fs::remove_file(dir.join(name)).unwrap();
                }
                continue;
            }
            let err = result.unwrap_err();
            let msg = err.to_string();
            assert!(msg.contains("injected"), "{fail_at:?}: {msg}");
            let i = match fail_at {
                Step::Stage(i) | Step::Backup(i) | Step::Install(i) => i,
            };
            assert!(msg.contains(FILE_NAMES[i]), "{fail_at:?}: {msg}");
            assert!(
                matches!(err, OutputError::Io { .. }),
                "{fail_at:?}: {err:?}"
            );
            assert_eq!(snapshot(&dir), before, "{fail_at:?}, previous {previous}");
        }
        // And with no failure the new render replaces the old one completely.
        write_render(&dir, &outputs(3, 2, 2, 0.75)).unwrap();
        let after = snapshot(&dir);
        let names: Vec<&str> = after.iter().map(|(n, _)| n.as_str()).collect();
        let mut expected: Vec<&str> = FILE_NAMES.to_vec();
        expected.push("notes.txt");
        expected.sort();
        assert_eq!(names, expected);
        let (_, _, v) = read_exr_rgba(&dir.join(VISIBILITY_EXR)).unwrap();
        assert!(v.iter().all(|p| p[0] == 0.75));
        let _ = fs::remove_dir_all(&dir);
    }
}

/// A folder made for the render (with its missing parents) is taken away again when
/// writing fails at any step, and made only once the outputs are checked.
#[test]
fn a_new_folder_is_not_left_behind_after_a_failure() {
    let base = temp_dir("new-dir");
    let dir = base.join("a").join("b");
    for fail_at in [Step::Stage(0), Step::Stage(6), Step::Install(3)] {
        let result = write_render_with(&dir, &outputs(3, 2, 2, 0.5), &mut |step| {
            if step == fail_at {
                Err(io::Error::other("injected"))
            } else {
                Ok(())
            }
        });
        assert!(result.is_err(), "{fail_at:?}");
        assert!(
            !base.join("a").exists(),
            "{fail_at:?} left {}",
            dir.display()
        );
    }
    // Outputs that fail their checks create nothing at all.
    let mut bad = outputs(3, 2, 2, 0.5);
    bad.visibility.pop();
    assert!(write_render(&dir, &bad).is_err());
    assert!(!base.join("a").exists());
    // A folder that was there before stays.
    fs::create_dir_all(&dir).unwrap();
    let result = write_render_with(&dir, &outputs(3, 2, 2, 0.5), &mut |step| match step {
        Step::Stage(0) => Err(io::Error::other("injected")),
        _ => Ok(()),
    });
    assert!(result.is_err() && dir.is_dir());
    let _ = fs::remove_dir_all(&base);
}

/// Output targets are checked before any work: a file where the folder should be, a
/// folder under a file, a place nothing can be created in, a device or FIFO as a file.
#[test]
fn output_targets_are_checked_up_front() {
    let base = temp_dir("targets");
    let file = base.join("file.txt");
    fs::write(&file, b"x").unwrap();
    let e = check_out_dir(&file, &FILE_NAMES).unwrap_err();
    assert!(matches!(e, OutputError::NotADirectory { .. }), "{e:?}");
    assert!(e.to_string().contains("a regular file"), "{e}");
    let e = check_out_dir(&file.join("sub"), &FILE_NAMES).unwrap_err();
    assert!(e.to_string().contains("file.txt"), "{e}");
    check_out_dir(&base.join("new").join("deeper"), &FILE_NAMES).unwrap();
    assert!(!base.join("new").exists(), "checking creates nothing");
    #[cfg(target_os = "linux")]
    {
        // /proc takes no new entries, whoever asks (root included).
        let e = check_out_dir(Path::new("/proc/dbuffer-out"), &FILE_NAMES).unwrap_err();
        assert!(matches!(e, OutputError::Unwritable { .. }), "{e:?}");
        let e = check_out_file(Path::new("/dev/null")).unwrap_err();
        assert!(e.to_string().contains("never replaced"), "{e}");
        // Named exactly, as reading names it (one `kind_of`): not "a device, FIFO or socket".
        assert!(
            e.to_string()
                .contains("it is a character device, not a regular file"),
            "{e}"
        );
        // An output folder under a device is refused for what stands in the way.
        let e = check_out_dir(&Path::new("/dev/null").join("out"), &FILE_NAMES).unwrap_err();
        assert!(matches!(e, OutputError::NotADirectory { .. }), "{e:?}");
        assert!(
            e.to_string()
                .contains("is a character device, not a directory"),
            "{e}"
        );
    }
    check_out_file(&file).unwrap();
    check_out_file(&base.join("new.png")).unwrap();
    let e = check_out_file(&base.join("missing").join("x.png")).unwrap_err();
    assert!(e.to_string().contains("missing"), "{e}");
    let e = check_out_file(&base).unwrap_err();
    assert!(matches!(e, OutputError::TargetIsDirectory { .. }), "{e:?}");
    let leftovers: Vec<_> = fs::read_dir(&base)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("probe"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let _ = fs::remove_dir_all(&base);
}
