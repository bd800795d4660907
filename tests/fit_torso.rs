//! Acceptance of the fit on the torso itself (LOD 0): synthetic recordings with known
//! parameters (0.5 mm noise, random camera pose) fitted back. Two short fits run in CI; the
//! six-recording sweep of the issue (quiet and forced x three postures, two subjects, 18 s)
//! is `cargo test --release --test fit_torso -- --ignored`.

use breathing_torso::Config;
use breathing_torso::anatomy::{Posture, Sex, Subject};
use breathing_torso::fit::fitting::wrap_angle;
use breathing_torso::fit::{FitOptions, SynthOptions, TorsoMarkers, fit_recording, synthesize};
use breathing_torso::model::Drive;

fn config(subject: Subject) -> Config {
    let mut c = Config {
        subject,
        ..Config::default()
    };
    c.scene.level_of_detail = 0;
    // 1.5x faster than 1e-6 with the same tidal volume to 1 mL.
    c.solver.rtol = 1e-4;
    c
}

/// False (with the reason printed) while the torso has no marker outputs.
fn subject_b() -> Subject {
    Subject {
        sex: Sex::Female,
        age: 45.0,
        stature: 1.62,
        mass: 60.0,
        breast_size: 0.4,
        ..Subject::default()
    }
}

/// Quiet and forced drives of the thesis's ranges (Table 4.3), with the abdominal muscles
/// off: the fit searches the rib-cage and diaphragm waves only (the acceptance sweep's).
fn drive(forced: bool) -> Drive {
    breathing_torso::fit::sweep::case_drive(forced)
}

/// Synthesises, fits, checks the acceptance bounds; returns the fit's wall time.
fn accept(subject: Subject, posture: Posture, forced: bool, duration: f64, seed: u64) -> f64 {
    let subject = Subject { posture, ..subject };
    let mut source = TorsoMarkers::new(config(subject.clone())).unwrap();
    let synth = SynthOptions {
        drive: drive(forced),
        duration,
        seed,
        ..SynthOptions::default()
    };
    let s = synthesize(&mut source, &synth).unwrap();
    let mut source = TorsoMarkers::new(config(subject)).unwrap();
    let fit = fit_recording(
        &mut source,
        &s.recording,
        &FitOptions::default(),
        &mut |_, _| {},
    )
    .unwrap();
    let t = s.truth;
    eprintln!(
        "{posture:?} {} {duration} s: {} evaluations, {:.2} s, cost {:.4} mm (floor {:.4}), f {:.4}/{:.4}, A_r {:.4}/{:.4}, A_d {:.4}/{:.4}, dphi {:.3}/{:.3}",
        if forced { "forced" } else { "quiet" },
        fit.evaluations,
        fit.wall_s,
        fit.cost_m * 1e3,
        s.noise_floor_m * 1e3,
        fit.drive.frequency,
        t.frequency,
        fit.drive.ribs.amplitude,
        t.ribs.amplitude,
        fit.drive.diaphragm.amplitude,
        t.diaphragm.amplitude,
        fit.delta_phase,
        t.diaphragm.phase - t.ribs.phase,
    );
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(rel(fit.drive.frequency, t.frequency) < 0.01);
    assert!(rel(fit.drive.ribs.amplitude, t.ribs.amplitude) < 0.10);
    assert!(rel(fit.drive.diaphragm.amplitude, t.diaphragm.amplitude) < 0.10);
    assert!(wrap_angle(fit.delta_phase - (t.diaphragm.phase - t.ribs.phase)).abs() < 0.15);
    assert!(wrap_angle(fit.drive.ribs.phase - t.ribs.phase).abs() < 0.15);
    assert!(fit.cost_m <= 1.15 * s.noise_floor_m);
    assert!(fit.evaluations <= 120);
    fit.wall_s
}

#[test]
fn quiet_standing_is_recovered() {
    accept(Subject::default(), Posture::Standing, false, 10.0, 31);
}

#[test]
fn forced_supine_is_recovered() {
    accept(subject_b(), Posture::Supine, true, 10.0, 32);
}

