//! Benchmark of the fit (issue 5): native fit of an 18 s, 60-point synthetic recording at
//! 56 Hz (median of 3 wall times), then the same recording fitted through fmpy
//! (`python/fit_slp.py` on fmu/BreathingTorso.fmu) when the venv and the FMU exist.
//!
//! `cargo bench --bench fit [-- LOD]` (level of detail, default 0).

use breathing_torso::fit::{FitOptions, SynthOptions, TorsoMarkers, fit_recording, synthesize};
use breathing_torso::{Config, Quantity, Torso};
use std::path::Path;
use std::process::Command;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let lod: u32 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(0);
    let mut config = Config::default();
    config.scene.level_of_detail = lod;
    let mut probe = Torso::new(config.clone()).expect("torso");
    if let Err(e) = probe.read(Quantity::Marker { index: 0, axis: 0 }) {
        println!("fit benchmark skipped: {e}");
        return;
    }
    let dir = std::env::temp_dir().join(format!("fit_bench_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let rec_path = dir.join("rec.csv");
    let mut source = TorsoMarkers::new(config.clone()).expect("torso");
    let synth = SynthOptions {
        duration: 18.0,
        ..SynthOptions::default()
    };
    let s = synthesize(&mut source, &synth).expect("synthesize");
    s.recording.write(&rec_path).expect("write recording");
    println!(
        "recording: {} frames x {} points, LOD {lod}",
        s.recording.frames.len(),
        s.recording.points()
    );

    let mut fitted = Vec::new();
    config.scene.slp_reference = Some(rec_path.clone());
    for run in 0..3 {
        let start = std::time::Instant::now();
        let mut source = TorsoMarkers::new(config.clone()).expect("torso");
        let fit = fit_recording(
            &mut source,
            &s.recording,
            &FitOptions::default(),
            &mut |_, _| {},
        )
        .expect("fit");
        let wall = start.elapsed().as_secs_f64();
        println!(
            "native run {}: {wall:.2} s wall (build included), {} evaluations, {:.1} ms per evaluation, cost {:.3} mm",
            run + 1,
            fit.evaluations,
            1e3 * fit.wall_s / (fit.evaluations + 1) as f64,
            fit.cost_m * 1e3
        );
        fitted.push(wall);
    }
    let native = median(fitted);
    println!("native fit: median {native:.2} s (target < 10 s)");

    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".venv/bin/python");
    let fmu = root.join("fmu/BreathingTorso.fmu");
    if !python.exists() || !fmu.exists() {
        println!(
            "fmpy fit skipped: needs .venv (scripts/python-env.sh) and fmu/BreathingTorso.fmu (torso fmu build)"
        );
        return;
    }
    let mut times = Vec::new();
    for _ in 0..3 {
        let start = std::time::Instant::now();
        let out = Command::new(&python)
            .arg(root.join("python/fit_slp.py"))
            .args(["--fmu", fmu.to_str().unwrap_or_default()])
            .args(["--slp", rec_path.to_str().unwrap_or_default()])
            .args(["--lod", &lod.to_string()])
            .args(["--out", dir.join("fmpy.json").to_str().unwrap_or_default()])
            .output()
            .expect("run python");
        if !out.status.success() {
            println!("fmpy fit failed: {}", String::from_utf8_lossy(&out.stderr));
            return;
        }
        times.push(start.elapsed().as_secs_f64());
    }
    let fmpy = median(times);
    println!(
        "fmpy fit: median {fmpy:.2} s, {:.2}x the native time (target < 3x)",
        fmpy / native
    );
}
