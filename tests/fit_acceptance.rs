//! Issue 33's acceptance on data made differently (deliverable 7), through `torso fit` with
//! its defaults: recordings made by the level of detail 2 torso of a subject 8 % taller and
//! heavier than the default man (src/fit/mismatch.rs, `make_truth`: a non-sine drive with
//! Ti/Ttot drawn in 0.38-0.45, 10 % breath-to-breath variation of depth and period, 18 s,
//! 0.5 mm noise per coordinate, 2 % of the samples missing), then given the nuisances:
//!
//! - a random laboratory rotation (the SLP grid in a random camera frame; the named sets in
//!   a z-up laboratory turned at random about the vertical, standing, and the chest-and-back
//!   set once more lying supine: the body's antero-posterior axis the lab's vertical, no
//!   sway, as on a couch);
//! - sway on the standing sets with back markers (rigid: an inverted pendulum about the
//!   floor at 0.03 and 0.12 Hz and a 0.07 Hz shift, 5-10 mm at the chest);
//! - each marker drifting 10 mm over the recording along its own direction;
//! - one label swap of two neighbouring markers halfway through.
//!
//! Each is written to a file and fitted by `torso fit --lod L --threads 1` with no other
//! flag (size estimated, each marker about its mean, drift projected out, sway removed,
//! swaps repaired, Ti/Ttot 0.5), at levels of detail 0 and 1. Bounds (the issue's): the
//! lung's tidal volume within 10 % of the truth's mean over the recording's breaths; the
//! breath timing the fit reads off the recording within the SLP limits of agreement against
//! the drive's breaths (Ti, Te, Ttot within 0.22, 0.29, 0.32 s; Motamedi-Fakhr et al.
//! 2017), the worst breath counted; the marker residual at most 1.15 x the noise plus the
//! mismatch floor.
//!
//! The residual is the one the fit reports after its nuisance terms,
//! `quality.variance_explained.split.residual_rms_m`: the root mean square, over every
//! tracked sample of every marker, of the length of the 3-D vector recorded (after the
//! sway is removed) minus fitted minus the fitted drift, about each marker's mean, in
//! metres. The noise in that measure is the rms length of the 3-D noise vector, sqrt(3)
//! sigma for the recording's sigma = 0.5 mm per coordinate (0.866 mm); the fit's own
//! estimate of sigma is printed beside it. The mismatch floor is the same residual of the
//! same command at the same level of detail on the truth's noise-free twin: the same truth
//! run, breaths, frame and dropped points, with no noise, sway, drift or swap (model
//! mismatch alone: another level of detail and another subject); one per marker set and
//! level, the supine case sharing the standing one's. The bound is the linear sum,
//! 1.15 x sqrt(3) sigma + floor. Noise and mismatch being independent, their residuals add in
//! quadrature (residual^2 = 3 sigma^2 + floor^2, less what the fit's few parameters take up
//! of the noise), which the linear sum exceeds: the bound is the looser of the two.
//!
//! It takes about 8 minutes on one core (499 s measured on a shared 2-core machine: about 30
//! s per truth made, 13-34 s per command at level of detail 0 and 33-41 s at level 1, each
//! including the size estimate): `cargo test --release --test fit_acceptance -- --ignored
//! --nocapture`. Measured (docs/fit_report.md), tidal volume at levels 0 / 1: grid -9.4 /
//! -5.4 %, chest30 standing -4.1 / +0.6 %, chest30 supine -4.1 / +0.8 %, oep89 **-10.8** /
//! -5.9 % (over the bound at level 0). Breath timing within the limits in all eight fits
//! (worst Ti 0.165 s, Te 0.255 s, Ttot 0.226 s). Residual against 1.15 x 0.866 mm + floor,
//! levels 0 / 1: grid 1.297 / 1.247 mm (floors 0.977 / 0.906 mm), chest30 standing 0.965 /
//! 0.945 mm and supine 0.958 / 0.937 mm (floors 0.422 / 0.340 mm), oep89 0.997 / 0.966 mm
//! (floors 0.473 / 0.398 mm): within the bound in all eight, and within 2 % of the
//! quadrature sum sqrt(0.866^2 + floor^2).

use breathing_torso::anatomy::skin::RigidTransform;
use breathing_torso::fit::mismatch::{
    LIMIT_TE_S, LIMIT_TI_S, LIMIT_TTOT_S, MismatchOptions, MismatchTruth, make_truth,
};
use breathing_torso::numeric::rng::Pcg64;
use breathing_torso::recording::{Format, Markers, Units};
use nalgebra::{Matrix3, Point3, Rotation3, UnitQuaternion, Vector3};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

type Frames = Vec<Vec<Option<Point3<f64>>>>;

