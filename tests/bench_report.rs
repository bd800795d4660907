//! `torso bench report --quick` writes the report's structure: the stamp (commit, tree, date,
//! CPU, cores, load, run time), every section with a table, every table cell a number, a
//! command or one of the few words the tables use, and each table row with the command that
//! reproduces it. The timings themselves are not checked (the machine is shared).

use breathing_torso::cli::bench_report::SECTIONS;
use std::process::Command;

/// The rows of the markdown tables of `text` (header and separator rows included), as cells.
fn table_rows(text: &str) -> Vec<Vec<String>> {
    text.lines()
        .filter(|l| l.starts_with('|') && l.ends_with('|'))
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect()
}

/// Whether `cell` is a figure: a number, a pair "a / b" of numbers, or "-" (no figure).
fn is_figure(cell: &str) -> bool {
    cell == "-"
        || cell.parse::<f64>().is_ok_and(f64::is_finite)
        || cell
            .split(" / ")
            .all(|p| p.parse::<f64>().is_ok_and(f64::is_finite))
}

#[test]
fn quick_report_has_the_stamp_every_section_and_numeric_tables() {
    let dir = std::env::temp_dir().join(format!("bench_report_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("BENCHMARKS.md");
    let run = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["bench", "report", "--quick", "--out"])
        .arg(&out)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("torso bench report runs");
    assert!(
        run.status.success(),
        "torso bench report --quick failed:\n{}\n{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&out).expect("report written");
    assert!(text.starts_with("# Benchmarks\n"), "{text}");
    assert!(text.contains("**Quick run**"), "a quick report says so");

    // the stamp: the first table, one row under its header
    let stamp_header =
        "| commit | tree | date | CPU | cores | load average at start / end | run time [s] |";
    let at = text.find(stamp_header).expect("stamp table");
    let row = table_rows(&text[at..])[2].clone();
    let commit = &row[0];
    assert!(
        commit == "unknown" || (commit.len() >= 7 && commit.chars().all(|c| c.is_ascii_hexdigit())),
        "commit `{commit}`"
    );
    assert!(
        ["clean", "uncommitted changes", "unknown"].contains(&row[1].as_str()),
        "tree `{}`",
        row[1]
    );
    let date = &row[2];
    assert!(
        date.len() == "2026-01-31 12:00 UTC".len()
            && date.ends_with(" UTC")
            && date[..4].parse::<u32>().is_ok_and(|y| y >= 2024),
        "date `{date}`"
    );
    assert!(!row[3].is_empty(), "CPU model");
    assert!(
        row[4].parse::<usize>().is_ok_and(|n| n >= 1),
        "cores `{}`",
        row[4]
    );
    assert!(
        row[5]
            .split(" / ")
            .all(|l| l == "unknown" || l.parse::<f64>().is_ok()),
        "load `{}`",
        row[5]
    );
    assert!(
        row[6].parse::<f64>().is_ok_and(|s| s >= 0.0),
        "run time `{}`",
        row[6]
    );

    // every section, in order, each with a table whose rows carry figures and a command
    let mut last = 0;
    let words = ["dopri5", "quasi-static", "yes", "no"];
    for (i, name) in SECTIONS.iter().enumerate() {
        let heading = format!("\n## {name}\n");
        let start = text
            .find(&heading)
            .unwrap_or_else(|| panic!("section `{name}` missing"));
        assert!(start > last, "section `{name}` out of order");
        last = start;
        let end = SECTIONS
            .get(i + 1)
            .and_then(|n| text.find(&format!("\n## {n}\n")))
            .or_else(|| text.find("\n## Not in this run"))
            .expect("a section follows");
        let rows = table_rows(&text[start..end]);
        assert!(rows.len() >= 3, "section `{name}` has no table");
        let mut figures = 0;
        let mut commands = 0;
        for row in rows.iter().filter(|r| !r[0].starts_with("---")) {
            // header rows name columns; data rows start with a figure or a solver's name
            if !(is_figure(&row[0]) || words.contains(&row[0].as_str())) {
                continue;
            }
            for cell in row {
                if cell.starts_with('`') {
                    assert!(
                        cell.starts_with("`torso "),
                        "section `{name}`: command `{cell}`"
                    );
                    commands += 1;
                } else {
                    assert!(
                        is_figure(cell) || words.contains(&cell.as_str()),
                        "section `{name}`: cell `{cell}` is neither a figure nor a command"
                    );
                    figures += usize::from(is_figure(cell));
                }
            }
        }
        assert!(figures > 0, "section `{name}`: no figures");
        assert!(
            commands > 0,
            "section `{name}`: no command beside its table"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
