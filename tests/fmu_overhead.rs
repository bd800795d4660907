//! The FMU-overhead harness (`benches/c/fmu_overhead.c`, run for figures by
//! `scripts/bench-fmu-overhead.sh`) built against the official FMI 2.0 headers (fmpy's
//! `c-code/`) and run briefly on the library the FMU ships: the FMI calls and the C ABI run
//! the same scene in one process, and the last step's four volumes and 60 markers (184
//! values) must be identical, bit for bit, both ways, with the Dormand-Prince and with the
//! quasi-static method. The harness's timings are printed, not checked (machines are shared).

use breathing_torso::fmi::table;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `fmpy/c-code` inside the project's venv (made by scripts/python-env.sh).
fn official_headers() -> Option<PathBuf> {
    std::fs::read_dir(root().join(".venv/lib"))
        .ok()?
        .filter_map(|e| e.ok())
        .map(|e| e.path().join("site-packages/fmpy/c-code"))
        .find(|p| p.join("fmi2FunctionTypes.h").is_file())
}

/// `target/<profile>/libbreathing_torso.so`, built with this test.
fn library() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let lib = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>")
        .join("libbreathing_torso.so");
    assert!(lib.is_file(), "no cdylib at {}", lib.display());
    lib
}

#[test]
fn fmi_and_c_abi_read_the_same_values_bit_for_bit() {
    let Some(headers) = official_headers() else {
        println!(
            "SKIPPED: no .venv with fmpy (run scripts/python-env.sh, as scripts/test.sh does)"
        );
        return;
    };
    let dir = std::env::temp_dir().join(format!("bt_fmu_overhead_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("fmu_overhead");
    let o = Command::new("gcc")
        .args([
            "-std=c11",
            "-D_POSIX_C_SOURCE=199309L",
            "-Wall",
            "-Wextra",
            "-Werror",
        ])
        .arg("-O2")
        .arg("-I")
        .arg(&headers)
        .arg("-o")
        .arg(&exe)
        .arg(root().join("benches/c/fmu_overhead.c"))
        .arg("-ldl")
        .output()
        .expect("gcc runs");
    assert!(
        o.status.success(),
        "gcc failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // 0: Dormand-Prince on the inertial model; 4: quasi-static
    for method in ["0", "4"] {
        let o = Command::new(&exe)
            .arg(library())
            .arg(table().guid())
            .args(["40", "1", method])
            .output()
            .expect("harness runs");
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success() && stdout.contains("identical, bit for bit"),
            "method {method}: {}\n{stdout}\n{}",
            o.status,
            String::from_utf8_lossy(&o.stderr)
        );
        println!("{stdout}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
