//! The pose of a recorded marker set on the body (src/fit/orient.rs), on 200 recordings made
//! differently from the fitting model: recorded at level of detail 1 by a smaller subject
//! (1.62 m, 64 kg) breathing a non-sine drive (Ti/Ttot 0.42) with 10 % breath-to-breath
//! variation, chosen on the default subject's skin at level of detail 0. Marker sets:
//! front only, front and back, and three rings around the trunk; each recording in one of
//! the 24 axis-aligned laboratory frames (Y-up, Z-up, X-up labs and their turns; with the
//! supine subject, the lab vertical is whichever axis the body's antero-posterior axis
//! lands on) then tilted up to 20 degrees about a random axis and moved up to 2 m, with
//! 0.5 mm of noise per coordinate and 2 % of the samples missing. The requirement (the
//! issue's): the right pose in at least 99 % of the recordings, every one of them fully
//! chosen (registration candidates, breathing-motion front, short fits).

use breathing_torso::anatomy::skin::SurfaceBinding;
use breathing_torso::anatomy::skin::{
    DISTINCT_POSE_DEG, MarkerSet, RigidTransform, Skin, SkinOptions, SurfaceOptions,
};
use breathing_torso::anatomy::{Posture, Subject};
use breathing_torso::fit::orient::{PoseOptions, orient};
use breathing_torso::fit::{Camera, SynthOptions, TorsoMarkers, synthesize};
use breathing_torso::model::Drive;
use breathing_torso::numeric::rng::Pcg64;
use breathing_torso::recording::{Format, Markers, Units};
use breathing_torso::{Config, Torso};
use nalgebra::{Matrix3, Point3, Rotation3, Unit, UnitQuaternion, Vector3};
use std::sync::Arc;

/// Recordings in the acceptance.
const CASES: usize = 200;
/// Required share of right poses (the 99 %).
const REQUIRED: f64 = 0.99;
/// A pose is right when its rotation is within 45 degrees of the truth: half the quarter
/// turn that separates the discrete alternatives this test is about (the 24 axis-aligned
/// frames: front and back, up and down, a side forwards). How closely a pose is refined is
/// tests/marker_registration.rs's subject; the count within 20 degrees is printed too.
const RIGHT_POSE_DEG: f64 = 45.0;

fn config(subject: Subject, lod: u32) -> Config {
    let mut c = Config {
        subject,
        ..Config::default()
    };
    c.scene.level_of_detail = lod;
    c.solver.rtol = 1e-4;
    c
}

/// A pool of points on the trunk's skin between 4 cm below the umbilicus and 1.5 cm below
/// the suprasternal notch, all around, uniform by area: bindings and outward normals.
fn pool(skin: &Skin, n: usize, rng: &mut Pcg64) -> Vec<(SurfaceBinding, Vector3<f64>, f64)> {
    let lm = &skin.landmarks;
    let (lo, hi) = (lm.omphalion_height - 0.04, lm.suprasternale_height - 0.015);
    let tris: Vec<(usize, f64)> = skin
        .triangles
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            let [a, b, c] = t.map(|k| skin.vertices[k as usize]);
            let y = (a.y + b.y + c.y) / 3.0;
            (lo..hi)
                .contains(&y)
                .then(|| (i, 0.5 * (b - a).cross(&(c - a)).norm()))
        })
        .collect();
    let total: f64 = tris.iter().map(|t| t.1).sum();
    (0..n)
        .map(|_| {
            let mut u = rng.uniform() * total;
            let mut pick = tris[tris.len() - 1].0;
            for (i, a) in &tris {
                if u < *a {
                    pick = *i;
                    break;
                }
                u -= a;
            }
            let [a, b, c] = skin.triangles[pick].map(|k| skin.vertices[k as usize]);
            let (mut r1, mut r2) = (rng.uniform(), rng.uniform());
            if r1 + r2 > 1.0 {
                (r1, r2) = (1.0 - r1, 1.0 - r2);
            }
            let normal = (b - a).cross(&(c - a)).normalize();
            let y = (a + (b - a) * r1 + (c - a) * r2).y;
            (
                SurfaceBinding {
                    triangle: pick as u32,
                    barycentric: [1.0 - r1 - r2, r1, r2],
                },
                normal,
                (y - lo) / (hi - lo),
            )
        })
        .collect()
}

