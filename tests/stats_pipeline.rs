//! End-to-end tests of the validation pipeline through the library API: breath counts on
//! synthetic noisy curves, exact lag recovery from a synthetic spirogram, flow input, the
//! outputs written by `write_outputs`, and the refusals of records that cannot be compared
//! (no time overlap, less than two breaths of overlap, a flat series, a lag search beyond
//! the overlap), each naming the file and the figure.

use breathing_torso::numeric::rng::Pcg64;
use breathing_torso::stats::autoreg::ArGlsConfig;
use breathing_torso::stats::bars::BarsConfig;
use breathing_torso::stats::breaths::{BreathDetector, segment_breaths};
use breathing_torso::stats::io::Series;
use breathing_torso::stats::prepare::SpiroKind;
use breathing_torso::stats::synth::{SpiroSynthOptions, VolumeSource, synth_spirometry};
use breathing_torso::stats::validation::{ValidationOptions, validate, write_outputs};
use std::f64::consts::PI;

/// A volume curve whose troughs sit at `phase + j / f`, `breaths` complete cycles, the
/// record starting and ending mid-breath (0.3 and 0.4 periods from the end troughs).
fn curve(
    f: f64,
    breaths: usize,
    fs: f64,
    noise: f64,
    drift: f64,
    h2: f64,
    seed: u64,
) -> (Vec<f64>, Vec<f64>) {
    let phase = 0.3 / f;
    let dur = phase + breaths as f64 / f + 0.4 / f;
    let n = (dur * fs) as usize;
    let mut g = Pcg64::new(seed, 5);
    let t: Vec<f64> = (0..n).map(|i| i as f64 / fs).collect();
    let v = t
        .iter()
        .map(|&s| {
            let a = 2.0 * PI * f * (s - phase);
            // The harmonic term vanishes at the troughs (a = 2 pi j): sin(2a) = 0 there.
            2.4 + 0.25 * (1.0 - a.cos())
                + h2 * 0.25 * (2.0 * a).sin() * (1.0 - a.cos()) / 2.0
                + drift * s
                + noise * g.normal()
        })
        .collect();
    (t, v)
}

#[test]
fn breath_segmentation_counts_synthetic_noisy_breaths() {
    for (f, breaths, noise, drift, h2) in [
        (0.2, 3, 0.0, 0.0, 0.0),
        (0.27, 7, 0.025, 0.004, 0.0),
        (0.33, 15, 0.03, -0.003, 0.5),
        (0.5, 12, 0.02, 0.002, 0.8),
        (0.15, 4, 0.04, 0.0, 0.3),
    ] {
        for seed in 1..=4 {
            let (t, v) = curve(f, breaths, 56.0, noise, drift, h2, seed);
            let b = segment_breaths(&t, &v, &BreathDetector::for_period(1.0 / f));
            assert_eq!(
                b.len(),
                breaths,
                "f {f} noise {noise} h2 {h2} seed {seed}: {b:?}"
            );
            for br in &b {
                assert!((br.ti + br.te - 1.0 / f).abs() < 0.15 / f, "{br:?}");
            }
        }
    }
}

fn sine_pair(offset_frames: i64, flow: bool, noise: f64) -> (Series, Series) {
    let fs = 56.0;
    let src = VolumeSource::Sine {
        frequency_hz: 0.25,
        tidal_volume_l: 0.5,
        harmonic2: 0.2,
        phase: 0.4,
        base_l: 2.6,
        duration_s: 20.0,
    };
    // The simulation: the same model sampled at 56 Hz from t = 0 (drawn with no errors).
    let sim = synth_spirometry(
        &src,
        &SpiroSynthOptions {
            rate_hz: fs,
            ..SpiroSynthOptions::default()
        },
    )
    .unwrap();
    let spiro = synth_spirometry(
        &src,
        &SpiroSynthOptions {
            start_offset_s: offset_frames as f64 / fs,
            noise_sd: noise,
            scale: 1.05,
            drift_l_per_s: 0.003,
            output: if flow {
                SpiroKind::Flow
            } else {
                SpiroKind::Volume
            },
            ..SpiroSynthOptions::default()
        },
    )
    .unwrap();
    (sim, spiro)
}

fn quick() -> ValidationOptions {
    ValidationOptions {
        bars: BarsConfig {
            samples: 300,
            ..BarsConfig::default()
        },
        robust: ArGlsConfig {
            bootstrap: 99,
            ..ArGlsConfig::default()
        },
        ..ValidationOptions::default()
    }
}