/// The residual may reach this many times the noise plus the mismatch floor (issue 33,
/// deliverable 7: 1.15).
const RESIDUAL_NOISE_FACTOR: f64 = 1.15;

/// The sway of tests/fit_sway.rs (z-up laboratory, pivot on the floor).
fn sway(frames: &Frames, times: &[f64]) -> Frames {
    let tracked: Vec<Vector3<f64>> = frames[0].iter().flatten().map(|p| p.coords).collect();
    let c = tracked.iter().sum::<Vector3<f64>>() / tracked.len() as f64;
    let pivot = Vector3::new(c.x, c.y, 0.0);
    frames
        .iter()
        .zip(times)
        .map(|(f, &t)| {
            let turn = UnitQuaternion::from_scaled_axis(Vector3::new(
                0.006 * (2.0 * PI * 0.03 * t + 0.4).sin(),
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

/// Each marker drifting 10 mm along its own random direction over the recording.
fn drift(frames: &Frames, times: &[f64], seed: u64) -> Frames {
    let mut rng = Pcg64::new(seed, 17);
    let n = frames[0].len();
    let directions: Vec<Vector3<f64>> = (0..n)
        .map(|_| Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize())
        .collect();
    let span = times[times.len() - 1] - times[0];
    frames
        .iter()
        .zip(times)
        .map(|(f, t)| {
            f.iter()
                .zip(&directions)
                .map(|(q, d)| q.map(|q| q + d * 10e-3 * (t - times[0]) / span))
                .collect()
        })
        .collect()
}

/// Lying supine: each recorded point taken back to the model frame (`camera`: model ->
/// lab) and laid down, the body's front (model x) up the lab's z, its head (model y) along
/// the lab's x, then turned at random about the vertical.
fn supine(frames: &Frames, camera: &RigidTransform, seed: u64) -> Frames {
    let mut rng = Pcg64::new(seed, 19);
    let lay = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
        Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0),
    ));
    let yaw = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 2.0 * PI * rng.uniform());
    let shift = Vector3::new(0.3, -0.2, 0.9);
    frames
        .iter()
        .map(|f| {
            f.iter()
                .map(|q| {
                    q.map(|q| Point3::from(yaw * lay * camera.apply_inverse(&q).coords + shift))
                })
                .collect()
        })
        .collect()
}

/// The pair of neighbouring markers swapped halfway through.
fn swap_pair(set: &str) -> (&'static str, &'static str) {
    match set {
        "grid" => ("marker[14]", "marker[15]"),
        "chest30" => ("C3FR1", "C3FL1"),
        _ => ("O4A2", "O4A3"),
    }
}

struct Case {
    name: String,
    file: PathBuf,
    truth_tv: f64,
    truth_breaths: Vec<(f64, f64)>,
    ti_ttot: f64,
    /// Index of the truth (and of its noise-free twin's file in the floors).
    truth: usize,
}

/// The truth's noise-free twin (same truth run, breaths, frame and dropped points; no noise,
/// sway, drift or swap), written as its noisy recording is: the file of the mismatch floor.
fn write_clean(t: &MismatchTruth, dir: &Path) -> PathBuf {
    let rec = &t.clean;
    if t.labels.is_empty() {
        let path = dir.join(format!("{}_clean.csv", t.marker_set));
        rec.write(&path).unwrap();
        path
    } else {
        let path = dir.join(format!("{}_clean.c3d", t.marker_set));
        Markers {
            labels: t.labels.clone(),
            times: rec.times.clone(),
            frames: rec.frames.clone(),
            units: Units::Millimetres,
            format: Format::C3d,
            provenance: Vec::new(),
        }
        .write(&path)
        .unwrap();
        path
    }
}

fn write_case(t: &MismatchTruth, truth: usize, standing: bool, dir: &Path, seed: u64) -> Case {
    let rec = &t.synthetic.recording;
    let times = &rec.times;
    let grid = t.labels.is_empty();
    let labels: Vec<String> = if grid {
        (0..rec.points())
            .map(|k| format!("marker[{}]", k + 1))
            .collect()
    } else {
        t.labels.clone()
    };
    let mut frames = rec.frames.clone();
    let mut what = vec!["noise 0.5 mm", "2 % gaps"];
    if !grid {
        if standing {
            frames = sway(&frames, times);
            what.push("sway");
        } else {
            frames = supine(&frames, &t.synthetic.camera, seed);
            what.push("supine");
        }
    }
    frames = drift(&frames, times, seed);
    let (a, b) = swap_pair(&t.marker_set);
    let (ia, ib) = (
        labels.iter().position(|l| l == a).unwrap(),
        labels.iter().position(|l| l == b).unwrap(),
    );
    let half = frames.len() / 2;
    for f in frames.iter_mut().skip(half) {
        f.swap(ia, ib);
    }
    what.extend(["drift 10 mm", "one label swap"]);
    let name = format!(
        "{} {}",
        t.marker_set,
        if grid {
            "camera"
        } else if standing {
            "standing"
        } else {
            "supine"
        }
    );
    let file = if grid {
        let path = dir.join(format!("{}.csv", name.replace(' ', "_")));
        breathing_torso::recording::Recording {
            frames,
            ..rec.clone()
        }
        .write(&path)
        .unwrap();
        path
    } else {
        let path = dir.join(format!("{}.c3d", name.replace(' ', "_")));
        Markers {
            labels,
            times: times.clone(),
            frames,
            units: Units::Millimetres,
            format: Format::C3d,
            provenance: Vec::new(),
        }
        .write(&path)
        .unwrap();
        path
    };
    println!("{name}: {}", what.join(", "));
    Case {
        name,
        file,
        truth_tv: t.mean_tidal_volume_l(),
        truth_breaths: t.breaths.clone(),
        ti_ttot: t.ti_ttot,
        truth,
    }
}

/// Worst |error| of Ti, Te, Ttot of the recording's breaths (result JSON) against the
/// drive's (onsets within 0.5 s), and the breaths matched of those found.
fn timing(json: &serde_json::Value, c: &Case) -> ([f64; 3], usize, usize) {
    let rb = &json["recording_breaths"];
    let get = |k: &str| -> Vec<f64> {
        rb[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap_or(f64::NAN))
            .collect()
    };
    let (onsets, ti, te, ttot) = (get("onset_s"), get("ti_s"), get("te_s"), get("ttot_s"));
    let mut worst = [0.0f64; 3];
    let mut matched = 0;
    for k in 0..ti.len() {
        let Some(&(start, period)) = c
            .truth_breaths
            .iter()
            .min_by(|a, b| (a.0 - onsets[k]).abs().total_cmp(&(b.0 - onsets[k]).abs()))
        else {
            continue;
        };
        if (start - onsets[k]).abs() > 0.5 {
            continue;
        }
        matched += 1;
        let tti = c.ti_ttot * period;
        worst[0] = worst[0].max((ti[k] - tti).abs());
        worst[1] = worst[1].max((te[k] - (period - tti)).abs());
        worst[2] = worst[2].max((ttot[k] - period).abs());
    }
    (worst, matched, ti.len())
}

/// Runs `torso fit --lod LOD --threads 1 --slp FILE --out JSON` with no other flag; the
/// result JSON, the command's wall time and the report lines worth printing.
fn run_fit(
    file: &Path,
    lod: u32,
    out: &Path,
) -> Result<(serde_json::Value, f64, Vec<String>), String> {
    let start = std::time::Instant::now();
    let run = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["fit", "--lod", &lod.to_string(), "--threads", "1", "--slp"])
        .arg(file)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    let wall = start.elapsed().as_secs_f64();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    if !run.status.success() {
        return Err(format!("torso fit failed:\n{stdout}\n{stderr}"));
    }
    let lines = stdout
        .lines()
        .chain(stderr.lines())
        .filter(|line| {
            [
                "repaired",
                "sway",
                "subject size",
                "warning",
                "quality",
                "explained",
            ]
            .iter()
            .any(|k| line.starts_with(k))
        })
        .map(str::to_string)
        .collect();
    let json = serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
    Ok((json, wall, lines))
}

