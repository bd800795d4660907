//! The `torso bench` commands on tiny workloads: they run, and what they write is complete
//! and consistent (JSON fields, one CSV row per method and tolerance, a PNG plot).

use std::path::PathBuf;
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("torso-bench-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

fn torso(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(args)
        .output()
        .expect("torso runs");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "torso {args:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn bench_core_writes_consistent_json() {
    let dir = scratch("core");
    let json = dir.join("core.json");
    let stdout = torso(&[
        "bench",
        "core",
        "--frames",
        "28",
        "--repeats",
        "1",
        "--lod",
        "0",
        "--rhs-calls",
        "5",
        "--json",
        json.to_str().expect("utf-8 path"),
    ]);
    assert!(stdout.contains("ratio (60 markers / volumes only)"));
    assert!(stdout.contains("ratio (whole skin / volumes only)"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json written"))
            .expect("valid JSON");
    let volumes = &v["volumes"];
    let markers = &v["markers"];
    assert_eq!(volumes["frames"], 28);
    let rhs = volumes["rhs_evaluations"].as_u64().expect("count");
    assert!(rhs > 28, "at least one evaluation per frame, got {rhs}");
    // the same integration whatever is read
    assert_eq!(volumes["rhs_evaluations"], markers["rhs_evaluations"]);
    assert_eq!(volumes["rhs_evaluations"], v["skin"]["rhs_evaluations"]);
    assert!(v["ratio_skin_over_volumes"].as_f64().expect("ratio") > 0.0);
    assert!(volumes["median_wall_s"].as_f64().expect("wall") > 0.0);
    let levels = v["rhs"].as_array().expect("rhs per level");
    assert_eq!(levels.len(), 3);
    let dims: Vec<u64> = levels
        .iter()
        .map(|l| l["state_dim"].as_u64().expect("dim"))
        .collect();
    assert!(dims[0] < dims[1] && dims[1] < dims[2], "{dims:?}");
    for l in levels {
        assert!(l["ns_rest"].as_f64().expect("ns") > 0.0);
        assert!(l["ns_breathing"].as_f64().expect("ns") > 0.0);
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bench_work_precision_writes_every_combination_and_a_plot() {
    let dir = scratch("wp");
    torso(&[
        "bench",
        "work-precision",
        "--scenario",
        "forced",
        "--duration",
        "0.25",
        "--repeats",
        "1",
        "--cap",
        "10",
        "--lod",
        "0",
        "--out",
        dir.to_str().expect("utf-8 path"),
    ]);
    let csv = std::fs::read_to_string(dir.join("work_precision_forced.csv")).expect("csv");
    let rows: Vec<&str> = csv
        .lines()
        .skip(1)
        .filter(|l| !l.starts_with('#'))
        .collect();
    let methods = breathing_torso::solver::Method::ALL.len();
    assert_eq!(
        rows.len(),
        methods * 8,
        "{methods} methods x 8 tolerances:\n{csv}"
    );
    let mut previous_error = f64::INFINITY;
    for row in rows.iter().filter(|r| r.starts_with("dopri5,")) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!(f[3], "ok", "{row}");
        let lung: f64 = f[7].parse().expect("lung error");
        assert!(lung.is_finite() && lung >= 0.0);
        previous_error = previous_error.min(lung);
    }
    assert!(
        previous_error < 1e-6,
        "tight tolerances approach the reference"
    );
    assert!(dir.join("work_precision_forced.png").exists());
    std::fs::remove_dir_all(dir).ok();
}

/// The quasi-static sweep: one row per tolerance with the static solves' counts, the
/// reference's frames with the scene (`solver.method=4`) for external integrators, a plot.
#[test]
fn bench_work_precision_quasi_static_writes_every_tolerance() {
    let dir = scratch("wpq");
    torso(&[
        "bench",
        "work-precision",
        "--formulation",
        "quasi-static",
        "--duration",
        "0.25",
        "--repeats",
        "1",
        "--lod",
        "0",
        "--out",
        dir.to_str().expect("utf-8 path"),
    ]);
    let csv =
        std::fs::read_to_string(dir.join("work_precision_quiet_quasi_static.csv")).expect("csv");
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 7, "rtol 1e-3 .. 1e-9:\n{csv}");
    for row in rows.iter().filter(|r| r[col("status")] == "ok") {
        let solves: u64 = row[col("static_solves")].parse().expect("solves");
        let rhs: u64 = row[col("rhs_evaluations")].parse().expect("rhs");
        // every right-hand side is a static solve, and every frame read one more
        assert!(solves >= rhs, "{row:?}");
        let lung: f64 = row[col("lung_error_l")].parse().expect("lung error");
        assert!(lung.is_finite() && lung >= 0.0, "{row:?}");
    }
    let tightest = &rows[6];
    assert_eq!(tightest[col("status")], "ok", "{tightest:?}");
    let reference =
        std::fs::read_to_string(dir.join("work_precision_quiet_quasi_static_reference.csv"))
            .expect("reference");
    assert!(
        reference
            .lines()
            .next()
            .expect("scene")
            .contains("solver.method=4")
    );
    assert!(dir.join("work_precision_quiet_quasi_static.png").exists());
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bench_rejects_bad_arguments() {
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["bench", "work-precision", "--scenario", "panting"])
        .output()
        .expect("torso runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--scenario") && err.contains("quiet or forced"),
        "{err}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["bench", "work-precision", "--scene", "soft-everything"])
        .output()
        .expect("torso runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--scene") && err.contains("stiff-cartilage"),
        "{err}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["bench", "work-precision", "--formulation", "lagrangian"])
        .output()
        .expect("torso runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--formulation") && err.contains("quasi-static"),
        "{err}"
    );
}

#[test]
fn bench_stress_runs_short_items_and_rejects_unknown_ones() {
    let dir = scratch("stress");
    let stdout = torso(&[
        "bench",
        "stress",
        "--items",
        "hold,drift",
        "--lod",
        "0",
        "--seconds",
        "0.5",
        "--drift-lod",
        "0",
        "--drift-seconds",
        "12",
        "--out",
        dir.to_str().expect("utf-8 path"),
    ]);
    assert!(stdout.contains("every item passed"), "{stdout}");
    let hold: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("stress_hold.json")).expect("hold json"),
    )
    .expect("valid JSON");
    assert_eq!(hold["seconds"], 0.5);
    assert_eq!(hold["monitor"]["checks"], 28);
    let csv = std::fs::read_to_string(dir.join("stress_drift.csv")).expect("drift csv");
    // 12 s at 0.25 Hz: the minima at about 3, 7 and 11 s (the last within half a breath of
    // the end is left out)
    assert_eq!(csv.lines().count(), 1 + 2, "{csv}");
    assert!(dir.join("stress_drift.png").exists());
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["bench", "stress", "--items", "hold,panting"])
        .output()
        .expect("torso runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--items") && err.contains("panting"), "{err}");
    std::fs::remove_dir_all(dir).ok();
}