#[test]
fn a_recording_of_another_grid_is_rejected_naming_both_sizes() {
    let mut c = config(Subject::default());
    c.scene.grid_rows = 8;
    let mut source = TorsoMarkers::new(c).unwrap();
    let s = synthesize(
        &mut source,
        &SynthOptions {
            duration: 4.0,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let mut source = TorsoMarkers::new(config(Subject::default())).unwrap();
    let e = fit_recording(
        &mut source,
        &s.recording,
        &FitOptions::default(),
        &mut |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("8x6 (48 points)") && e.contains("10x6 (60 points)"),
        "{e}"
    );
}

#[test]
#[ignore = "six 18 s fits: several minutes; run with --ignored"]
fn six_recording_sweep() {
    let cases = [
        (Subject::default(), Posture::Standing, false),
        (subject_b(), Posture::Standing, true),
        (subject_b(), Posture::Sitting, false),
        (Subject::default(), Posture::Sitting, true),
        (Subject::default(), Posture::Supine, false),
        (subject_b(), Posture::Supine, true),
    ];
    for (k, (subject, posture, forced)) in cases.into_iter().enumerate() {
        accept(subject, posture, forced, 18.0, 100 + k as u64);
    }
}

/// Skin fitting at the pose the recording implies (`torso fit --skin-fit`): the model fits
/// its rest skin to the rest-pose grid a first fit implies, then polishes; the cost stays
/// at the noise floor (fitting the skin to the first frame as if it were the rest pose left
/// an offset of about 2.5 mm the drive cannot remove), within the evaluation budget.
#[test]
fn skin_fit_at_the_implied_rest_pose_keeps_the_noise_floor() {
    let mut source = TorsoMarkers::new(config(Subject::default())).unwrap();
    let s = synthesize(
        &mut source,
        &SynthOptions {
            drive: drive(false),
            duration: 8.0,
            seed: 33,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("bt_skin_fit_{}", std::process::id()));
    let reference = dir.join("reference.csv");
    let fit = breathing_torso::fit::fitting::fit_with_skin(
        &config(Subject::default()),
        &s.recording,
        &reference,
        &FitOptions::default(),
        &mut |_, _| {},
    )
    .unwrap();
    let (before, after) = fit.skin_fit.expect("the model fitted its skin");
    eprintln!(
        "skin fit {:.3} -> {:.3} mm; cost {:.4} mm (floor {:.4}), {} evaluations",
        before * 1e3,
        after * 1e3,
        fit.cost_m * 1e3,
        s.noise_floor_m * 1e3,
        fit.evaluations
    );
    assert!(reference.is_file());
    assert!(fit.cost_m <= 1.15 * s.noise_floor_m);
    assert!(fit.evaluations <= 120);
    let t = s.truth;
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(rel(fit.drive.ribs.amplitude, t.ribs.amplitude) < 0.10);
    assert!(rel(fit.drive.diaphragm.amplitude, t.diaphragm.amplitude) < 0.10);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two threads (a second torso on the same compiled model evaluating ahead) give the fit of
/// one thread, bit for bit, with the same evaluation count.
#[test]
fn two_threads_fit_as_one() {
    let mut source = TorsoMarkers::new(config(Subject::default())).unwrap();
    let s = synthesize(
        &mut source,
        &SynthOptions {
            drive: drive(false),
            duration: 8.0,
            seed: 21,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let fit = |threads: usize| {
        let mut source = TorsoMarkers::new(config(Subject::default())).unwrap();
        fit_recording(
            &mut source,
            &s.recording,
            &FitOptions {
                threads,
                ..FitOptions::default()
            },
            &mut |_, _| {},
        )
        .unwrap()
    };
    let (one, two) = (fit(1), fit(2));
    eprintln!(
        "one thread {:.2} s, two {:.2} s; {} evaluations, {} evaluated ahead and unused",
        one.wall_s, two.wall_s, two.evaluations, two.unused_ahead
    );
    assert_eq!(one.drive, two.drive);
    assert_eq!(one.cost_m, two.cost_m);
    assert_eq!(one.evaluations, two.evaluations);
    assert_eq!(one.fitted, two.fitted);
    assert_eq!(one.unused_ahead, 0);
}
