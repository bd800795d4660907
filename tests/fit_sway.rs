//! The trunk's sway (src/fit/sway.rs): a rigid motion of the whole trunk estimated from the
//! markers over the back and removed where it is slower than the breath.
//!
//! - On a cloud of markers (no model): a rigid sway of 7 mm and 0.57 degrees at 0.05 and
//!   0.1 Hz is taken out, the breath of the front markers left in place.
//! - On recordings of the 30 chest-and-back markers made at level of detail 1 in a
//!   laboratory frame, with 0.5 mm of noise, given the sway (rigid, 5-10 mm,
//!   0.02-0.15 Hz: an inverted pendulum about the floor under the subject swaying at 0.03
//!   and 0.12 Hz plus a 0.07 Hz shift), fitted at level of detail 0 with the command line's
//!   defaults (each marker about its mean, drift removed), with and without the sway
//!   removed, and the same recording without sway, with and without.
//!
//! Bounds, from the acceptance: the tidal volume within 10 % of the truth; and the
//! marker residual at most 1.15 times the noise sigma, so what the sway removal leaves or
//! takes wrongly (e per coordinate, rms) may add at most sqrt(1.15^2 - 1) = 0.57 sigma to
//! the noise (sqrt(sigma^2 + e^2) <= 1.15 sigma).

use breathing_torso::anatomy::skin::{
    MarkerSet, Skin, SkinOptions, SurfaceOptions, register_rigid,
};
use breathing_torso::fit::sway::remove_sway;
use breathing_torso::fit::{
    Camera, FitOptions, PoseOptions, SynthOptions, TorsoMarkers, fit_any_markers, synthesize,
};
use breathing_torso::model::Drive;
use breathing_torso::recording::{Format, Markers, Units};
use breathing_torso::{Config, Torso};
use nalgebra::{Point3, UnitQuaternion, Vector3};
use std::f64::consts::PI;
use std::sync::Arc;

/// The noise of the synthetic recordings [m] (the 0.5 mm).
const NOISE: f64 = 0.5e-3;
/// What sway removal may leave or take, per coordinate, as a share of the noise sigma.
const LEFT_OF_SIGMA: f64 = 0.57;

#[test]
fn slow_rigid_motion_of_a_cloud_is_removed_and_the_breath_kept() {
    let times: Vec<f64> = (0..=900).map(|k| k as f64 / 50.0).collect();
    let f = 0.25;
    // 12 markers: 6 on a back plane standing still, 6 on a front plane breathing 5 mm.
    let base: Vec<Point3<f64>> = (0..12)
        .map(|k| {
            let x = if k < 6 { -0.1 } else { 0.1 };
            Point3::new(x, 0.1 * (k % 3) as f64, 0.1 * ((k / 3) % 2) as f64)
        })
        .collect();
    let labels: Vec<String> = (0..12).map(|k| format!("m{k}")).collect();
    let frames: Vec<Vec<Option<Point3<f64>>>> = times
        .iter()
        .map(|&t| {
            let breath = 0.005 * (2.0 * PI * f * t).sin();
            let sway = Vector3::new(0.007 * (2.0 * PI * 0.05 * t).sin(), 0.0, 0.0);
            let turn = UnitQuaternion::from_scaled_axis(Vector3::new(
                0.0,
                0.01 * (2.0 * PI * 0.1 * t).sin(),
                0.0,
            ));
            base.iter()
                .enumerate()
                .map(|(k, b)| {
                    let moved = if k < 6 {
                        *b
                    } else {
                        b + Vector3::new(breath, 0.0, 0.0)
                    };
                    Some(Point3::from(turn * moved.coords + sway))
                })
                .collect()
        })
        .collect();
    let d = remove_sway(
        &times,
        &frames,
        &labels,
        &[0, 1, 2, 3, 4, 5],
        "named",
        false,
    )
    .unwrap();
    println!("{}", d.sway.summary());
    assert!(d.sway.removed);
    assert!(
        (d.sway.breathing_hz - f).abs() < 0.01,
        "{}",
        d.sway.breathing_hz
    );
    // The whole-trunk motion removed: each marker, against its own first frame, stands
    // still (back) or moves by the breath (front) within 0.2 mm; the breath kept whole.
    let mut worst: f64 = 0.0;
    for (i, frame) in d.frames.iter().enumerate() {
        let breath = 0.005 * (2.0 * PI * f * times[i]).sin();
        for (k, q) in frame.iter().enumerate() {
            let want = d.frames[0][k].unwrap().coords
                + if k < 6 {
                    Vector3::zeros()
                } else {
                    Vector3::new(breath, 0.0, 0.0)
                };
            worst = worst.max((q.unwrap().coords - want).norm());
        }
    }
    println!(
        "largest error of a marker after the sway's removal: {:.3} mm",
        worst * 1e3
    );
    assert!(worst < 2e-4, "{worst}");
    // Too few reference markers, or a set of 6 or fewer: nothing removed, and said.
    for (frames, reference) in [
        (frames.clone(), vec![0, 1]),
        (
            frames.iter().map(|f| f[..6].to_vec()).collect::<Vec<_>>(),
            vec![0, 1, 2],
        ),
    ] {
        let few = remove_sway(&times, &frames, &labels, &reference, "named", false).unwrap();
        assert!(!few.sway.removed, "{}", few.sway.note);
        println!("{}", few.sway.summary());
        assert_eq!(few.frames, frames);
    }
}

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

