//! The README's table of the quiet breath's figures is what the program prints: `torso
//! simulate --duration 20` at its defaults (the default subject, level of detail 1, the
//! quiet drive) is run, and each figure of the table's quiet column equals the program's,
//! rounded to the decimals the README gives. A figure changed by a model change fails here
//! until the README is updated with the new output.

use std::path::PathBuf;
use std::process::Command;

/// The number leading `text` (after spaces) and its count of decimals.
fn leading_number(text: &str) -> Option<(f64, usize)> {
    let t = text.trim_start();
    let end = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
        .unwrap_or(t.len());
    let n = &t[..end];
    let decimals = n.split_once('.').map_or(0, |(_, d)| d.len());
    n.parse().ok().map(|v| (v, decimals))
}

/// The quiet column (the second cell) of the README table row whose first cell is `name`.
fn readme_cell(readme: &str, name: &str) -> String {
    readme
        .lines()
        .find_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            (cells.len() > 2 && cells[1] == name).then(|| cells[2].to_string())
        })
        .unwrap_or_else(|| panic!("README.md has no table row `| {name} |`"))
}

/// The number after `label` on the line of `output` that starts with it.
fn printed(output: &str, label: &str) -> f64 {
    output
        .lines()
        .find_map(|l| l.strip_prefix(label))
        .and_then(leading_number)
        .unwrap_or_else(|| panic!("`torso simulate` printed no `{label}` line:\n{output}"))
        .0
}

#[test]
fn the_readme_quotes_what_torso_simulate_prints() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md");
    let dir = std::env::temp_dir().join(format!("readme_figures_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["simulate", "--duration", "20", "--out"])
        .arg(dir.join("simulation.csv"))
        .output()
        .expect("run torso simulate");
    let output = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "torso simulate failed:\n{output}");
    let mass = 75.0; // the default subject's [kg], as the README's table states
    let tidal = printed(&output, "tidal volume");
    // (README row, program's figure in the README's unit)
    let figures = [
        ("tidal volume", tidal),
        (
            "diaphragm excursion",
            printed(&output, "diaphragm excursion"),
        ),
        (
            "rib-cage share of displaced volume",
            printed(&output, "rib-cage share"),
        ),
        (
            "abdominal volume swing",
            printed(&output, "abdominal volume swing"),
        ),
    ];
    for (row, program) in figures {
        let cell = readme_cell(&readme, row);
        let (quoted, decimals) = leading_number(&cell)
            .unwrap_or_else(|| panic!("README row `{row}`: no figure in `{cell}`"));
        let rounded = format!("{program:.decimals$}");
        assert_eq!(
            format!("{quoted:.decimals$}"),
            rounded,
            "README row `{row}` quotes {quoted}, `torso simulate --duration 20` prints {program}:\n{output}"
        );
    }
    // The tidal volume per kilogram, in brackets after it.
    let cell = readme_cell(&readme, "tidal volume");
    let per_kg = cell
        .split_once('(')
        .and_then(|(_, rest)| leading_number(rest))
        .expect("the tidal volume's mL/kg");
    assert_eq!(
        format!("{:.*}", per_kg.1, per_kg.0),
        format!("{:.*}", per_kg.1, tidal * 1e3 / mass),
        "README's mL/kg"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
