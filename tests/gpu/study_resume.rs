//! A study stopped part-way resumes from the cells it finished: nothing measured twice, and the
//! same errors as a run that never stopped.

use dbuffer::render::offline::Offline;
use dbuffer::render::Method;
use dbuffer::study::{self, Flow, Progress, Study, StudySpec};

fn spec() -> StudySpec {
    let mut spec = StudySpec::quick();
    let pcss: Method = "pcss".parse().expect("pcss is a method");
    spec.narrow(
        Some(vec!["table1-224".into()]),
        Some(vec![Method::HARD, pcss, Method::DBUFFER]),
        Some((48, 48)),
    )
    .expect("narrowed");
    spec.samples = 16;
    spec.warmup = 0;
    spec.frames = 1;
    spec
}

fn errors(s: &Study) -> Vec<Option<u64>> {
    s.scenes[0]
        .cells
        .iter()
        .map(|c| c.error.map(|e| e.penumbra_mae.to_bits() ^ e.flip.to_bits()))
        .collect()
}

#[test]
fn a_stopped_study_resumes_from_the_cells_it_finished() {
    let offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let ctx = &offline.ctx;
    let spec = spec();
    let scene = dbuffer::scene::load("table1-224").expect("a built-in");
    let dir = std::env::temp_dir().join(format!("dbuffer-study-resume-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let cells = spec.cell_count() as usize;
    assert_eq!(cells, 9);

    // Stop once the reference and four cells' errors are done.
    let mut stop_at = |p: Progress<'_>| match p {
        Progress::Done { done, .. } if done >= 5 => Flow::Stop,
        _ => Flow::Go,
    };
    let first =
        study::run(ctx, &spec, std::slice::from_ref(&scene), &dir, &mut stop_at).expect("runs");
    assert!(first.stopped);
    let with_error = first.scenes[0]
        .cells
        .iter()
        .filter(|c| c.error.is_some())
        .count();
    assert_eq!(with_error, 4, "four errors before the stop");
    assert!(first.scenes[0].cells.iter().all(|c| c.cost.is_none()));

    // The rest: the four errors come from the cache, everything else is measured.
    let mut measured = 0;
    let mut count = |p: Progress<'_>| {
        if let Progress::Done { done, .. } = p {
            measured = done;
        }
        Flow::Go
    };
    let second =
        study::run(ctx, &spec, std::slice::from_ref(&scene), &dir, &mut count).expect("runs");
    assert!(!second.stopped);
    assert!(second.scenes[0].cells.iter().all(|c| c.complete()));
    let cached: Vec<bool> = second.scenes[0].cells.iter().map(|c| c.cached).collect();
    assert_eq!(cached.iter().filter(|&&c| c).count(), 4, "{cached:?}");
    assert_eq!(measured, 1 + 2 * cells);

    // A fresh folder, never stopped: the same errors.
    let fresh = dir.join("fresh");
    let whole = study::run(
        ctx,
        &spec,
        std::slice::from_ref(&scene),
        &fresh,
        &mut |_| Flow::Go,
    )
    .expect("runs");
    assert_eq!(errors(&whole), errors(&second));
    let _ = std::fs::remove_dir_all(&dir);
}
