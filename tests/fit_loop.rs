//! The fit loop on a stand-in marker model with known behaviour (first-order muscle
//! response, chest markers driven by the rib cage, abdominal markers by the diaphragm):
//! synthetic recording -> registration, frequency, search -> parameters recovered. The
//! same loop runs on the torso in `fit_torso.rs`.

use breathing_torso::Result;
use breathing_torso::anatomy::MuscleGroup;
use breathing_torso::fit::fitting::{check_grid, mean_distance, wrap_angle};
use breathing_torso::fit::principal::recording_frequency;
use breathing_torso::fit::report::{truth_json, write_fit};
use breathing_torso::fit::source::DriveSchedule;
use breathing_torso::fit::{
    Camera, FitOptions, MarkerSource, Method, SynthOptions, Trajectory, fit_recording, synthesize,
};
use breathing_torso::model::{Drive, Wave};
use breathing_torso::recording::Recording;
use nalgebra::{Point3, Vector3};

/// Markers on a curved front surface; each moves with lagged rib-cage and diaphragm
/// activations (time constant 0.3 s), the chest ventrally and cranially, the abdomen
/// ventrally, with a mild nonlinearity.
struct LaggedGrid {
    rows: usize,
    cols: usize,
    runs: usize,
}

impl LaggedGrid {
    fn rest(&self) -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        for r in 0..self.rows {
            for c in 0..self.cols {
                let z = (0.5 * (self.cols - 1) as f64 - c as f64) * 0.04;
                let y = 1.45 - r as f64 * 0.045;
                out.push(Point3::new(0.12 - 2.0 * z * z, y, z));
            }
        }
        out
    }

    fn markers(&self, rib: f64, dia: f64, out: &mut Vec<Point3<f64>>) {
        out.clear();
        let n = (self.rows - 1) as f64;
        for (j, p) in self.rest().iter().enumerate() {
            let row = (j / self.cols) as f64 / n;
            let chest = (1.0 - row).powi(2);
            let belly = row * row;
            let d = Vector3::new(0.012, 0.006, 0.0) * chest * (rib + 0.3 * rib * rib)
                + Vector3::new(0.02, -0.002, 0.0) * belly * dia
                + Vector3::new(0.003, 0.0, 0.0) * rib * dia;
            out.push(p + d);
        }
    }
}

impl MarkerSource for LaggedGrid {
    fn grid(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }
    fn rest_markers(&mut self) -> Result<Vec<Point3<f64>>> {
        Ok(self.rest())
    }
    fn run(
        &mut self,
        schedule: &DriveSchedule,
        times: &[f64],
        volumes: bool,
        out: &mut Trajectory,
    ) -> Result<()> {
        self.runs += 1;
        let tau = 0.3;
        let dt: f64 = 2e-3;
        let (mut t, mut rib, mut dia) = (0.0, 0.0, 0.0);
        let drive_at = |t: f64| -> Drive {
            schedule
                .iter()
                .rev()
                .find(|s| s.0 <= t)
                .map_or(schedule[0].1, |s| s.1)
        };
        out.markers.resize_with(times.len(), Vec::new);
        out.lung_volume.clear();
        for (k, &target) in times.iter().enumerate() {
            while t < target - 1e-12 {
                let h = dt.min(target - t);
                let d = drive_at(t);
                let ar = d.activation(MuscleGroup::ExternalIntercostals, t + 0.5 * h);
                let ad = d.activation(MuscleGroup::Diaphragm, t + 0.5 * h);
                // Exact step of the linear lag with the input held at the midpoint value.
                let e = (-h / tau).exp();
                rib = ar + (rib - ar) * e;
                dia = ad + (dia - ad) * e;
                t += h;
            }
            self.markers(rib, dia, &mut out.markers[k]);
            if volumes {
                out.lung_volume.push(2.5 + 0.8 * rib + 1.1 * dia);
            }
        }
        Ok(())
    }
}

fn grid_model() -> LaggedGrid {
    LaggedGrid {
        rows: 10,
        cols: 6,
        runs: 0,
    }
}

fn drive(f: f64, ar: f64, ad: f64, dphi: f64) -> Drive {
    Drive {
        enabled: true,
        frequency: f,
        inspiratory_fraction: 0.5,
        ribs: Wave {
            amplitude: ar,
            phase: 0.4,
        },
        diaphragm: Wave {
            amplitude: ad,
            phase: 0.4 + dphi,
        },
        abdominals: Wave::default(),
    }
}

