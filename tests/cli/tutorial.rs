//! `docs/guide/tutorial.md`, run as a reader runs it: every code block, in order, in a fresh
//! folder. A `wgsl NAME` block is written to NAME; each line of an `sh` block is run (`touch`
//! makes an empty file, `dbuffer` runs the binary) and must succeed, but for the last line of
//! one followed by a `text fails` block, which must fail with each of that block's lines in its
//! output; a `text output` block's table rows must come out of the `sh` block before it with the
//! same cells, numbers free (they are one machine's). Any other kind of block is refused: the
//! page holds nothing the suite does not run. Then what the page says of the numbers: the hard
//! shadow scores as `hard` exactly, the filter brings the penumbra error down, a wider one more,
//! and the blocker-sized filter to under a quarter of the hard shadow's, near `pcss`.

use std::path::Path;

use dbuffer::compare::report::Report;

use crate::support::{self as cli, dbuffer};

const PAGE: &str = include_str!("../../docs/guide/tutorial.md");

#[derive(Debug)]
enum Block {
    File { name: String, text: String },
    Sh(Vec<String>),
    Fails(Vec<String>),
    Output(Vec<String>),
}

/// The page's fenced blocks, in order; an info string it does not know is an error.
fn blocks(page: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut lines = page.lines().enumerate();
    while let Some((at, line)) = lines.next() {
        let Some(info) = line.strip_prefix("```") else {
            continue;
        };
        let body: Vec<String> = lines
            .by_ref()
            .map(|(_, l)| l)
            .take_while(|l| !l.starts_with("```"))
            .map(str::to_string)
            .collect();
        let words: Vec<&str> = info.split_whitespace().collect();
        out.push(match words.as_slice() {
            ["wgsl", name] => Block::File {
                name: (*name).to_string(),
                text: body.iter().map(|l| format!("{l}\n")).collect(),
            },
            ["sh"] => Block::Sh(body),
            ["text", "fails"] => Block::Fails(body),
            ["text", "output"] => Block::Output(body),
            _ => panic!(
                "tutorial.md:{}: a ```{info} block: the suite runs only wgsl NAME, sh, \
                 text fails and text output blocks",
                at + 1
            ),
        });
    }
    out
}

/// The cells of a table row, trimmed.
fn cells(row: &str) -> Vec<String> {
    row.replace("\\|", "¦")
        .split('|')
        .map(|c| c.trim().to_string())
        .collect()
}

/// `expected` and `actual` are the same row but for their numbers.
fn same_row(expected: &str, actual: &str) -> bool {
    let (e, a) = (cells(expected), cells(actual));
    e.len() == a.len()
        && e.iter().zip(&a).all(|(e, a)| match e.parse::<f64>() {
            Ok(_) => a.parse::<f64>().is_ok(),
            Err(_) => e == a,
        })
}

/// Run one line of an `sh` block in `dir`: its success and its output, both streams.
fn run_line(dir: &Path, line: &str) -> (bool, String) {
    let words: Vec<&str> = line.split_whitespace().collect();
    match words.as_slice() {
        ["touch", file] => {
            std::fs::write(dir.join(file), "").expect("touch");
            (true, String::new())
        }
        ["dbuffer", args @ ..] => {
            let o = dbuffer()
                .current_dir(dir)
                .args(args)
                .output()
                .expect("the binary runs");
            let text = format!(
                "{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            );
            (o.status.success(), text)
        }
        _ => panic!("tutorial.md: `{line}`: the suite runs `touch FILE` and `dbuffer …` lines"),
    }
}

fn penumbra_mae(dir: &Path, out: &str, method: &str) -> f64 {
    let json = std::fs::read(dir.join(out).join("report.json")).expect("report.json written");
    let report: Report = serde_json::from_slice(&json).expect("report.json parses");
    report
        .methods
        .iter()
        .find(|m| m.method == method)
        .unwrap_or_else(|| panic!("{out}: no {method} row"))
        .penumbra_mae
}

#[test]
fn every_block_of_the_tutorial_runs_as_the_page_says() {
    let dir = cli::temp_dir("tutorial", "run");
    std::fs::create_dir_all(&dir).expect("temp dir made");
    let blocks = blocks(PAGE);
    assert!(blocks.len() >= 10, "the page's blocks: {blocks:?}");
    let mut ran = 0;
    for (i, block) in blocks.iter().enumerate() {
        let Block::Sh(lines) = block else {
            if let Block::File { name, text } = block {
                std::fs::write(dir.join(name), text).expect("file written");
            }
            continue;
        };
        let lines: Vec<&String> = lines
            .iter()
            .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
            .collect();
        let next = blocks.get(i + 1);
        let mut output = String::new();
        for (k, line) in lines.iter().enumerate() {
            let (ok, text) = run_line(&dir, line);
            ran += 1;
            let must_fail = k + 1 == lines.len() && matches!(next, Some(Block::Fails(_)));
            assert_eq!(!ok, must_fail, "`{line}` (must fail: {must_fail}):\n{text}");
            output.push_str(&text);
        }
        match next {
            Some(Block::Fails(expected)) => {
                for e in expected {
                    assert!(
                        output.lines().any(|l| l == e),
                        "`{}` printed no line `{e}`:\n{output}",
                        lines.last().map_or("", |l| l.as_str())
                    );
                }
            }
            Some(Block::Output(rows)) => {
                for row in rows {
                    assert!(
                        output.lines().any(|l| same_row(row, l)),
                        "no row like `{row}` in:\n{output}"
                    );
                }
            }
            _ => {}
        }
    }
    assert!(ran >= 8, "{ran} commands ran");

    // What the page says of the numbers.
    let hard = penumbra_mae(&dir, "out/step2", "hard");
    let mine_hard = penumbra_mae(&dir, "out/step2", "user-mine");
    assert_eq!(
        mine_hard.to_bits(),
        hard.to_bits(),
        "step 2 is the built-in hard shadow"
    );
    let filtered = penumbra_mae(&dir, "out/step4", "user-mine");
    let wide = penumbra_mae(&dir, "out/step4-wide", "user-mine");
    assert!(
        filtered < hard && wide < filtered,
        "{hard} > {filtered} > {wide}"
    );
    let sized = penumbra_mae(&dir, "out/step5", "user-mine");
    let pcss = penumbra_mae(&dir, "out/step5", "pcss");
    assert!(
        sized < 0.25 * hard,
        "a fifth of the hard shadow's: {sized} against {hard}"
    );
    assert!(sized < 1.5 * pcss, "near pcss: {sized} against {pcss}");
    let json = std::fs::read(dir.join("out/study/study.json")).expect("study.json written");
    let study: dbuffer::study::Study = serde_json::from_slice(&json).expect("study.json parses");
    assert!(
        study.scenes[0]
            .cells
            .iter()
            .any(|c| c.method == "user-mine" && c.error.is_some() && c.cost.is_some()),
        "the study measured the file"
    );
}
