//! Drift as a nuisance of the cost (src/fit/drift.rs): a recording of the 30 chest-and-back
//! markers made at level of detail 1, each marker drifting 10 mm over the recording along its
//! own direction (the "linear or slow drift, 10 mm over the recording"), with 0.5 mm
//! of noise, fitted at level of detail 0 with each marker about its own mean, with and
//! without the drift removed. The bound is the acceptance: the tidal volume within
//! 10 % of the truth.

use breathing_torso::anatomy::skin::{MarkerSet, Skin, SkinOptions, SurfaceOptions};
use breathing_torso::fit::quality::quality;
use breathing_torso::fit::{
    Camera, FitOptions, PoseOptions, SynthOptions, TorsoMarkers, fit_any_markers, synthesize,
};
use breathing_torso::model::Drive;
use breathing_torso::numeric::rng::Pcg64;
use breathing_torso::recording::{Format, Markers, Units};
use breathing_torso::{Config, Torso};
use nalgebra::Vector3;
use std::sync::Arc;

fn config(lod: u32) -> Config {
    let mut c = Config::default();
    c.scene.level_of_detail = lod;
    c.solver.rtol = 1e-4;
    c
}

fn tidal_volume(config: &Config, drive: Drive) -> f64 {
    let mut c = config.clone();
    c.drive = drive;
    c.drive.enabled = true;
    let period = 1.0 / drive.frequency;
    let mut torso = Torso::new(c).unwrap();
    let frames = breathing_torso::model::run::run(&mut torso, 3.0 * period, 28.0).unwrap();
    breathing_torso::model::run::summarise(&frames, period).tidal_volume
}

#[test]
fn a_ten_millimetre_drift_is_projected_out_and_the_tidal_volume_kept() {
    let truth_config = config(1);
    let mut torso = Torso::new(truth_config.clone()).unwrap();
    let skin = Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default()).unwrap();
    let set = MarkerSet::builtin(&skin, "chest30").unwrap();
    torso.set_marker_set(Some(Arc::new(set.clone())));
    let mut source = TorsoMarkers::from_torso(torso).unwrap();
    let s = synthesize(
        &mut source,
        &SynthOptions {
            duration: 18.0,
            rate: 30.0,
            camera: Camera::Lab,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let mut rng = Pcg64::new(17, 2);
    let directions: Vec<Vector3<f64>> = (0..set.len())
        .map(|_| Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize())
        .collect();
    let duration = s.recording.times.last().unwrap() - s.recording.times[0];
    let markers = Markers {
        labels: set.labels.clone(),
        times: s.recording.times.clone(),
        frames: s
            .recording
            .frames
            .iter()
            .zip(&s.recording.times)
            .map(|(f, t)| {
                f.iter()
                    .zip(&directions)
                    .map(|(q, d)| q.map(|q| q + d * 10e-3 * (t - s.recording.times[0]) / duration))
                    .collect()
            })
            .collect(),
        units: Units::Metres,
        format: Format::MarkerCsv,
        provenance: Vec::new(),
    };
    let truth = tidal_volume(&truth_config, s.truth);
    let mut errors = Vec::new();
    for drift in [false, true] {
        let fit = fit_any_markers(
            config(0),
            &markers,
            &SurfaceOptions::default(),
            &PoseOptions::default(),
            &FitOptions {
                max_evals: 120,
                drift,
                ..FitOptions::default()
            },
            &mut |_, _| {},
        )
        .unwrap()
        .fit;
        let q = quality(&fit);
        let tv = tidal_volume(&config(0), fit.drive);
        println!(
            "drift removed {drift}: tidal volume {tv:.4} L against the truth {truth:.4} L ({:+.1} %), \
             cost {:.3} mm, {} evaluations, {:.1} s; drift share {:?}, drive explains {:.2} above the noise; \
             sensitivities {:?}",
            100.0 * (tv / truth - 1.0),
            fit.cost_m * 1e3,
            fit.evaluations,
            fit.wall_s,
            q.drift_share,
            q.after_drift.as_ref().unwrap_or(&q.explained).above_noise,
            fit.sensitivity
        );
        errors.push(tv / truth - 1.0);
        if drift {
            assert!(q.drift_share.unwrap() > 0.1, "{:?}", q.drift_share);
            assert!(q.explains, "{:?}", q.notes);
            assert_eq!(fit.sensitivity.len(), 4);
        }
    }
    assert!(
        errors[1].abs() < 0.10,
        "with drift removed: {:+.3}",
        errors[1]
    );
}