/// The truth: the pool's markers recorded on the smaller subject at level of detail 1, in
/// the model frame without noise. Returns the pool (normals, heights) and the frames.
struct Truth {
    pool: Vec<(SurfaceBinding, Vector3<f64>, f64)>,
    times: Vec<f64>,
    frames: Vec<Vec<Option<Point3<f64>>>>,
}

fn truth(posture: Posture, seed: u64) -> Truth {
    let subject = Subject {
        stature: 1.62,
        mass: 64.0,
        posture,
        ..Subject::default()
    };
    let mut torso = Torso::new(config(subject, 1)).unwrap();
    let skin = Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default()).unwrap();
    let mut rng = Pcg64::new(seed, 1);
    let pool = pool(&skin, 900, &mut rng);
    torso.set_marker_set(Some(Arc::new(MarkerSet {
        name: "pool".into(),
        labels: (0..pool.len()).map(|k| format!("P{k}")).collect(),
        bindings: pool.iter().map(|p| p.0).collect(),
    })));
    let mut source = TorsoMarkers::from_torso(torso).unwrap();
    let drive = Drive {
        inspiratory_fraction: 0.42,
        ..Drive::quiet()
    };
    let s = synthesize(
        &mut source,
        &SynthOptions {
            drive,
            rate: 20.0,
            duration: 12.0,
            noise: 0.0,
            seed,
            camera: Camera::Identity,
            variability: 0.1,
            dropout: 0.0,
        },
    )
    .unwrap();
    Truth {
        pool,
        times: s.recording.times,
        frames: s.recording.frames,
    }
}

/// The 24 proper rotations that permute and flip the axes.
fn axis_frames() -> Vec<Matrix3<f64>> {
    let mut out = Vec::new();
    for p in [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ] {
        for signs in 0..8u32 {
            let mut m = Matrix3::zeros();
            for (i, &j) in p.iter().enumerate() {
                m[(i, j)] = if signs & (1 << i) != 0 { -1.0 } else { 1.0 };
            }
            if m.determinant() > 0.0 {
                out.push(m);
            }
        }
    }
    out
}

/// The kinds of marker set.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    FrontOnly,
    FrontAndBack,
    Rings,
}

/// Picks the markers of a set of `kind` from the pool (indices).
fn pick(truth: &Truth, kind: Kind, rng: &mut Pcg64) -> Vec<usize> {
    let take = |mut idx: Vec<usize>, n: usize, rng: &mut Pcg64| {
        for i in 0..idx.len() {
            let j = i + ((rng.uniform() * (idx.len() - i) as f64) as usize).min(idx.len() - i - 1);
            idx.swap(i, j);
        }
        idx.truncate(n);
        idx
    };
    let front: Vec<usize> = (0..truth.pool.len())
        .filter(|&k| truth.pool[k].1.x > 0.6)
        .collect();
    let back: Vec<usize> = (0..truth.pool.len())
        .filter(|&k| truth.pool[k].1.x < -0.6)
        .collect();
    match kind {
        Kind::FrontOnly => take(front, 24, rng),
        Kind::FrontAndBack => {
            let mut a = take(front, 18, rng);
            a.extend(take(back, 10, rng));
            a
        }
        Kind::Rings => {
            let mut out = Vec::new();
            for h in [0.2, 0.5, 0.85] {
                let band: Vec<usize> = (0..truth.pool.len())
                    .filter(|&k| (truth.pool[k].2 - h).abs() < 0.04)
                    .collect();
                // Ten spread around the ring: sorted by the angle of the outward normal.
                let mut band = band;
                band.sort_by(|&a, &b| {
                    let n = |k: usize| truth.pool[k].1.z.atan2(truth.pool[k].1.x);
                    n(a).total_cmp(&n(b))
                });
                let step = band.len() as f64 / 10.0;
                let offset = rng.uniform() * step;
                out.extend(
                    (0..10)
                        .map(|i| band[((offset + i as f64 * step) as usize).min(band.len() - 1)]),
                );
            }
            out.sort_unstable();
            out.dedup();
            out
        }
    }
}

