//! The command-line guide's knob table (`docs/guide/command-line.md`, section "Knobs") is the
//! registry's: one row per knob of [`all_knobs`], flag `--NAME`, the methods whose `knobs()`
//! hold it, its range and default as the flag writes them (with the unit of a share: `%`, `‰`
//! or `mrad`, `ppm`), and no row the registry lacks. The table is written by hand, for its
//! prose; this test keeps its facts from drifting.
//!
//! The checker is a function over the page's text and the registry's rows, and the
//! `*_catches_*` test feeds it edited tables, so each assertion here is one that can fail.

use std::collections::BTreeSet;
use std::path::PathBuf;

use dbuffer::render::methods::{all_knobs, KnobKind, ALL};

use crate::docs::cells;

/// What the table should say of one knob.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Row {
    flag: String,
    methods: BTreeSet<String>,
    min: u32,
    max: u32,
    default: u32,
    /// The units the range may be written in: none for a whole number or a switch.
    units: Vec<&'static str>,
    /// For a choice, how many options the meaning must number (`0 = …`, `1 = …`).
    choices: usize,
}

/// Every knob of the registry as a row, in registry order.
fn registry_rows() -> Vec<Row> {
    all_knobs()
        .iter()
        .map(|k| {
            let (min, max) = k.range();
            let units = match k.kind {
                KnobKind::Scaled { per: 100, .. } => vec!["%"],
                KnobKind::Scaled { per: 1000, .. } => vec!["‰", "mrad"],
                KnobKind::Scaled { per: 1_000_000, .. } => vec!["ppm"],
                KnobKind::Scaled { per, .. } => panic!(
                    "--{}: no unit is known for a share counted in 1/{per}; add one here",
                    k.name
                ),
                _ => Vec::new(),
            };
            let choices = match k.kind {
                KnobKind::Choice { choices } => choices.len(),
                _ => 0,
            };
            Row {
                flag: format!("--{}", k.name),
                methods: ALL
                    .iter()
                    .filter(|m| m.knobs().iter().any(|mk| mk.name == k.name))
                    .map(|m| m.name().to_string())
                    .collect(),
                min,
                max,
                default: k.default,
                units,
                choices,
            }
        })
        .collect()
}

/// A table row as written: its cells and its line number.
struct Written {
    line: usize,
    flag: String,
    methods: BTreeSet<String>,
    range: String,
    meaning: String,
}

/// The rows of the table under the heading `## Knobs` whose header is
/// `| flag | method | range (default) | meaning |`.
fn knob_table(page: &str) -> Result<Vec<Written>, String> {
    let lines: Vec<&str> = page.lines().collect();
    let section = lines
        .iter()
        .position(|l| l.trim() == "## Knobs")
        .ok_or("no section `## Knobs`")?;
    let header = lines[section..]
        .iter()
        .take_while(|l| !(l.starts_with("## ") && l.trim() != "## Knobs"))
        .position(|l| cells(l) == ["flag", "method", "range (default)", "meaning"])
        .map(|p| section + p)
        .ok_or("no table `| flag | method | range (default) | meaning |` in `## Knobs`")?;
    let mut rows = Vec::new();
    for (i, line) in lines
        .iter()
        .enumerate()
        .skip(header + 2)
        .take_while(|(_, l)| l.trim_start().starts_with('|'))
    {
        let c = cells(line);
        if c.len() != 4 {
            return Err(format!("line {}: {} cells: {line}", i + 1, c.len()));
        }
        rows.push(Written {
            line: i + 1,
            flag: c[0].trim_matches('`').to_string(),
            methods: c[1]
                .split(',')
                .map(|m| m.trim().trim_matches('`').to_string())
                .filter(|m| !m.is_empty())
                .collect(),
            range: c[2].clone(),
            meaning: c[3].clone(),
        });
    }
    if rows.is_empty() {
        return Err("the knob table has no rows".into());
    }
    Ok(rows)
}

/// A whole number as the page writes it, thousands maybe split by a (thin) space; what follows
/// it, trimmed.
fn number(text: &str) -> Option<(u32, &str)> {
    let text = text.trim_start();
    let end = text
        .char_indices()
        .find(|&(_, c)| !(c.is_ascii_digit() || c == ' ' || c == '\u{2009}' || c == '\u{202f}'))
        .map_or(text.len(), |(i, _)| i);
    let digits: String = text[..end].chars().filter(char::is_ascii_digit).collect();
    Some((digits.parse().ok()?, text[end..].trim()))
}