#[test]
fn validation_recovers_known_lag_exactly() {
    for frames in [-30i64, 0, 9, 55] {
        let (sim, spiro) = sine_pair(frames, false, 0.01);
        let v = validate(&sim, &spiro, SpiroKind::Volume, &quick()).unwrap();
        assert_eq!(v.preparation.lag_frames, -frames, "offset {frames} frames");
        assert!(!v.preparation.lag_at_search_limit);
        assert!(v.pearson.r > 0.99);
        assert!((v.frequency_sim.frequency_hz - 0.25).abs() < 0.005);
    }
}

#[test]
fn lag_outside_the_search_window_is_flagged() {
    // True lag -150 frames, one breath is 224 frames: within +-40 the best lag is the edge.
    let (sim, spiro) = sine_pair(150, false, 0.01);
    let mut opts = quick();
    opts.prepare.max_lag = 40;
    let v = validate(&sim, &spiro, SpiroKind::Volume, &opts).unwrap();
    assert!(
        v.preparation.lag_at_search_limit,
        "lag {}",
        v.preparation.lag_frames
    );
}

#[test]
fn flow_spirogram_is_integrated_and_agrees() {
    let (sim, spiro) = sine_pair(12, true, 0.005);
    let v = validate(&sim, &spiro, SpiroKind::Flow, &quick()).unwrap();
    assert_eq!(v.preparation.lag_frames, -12);
    assert!(v.pearson.r > 0.99, "{}", v.pearson.r);
    // The 5 % scale error shows as a tidal-volume bias of about -0.025 L per breath.
    let vt = v.breaths.tidal_volume.as_ref().unwrap();
    assert!((vt.bias + 0.025).abs() < 0.01, "{}", vt.bias);
}

