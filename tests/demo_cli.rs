//! The README's main command, `torso demo`, run as a user runs it from a fresh directory:
//! it packages the FMU (when the library is built), simulates the default subject, fits the
//! bundled recording and writes its files; the fit recovers the recording's drive.

use std::path::PathBuf;
use std::process::Command;

fn number(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing or not a number in {v}"))
}

#[test]
fn demo_fits_the_bundled_recording() {
    let dir = std::env::temp_dir().join(format!("demo_cli_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["demo", "--out", "out"])
        .current_dir(&dir)
        .output()
        .expect("run torso demo");
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    println!("{text}");
    assert!(out.status.success(), "torso demo failed:\n{text}");
    for f in [
        "simulation.csv",
        "fit.json",
        "fit_lung_volume.csv",
        "fit_report.png",
    ] {
        let p = dir.join("out").join(f);
        assert!(
            p.metadata().map(|m| m.len() > 0).unwrap_or(false),
            "{} missing",
            p.display()
        );
    }
    // The FMU goes under --out with the rest, nothing into the working directory's fmu/.
    if text.contains("wrote out/BreathingTorso.fmu") {
        assert!(dir.join("out/BreathingTorso.fmu").exists());
    }
    assert!(!dir.join("fmu").exists(), "the demo wrote outside --out");
    // The output explains itself: what registration, cost, noise floor and the phases are,
    // a headed fitted-against-truth table, and every file written, the SVG report included.
    for line in [
        "  registration: the recording's first frame (end-expiration) rigidly moved",
        "  cost: the mean distance between the model's markers and the recorded points",
        "  noise floor: the mean length of the noise in the recording",
        "  phases: of each muscle family's sine",
        "parameter                     fitted     truth     error",
        "fit_report.png and out/fit_report.svg",
    ] {
        assert!(
            text.contains(line),
            "the demo's output lacks `{line}`:\n{text}"
        );
    }
    assert!(dir.join("out/fit_report.svg").is_file());
    let cost_line = text
        .lines()
        .find(|l| l.starts_with("cost ") && l.contains("against the recording's noise floor"))
        .unwrap_or_else(|| panic!("no cost against noise floor line in\n{text}"));
    assert!(cost_line.ends_with("x the floor)"), "{cost_line}");
    // The help names no build-time path as a default.
    let help = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["demo", "--help"])
        .output()
        .expect("run torso demo --help");
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        !help.contains(env!("CARGO_MANIFEST_DIR")),
        "torso demo --help shows a build-time path:\n{help}"
    );
    let read = |p: PathBuf| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()
    };
    let fit = read(dir.join("out/fit.json"));
    let truth = read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/recordings/demo_quiet.truth.json"),
    );
    for key in [
        "drive.ribs.amplitude",
        "drive.diaphragm.amplitude",
        "drive.frequency",
    ] {
        let (got, want) = (number(&fit, key), number(&truth, key));
        assert!(
            (got - want).abs() <= 0.05 * want,
            "{key}: fitted {got}, truth {want}"
        );
    }
    // The fit reaches the recording's noise floor.
    let cost = number(&fit, "cost_m");
    let floor = number(&truth, "noise_floor_m");
    assert!(
        cost <= 1.15 * floor,
        "cost {cost} m against noise floor {floor} m"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