/// `MIN–MAX[ UNIT] (DEFAULT)` read as (min, max, unit, default).
fn range_cell(cell: &str) -> Option<(u32, u32, String, u32)> {
    let open = cell.rfind('(')?;
    let (default, rest) = number(&cell[open + 1..])?;
    if rest != ")" {
        return None;
    }
    let span = cell[..open].trim();
    let (lo, hi) = span.split_once('–').or_else(|| span.split_once('-'))?;
    let (min, after_min) = number(lo)?;
    let (max, unit) = number(hi)?;
    if !after_min.is_empty() {
        return None;
    }
    Some((min, max, unit.to_string(), default))
}

/// What the page's table gets wrong against `want`, one line a problem.
fn knob_table_problems(page: &str, want: &[Row]) -> Vec<String> {
    let written = match knob_table(page) {
        Ok(w) => w,
        Err(e) => return vec![e],
    };
    let mut problems = Vec::new();
    let mut seen = BTreeSet::new();
    for w in &written {
        let at = format!("line {}, {}", w.line, w.flag);
        if !seen.insert(w.flag.clone()) {
            problems.push(format!("{at}: listed twice"));
            continue;
        }
        let Some(row) = want.iter().find(|r| r.flag == w.flag) else {
            problems.push(format!("{at}: no knob of the registry has this flag"));
            continue;
        };
        if w.methods != row.methods {
            problems.push(format!(
                "{at}: methods {:?}, the registry's {:?}",
                w.methods, row.methods
            ));
        }
        match range_cell(&w.range) {
            None => problems.push(format!(
                "{at}: range `{}` is not `MIN–MAX[ UNIT] (DEFAULT)`",
                w.range
            )),
            Some((min, max, unit, default)) => {
                if (min, max, default) != (row.min, row.max, row.default) {
                    problems.push(format!(
                        "{at}: {min}–{max} ({default}), the registry's {}–{} ({})",
                        row.min, row.max, row.default
                    ));
                }
                let unit_ok = if row.units.is_empty() {
                    unit.is_empty()
                } else {
                    row.units.contains(&unit.as_str())
                };
                if !unit_ok {
                    problems.push(format!(
                        "{at}: unit `{unit}`, expected {}",
                        if row.units.is_empty() {
                            "none (a whole number)".to_string()
                        } else {
                            format!("one of {:?}", row.units)
                        }
                    ));
                }
            }
        }
        if w.meaning.is_empty() {
            problems.push(format!("{at}: no meaning"));
        }
        for i in 0..row.choices {
            if !w.meaning.contains(&format!("{i} = ")) {
                problems.push(format!("{at}: the meaning does not say what `{i} = ` is"));
            }
        }
    }
    for row in want {
        if !seen.contains(&row.flag) {
            problems.push(format!(
                "{} ({}) is missing from the table",
                row.flag,
                row.methods.iter().cloned().collect::<Vec<_>>().join(", ")
            ));
        }
    }
    problems
}

fn guide() -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/guide/command-line.md");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
}

