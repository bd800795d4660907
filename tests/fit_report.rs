//! `torso fit` writes the report a clinician reads and shows its progress: run on a
//! synthetic recording with stderr piped, it prints progress lines ending at 100 %;
//! the PNG report has the stated size; the JSON's per-breath numbers are those of the
//! fitted trajectory it writes beside it (the lung-volume CSV with the rib-cage and
//! abdominal displaced volumes); the text summary carries the per-breath table.

use breathing_torso::fit::figure::{WIDTH, figure_height};
use breathing_torso::stats::thoracoabdominal::lissajous_phase_deg;
use std::path::Path;
use std::process::Command;

/// The fitted trajectory CSV: time, lung, rib cage, abdomen.
fn read_csv(path: &Path) -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time,volume.lung,volume.rib_cage_displaced,volume.abdomen_displaced"
    );
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

#[test]
fn fit_writes_the_breath_report_png_and_progress() {
    let dir = std::env::temp_dir().join(format!("fit_report_{}", std::process::id()));
    let out = dir.join("result.json");
    std::fs::create_dir_all(&dir).unwrap();
    // A synthetic recording of 20 s of quiet breathing (five breaths) at level of detail 0
    // and rtol 1e-4, as the bundled one; a short search is enough for the outputs.
    let rec = dir.join("rec.csv");
    let synth = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args([
            "synth",
            "--lod",
            "0",
            "--rtol",
            "1e-4",
            "--duration",
            "20",
            "--seed",
            "3",
        ])
        .arg("--out")
        .arg(&rec)
        .arg("--truth")
        .arg(dir.join("rec.truth.json"))
        .output()
        .unwrap();
    assert!(
        synth.status.success(),
        "{}",
        String::from_utf8_lossy(&synth.stderr)
    );
    let run = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["fit", "--lod", "0", "--rtol", "1e-4", "--max-evals", "24"])
        .args(["--threads", "1", "--slp"])
        .arg(&rec)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}\n{stdout}");

    // Progress: piped stderr gets lines, the last at 100 %.
    let progress: Vec<&str> = stderr.lines().filter(|l| l.starts_with("fit: ")).collect();
    assert!(progress.len() >= 2, "{stderr}");
    assert!(
        progress.iter().all(|l| l.contains(" evaluations (")),
        "{stderr}"
    );
    let last = progress.last().unwrap();
    assert!(last.contains("(100 %)") && last.ends_with("done"), "{last}");
    assert!(progress[0].contains("ETA"), "{stderr}");

    // The per-breath table in the summary.
    assert!(
        stdout.contains("Ti [s]")
            && stdout.contains("IE50")
            && stdout.contains("phase [deg]")
            && stdout.contains("  mean "),
        "{stdout}"
    );

    // The PNG: 1400 wide, three time panels (lung, compartments, markers) and the front view.
    let png = dir.join("result_report.png");
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!((info.width, info.height), (WIDTH, figure_height(3)));
    assert!(dir.join("result_report.svg").is_file());

    // The JSON's breaths against the trajectory written beside it.
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let rows = read_csv(&dir.join("result_lung_volume.csv"));
    let breaths = v["breaths"].as_array().unwrap();
    // Five breaths of 4 s in 20 s: at least three whole ones whatever the phase at the
    // first frame.
    assert!(breaths.len() >= 3, "{}", v["breaths"]);
    assert_eq!(
        v["breaths_summary"]["count"].as_u64().unwrap() as usize,
        breaths.len()
    );
    assert!(v["recording_breaths"]["median_ti_ttot"].is_number());
    let h = rows[1][0] - rows[0][0];
    for b in breaths {
        let g = |k: &str| b[k].as_f64().unwrap_or_else(|| panic!("{k} in {b}"));
        let (onset, ti, te, ttot) = (g("onset_s"), g("ti_s"), g("te_s"), g("ttot_s"));
        assert!((ti + te - ttot).abs() < 1e-9 && (g("ti_ttot") - ti / ttot).abs() < 1e-9);
        let i0 = rows
            .iter()
            .position(|r| (r[0] - onset).abs() < 1e-5)
            .unwrap();
        let n = (ttot / h).round() as usize;
        let breath = &rows[i0..i0 + n];
        // The peak of the written lung volume is Ti after the onset (within one frame),
        // and the inspired volume is the tidal volume. The CSV's lung volume is the fit's
        // own run; the breaths are read off a second run of the same drive, so the two
        // agree to the solver's tolerance (rtol 1e-4 of ~3 L: 0.3 mL) and the CSV's 1 uL
        // rounding.
        let (k_peak, peak) = breath
            .iter()
            .enumerate()
            .max_by(|a, b| a.1[1].total_cmp(&b.1[1]))
            .map(|(k, r)| (k, r[1]))
            .unwrap();
        assert!(
            (k_peak as f64 * h - ti).abs() <= 1.01 * h,
            "peak at {} s, Ti {ti}",
            k_peak as f64 * h
        );
        assert!(
            (peak - breath[0][1] - g("tidal_volume_l")).abs() < 5e-4,
            "{b}"
        );
        let rc: Vec<f64> = breath.iter().map(|r| r[2]).collect();
        let ab: Vec<f64> = breath.iter().map(|r| r[3]).collect();
        let swing = |x: &[f64]| {
            x.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - x.iter().cloned().fold(f64::INFINITY, f64::min)
        };
        let share = swing(&rc) / (swing(&rc) + swing(&ab));
        // The CSV holds 0.1 uL: the share is exact to a few 1e-4.
        assert!((share - g("rib_cage_share")).abs() < 1e-3, "{share} {b}");
        let phase = lissajous_phase_deg(&rc, &ab).unwrap();
        assert!((phase - g("phase_angle_deg")).abs() < 0.5, "{phase} {b}");
        assert!(g("ie50").is_finite() && g("ie50") > 0.0, "{b}");
    }
    let mean_vt = breaths
        .iter()
        .map(|b| b["tidal_volume_l"].as_f64().unwrap())
        .sum::<f64>()
        / breaths.len() as f64;
    let json_mean = v["breaths_summary"]["mean"]["tidal_volume_l"]
        .as_f64()
        .unwrap();
    assert!((mean_vt - json_mean).abs() < 1e-12);
    let _ = std::fs::remove_dir_all(&dir);
}