/// One recording: the picked markers through a random lab pose, with noise and gaps.
fn record(truth: &Truth, picked: &[usize], lab: &RigidTransform, rng: &mut Pcg64) -> Markers {
    let frames = truth
        .frames
        .iter()
        .enumerate()
        .map(|(f, frame)| {
            picked
                .iter()
                .map(|&k| {
                    if f > 0 && rng.uniform() < 0.02 {
                        return None;
                    }
                    let e = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.5e-3;
                    frame[k].map(|p| lab.apply(&(p + e)))
                })
                .collect()
        })
        .collect();
    Markers {
        labels: picked.iter().map(|k| format!("M{k}")).collect(),
        times: truth.times.clone(),
        frames,
        units: Units::Metres,
        format: Format::MarkerCsv,
        provenance: Vec::new(),
    }
}

/// A random lab pose: one of the 24 axis frames, then a tilt up to 20 degrees about a random
/// axis, then a shift up to 2 m.
fn lab_pose(frames: &[Matrix3<f64>], rng: &mut Pcg64) -> RigidTransform {
    let k = ((rng.uniform() * 24.0) as usize).min(23);
    let base = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(frames[k]));
    let axis = Unit::new_normalize(Vector3::new(rng.normal(), rng.normal(), rng.normal()));
    let tilt = UnitQuaternion::from_axis_angle(&axis, 20f64.to_radians() * rng.uniform());
    RigidTransform {
        rotation: tilt * base,
        translation: Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize()
            * 2.0
            * rng.uniform(),
        scale: 1.0,
    }
}

/// Rotation error [deg] of a found pose (recording -> model) against the lab pose (model ->
/// recording).
fn pose_error(found: &RigidTransform, lab: &RigidTransform) -> f64 {
    (found.rotation * lab.rotation).angle().to_degrees()
}