/// The fit's residual after its nuisance terms (`quality.variance_explained.split.
/// residual_rms_m`, see the module doc) [m].
fn residual_rms(json: &serde_json::Value) -> f64 {
    json["quality"]["variance_explained"]["split"]["residual_rms_m"]
        .as_f64()
        .unwrap_or(f64::NAN)
}

#[test]
#[ignore = "issue 33: about 8 minutes (499 s measured), and oep89 at level of detail 0 misses the 10 % tidal volume bound (-10.8 % measured; -5.9 % at level 1; grid -9.4 / -5.4 %, chest30 standing -4.1 / +0.6 %, supine -4.1 / +0.8 % at levels 0 / 1); breath timing and the residual bound met in all eight fits: cargo test --release --test fit_acceptance -- --ignored --nocapture"]
fn recordings_made_differently_with_every_nuisance_are_fitted_by_the_defaults() {
    let dir = std::env::temp_dir().join(format!("torso_fit_acceptance_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let o = MismatchOptions {
        fit_lods: vec![0, 1],
        ..MismatchOptions::default()
    };
    // The noise's residual in the residual's measure: the root mean square length of a 3-D
    // vector of independent N(0, sigma^2) coordinates.
    let noise_rms = 3f64.sqrt() * o.noise;
    let mut cases = Vec::new();
    let mut clean = Vec::new();
    for k in 0..o.marker_sets.len() {
        let t = make_truth(&o, k).unwrap();
        println!(
            "truth {}: Ti/Ttot {:.3}, tidal volume {:.4} L over {} breaths, made in {:.1} s",
            t.marker_set,
            t.ti_ttot,
            t.mean_tidal_volume_l(),
            t.tidal_volumes_l.len(),
            t.wall_s
        );
        clean.push((t.marker_set.clone(), write_clean(&t, &dir)));
        cases.push(write_case(&t, k, true, &dir, o.seed + k as u64));
        if t.marker_set == "chest30" {
            cases.push(write_case(&t, k, false, &dir, o.seed + 100));
        }
    }
    let mut failures = Vec::new();
    for &lod in &o.fit_lods {
        // The mismatch floor of each truth at this level: the residual of the same fit of
        // its noise-free, nuisance-free twin.
        let mut floors = Vec::new();
        for (set, file) in &clean {
            let out = dir.join(format!("{set}_clean_lod{lod}.json"));
            let floor = match run_fit(file, lod, &out) {
                Ok((json, wall, _)) => {
                    let r = residual_rms(&json);
                    println!(
                        "level {lod}, {set} noise-free: residual {:.3} mm rms (the mismatch floor), \
                         tidal volume {:.4} L, {} evaluations, whole command {wall:.1} s",
                        r * 1e3,
                        json["breaths_summary"]["mean"]["tidal_volume_l"]
                            .as_f64()
                            .unwrap_or(f64::NAN),
                        json["evaluations"],
                    );
                    r
                }
                Err(e) => {
                    println!("level {lod}, {set} noise-free: {e}");
                    failures.push(format!("level {lod}, {set} noise-free: the fit failed"));
                    f64::NAN
                }
            };
            floors.push(floor);
        }
        for c in &cases {
            let out = dir.join(format!("{}_lod{lod}.json", c.name.replace(' ', "_")));
            let (json, wall, lines) = match run_fit(&c.file, lod, &out) {
                Ok(r) => r,
                Err(e) => {
                    println!("level {lod}, {}: {e}", c.name);
                    failures.push(format!("level {lod}, {}: the fit failed", c.name));
                    continue;
                }
            };
            for line in lines {
                println!("  {line}");
            }
            let tv = json["breaths_summary"]["mean"]["tidal_volume_l"]
                .as_f64()
                .unwrap();
            let e = tv / c.truth_tv - 1.0;
            let (worst, matched, found) = timing(&json, c);
            let residual = residual_rms(&json);
            let floor = floors[c.truth];
            let bound = RESIDUAL_NOISE_FACTOR * noise_rms + floor;
            println!(
                "level {lod}, {}: tidal volume {tv:.4} L against {:.4} L ({:+.1} %); breath timing worst |error| Ti {:.3} s, \
                 Te {:.3} s, Ttot {:.3} s ({matched} of {found} breaths matched); residual {:.3} mm rms against \
                 {RESIDUAL_NOISE_FACTOR} x noise {:.3} mm + mismatch floor {:.3} mm = {:.3} mm (noise sigma {:.3} mm per \
                 coordinate, the fit's estimate {:.3} mm; cost {:.3} mm); {} evaluations, fit {:.1} s, whole command {wall:.1} s",
                c.name,
                c.truth_tv,
                100.0 * e,
                worst[0],
                worst[1],
                worst[2],
                residual * 1e3,
                noise_rms * 1e3,
                floor * 1e3,
                bound * 1e3,
                o.noise * 1e3,
                json["quality"]["noise"]["sigma_m"]
                    .as_f64()
                    .unwrap_or(f64::NAN)
                    * 1e3,
                json["cost_m"].as_f64().unwrap_or(f64::NAN) * 1e3,
                json["evaluations"],
                json["wall_s"].as_f64().unwrap_or(f64::NAN),
            );
            if e.abs() > 0.10 {
                failures.push(format!(
                    "level {lod}, {}: tidal volume {:+.1} %",
                    c.name,
                    100.0 * e
                ));
            }
            for (k, (w, lim)) in worst
                .iter()
                .zip([LIMIT_TI_S, LIMIT_TE_S, LIMIT_TTOT_S])
                .enumerate()
            {
                if *w > lim || matched == 0 {
                    failures.push(format!(
                        "level {lod}, {}: {} worst error {w:.3} s over {lim} s",
                        c.name,
                        ["Ti", "Te", "Ttot"][k]
                    ));
                }
            }
            if residual.is_nan() || residual > bound {
                failures.push(format!(
                    "level {lod}, {}: residual {:.3} mm over {:.3} mm",
                    c.name,
                    residual * 1e3,
                    bound * 1e3
                ));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{failures:#?}");
}
