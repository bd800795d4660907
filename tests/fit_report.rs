//! `torso fit` writes the report a clinician reads and shows its progress: run on a
//! synthetic recording with stderr piped, it prints progress lines ending at 100 %;
//! the PNG report has the stated size; the JSON lists every whole breath of the recording
//! (the first starting on the first frame, the last ending on the last) and its per-breath
//! numbers are those of the fitted trajectory it writes beside it (the lung-volume CSV with
//! the rib-cage and abdominal displaced volumes); the text summary carries the per-breath
//! table. The figure's front view and ventral displacements are the same with and without
//! skin fitting (whose markers are in the recording's frame).

use breathing_torso::Config;
use breathing_torso::fit::figure::{WIDTH, figure_height, front_view, ventral_displacement};
use breathing_torso::fit::fitting::fit_with_skin;
use breathing_torso::fit::{FitOptions, SynthOptions, TorsoMarkers, fit_recording, synthesize};
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
    // The synthetic recording starts at end-expiration (its first frame is the true lung
    // volume's minimum) and its breaths repeat every 1/f (no variability), so its troughs
    // fall on the first frame and every 1/f after: floor(duration f) whole breaths, the
    // last ending on the last frame when duration f is whole (5 in 20 s at 0.25 Hz).
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("rec.truth.json")).unwrap())
            .unwrap();
    assert_eq!(truth["variability"].as_f64(), Some(0.0));
    let whole = truth["duration_s"].as_f64().unwrap() * truth["drive.frequency"].as_f64().unwrap();
    let expected = (whole + 1e-9).floor() as usize;
    assert_eq!(expected, 5);
    assert_eq!(breaths.len(), expected, "{}", v["breaths"]);
    assert_eq!(
        v["breaths_summary"]["count"].as_u64().unwrap() as usize,
        breaths.len()
    );
    assert!(v["recording_breaths"]["median_ti_ttot"].is_number());
    let h = rows[1][0] - rows[0][0];
    // The first breath starts on the first frame, the last ends on the last, within the
    // one frame by which a sampled trough places the minimum (the report's rule).
    let first = &breaths[0];
    let last = &breaths[breaths.len() - 1];
    assert!(
        first["onset_s"].as_f64().unwrap().abs() <= 1.01 * h,
        "{first}"
    );
    let end = last["onset_s"].as_f64().unwrap() + last["ttot_s"].as_f64().unwrap();
    let span = rows[rows.len() - 1][0];
    assert!((end - span).abs() <= 1.01 * h, "{last}");
    let mut checked = 0;
    for b in breaths {
        let g = |k: &str| b[k].as_f64().unwrap_or_else(|| panic!("{k} in {b}"));
        let (onset, ti, te, ttot) = (g("onset_s"), g("ti_s"), g("te_s"), g("ttot_s"));
        assert!((ti + te - ttot).abs() < 1e-9 && (g("ti_ttot") - ti / ttot).abs() < 1e-9);
        // A breath whose trough sits one frame before the first frame starts on a sample
        // of the report's longer run, not in the CSV: nothing to compare it with.
        let Some(i0) = rows.iter().position(|r| (r[0] - onset).abs() < 1e-5) else {
            assert!(onset < 0.0, "{b}");
            continue;
        };
        checked += 1;
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
    assert!(checked >= breaths.len() - 1);
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

/// The figure of a fit is drawn in the model's anatomical frame (x anterior, y superior, z
/// right) with and without skin fitting, although a skin-fitted model gives its markers in
/// the recording's frame (here a camera's: 1.2 m in front of the chest, tilted): the front
/// view keeps column 0 (the subject's right) on the viewer's left and row 0 (the clavicle
/// line) on top, and shows the same grid; the midline markers' ventral displacement has
/// the same range.
#[test]
fn figure_views_are_anatomical_with_and_without_skin_fitting() {
    let mut config = Config::default();
    config.scene.level_of_detail = 0;
    config.solver.rtol = 1e-4;
    let mut source = TorsoMarkers::new(config.clone()).unwrap();
    let s = synthesize(
        &mut source,
        &SynthOptions {
            duration: 8.0,
            seed: 5,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let rigid = fit_recording(
        &mut TorsoMarkers::new(config.clone()).unwrap(),
        &s.recording,
        &FitOptions {
            max_evals: 30,
            threads: 1,
            ..FitOptions::default()
        },
        &mut |_, _| {},
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("fit_report_skin_{}", std::process::id()));
    let skin = fit_with_skin(
        &config,
        &s.recording,
        &dir.join("reference.csv"),
        &FitOptions {
            max_evals: 60,
            threads: 1,
            ..FitOptions::default()
        },
        &mut |_, _| {},
    )
    .unwrap();
    assert!(skin.skin_fit.is_some());
    // The case at issue: the skin-fitted model's markers are in the camera's frame, turned
    // about 180 deg from the model's (depth along -x, image y down), the rigid fit's in
    // the model's.
    assert!(skin.to_anatomy.rotation.angle() > 90f64.to_radians());
    assert!(rigid.to_anatomy.rotation.angle() < 1e-12);
    let (rows, cols) = rigid.grid;
    let centred = |fit: &breathing_torso::fit::Fit| {
        let p = front_view(fit);
        assert_eq!(p.len(), rows * cols);
        let n = p.len() as f64;
        let (mu, mv) = p
            .iter()
            .fold((0.0, 0.0), |a, q| (a.0 + q.0 / n, a.1 + q.1 / n));
        p.iter().map(|q| (q.0 - mu, q.1 - mv)).collect::<Vec<_>>()
    };
    let (a, b) = (centred(&rigid), centred(&skin));
    for p in [&a, &b] {
        for r in 0..rows {
            for c in 1..cols {
                // Column 0 on the subject's right, seen on the viewer's left.
                assert!(
                    p[r * cols + c].0 > p[r * cols + c - 1].0,
                    "row {r} col {c}: {p:?}"
                );
            }
        }
        for c in 0..cols {
            for r in 1..rows {
                // Row 0 on top.
                assert!(
                    p[r * cols + c].1 < p[(r - 1) * cols + c].1,
                    "row {r} col {c}: {p:?}"
                );
            }
        }
    }
    // The same grid: the two views differ by the skin fit's reshaping of the grid and the
    // two registrations, small against the grid's extent (a side view for a front view
    // would differ by a large part of it). One tenth of the width is the bound of "the same
    // picture".
    let width = a.iter().map(|q| q.0).fold(f64::NEG_INFINITY, f64::max)
        - a.iter().map(|q| q.0).fold(f64::INFINITY, f64::min);
    let rms = (a
        .iter()
        .zip(&b)
        .map(|(p, q)| (p.0 - q.0).powi(2) + (p.1 - q.1).powi(2))
        .sum::<f64>()
        / a.len() as f64)
        .sqrt();
    eprintln!(
        "front view: width {:.1} mm, RMS difference with and without skin fitting {:.2} mm",
        width * 1e3,
        rms * 1e3
    );
    assert!(rms < 0.1 * width, "{rms} of {width}");
    // The midline marker of the middle row: its ventral displacement ranges alike (the same
    // recording fitted twice; a lateral or vertical axis would show a fraction of it).
    let j = (rows / 2) * cols + cols / 2;
    let range = |v: Vec<f64>| {
        v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().cloned().fold(f64::INFINITY, f64::min)
    };
    let (ra, rb) = (
        range(ventral_displacement(&rigid, j)),
        range(ventral_displacement(&skin, j)),
    );
    eprintln!("ventral range of marker[{}]: {ra:.3} / {rb:.3} mm", j + 1);
    assert!(ra > 0.0 && (ra - rb).abs() < 0.1 * ra, "{ra} {rb}");
    let _ = std::fs::remove_dir_all(&dir);
}