/// The sway in a z-up laboratory: an inverted pendulum about the floor point under
/// the markers' centroid, `slow` rad at 0.03 Hz about one horizontal axis and 0.004 rad at
/// 0.12 Hz about the other, plus a 3 mm shift at 0.07 Hz: 5-10 mm at the chest.
fn sway(
    frames: &[Vec<Option<Point3<f64>>>],
    times: &[f64],
    slow: f64,
) -> Vec<Vec<Option<Point3<f64>>>> {
    let tracked: Vec<Vector3<f64>> = frames[0].iter().flatten().map(|p| p.coords).collect();
    let c = tracked.iter().sum::<Vector3<f64>>() / tracked.len() as f64;
    let pivot = Vector3::new(c.x, c.y, 0.0);
    frames
        .iter()
        .zip(times)
        .map(|(f, &t)| {
            let turn = UnitQuaternion::from_scaled_axis(Vector3::new(
                slow * (2.0 * PI * 0.03 * t + 0.4).sin(),
                0.004 * (2.0 * PI * 0.12 * t + 1.1).sin(),
                0.0,
            ));
            let shift = Vector3::new(0.0, 0.003 * (2.0 * PI * 0.07 * t).sin(), 0.0);
            f.iter()
                .map(|q| q.map(|q| Point3::from(turn * (q.coords - pivot) + pivot + shift)))
                .collect()
        })
        .collect()
}

/// Per coordinate rms of `a` against `b` after one rigid transform over all frames.
fn rigid_rms(a: &[Vec<Option<Point3<f64>>>], b: &[Vec<Option<Point3<f64>>>]) -> f64 {
    let model: Vec<Point3<f64>> = b.iter().flatten().map(|q| q.unwrap()).collect();
    let moved: Vec<Option<Point3<f64>>> = a.iter().flatten().copied().collect();
    let (_, rms) = register_rigid(&model, &moved, false).unwrap();
    rms / 3f64.sqrt()
}

