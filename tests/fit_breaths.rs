//! Breath-to-breath variation on the torso itself (level of detail 0): a synthetic recording
//! with a non-sinusoidal drive (Ti/Ttot 0.42) and 10 % variation of depth and period is
//! fitted back with the inspiratory fraction read off the recording (`--ti-ttot auto`). The
//! breaths the fit finds on the recording's principal displacement match the drive's
//! breaths within the breath-by-breath limits of agreement of SLP against a
//! pneumotachograph (Motamedi-Fakhr et al. 2017, Physiol. Rep. 5(3):e13124: Ti +-0.22 s,
//! Te +-0.29 s, Ttot +-0.32 s), and the fitted Ti/Ttot is within 0.03 of the drive's.

use breathing_torso::Config;
use breathing_torso::fit::{
    Camera, FitOptions, SynthOptions, TorsoMarkers, fit_recording, synthesize,
};

fn config() -> Config {
    let mut c = Config::default();
    c.scene.level_of_detail = 0;
    c.solver.rtol = 1e-4;
    c
}

#[test]
fn variable_breaths_are_found_and_the_shape_is_fitted() {
    let fraction = 0.42;
    let mut drive = breathing_torso::fit::sweep::case_drive(false);
    drive.inspiratory_fraction = fraction;
    let mut source = TorsoMarkers::new(config()).unwrap();
    let s = synthesize(
        &mut source,
        &SynthOptions {
            drive,
            duration: 30.0,
            variability: 0.1,
            seed: 7,
            camera: Camera::Random,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    // The drive's breaths in recording time: each starts at its rib-cage inspiration onset.
    let truth: Vec<(f64, f64)> = s
        .breaths
        .0
        .iter()
        .map(|b| (b.start - s.start_time, b.period))
        .collect();
    let periods: Vec<f64> = truth.iter().map(|b| b.1).collect();
    let mean = periods.iter().sum::<f64>() / periods.len() as f64;
    let sd =
        (periods.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / periods.len() as f64).sqrt();
    let depths: Vec<f64> = s.breaths.0.iter().map(|b| b.depth).collect();
    let starts: Vec<f64> = truth.iter().map(|b| b.0).collect();
    println!(
        "drive breaths from {starts:.3?} s: periods {periods:.3?} (CV {:.3}), depths {depths:.3?}",
        sd / mean
    );
    assert!(sd / mean > 0.03, "the schedule varies");

    let mut source = TorsoMarkers::new(config()).unwrap();
    let fit = fit_recording(
        &mut source,
        &s.recording,
        &FitOptions {
            inspiratory_fraction: None,
            max_evals: 60,
            ..FitOptions::default()
        },
        &mut |_, _| {},
    )
    .unwrap();
    let found = &fit.breathing;
    assert!(
        found.breaths.len() >= 5,
        "{} breaths found",
        found.breaths.len()
    );
    let mut worst: (f64, f64, f64) = (0.0, 0.0, 0.0);
    let mut depth_pairs = Vec::new();
    for ((b, &onset), &depth) in found.breaths.iter().zip(&found.onsets).zip(&found.depths) {
        // The drive breath whose onset is nearest the found onset.
        let k = (0..truth.len())
            .min_by(|&a, &c| {
                (truth[a].0 - onset)
                    .abs()
                    .total_cmp(&(truth[c].0 - onset).abs())
            })
            .unwrap();
        let (start, period) = truth[k];
        depth_pairs.push((depth, s.breaths.0[k].depth));
        assert!(
            (start - onset).abs() < 0.5,
            "onset {onset:.3} s, drive {start:.3} s"
        );
        let ti = fraction * period;
        let (dti, dte, dttot) = (b.ti - ti, b.te - (period - ti), b.ttot - period);
        println!(
            "onset {onset:6.3} s (drive {start:6.3}): Ti {:.3}/{ti:.3} Te {:.3}/{:.3} Ttot {:.3}/{period:.3}",
            b.ti,
            b.te,
            period - ti,
            b.ttot
        );
        worst = (
            worst.0.max(dti.abs()),
            worst.1.max(dte.abs()),
            worst.2.max(dttot.abs()),
        );
    }
    println!(
        "worst |error|: Ti {:.3} s, Te {:.3} s, Ttot {:.3} s; fitted Ti/Ttot {:.4} (drive {fraction})",
        worst.0, worst.1, worst.2, fit.drive.inspiratory_fraction
    );
    // Depths relative to their median, found against the drive's.
    let mut drive_depths: Vec<f64> = depth_pairs.iter().map(|p| p.1).collect();
    drive_depths.sort_by(f64::total_cmp);
    let n = drive_depths.len();
    let mid = 0.5 * (drive_depths[(n - 1) / 2] + drive_depths[n / 2]);
    // The depth estimate beats taking every breath as deep as the median: its RMS error is
    // below the RMS deviation of the drive's relative depths from 1.
    let rms = |e: &mut dyn Iterator<Item = f64>| {
        let v: Vec<f64> = e.collect();
        (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
    };
    let error = rms(&mut depth_pairs.iter().map(|(f, d)| f - d / mid));
    let baseline = rms(&mut depth_pairs.iter().map(|(_, d)| d / mid - 1.0));
    println!(
        "depths found against drive: {depth_pairs:.3?}; RMS error {error:.3} against {baseline:.3} for equal breaths"
    );
    assert!(error < baseline, "depth RMS error {error} >= {baseline}");
    assert!(
        worst.0 <= 0.22 && worst.1 <= 0.29 && worst.2 <= 0.32,
        "{worst:?}"
    );
    assert!((fit.drive.inspiratory_fraction - fraction).abs() <= 0.03);
    assert_eq!(fit.drive.inspiratory_fraction, found.ti_ttot);
}
