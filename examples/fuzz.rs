//! The long run of the parser fuzzer (the `dbuffer-fuzzer` crate, `tests/fuzzer/`): scene TOML,
//! OBJ and glTF, in-process, structure-aware, with a counting allocator and a hang watchdog.
//!
//!     cargo run --release --example fuzz -- --execs 10000000
//!     cargo run --release --example fuzz -- --execs 1000000 --target obj --seed 7 --jobs 1
//!     cargo run --release --example fuzz -- --execs 1000000 --target gltf
//!
//! `--execs N` is the total over the targets and jobs (split evenly); `--target NAME` runs one
//! target (`scene-toml`, `obj`, `gltf`). `--jobs J` runs J
//! threads, each from its own seed (default: one less than the cores, at least 1). Every
//! failure is printed as it is found and written to `fuzz-failures/TARGET-N.bin`; the exit
//! status is 1 if there was any. Add each one to `REGRESSIONS` in `tests/cpu/fuzz_parsers.rs`.

use dbuffer_fuzzer as fuzz;

use std::time::Instant;

use fuzz::{escape, CountingAlloc, Limits, Sandbox};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

fn main() -> std::process::ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let execs: u64 = value("--execs")
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let seed: u64 = value("--seed").and_then(|v| v.parse().ok()).unwrap_or(1);
    let only = value("--target");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs: usize = value("--jobs")
        .and_then(|v| v.parse().ok())
        .unwrap_or((cores.saturating_sub(1)).max(1));
    let targets: Vec<_> = fuzz::targets()
        .into_iter()
        .filter(|t| only.as_deref().is_none_or(|o| o == t.name))
        .collect();
    if targets.is_empty() {
        eprintln!("no target named {only:?}");
        return std::process::ExitCode::FAILURE;
    }
    let per_run = execs / (targets.len() * jobs) as u64;
    let _ = std::fs::create_dir_all("fuzz-failures");
    let start = Instant::now();
    let mut total = 0u64;
    let mut failed = 0usize;
    for target in &targets {
        let t0 = Instant::now();
        let reports: Vec<_> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..jobs)
                .map(|j| {
                    s.spawn(move || {
                        let sandbox = Sandbox::new(&format!("{}-{j}", target.name));
                        let job_seed = seed.wrapping_mul(1000).wrapping_add(j as u64);
                        fuzz::fuzz(
                            target,
                            &sandbox,
                            job_seed,
                            per_run,
                            Limits::default(),
                            |f| {
                                // A glTF input is up to 256 KB: its head here, the whole
                                // in fuzz-failures/ at the end.
                                let head = &f.input[..f.input.len().min(1024)];
                                eprintln!(
                                    "FAILURE {}: {}\n  input ({} bytes): b\"{}\"{}",
                                    f.target,
                                    f.problem,
                                    f.input.len(),
                                    escape(head),
                                    if head.len() < f.input.len() {
                                        "..."
                                    } else {
                                        ""
                                    }
                                );
                            },
                        )
                    })
                })
                .collect();
            let results: Vec<_> = handles.into_iter().map(|h| h.join()).collect();
            // A panic outside the target's run (in a mutator) ends its job: say so, and fail.
            let lost = results.iter().filter(|r| r.is_err()).count();
            if lost > 0 {
                eprintln!(
                    "FAILURE {}: {lost} of {jobs} jobs panicked outside the target (a mutator)",
                    target.name
                );
                failed += lost;
            }
            results.into_iter().filter_map(Result::ok).collect()
        });
        let execs: u64 = reports.iter().map(|r| r.execs).sum();
        let outcomes = reports.iter().map(|r| r.outcomes).max().unwrap_or(0);
        let corpus: usize = reports.iter().map(|r| r.corpus).sum();
        for (k, f) in reports.iter().flat_map(|r| &r.failures).enumerate() {
            let path = format!("fuzz-failures/{}-{k}.bin", f.target);
            let _ = std::fs::write(&path, &f.input);
            failed += 1;
        }
        let secs = t0.elapsed().as_secs_f64();
        println!(
            "{:<11} {execs:>10} execs in {secs:8.1} s ({:>8.0}/s, {jobs} jobs), {outcomes} \
             distinct outcomes, corpus {corpus}, {} failures",
            target.name,
            execs as f64 / secs,
            reports.iter().map(|r| r.failures.len()).sum::<usize>()
        );
        total += execs;
    }
    println!(
        "total       {total:>10} execs in {:8.1} s, {failed} failures",
        start.elapsed().as_secs_f64()
    );
    if failed > 0 {
        std::process::ExitCode::FAILURE
    } else {
        std::process::ExitCode::SUCCESS
    }
}