#[test]
fn sway_of_a_chest_and_back_set_is_removed_and_the_tidal_volume_kept() {
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
            noise: NOISE,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let times = &s.recording.times;
    let still = s.recording.frames.clone();
    let swayed = sway(&still, times, 0.006);
    // Without the slow part: the breath stays the largest motion.
    let quick = sway(&still, times, 0.0);
    let back: Vec<usize> = (0..set.len())
        .filter(|&k| set.labels[k].as_bytes()[2] == b'B')
        .collect();
    // What the removal leaves of the sway, and what it does to a recording without sway.
    let removed = remove_sway(times, &swayed, &set.labels, &back, "named", false).unwrap();
    let untouched = remove_sway(times, &still, &set.labels, &back, "named", false).unwrap();
    let (left, changed) = (
        rigid_rms(&removed.frames, &still),
        rigid_rms(&untouched.frames, &still),
    );
    let before = rigid_rms(&swayed, &still);
    println!("swayed: {}", removed.sway.summary());
    println!("still:  {}", untouched.sway.summary());
    println!(
        "per coordinate rms against the recording without sway: {:.3} mm swayed, {:.3} mm after removal; \
         removal from the recording without sway changes it by {:.3} mm (allowed {:.3} mm)",
        before * 1e3,
        left * 1e3,
        changed * 1e3,
        LEFT_OF_SIGMA * NOISE * 1e3
    );
    assert!(left < LEFT_OF_SIGMA * NOISE, "{left}");
    assert!(changed < LEFT_OF_SIGMA * NOISE, "{changed}");
    // Each marker drifting 10 mm along its own direction, no sway: the back markers' drifts
    // read as a slow rigid motion unless the drift projection is left that part.
    let mut rng = breathing_torso::numeric::rng::Pcg64::new(17, 2);
    let span = times[times.len() - 1] - times[0];
    let directions: Vec<Vector3<f64>> = (0..set.len())
        .map(|_| Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize())
        .collect();
    let drifting: Vec<Vec<Option<Point3<f64>>>> = still
        .iter()
        .zip(times)
        .map(|(f, t)| {
            f.iter()
                .zip(&directions)
                .map(|(q, d)| q.map(|q| q + d * 10e-3 * (t - times[0]) / span))
                .collect()
        })
        .collect();
    let alone = remove_sway(times, &drifting, &set.labels, &back, "named", false).unwrap();
    let with = remove_sway(times, &drifting, &set.labels, &back, "named", true).unwrap();
    println!(
        "10 mm drift per marker, no sway: {:.2} mm rms taken for sway, {:.2} mm when the drift projection is left its part",
        alone.sway.displacement_rms_m * 1e3,
        with.sway.displacement_rms_m * 1e3
    );
    println!("{}\n{}", alone.sway.summary(), with.sway.summary());
    assert!(with.sway.displacement_rms_m < LEFT_OF_SIGMA * NOISE);

    let truth = tidal_volume(&truth_config, s.truth);
    let markers = |frames: Vec<Vec<Option<Point3<f64>>>>| Markers {
        labels: set.labels.clone(),
        times: times.clone(),
        frames,
        units: Units::Metres,
        format: Format::MarkerCsv,
        provenance: Vec::new(),
    };
    let mut errors = Vec::new();
    for (name, frames) in [
        ("swayed", &swayed),
        ("quick sway", &quick),
        ("still", &still),
    ] {
        for remove in [true, false] {
            let fit = match fit_any_markers(
                config(0),
                &markers(frames.clone()),
                &SurfaceOptions::default(),
                &PoseOptions::default(),
                &FitOptions {
                    drift: true,
                    sway: remove,
                    ..FitOptions::default()
                },
                &mut |_, _| {},
            ) {
                Ok(f) => f.fit,
                Err(e) if !remove => {
                    println!("{name}, sway removed {remove}: the fit failed: {e}");
                    continue;
                }
                Err(e) => panic!("{name}, sway removed: {e}"),
            };
            let tv = tidal_volume(&config(0), fit.drive);
            let e = tv / truth - 1.0;
            println!(
                "{name}, sway removed {remove}: tidal volume {tv:.4} L against {truth:.4} L ({:+.1} %), cost {:.3} mm, \
                 {} evaluations, {:.1} s, frequency {:.4} Hz (truth {:.4})",
                100.0 * e,
                fit.cost_m * 1e3,
                fit.evaluations,
                fit.wall_s,
                fit.drive.frequency,
                s.truth.frequency
            );
            if remove {
                let sw = fit.sway.as_ref().unwrap();
                println!("  {}", sw.summary());
                assert!(sw.removed, "{}", sw.note);
                assert_eq!(sw.reference.len(), back.len(), "{:?}", sw.reference);
                assert!(sw.reference.iter().all(|l| l.as_bytes()[2] == b'B'));
            }
            errors.push((name, remove, e));
        }
    }
    for (name, remove, e) in errors {
        if remove {
            assert!(e.abs() < 0.10, "{name}, sway removed: {e:+.3}");
        }
    }
}

