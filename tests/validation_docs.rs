//! The shell examples of docs/validation.md run as written, in order, from an empty
//! directory with the built `torso` first on the PATH: every `sh` block succeeds and every
//! `torso validate --out DIR` in them writes its report. This is what a user following the
//! page does: the simulation's `volume.lung` column and the fit's `<stem>_lung_volume.csv`
//! are read as written by `torso simulate` and `torso fit`.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The fenced `sh` blocks of a Markdown text.
fn sh_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match &mut current {
            None if line.trim() == "```sh" => current = Some(String::new()),
            Some(b) if line.trim() == "```" => {
                blocks.push(std::mem::take(b));
                current = None;
            }
            Some(b) => {
                b.push_str(line);
                b.push('\n');
            }
            None => {}
        }
    }
    blocks
}

/// Output directories of the `torso validate` commands of a block.
fn validate_outputs(block: &str) -> Vec<String> {
    block
        .lines()
        .filter(|l| l.trim_start().starts_with("torso validate"))
        .filter_map(|l| {
            let words: Vec<&str> = l.split_whitespace().collect();
            words
                .iter()
                .position(|w| *w == "--out")
                .and_then(|i| words.get(i + 1))
                .map(|s| s.to_string())
        })
        .collect()
}

#[test]
fn validation_page_examples_run_as_written() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("docs/validation.md")).expect("read docs");
    let blocks = sh_blocks(&text);
    assert!(
        blocks.len() >= 2,
        "expected the simulation and the fit examples, found {} sh blocks",
        blocks.len()
    );
    let dir = std::env::temp_dir().join(format!("validation_docs_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_torso"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut reports = 0;
    for block in &blocks {
        let out = Command::new("bash")
            .args(["-euo", "pipefail", "-c", block])
            .env("PATH", &path)
            .current_dir(&dir)
            .output()
            .expect("run bash");
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "docs/validation.md block failed:\n{block}\n--- output ---\n{text}"
        );
        for o in validate_outputs(block) {
            for f in ["validation.json", "summary.md", "bland_altman.png"] {
                let p = dir.join(&o).join(f);
                assert!(
                    p.metadata().map(|m| m.len() > 0).unwrap_or(false),
                    "{} missing after:\n{block}",
                    p.display()
                );
            }
            reports += 1;
        }
    }
    assert!(
        reports >= 3,
        "only {reports} validation reports in the page"
    );
    // The fit example compared the fitted lung volume with the truth: it must agree closely.
    let v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("validation-fit/validation.json")).unwrap(),
    )
    .unwrap();
    let r = v["pearson"]["r"].as_f64().expect("pearson r");
    assert!(r > 0.99, "fitted against true lung volume: r = {r}");
    let _ = std::fs::remove_dir_all(&dir);
}