#[test]
fn two_hundred_recordings_in_any_lab_frame_get_the_right_pose() {
    let start = std::time::Instant::now();
    let frames = axis_frames();
    let postures = [Posture::Standing, Posture::Supine];
    let truths: Vec<Truth> = postures
        .iter()
        .enumerate()
        .map(|(i, &p)| truth(p, 41 + i as u64))
        .collect();
    let fitting: Vec<(Torso, Skin)> = postures
        .iter()
        .map(|&posture| {
            let torso = Torso::new_at_rest(config(
                Subject {
                    posture,
                    ..Subject::default()
                },
                0,
            ))
            .unwrap();
            let skin =
                Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default()).unwrap();
            (torso, skin)
        })
        .collect();
    println!(
        "truth runs and fitting models: {:.1} s",
        start.elapsed().as_secs_f64()
    );
    let mut rng = Pcg64::new(2033, 7);
    let (mut right, mut first_right, mut several, mut ties) = (0usize, 0usize, 0usize, 0usize);
    let mut wrong = Vec::new();
    let mut worst_right = 0.0f64;
    let mut within_20 = 0usize;
    let mut ups = Vec::new();
    for case in 0..CASES {
        let kind = [Kind::FrontOnly, Kind::FrontAndBack, Kind::Rings][case % 3];
        let p = (case / 3) % 2;
        let picked = pick(&truths[p], kind, &mut rng);
        let lab = lab_pose(&frames, &mut rng);
        let markers = record(&truths[p], &picked, &lab, &mut rng);
        let (torso, skin) = &fitting[p];
        let o = orient(
            torso,
            skin,
            &markers,
            &SurfaceOptions::default(),
            &PoseOptions::default(),
        )
        .unwrap();
        let error = pose_error(&o.registration().to_model, &lab);
        if let Some(c) = o
            .candidates
            .iter()
            .find(|c| pose_error(&c.registration.to_model, &lab) < 45.0)
        {
            ups.push((kind, c.up, c.front));
        }
        let first_error = pose_error(&o.candidates[0].registration.to_model, &lab);
        several += usize::from(o.candidates.len() > 1);
        ties += usize::from(!o.warnings.is_empty());
        first_right += usize::from(first_error < RIGHT_POSE_DEG);
        within_20 += usize::from(error < DISTINCT_POSE_DEG);
        if error < RIGHT_POSE_DEG {
            right += 1;
            worst_right = worst_right.max(error);
        } else {
            let summary: Vec<String> = o
                .candidates
                .iter()
                .map(|c| {
                    format!(
                        "[score {:.0} mm^2, front {:+.2}, up {:+.2}, short fit {:.2} mm, error {:.0} deg]",
                        c.registration.score * 1e6,
                        c.front,
                        c.up,
                        c.short_fit.rms_m() * 1e3,
                        pose_error(&c.registration.to_model, &lab)
                    )
                })
                .collect();
            let at_truth = breathing_torso::anatomy::skin::register_to_surface(
                &skin.vertices,
                &skin.triangles,
                &markers.frames[0],
                &SurfaceOptions {
                    start: Some(lab.inverse()),
                    ..SurfaceOptions::default()
                },
            )
            .unwrap();
            wrong.push(format!(
                "case {case} {kind:?} {:?}: error {error:.0} deg; from the truth: score {:.0} mm^2, error {:.0} deg; {}",
                postures[p],
                at_truth.score * 1e6,
                pose_error(&at_truth.to_model, &lab),
                summary.join(" ")
            ));
        }
    }
    for k in [Kind::FrontOnly, Kind::FrontAndBack, Kind::Rings] {
        let u: Vec<f64> = ups.iter().filter(|u| u.0 == k).map(|u| u.1).collect();
        let f: Vec<f64> = ups.iter().filter(|u| u.0 == k).map(|u| u.2).collect();
        println!(
            "{k:?}: right-pose up share min {:.2} max {:.2}; front share min {:.2} max {:.2}",
            u.iter().cloned().fold(f64::INFINITY, f64::min),
            u.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            f.iter().cloned().fold(f64::INFINITY, f64::min),
            f.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        );
    }
    for w in &wrong {
        println!("wrong pose: {w}");
    }
    println!(
        "{right} of {CASES} right (within {RIGHT_POSE_DEG} deg; worst right {worst_right:.1} deg; \
         {within_20} within {DISTINCT_POSE_DEG} deg); \
         the registration's first pose (motion verdict, then shape score): {first_right} right; {several} with more than one candidate \
         pose, {ties} tie warnings; {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(
        right as f64 >= REQUIRED * CASES as f64,
        "{right} of {CASES} right poses, need {:.0}",
        REQUIRED * CASES as f64
    );
}

#[test]
fn anterior_labels_choose_the_pose_and_unknown_labels_are_named() {
    let frames = axis_frames();
    let truth = truth(Posture::Standing, 5);
    let torso = Torso::new_at_rest(config(Subject::default(), 0)).unwrap();
    let skin = Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default()).unwrap();
    let mut rng = Pcg64::new(77, 3);
    let picked = pick(&truth, Kind::FrontAndBack, &mut rng);
    let lab = lab_pose(&frames, &mut rng);
    let markers = record(&truth, &picked, &lab, &mut rng);
    // The first five markers are front markers (picked front first).
    let anterior: Vec<String> = markers.labels[..5].to_vec();
    let o = orient(
        &torso,
        &skin,
        &markers,
        &SurfaceOptions::default(),
        &PoseOptions {
            anterior: anterior.clone(),
        },
    )
    .unwrap();
    let c = &o.candidates[o.chosen];
    assert_eq!(c.anterior_ok, Some(true));
    let error = pose_error(&c.registration.to_model, &lab);
    assert!(error < RIGHT_POSE_DEG, "pose error {error:.1} deg");
    let err = orient(
        &torso,
        &skin,
        &markers,
        &SurfaceOptions::default(),
        &PoseOptions {
            anterior: vec!["STRN".into()],
        },
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("--anterior") && err.contains("STRN"), "{err}");
}