#[test]
fn the_command_line_guides_knob_table_is_the_registry() {
    let want = registry_rows();
    assert!(want.len() > 10, "the registry has {} knobs", want.len());
    let problems = knob_table_problems(&guide(), &want);
    assert!(
        problems.is_empty(),
        "docs/guide/command-line.md, the knob table against methods::all_knobs():\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_knob_table_check_catches_each_kind_of_drift() {
    let want = vec![
        Row {
            flag: "--pcf-radius".into(),
            methods: ["pcf".to_string()].into(),
            min: 0,
            max: 8,
            default: 2,
            units: vec![],
            choices: 0,
        },
        Row {
            flag: "--vsm-bleed".into(),
            methods: ["vsm".to_string()].into(),
            min: 0,
            max: 95,
            default: 15,
            units: vec!["%"],
            choices: 0,
        },
        Row {
            flag: "--elm-pattern".into(),
            methods: ["extended-light-map".to_string()].into(),
            min: 0,
            max: 2,
            default: 0,
            units: vec![],
            choices: 3,
        },
        Row {
            flag: "--samples".into(),
            methods: ["reference".to_string(), "reference-hard".to_string()].into(),
            min: 1,
            max: 65536,
            default: 1024,
            units: vec![],
            choices: 0,
        },
    ];
    let table = |rows: &[&str]| {
        format!(
            "# Guide\n\n## Knobs\n\nIntro.\n\n| flag | method | range (default) | meaning |\n\
             |---|---|---|---|\n{}\n\nAfter.\n\n## Next\n",
            rows.join("\n")
        )
    };
    let good = [
        "| `--pcf-radius` | `pcf` | 0–8 (2) | kernel radius |",
        "| `--vsm-bleed` | `vsm` | 0–95 % (15) | bleeding |",
        "| `--elm-pattern` | `extended-light-map` | 0–2 (0) | 0 = a, 1 = b, 2 = c |",
        "| `--samples` | `reference`, `reference-hard` | 1–65 536 (1024) | K |",
    ];
    assert_eq!(
        knob_table_problems(&table(&good), &want),
        Vec::<String>::new()
    );

    // One edit at a time; each is caught, naming the flag.
    let cases: [(usize, &str, &str); 8] = [
        (
            0,
            "| `--pcf-radius` | `pcf` | 0–8 (3) | kernel radius |",
            "0–8 (3)",
        ),
        (
            0,
            "| `--pcf-radius` | `pcf` | 0–16 (2) | kernel radius |",
            "0–16 (2)",
        ),
        (
            0,
            "| `--pcf-radius` | `pcss` | 0–8 (2) | kernel radius |",
            "methods",
        ),
        (
            1,
            "| `--vsm-bleed` | `vsm` | 0–95 (15) | bleeding |",
            "unit",
        ),
        (
            1,
            "| `--vsm-bleed` | `vsm` | 0–95 % | bleeding |",
            "not `MIN–MAX",
        ),
        (
            2,
            "| `--elm-pattern` | `extended-light-map` | 0–2 (0) | 0 = a, 2 = c |",
            "`1 = `",
        ),
        (
            3,
            "| `--samples` | `reference` | 1–65 536 (1024) | K |",
            "methods",
        ),
        (
            3,
            "| `--sample` | `reference`, `reference-hard` | 1–65 536 (1024) | K |",
            "no knob",
        ),
    ];
    for (i, edited, needle) in cases {
        let mut rows = good;
        rows[i] = edited;
        let problems = knob_table_problems(&table(&rows), &want);
        assert!(
            problems.iter().any(|p| p.contains(needle)),
            "editing row {i} to {edited} should be caught ({needle}): {problems:#?}"
        );
    }

    // A row dropped, a row the registry lacks, a row twice.
    let problems = knob_table_problems(&table(&good[1..]), &want);
    assert_eq!(problems.len(), 1, "{problems:#?}");
    assert!(problems[0].contains("--pcf-radius") && problems[0].contains("missing"));
    let mut extra = good.to_vec();
    extra.push("| `--pcf-kernel` | `pcf` | 0–8 (2) | gone |");
    extra.push("| `--pcf-radius` | `pcf` | 0–8 (2) | kernel radius |");
    let problems = knob_table_problems(&table(&extra), &want);
    assert_eq!(problems.len(), 2, "{problems:#?}");
    assert!(problems[0].contains("--pcf-kernel") && problems[0].contains("no knob"));
    assert!(problems[1].contains("--pcf-radius") && problems[1].contains("twice"));

    // No section, or a section without the table.
    assert!(!knob_table_problems("# Guide\n\nno knobs here\n", &want).is_empty());
    assert!(!knob_table_problems("## Knobs\n\ntext only\n\n## Next\n", &want).is_empty());
}

#[test]
fn range_cells_read_as_the_guide_writes_them() {
    assert_eq!(
        range_cell("8–2048 (256)"),
        Some((8, 2048, String::new(), 256))
    );
    assert_eq!(
        range_cell("1–65 536 (1024)"),
        Some((1, 65536, String::new(), 1024))
    );
    assert_eq!(
        range_cell("1–1570 mrad (30)"),
        Some((1, 1570, "mrad".into(), 30))
    );
    assert_eq!(range_cell("0–1000 ‰ (50)"), Some((0, 1000, "‰".into(), 50)));
    assert_eq!(range_cell("0-1 (1)"), Some((0, 1, String::new(), 1)));
    assert_eq!(range_cell("0–1"), None);
    assert_eq!(range_cell("0 % – 1 (1)"), None);
    assert_eq!(range_cell("a–b (c)"), None);
}