/// The reference markers are found from the registered pose: the chest-and-back set's 10
/// back markers and the OEP-like set's 42 posterior ones, each recorded in a laboratory
/// frame at level of detail 0 and bound without correspondences; the front markers alone
/// have none, and no sway is removed from them, the report saying why.
#[test]
fn the_markers_over_the_back_are_found_from_the_registered_pose() {
    use breathing_torso::fit::bind_recording;
    for (name, back_tag) in [("chest30", b'B'), ("oep89", b'P')] {
        let mut torso = Torso::new(config(0)).unwrap();
        let skin = Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default()).unwrap();
        let set = MarkerSet::builtin(&skin, name).unwrap();
        torso.set_marker_set(Some(Arc::new(set.clone())));
        let mut source = TorsoMarkers::from_torso(torso).unwrap();
        let s = synthesize(
            &mut source,
            &SynthOptions {
                duration: 12.0,
                rate: 20.0,
                camera: Camera::Lab,
                ..SynthOptions::default()
            },
        )
        .unwrap();
        let markers = |keep: &dyn Fn(&str) -> bool| {
            let columns: Vec<usize> = (0..set.len()).filter(|&k| keep(&set.labels[k])).collect();
            Markers {
                labels: columns.iter().map(|&k| set.labels[k].clone()).collect(),
                times: s.recording.times.clone(),
                frames: s
                    .recording
                    .frames
                    .iter()
                    .map(|f| columns.iter().map(|&k| f[k]).collect())
                    .collect(),
                units: Units::Metres,
                format: Format::MarkerCsv,
                provenance: Vec::new(),
            }
        };
        let torso = Torso::new_at_rest(config(0)).unwrap();
        let is_back = |l: &str| l.as_bytes()[2] == back_tag;
        let all = markers(&|_| true);
        let bound = bind_recording(
            &torso,
            &all,
            &SurfaceOptions::default(),
            &PoseOptions::default(),
        )
        .unwrap();
        let found: Vec<&str> = bound
            .back
            .iter()
            .map(|&k| bound.set.labels[k].as_str())
            .collect();
        let want = set.labels.iter().filter(|l| is_back(l)).count();
        println!(
            "{name}: {} markers over the back found ({} posterior in the set)",
            found.len(),
            want
        );
        assert_eq!(found.len(), want, "{found:?}");
        assert!(found.iter().all(|l| is_back(l)), "{found:?}");
        let front = markers(&|l| l.as_bytes()[2] == if back_tag == b'B' { b'F' } else { b'A' });
        let bound = bind_recording(
            &torso,
            &front,
            &SurfaceOptions::default(),
            &PoseOptions::default(),
        )
        .unwrap();
        assert!(bound.back.is_empty(), "{:?}", bound.back);
        let d = remove_sway(
            &bound.recording.times,
            &bound.recording.frames,
            &bound.set.labels,
            &bound.back,
            "back",
            true,
        )
        .unwrap();
        println!("{name}, front only: {}", d.sway.summary());
        assert!(!d.sway.removed && d.sway.note.contains("front-only"));
    }
}

/// `torso fit --reference LABELS`: labels the recording does not have are refused, naming
/// the flag and the label; named ones are the sway's reference (the bundled 6 s recording
/// spans 1.6 breaths, too few to tell sway from breath: none is removed, and the result says
/// why). `--marker-radius` is refused for the grid.
#[test]
fn the_command_line_names_the_reference_and_refuses_what_it_cannot_use() {
    let dir = std::env::temp_dir().join(format!("torso_fit_sway_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("result.json");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let fit = |recording: &str, extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_torso"))
            .args([
                "fit",
                "--no-fit-size",
                "--max-evals",
                "12",
                "--threads",
                "1",
                "--slp",
            ])
            .arg(root.join(recording))
            .arg("--out")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let bad = fit(
        "data/recordings/chest30_lab.c3d",
        &["--reference", "C1BR1,C2BR1,NOPE"],
    );
    let err = String::from_utf8_lossy(&bad.stderr);
    println!("{err}");
    assert!(!bad.status.success());
    assert!(err.contains("--reference") && err.contains("NOPE"), "{err}");
    let good = fit(
        "data/recordings/chest30_lab.c3d",
        &["--reference", "C1BR1,C2BR1,C3BR1,C4BL1"],
    );
    assert!(
        good.status.success(),
        "{}",
        String::from_utf8_lossy(&good.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    println!("{}", json["sway"]);
    assert_eq!(json["sway"]["reference_chosen_by"], "named");
    assert_eq!(
        json["sway"]["reference_markers"].as_array().unwrap().len(),
        4
    );
    assert_eq!(json["sway"]["removed"], false);
    assert!(json["sway"]["note"].as_str().unwrap().contains("breaths"));
    assert!(
        json["cost_basis"]["marker_radius_assumption"]
            .as_str()
            .unwrap()
            .contains("skin points")
    );
    let grid = fit("data/recordings/demo_quiet.csv", &["--marker-radius", "6"]);
    let err = String::from_utf8_lossy(&grid.stderr);
    assert!(
        !grid.status.success() && err.contains("--marker-radius"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