fn check_recovery(
    truth: &Drive,
    noise_floor: f64,
    method: Method,
    synth: &SynthOptions,
) -> breathing_torso::fit::Fit {
    let mut model = grid_model();
    let s = synthesize(&mut model, synth).unwrap();
    assert_eq!(s.recording.grid, (10, 6));
    let _ = noise_floor;
    let mut model = grid_model();
    let options = FitOptions {
        method,
        ..FitOptions::default()
    };
    let fit = fit_recording(&mut model, &s.recording, &options, &mut |_, _| {}).unwrap();
    let t = s.truth;
    eprintln!(
        "{method:?}: evaluations {}, cost {:.4} mm (noise floor {:.4} mm, start {:.4} mm), A_r {:.4}/{:.4}, A_d {:.4}/{:.4}, dphi {:.3}/{:.3}",
        fit.evaluations,
        fit.cost_m * 1e3,
        s.noise_floor_m * 1e3,
        fit.initial_cost_m * 1e3,
        fit.drive.ribs.amplitude,
        t.ribs.amplitude,
        fit.drive.diaphragm.amplitude,
        t.diaphragm.amplitude,
        fit.delta_phase,
        t.diaphragm.phase - t.ribs.phase
    );
    assert_eq!(truth.frequency, t.frequency);
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(
        rel(fit.drive.frequency, t.frequency) < 0.01,
        "frequency {} vs {}",
        fit.drive.frequency,
        t.frequency
    );
    assert!(
        rel(fit.drive.ribs.amplitude, t.ribs.amplitude) < 0.10,
        "{:?}\ntruth {t:?}",
        fit.drive
    );
    assert!(
        rel(fit.drive.diaphragm.amplitude, t.diaphragm.amplitude) < 0.10,
        "{:?} truth {t:?}",
        fit.drive
    );
    for (a, b) in [
        (fit.drive.ribs.phase, t.ribs.phase),
        (fit.drive.diaphragm.phase, t.diaphragm.phase),
        (fit.delta_phase, t.diaphragm.phase - t.ribs.phase),
    ] {
        assert!(
            wrap_angle(a - b).abs() < 0.15,
            "phase {a} vs {b}: {:?}",
            fit.drive
        );
    }
    assert!(fit.evaluations <= 120, "{} evaluations", fit.evaluations);
    assert!(
        fit.cost_m <= 1.15 * s.noise_floor_m,
        "cost {} vs noise floor {}",
        fit.cost_m,
        s.noise_floor_m
    );
    assert!(fit.cost_m < fit.initial_cost_m);
    assert_eq!(
        model.runs,
        fit.evaluations + 1,
        "one run per evaluation and a final run"
    );
    fit
}

#[test]
fn nelder_mead_recovers_quiet_breathing() {
    let d = drive(0.25, 0.22, 0.3, 0.2);
    let synth = SynthOptions {
        drive: d,
        duration: 18.0,
        dropout: 0.02,
        seed: 4,
        ..SynthOptions::default()
    };
    let fit = check_recovery(&d, 0.0, Method::NelderMead, &synth);
    // Registration recovered the camera: the first frame sits on the rest markers.
    assert!(fit.registration_rms_m < 2e-3, "{}", fit.registration_rms_m);
}

#[test]
fn nelder_mead_recovers_forced_breathing() {
    let d = drive(0.18, 0.45, 0.5, -0.3);
    let synth = SynthOptions {
        drive: d,
        seed: 8,
        ..SynthOptions::default()
    };
    check_recovery(&d, 0.0, Method::NelderMead, &synth);
}

#[test]
fn robust_methods_recover_too() {
    let d = drive(0.3, 0.3, 0.15, 0.5);
    let synth = SynthOptions {
        drive: d,
        seed: 12,
        duration: 12.0,
        ..SynthOptions::default()
    };
    check_recovery(&d, 0.0, Method::Multistart, &synth);
    check_recovery(&d, 0.0, Method::Cmaes, &synth);
}