#[test]
fn outputs_are_written() {
    let (sim, spiro) = sine_pair(5, false, 0.01);
    let v = validate(&sim, &spiro, SpiroKind::Volume, &quick()).unwrap();
    let dir = std::env::temp_dir().join(format!("torso-stats-out-{}", std::process::id()));
    write_outputs(&v, &dir).unwrap();
    for f in [
        "validation.json",
        "aligned.csv",
        "spiro_resampled.csv",
        "summary.md",
        "aligned.png",
        "aligned.svg",
        "bland_altman.png",
        "bland_altman.svg",
        "cosinor.png",
        "cosinor.svg",
        "bars.png",
        "bars.svg",
    ] {
        let meta = std::fs::metadata(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(meta.len() > 500, "{f} is only {} bytes", meta.len());
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("validation.json")).unwrap())
            .unwrap();
    assert!(json["bars"]["equality"]["p_h0"].is_number());
    assert!(json["cosinor"]["equality"]["robust_without_intercept"]["p_value"].is_number());
    let md = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(md.contains("BARS P(H0"));
    // SVG text is real text, so the plots are readable without raster fonts.
    let svg = std::fs::read_to_string(dir.join("bland_altman.svg")).unwrap();
    assert!(svg.contains("Bland-Altman"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The message of a validation that must fail.
fn refusal(sim: &Series, spiro: &Series, opts: &ValidationOptions) -> String {
    match validate(sim, spiro, SpiroKind::Volume, opts) {
        Ok(_) => panic!(
            "validation of {} against {} succeeded",
            sim.source, spiro.source
        ),
        Err(e) => e.to_string(),
    }
}

fn named(mut s: Series, source: &str) -> Series {
    s.source = source.into();
    s
}

#[test]
fn records_without_time_overlap_are_refused() {
    let (sim, spiro) = sine_pair(0, false, 0.01);
    let (sim, mut spiro) = (named(sim, "sim.csv"), named(spiro, "spiro.csv"));
    for t in &mut spiro.time {
        *t += 1000.0;
    }
    let e = refusal(&sim, &spiro, &quick());
    assert!(
        e.contains("sim.csv covers 0.000-")
            && e.contains("spiro.csv covers 1000.000-")
            && e.contains("do not overlap"),
        "{e}"
    );
}

#[test]
fn overlap_shorter_than_two_breaths_is_refused() {
    // 3 s of spirometry against 20 s of simulation at 0.25 Hz: two breaths need 8 s.
    let (sim, spiro) = sine_pair(0, false, 0.01);
    let (sim, mut spiro) = (named(sim, "sim.csv"), named(spiro, "spiro.csv"));
    spiro.time.truncate(300);
    spiro.values.truncate(300);
    let e = refusal(&sim, &spiro, &quick());
    assert!(
        e.contains("sim.csv and spiro.csv overlap for 2.99 s")
            && e.contains("shorter than two breaths")
            && e.contains("(8.00 s)"),
        "{e}"
    );
}

#[test]
fn flat_series_are_refused() {
    let (sim, spiro) = sine_pair(0, false, 0.01);
    let (sim, mut spiro) = (named(sim, "sim.csv"), named(spiro, "spiro.csv"));
    spiro.values.iter_mut().for_each(|v| *v = 0.7);
    let e = refusal(&sim, &spiro, &quick());
    assert!(
        e.contains("spiro.csv: the spirometry column `volume` is flat") && e.contains("of 0.7"),
        "{e}"
    );
    let (sim, spiro) = sine_pair(0, false, 0.01);
    let (mut sim, spiro) = (named(sim, "sim.csv"), named(spiro, "spiro.csv"));
    sim.values.iter_mut().for_each(|v| *v = 3.1);
    let e = refusal(&sim, &spiro, &quick());
    assert!(e.contains("sim.csv: the simulation column"), "{e}");
}

#[test]
fn lag_search_beyond_the_overlap_is_refused() {
    let (sim, spiro) = sine_pair(0, false, 0.01);
    let (sim, spiro) = (named(sim, "sim.csv"), named(spiro, "spiro.csv"));
    let mut opts = quick();
    opts.prepare.max_lag = 100_000;
    let e = refusal(&sim, &spiro, &opts);
    assert!(
        e.contains("--max-lag 100000 frames")
            && e.contains("beyond the overlap of sim.csv and spiro.csv"),
        "{e}"
    );
    // The largest accepted lag is the one the message names.
    let at_most: usize = e
        .split("at most ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no limit in {e}"));
    opts.prepare.max_lag = at_most;
    validate(&sim, &spiro, SpiroKind::Volume, &opts).expect("the named limit is accepted");
}

/// Volume of breaths of period `period` with inspiration `ti` s long: half-cosine rise and
/// fall, tidal volume 0.5 L, the record starting 0.5 s into a breath.
fn asymmetric_breaths(fs: f64, duration: f64, period: f64, ti: f64) -> Series {
    let time: Vec<f64> = (0..(duration * fs) as usize)
        .map(|i| i as f64 / fs)
        .collect();
    let values = time
        .iter()
        .map(|&t| {
            let tau = (t + 0.5) % period;
            if tau < ti {
                2.4 + 0.25 * (1.0 - (PI * tau / ti).cos())
            } else {
                2.4 + 0.25 * (1.0 + (PI * (tau - ti) / (period - ti)).cos())
            }
        })
        .collect();
    Series {
        time,
        values,
        column: "volume".into(),
        source: format!("breaths with Ti = {ti} s"),
    }
}

#[test]
fn breath_timing_agreement_recovers_known_differences() {
    // Half-cosine phases: flow at half volume is pi V / (2 T) in each phase, so
    // IE50 = Te / Ti for equal inspired and expired volumes: 2.4 / 1.6 = 1.5 for the
    // simulation and 2.2 / 1.8 for the spirogram.
    let sim = asymmetric_breaths(56.0, 24.0, 4.0, 1.6);
    let spiro = asymmetric_breaths(100.0, 24.0, 4.0, 1.8);
    let v = validate(&sim, &spiro, SpiroKind::Volume, &quick()).unwrap();
    let b = &v.breaths;
    assert!(b.pairs.len() >= 4, "{} pairs", b.pairs.len());
    // The 0.2 s moving average moves an extremum between phases of curvatures k1 and k2
    // towards the flatter side by h (sqrt k1 - sqrt k2) / (sqrt k1 + sqrt k2) with
    // h = 0.1 s: at most 0.02 s here, and the same way in both series. The differences
    // therefore carry about the sampling error, one sample at 56 Hz (0.018 s) per
    // extremum, two per duration: 0.04 s.
    for (name, x, want, tol) in [
        ("Ti", &b.ti, -0.2, 0.04),
        ("Te", &b.te, 0.2, 0.04),
        ("Ttot", &b.ttot, 0.0, 0.04),
        ("Ti/Ttot", &b.ti_ttot, 0.4 - 0.45, 0.01),
        ("IE50", &b.ie50, 1.5 - 2.2 / 1.8, 0.05),
    ] {
        let x = x.as_ref().unwrap_or_else(|| panic!("{name}: no agreement"));
        assert!(
            (x.bias - want).abs() < tol && x.loa_high - x.loa_low < 2.0 * tol,
            "{name}: bias {} limits [{}, {}], expected bias {want}",
            x.bias,
            x.loa_low,
            x.loa_high
        );
    }
    // Each breath alone: two extrema, each off by the smoothing shift (0.02 s) and a
    // sample (0.018 s): Ti within 0.08 s, Ti/Ttot within 0.08 / 4 = 0.02.
    for br in &b.sim_breaths {
        assert!(
            (br.ti - 1.6).abs() < 0.08 && (br.ti_ttot - 0.4).abs() < 0.02,
            "{br:?}"
        );
        assert!((br.ie50 - 1.5).abs() < 0.05, "{br:?}");
    }
}
