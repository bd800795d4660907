//! The FMI call-sequence fuzzer (`tests/c/fmi_fuzz.c`) against the library the FMU ships
//! (`target/<profile>/libbreathing_torso.so`, the file `torso fmu build` copies to
//! `binaries/linux64/BreathingTorso.so`), loaded with dlopen in one process.
//!
//! Always: the harness built with AddressSanitizer and UndefinedBehaviorSanitizer (gcc has
//! both). ASan replaces malloc and free for the whole process, so double frees, invalid frees
//! and leaks in the uninstrumented Rust library are caught as well as every fault in the
//! harness; the run must end with exit status 0 (every return a proper `fmi2Status`, NULL
//! instances refused with `fmi2Error`, every discard explained, no crash, no leak).
//!
//! Also, when valgrind is installed (`.ci/run` installs it): a shorter run under memcheck,
//! which checks every memory access of the library itself. Without valgrind the test prints
//! "skipped" (the sanitizer run above is the check that always happens), and fails where
//! `BT_REQUIRE_VALGRIND` is set, as `.ci/run` sets it.
//!
//! `FMI_FUZZ_SEQUENCES` and `FMI_FUZZ_CALLS` enlarge the run (defaults 40 x 200), and
//! `FMI_FUZZ_VALGRIND_SEQUENCES` the memcheck run (default 2).

use breathing_torso::fmi::table;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `target/<profile>`, holding the cdylib built with this test.
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    exe.parent()
        .and_then(Path::parent)
        .expect("target/<profile>")
        .to_path_buf()
}

fn library() -> PathBuf {
    let lib = lib_dir().join("libbreathing_torso.so");
    assert!(lib.is_file(), "no cdylib at {}", lib.display());
    lib
}

fn compile(out: &Path, sanitize: bool) {
    let mut cmd = Command::new("gcc");
    cmd.args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-O1", "-g"]);
    if sanitize {
        cmd.args(["-fsanitize=address,undefined", "-fno-omit-frame-pointer"]);
        cmd.arg("-fno-sanitize-recover=undefined");
    }
    let o = cmd
        .arg("-o")
        .arg(out)
        .arg(root().join("tests/c/fmi_fuzz.c"))
        .args(["-ldl", "-lm"])
        .output()
        .expect("gcc runs");
    assert!(
        o.status.success(),
        "gcc failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn env_count(name: &str, default: u32) -> String {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .unwrap_or(default)
        .to_string()
}

fn report(what: &str, o: &Output) -> String {
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && stdout.contains(": ok"),
        "{what} failed ({}):\n{stdout}\n{}",
        o.status,
        stderr.chars().take(20_000).collect::<String>()
    );
    println!("{what}: {}", stdout.trim());
    stdout.to_string()
}

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bt_fmi_fuzz_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

#[test]
fn random_call_sequences_under_address_sanitizer_give_proper_statuses() {
    let dir = scratch();
    let exe = dir.join("fmi_fuzz_asan");
    compile(&exe, true);
    let o = Command::new(&exe)
        .arg(library())
        .arg(table().guid())
        .arg("2011")
        .arg(env_count("FMI_FUZZ_SEQUENCES", 40))
        .arg(env_count("FMI_FUZZ_CALLS", 200))
        .env(
            "ASAN_OPTIONS",
            "detect_leaks=1:abort_on_error=0:exitcode=86",
        )
        .env("UBSAN_OPTIONS", "print_stacktrace=1:halt_on_error=1")
        .output()
        .expect("the fuzzer runs");
    let out = report("AddressSanitizer run", &o);
    // the sequences reach the working states, not only the refusals
    let ok: u64 = out
        .split("(OK ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .expect("OK count in the summary");
    assert!(ok > 500, "too few successful calls: {out}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn random_call_sequences_under_valgrind_memcheck() {
    let have_valgrind = Command::new("valgrind")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !have_valgrind {
        // CI (.ci/run) installs valgrind and sets BT_REQUIRE_VALGRIND, so there the run
        // cannot be skipped silently.
        assert!(
            std::env::var_os("BT_REQUIRE_VALGRIND").is_none(),
            "valgrind is not installed but BT_REQUIRE_VALGRIND is set: the memcheck run cannot happen"
        );
        eprintln!(
            "skipped: valgrind is not installed, so the memcheck run did not happen (the AddressSanitizer test still ran; .ci/run installs valgrind)"
        );
        return;
    }
    let dir = scratch().join("valgrind");
    std::fs::create_dir_all(&dir).expect("scratch");
    let exe = dir.join("fmi_fuzz");
    compile(&exe, false);
    let o = Command::new("valgrind")
        .args([
            "--error-exitcode=99",
            "--leak-check=full",
            "--errors-for-leak-kinds=definite",
            "--show-leak-kinds=definite",
            "-q",
        ])
        .arg(&exe)
        .arg(library())
        .arg(table().guid())
        .arg("2012")
        .arg(env_count("FMI_FUZZ_VALGRIND_SEQUENCES", 2))
        .arg(env_count("FMI_FUZZ_CALLS", 200))
        .output()
        .expect("valgrind runs");
    report("valgrind memcheck run", &o);
    std::fs::remove_dir_all(dir).ok();
}