#[test]
fn registration_recovers_the_camera_pose() {
    let d = drive(0.25, 0.3, 0.3, 0.0);
    let mut model = grid_model();
    let s = synthesize(
        &mut model,
        &SynthOptions {
            drive: d,
            noise: 0.0,
            duration: 8.0,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let mut model = grid_model();
    let fit = fit_recording(
        &mut model,
        &s.recording,
        &FitOptions {
            max_evals: 10,
            ..FitOptions::default()
        },
        &mut |_, _| {},
    )
    .unwrap();
    let composed = fit.to_model.rotation * s.camera.rotation;
    assert!(
        composed.angle().to_degrees() < 0.5,
        "{}",
        composed.angle().to_degrees()
    );
    let p = Point3::new(0.1, 1.3, 0.02);
    let back = fit.to_model.apply(&s.camera.apply(&p));
    assert!((back - p).norm() < 1e-3, "{}", (back - p).norm());
}

#[test]
fn frequency_from_the_principal_displacement() {
    for (f, seed) in [(0.2, 1), (0.27, 2), (0.4, 3)] {
        let mut model = grid_model();
        let s = synthesize(
            &mut model,
            &SynthOptions {
                drive: drive(f, 0.3, 0.3, 0.1),
                seed,
                dropout: 0.05,
                ..SynthOptions::default()
            },
        )
        .unwrap();
        let est = recording_frequency(&s.recording).unwrap();
        assert!((est.frequency_hz - f).abs() < 0.01 * f, "{f}: {est:?}");
    }
}

#[test]
fn variability_and_dropout_still_fit_close() {
    let d = drive(0.25, 0.25, 0.3, 0.2);
    let mut model = grid_model();
    let s = synthesize(
        &mut model,
        &SynthOptions {
            drive: d,
            variability: 0.1,
            dropout: 0.05,
            seed: 21,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    assert!(s.schedule.len() > 4, "one drive per breath");
    let untracked = s
        .recording
        .frames
        .iter()
        .flatten()
        .filter(|p| p.is_none())
        .count();
    let total = s.recording.frames.len() * 60;
    assert!((untracked as f64 / total as f64 - 0.05).abs() < 0.01);
    let mut model = grid_model();
    let fit = fit_recording(
        &mut model,
        &s.recording,
        &FitOptions::default(),
        &mut |_, _| {},
    )
    .unwrap();
    // Variable breaths cannot be matched by one sinusoid: looser bounds than the acceptance.
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(
        rel(fit.drive.frequency, d.frequency) < 0.06,
        "{:?}",
        fit.drive
    );
    assert!(
        rel(fit.drive.ribs.amplitude, d.ribs.amplitude) < 0.25,
        "{:?}",
        fit.drive
    );
    assert!(
        rel(fit.drive.diaphragm.amplitude, d.diaphragm.amplitude) < 0.25,
        "{:?}",
        fit.drive
    );
    assert!(fit.cost_m < 3.0 * s.noise_floor_m);
}

#[test]
fn a_grid_that_differs_from_the_model_is_rejected_naming_both() {
    let mut model = LaggedGrid {
        rows: 8,
        cols: 6,
        runs: 0,
    };
    let s = synthesize(
        &mut model,
        &SynthOptions {
            duration: 5.0,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let mut model = grid_model();
    let e = fit_recording(
        &mut model,
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
    assert!(check_grid((10, 6), (10, 6)).is_ok());
}

#[test]
fn recordings_without_motion_are_rejected() {
    let mut model = grid_model();
    let mut rest = Vec::new();
    model.markers(0.0, 0.0, &mut rest);
    let rec = Recording {
        grid: (10, 6),
        times: (0..100).map(|i| i as f64 / 56.0).collect(),
        frames: vec![rest.iter().map(|p| Some(*p)).collect(); 100],
        units: breathing_torso::recording::Units::Metres,
        provenance: Vec::new(),
    };
    let e = fit_recording(&mut model, &rec, &FitOptions::default(), &mut |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("do not move") || e.contains("0.1-1 Hz"), "{e}");
}

#[test]
fn cost_is_the_mean_distance_over_tracked_points() {
    let m = vec![vec![Point3::origin(), Point3::new(1.0, 0.0, 0.0)]; 2];
    let r = vec![
        vec![Some(Point3::new(0.0, 3.0, 0.0)), None],
        vec![
            Some(Point3::new(0.0, 0.0, 1.0)),
            Some(Point3::new(1.0, 2.0, 0.0)),
        ],
    ];
    assert!((mean_distance(&m, &r) - 2.0).abs() < 1e-12);
}

#[test]
fn outputs_are_written() {
    let d = drive(0.25, 0.3, 0.3, 0.1);
    let synth = SynthOptions {
        drive: d,
        duration: 8.0,
        ..SynthOptions::default()
    };
    let mut model = grid_model();
    let s = synthesize(&mut model, &synth).unwrap();
    let dir = std::env::temp_dir().join(format!("fit_outputs_{}", std::process::id()));
    let rec_path = dir.join("rec.csv");
    s.recording.write(&rec_path).unwrap();
    let back = Recording::read(&rec_path).unwrap();
    let mut model = grid_model();
    let fit = fit_recording(
        &mut model,
        &back,
        &FitOptions {
            max_evals: 30,
            ..FitOptions::default()
        },
        &mut |_, _| {},
    )
    .unwrap();
    let model = breathing_torso::Config::default();
    let out = write_fit(&fit, &dir.join("result.json"), &rec_path, &model, None).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out.json).unwrap()).unwrap();
    for key in [
        "drive.frequency",
        "drive.ribs.amplitude",
        "drive.ribs.phase",
        "drive.diaphragm.amplitude",
        "drive.diaphragm.phase",
        "cost_m",
        "initial_cost_m",
        "evaluations",
        "wall_s",
        "delta_phase",
        "lung_volume_csv",
    ] {
        assert!(v.get(key).is_some(), "result.json lacks {key}");
    }
    assert!(v["skin_fit_error_m"]["before"].is_number());
    assert_eq!(v["evaluations"].as_u64().unwrap() as usize, fit.evaluations);
    let csv = std::fs::read_to_string(&out.volume_csv).unwrap();
    assert_eq!(csv.lines().count(), back.frames.len() + 1);
    assert!(csv.starts_with("time,volume.lung\n"));
    assert!(std::fs::metadata(&out.png).unwrap().len() > 10_000);
    let truth = truth_json(&s, &model.subject, 0, &synth);
    // The first frame is at end-expiration, after the rib-cage activation minimum (-pi/2)
    // by the response's lag; the phase difference is the drive's.
    let phi_r = truth["drive.ribs.phase"].as_f64().unwrap();
    assert!(
        phi_r > -std::f64::consts::FRAC_PI_2 && phi_r < 0.0,
        "{phi_r}"
    );
    let dphi = truth["drive.diaphragm.phase"].as_f64().unwrap() - phi_r;
    assert!((wrap_angle(dphi) - 0.1).abs() < 1e-9, "{dphi}");
    assert!(truth["camera"]["rotation_matrix"].is_array());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn identity_camera_keeps_the_model_frame() {
    let mut model = grid_model();
    let s = synthesize(
        &mut model,
        &SynthOptions {
            camera: Camera::Identity,
            noise: 0.0,
            duration: 4.0,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let rest = grid_model().rest();
    let first: Vec<Point3<f64>> = s.recording.frames[0].iter().map(|p| p.unwrap()).collect();
    let d = mean_distance(&[rest], &[first.iter().map(|p| Some(*p)).collect()]);
    assert!(d < 2e-3, "first frame near rest: {d}");
}

/// The rest-pose grid a fit implies is the model's rest grid in the camera frame, far
/// closer than the recording's first frame (end-expiration, where the lagged activations are
/// not zero) and than its per-frame noise.
#[test]
fn rest_reference_recovers_the_rest_grid_in_the_camera_frame() {
    use breathing_torso::fit::fitting::rest_reference;
    let d = drive(0.25, 0.3, 0.35, 0.3);
    let mut model = grid_model();
    let s = synthesize(
        &mut model,
        &SynthOptions {
            drive: d,
            seed: 23,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let mut model = grid_model();
    let fit = fit_recording(
        &mut model,
        &s.recording,
        &FitOptions::default(),
        &mut |_, _| {},
    )
    .unwrap();
    let rest: Vec<Point3<f64>> = model.rest();
    let reference = rest_reference(&fit, &rest).unwrap();
    let truth: Vec<Point3<f64>> = rest.iter().map(|p| s.camera.apply(p)).collect();
    let mean = |a: &[Option<Point3<f64>>]| {
        a.iter()
            .zip(&truth)
            .map(|(q, p)| (q.unwrap() - p).norm())
            .sum::<f64>()
            / truth.len() as f64
    };
    let first = mean(&s.recording.frames[0]);
    let implied = mean(&reference);
    eprintln!(
        "rest grid: first frame {:.3} mm away, implied reference {:.3} mm (noise floor {:.3} mm)",
        first * 1e3,
        implied * 1e3,
        s.noise_floor_m * 1e3
    );
    assert!(
        first > s.noise_floor_m,
        "the first frame is not the rest pose"
    );
    assert!(implied < 0.15 * s.noise_floor_m, "{implied}");
    assert!(rest_reference(&fit, &rest[1..]).is_err());
}
