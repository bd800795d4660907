//! The README's C route as a user takes it: the shell block of its "FMU and C library"
//! section (build the library, compile `examples/capi_breathe.c` with a run path, run it) is
//! taken out of README.md and run as written by `bash` in the repository's root, with no
//! `LD_LIBRARY_PATH`; the program must run its breath and its bit-identical replay.

use std::path::PathBuf;
use std::process::Command;

/// The fenced ```sh blocks of a Markdown text, in order.
fn shell_blocks(markdown: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in markdown.lines() {
        match current.as_mut() {
            None if line.trim_end() == "```sh" => current = Some(String::new()),
            None => {}
            Some(_) if line.trim_end() == "```" => blocks.push(current.take().unwrap()),
            Some(block) => {
                block.push_str(line);
                block.push('\n');
            }
        }
    }
    assert!(current.is_none(), "README.md: a ```sh block is not closed");
    blocks
}

#[test]
fn readme_c_example_builds_and_runs_as_written() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).expect("read README.md");
    let blocks: Vec<String> = shell_blocks(&readme)
        .into_iter()
        .filter(|b| b.contains("-lbreathing_torso"))
        .collect();
    assert_eq!(
        blocks.len(),
        1,
        "README.md should hold exactly one ```sh block linking -lbreathing_torso"
    );
    let script = &blocks[0];
    assert!(
        script.starts_with("cargo build --release\n"),
        "the README's C block builds the library first:\n{script}"
    );
    let out = Command::new("bash")
        .args(["-euo", "pipefail", "-c", script])
        .current_dir(&root)
        .env_remove("LD_LIBRARY_PATH")
        .env_remove("CARGO_TARGET_DIR")
        .output()
        .expect("run bash");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the README's C block failed ({}):\n{script}\nstdout:\n{stdout}\nstderr:\n{stderr}",
        out.status
    );
    assert!(
        stdout.contains("replay identical") && stdout.contains("rhs consistent"),
        "capi_breathe output:\n{stdout}"
    );
}
