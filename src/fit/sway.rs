//! Whole-trunk sway removed the way motion-analysis pipelines remove it: the trunk's rigid
//! motion is estimated per frame by a rigid registration (Kabsch / Umeyama, without scale)
//! of quasi-rigid reference markers to their mean shape, and every marker is then compared
//! in that moving trunk frame.
//!
//! The reference markers are those over the spine and back (bound to skin whose outward
//! normal points backwards, [`back_markers`]), or those the user names (`--reference`).
//! Back markers are quasi-rigid, not rigid: the ribs' rotation moves them a little with
//! each breath, and a per-frame registration alone takes that motion for sway and removes
//! part of the breath from every marker. So the per-frame registration is split by
//! frequency, and only its slow part is removed:
//!
//! 1. **Breathing frequency first**, from the markers' motion after each frame's rigid
//!    motion of the whole set is taken out (so that sway in the breathing band, 0.1-0.15 Hz,
//!    cannot pass for the breath): the principal displacement's frequency
//!    ([`crate::stats::frequency`]).
//! 2. **Per-frame rigid motion** of the reference markers against their mean shape
//!    (generalised Procrustes: the mean shape re-estimated from the registered frames,
//!    [`PROCRUSTES_ITERATIONS`] times): per frame a rotation vector and the recorded point
//!    that maps to the mean shape's centroid (six numbers, the translation taken at the
//!    reference markers' centroid so that rotation and translation do not mix).
//! 3. **Slow part by least squares.** Each of the six numbers is regressed on a cosine
//!    (DCT-II) basis whose highest frequency is [`CUTOFF_OF_BREATHING`] of the breathing
//!    frequency (no wrap-around at the recording's ends), a line and a parabola (every
//!    cosine is flat at both ends, a sway need not be), together with the breath's
//!    first [`HARMONICS`] harmonics; the cosine part is the sway, the harmonics (the back's
//!    motion with each breath) are left in the recording. When the fit projects each
//!    marker's drift out ([`super::drift`]), the part of the slow motion the drift spline
//!    spans is left to it: the reference markers' own drift (marker slip, skin creep) reads
//!    as a slow rigid motion, and removing it from every marker would add it to the others.
//!    Standing sway lies at
//!    0.02-0.15 Hz (the sway; quiet-standing centre-of-pressure spectra have most of
//!    their power under 0.5 Hz and a median frequency near 0.1-0.3 Hz, Prieto et al. 1996,
//!    IEEE Trans Biomed Eng 43:956), quiet breathing at 0.2-0.33 Hz (12-20 breaths/min).
//!
//! Where there are no such markers (a front-only set, the SLP grid, [`MIN_REFERENCE`]
//! reference markers not tracked together, or a set of [`MAX_MARKERS_WITHOUT_SWAY`]
//! markers or fewer), or the recording spans fewer than [`MIN_BREATHS`] breaths, no sway is
//! removed and the fit's report says so: on the front alone
//! breathing and forward sway are the same signal.

use super::principal::principal_displacement;
use super::quality::explained;
use crate::anatomy::skin::{RigidTransform, Skin, SurfaceBinding, register_rigid};
use crate::recording::Recording;
use crate::stats::frequency::estimate_frequency;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, Point3, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// Sets of this many markers or fewer get no sway removal (the 6: too few to leave
/// a rigid reference beside the markers that breathe).
pub const MAX_MARKERS_WITHOUT_SWAY: usize = 6;
/// Fewest reference markers tracked in a frame for its rigid motion (a rigid transform
/// needs three points off a line).
pub const MIN_REFERENCE: usize = 3;
/// A marker is over the back when its skin's outward normal has an anterior component
/// under this (its normal within 53 degrees of straight back; the chest-and-back set's
/// back columns at 155 degrees and the OEP set's at 140-175 degrees qualify, the lateral
/// line at 90 degrees does not).
pub const BACK_NORMAL_X: f64 = -0.6;
/// Highest frequency of the sway kept, as a fraction of the breathing frequency: at
/// 0.25 Hz breathing, 0.15 Hz, the top of the sway band.
pub const CUTOFF_OF_BREATHING: f64 = 0.6;
/// Harmonics of the breathing frequency regressed beside the sway (and left in the
/// recording).
pub const HARMONICS: usize = 3;
/// Fewest breaths a recording must span for its sway to be told from its breath: the
/// frequency step of a recording of T seconds is 1/T, and sway under 0.6 f is told from a
/// breath at f only when 1/T is at most 0.4 f, 2.5 breaths; three, as the drift's knots
/// ([`super::drift::KNOT_BREATHS`]).
pub const MIN_BREATHS: f64 = 3.0;
/// Iterations of the generalised Procrustes mean shape.
pub const PROCRUSTES_ITERATIONS: usize = 3;

/// The sway a fit removed, or why it removed none.
#[derive(Clone, Debug, PartialEq)]
pub struct Sway {
    /// Whether sway was removed.
    pub removed: bool,
    /// What was done and why, in a sentence for the report.
    pub note: String,
    /// Labels of the reference markers (empty when none).
    pub reference: Vec<String>,
    /// How the reference markers were chosen: `back` (from the registered pose) or `named`
    /// (`--reference`).
    pub chosen_by: &'static str,
    /// Breathing frequency the sway was separated from [Hz] (NaN when none removed).
    pub breathing_hz: f64,
    /// Highest frequency of the removed sway [Hz] (NaN when none removed).
    pub cutoff_hz: f64,
    /// Root mean square of the trunk's translation about its mean [m].
    pub translation_rms_m: f64,
    /// Root mean square of the trunk's rotation about its mean [deg].
    pub rotation_rms_deg: f64,
    /// Root mean square over markers and frames of the markers' displacement by the
    /// removed sway, about each marker's mean [m].
    pub displacement_rms_m: f64,
    /// Largest displacement of a marker by the removed sway from its mean [m].
    pub displacement_max_m: f64,
    /// Share of the recorded motion about the markers' means that the sway explains.
    pub share: f64,
    /// Amplitude spectrum of the removed sway's marker displacement: (frequency [Hz],
    /// root mean square over markers of the displacement amplitude at that frequency [m]),
    /// at the recording's DFT frequencies k / duration up to the breathing frequency.
    pub spectrum: Vec<(f64, f64)>,
    /// Frequency of the spectrum's largest amplitude, k >= 1 [Hz] (NaN when none removed).
    pub peak_hz: f64,
    /// Root-mean-square registration residual of the reference markers to their mean shape
    /// [m]: how rigid they were (NaN when none removed).
    pub reference_rms_m: f64,
}

impl Sway {
    /// No sway removed, for the reason `note`.
    pub fn none(note: impl Into<String>, reference: Vec<String>, chosen_by: &'static str) -> Sway {
        Sway {
            removed: false,
            note: note.into(),
            reference,
            chosen_by,
            breathing_hz: f64::NAN,
            cutoff_hz: f64::NAN,
            translation_rms_m: 0.0,
            rotation_rms_deg: 0.0,
            displacement_rms_m: 0.0,
            displacement_max_m: 0.0,
            share: 0.0,
            spectrum: Vec::new(),
            peak_hz: f64::NAN,
            reference_rms_m: f64::NAN,
        }
    }

    /// The JSON of the report (`sway`).
    pub fn json(&self) -> serde_json::Value {
        let num = |v: f64| {
            if v.is_finite() {
                serde_json::json!(v)
            } else {
                serde_json::Value::Null
            }
        };
        serde_json::json!({
            "removed": self.removed,
            "note": self.note,
            "reference_markers": self.reference,
            "reference_chosen_by": self.chosen_by,
            "method": "per-frame rigid registration (Kabsch) of the reference markers to their mean shape; \
                       its part slower than the breath (cosine basis up to the cutoff, fitted beside the \
                       breath's first three harmonics) removed from every marker",
            "breathing_hz": num(self.breathing_hz),
            "cutoff_hz": num(self.cutoff_hz),
            "translation_rms_m": self.translation_rms_m,
            "rotation_rms_deg": self.rotation_rms_deg,
            "displacement_rms_m": self.displacement_rms_m,
            "displacement_max_m": self.displacement_max_m,
            "share_of_motion": self.share,
            "peak_hz": num(self.peak_hz),
            "reference_rms_m": num(self.reference_rms_m),
            "spectrum": self.spectrum.iter().map(|(f, a)| serde_json::json!({"frequency_hz": f, "amplitude_m": a})).collect::<Vec<_>>(),
        })
    }

    /// One line of the report.
    pub fn summary(&self) -> String {
        if !self.removed {
            return format!("sway                  none removed: {}", self.note);
        }
        format!(
            "sway                  removed, from {} reference markers ({}): {:.2} mm rms marker displacement (max {:.2} mm), \
             translation {:.2} mm rms, rotation {:.3} deg rms, peak at {:.3} Hz, below {:.3} Hz (breathing {:.3} Hz); \
             {:.0} % of the markers' motion",
            self.reference.len(),
            self.chosen_by,
            self.displacement_rms_m * 1e3,
            self.displacement_max_m * 1e3,
            self.translation_rms_m * 1e3,
            self.rotation_rms_deg,
            self.peak_hz,
            self.cutoff_hz,
            self.breathing_hz,
            100.0 * self.share
        )
    }
}

/// The outward unit normal of a bound skin point's triangle.
pub fn binding_normal(skin: &Skin, binding: &SurfaceBinding) -> Vector3<f64> {
    let [a, b, c] = skin.triangles[binding.triangle as usize].map(|k| skin.vertices[k as usize]);
    (b - a)
        .cross(&(c - a))
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::zeros)
}

/// The markers (indices into `bindings`) bound to skin facing backwards (outward normal's
/// anterior component under [`BACK_NORMAL_X`]), on `skin` in the model's anatomical frame.
pub fn back_markers(skin: &Skin, bindings: &[SurfaceBinding]) -> Vec<usize> {
    bindings
        .iter()
        .enumerate()
        .filter(|(_, b)| binding_normal(skin, b).x < BACK_NORMAL_X)
        .map(|(k, _)| k)
        .collect()
}

/// Per-frame rigid transforms (recorded -> mean shape) of the markers `columns` of `frames`
/// by generalised Procrustes; `None` for a frame with fewer than [`MIN_REFERENCE`] of them
/// tracked (or collinear). Returns the transforms, the mean shape and the registration rms
/// over the frames.
fn procrustes(
    frames: &[Vec<Option<Point3<f64>>>],
    columns: &[usize],
) -> (Vec<Option<RigidTransform>>, Vec<Point3<f64>>, f64) {
    let pick = |f: &Vec<Option<Point3<f64>>>| -> Vec<Option<Point3<f64>>> {
        columns.iter().map(|&c| f[c]).collect()
    };
    // The first mean: each marker's mean over the frames where it is tracked.
    let mut mean = vec![Vector3::zeros(); columns.len()];
    let mut count = vec![0usize; columns.len()];
    for f in frames {
        for (j, q) in pick(f).iter().enumerate() {
            if let Some(q) = q {
                mean[j] += q.coords;
                count[j] += 1;
            }
        }
    }
    let mut shape: Vec<Point3<f64>> = mean
        .iter()
        .zip(&count)
        .map(|(m, &c)| Point3::from(m / c.max(1) as f64))
        .collect();
    let mut transforms = vec![None; frames.len()];
    let mut rms = f64::NAN;
    for _ in 0..PROCRUSTES_ITERATIONS {
        let mut sum = vec![Vector3::zeros(); columns.len()];
        let mut n = vec![0usize; columns.len()];
        let (mut ss, mut m) = (0.0, 0usize);
        for (t, f) in transforms.iter_mut().zip(frames) {
            let q = pick(f);
            *t = register_rigid(&shape, &q, false).ok().map(|(t, r)| {
                let k = q.iter().flatten().count();
                ss += r * r * k as f64;
                m += k;
                t
            });
            if let Some(t) = t {
                for (j, q) in q.iter().enumerate() {
                    if let Some(q) = q {
                        sum[j] += t.apply(q).coords;
                        n[j] += 1;
                    }
                }
            }
        }
        rms = (ss / m.max(1) as f64).sqrt();
        for (j, s) in shape.iter_mut().enumerate() {
            if n[j] > 0 {
                *s = Point3::from(sum[j] / n[j] as f64);
            }
        }
    }
    (transforms, shape, rms)
}

/// The breathing frequency of `frames` (uniformly sampled at `times`) after each frame's
/// rigid motion of the whole set is taken out (step 1 of the module doc).
pub fn breathing_frequency(times: &[f64], frames: &[Vec<Option<Point3<f64>>>]) -> Result<f64> {
    let points = frames.first().map_or(0, Vec::len);
    let all: Vec<usize> = (0..points).collect();
    let (transforms, _, _) = procrustes(frames, &all);
    let registered: Vec<Vec<Option<Point3<f64>>>> = frames
        .iter()
        .zip(&transforms)
        .map(|(f, t)| match t {
            Some(t) => f.iter().map(|q| q.map(|q| t.apply(&q))).collect(),
            None => vec![None; points],
        })
        .collect();
    let recording = Recording {
        grid: (points, 1),
        times: times.to_vec(),
        frames: registered,
        units: crate::recording::Units::Metres,
        provenance: Vec::new(),
    };
    let pd = principal_displacement(&recording)?;
    let n = times.len();
    let rate = (n - 1) as f64 / (times[n - 1] - times[0]);
    Ok(estimate_frequency(&pd.signal, rate)?.frequency_hz)
}

/// The slow part of one series (per frame, `None` where missing) at `times` (from the
/// first frame): least squares on the cosine basis up to `cutoff` Hz with a line and a
/// parabola, beside the harmonics of `breathing` Hz; the slow part at every frame.
fn slow_part(times: &[f64], values: &[Option<f64>], breathing: f64, cutoff: f64) -> Vec<f64> {
    let t0 = times[0];
    let span = (times[times.len() - 1] - t0).max(1e-9);
    // cos(pi j t / span) has frequency j / (2 span); every cosine has zero slope at both
    // ends, so a line and a parabola join them (a sway's slope at the ends is free).
    let cosines = (2.0 * span * cutoff).floor() as usize + 1;
    let slow = cosines + 2;
    let columns = slow + 2 * HARMONICS;
    let row = |t: f64| -> Vec<f64> {
        let x = t - t0;
        let u = 2.0 * x / span - 1.0;
        let mut r: Vec<f64> = (0..cosines)
            .map(|j| (PI * j as f64 * x / span).cos())
            .collect();
        r.push(u);
        r.push(u * u);
        for h in 1..=HARMONICS {
            let w = 2.0 * PI * h as f64 * breathing * x;
            r.push(w.cos());
            r.push(w.sin());
        }
        r
    };
    // Least squares by singular value decomposition of the design matrix (the cosines,
    // line and parabola are far from orthogonal; normal equations would square that).
    let present: Vec<(f64, f64)> = times
        .iter()
        .zip(values)
        .filter_map(|(&t, v)| v.map(|v| (t, v)))
        .collect();
    if present.len() <= columns {
        return vec![0.0; times.len()];
    }
    let a = DMatrix::from_fn(present.len(), columns, |i, j| row(present[i].0)[j]);
    let b = DVector::from_iterator(present.len(), present.iter().map(|p| p.1));
    let c = a
        .svd(true, true)
        .solve(&b, 1e-12)
        .unwrap_or_else(|_| DVector::zeros(columns));
    times
        .iter()
        .map(|&t| {
            row(t)[..slow]
                .iter()
                .zip(c.iter())
                .map(|(a, b)| a * b)
                .sum()
        })
        .collect()
}

/// `frames` with each marker coordinate's part slower than the breath taken out: the
/// slow part of the regression of step 3 of the module doc (cutoff [`CUTOFF_OF_BREATHING`]
/// of `breathing` Hz), so that only the breathing band is left (sway, drift and each
/// marker's mean removed). Missing samples stay missing.
pub fn breathing_band(
    times: &[f64],
    frames: &[Vec<Option<Point3<f64>>>],
    breathing: f64,
) -> Vec<Vec<Option<Point3<f64>>>> {
    let points = frames.first().map_or(0, Vec::len);
    let mut out = frames.to_vec();
    for p in 0..points {
        for axis in 0..3 {
            let values: Vec<Option<f64>> = frames.iter().map(|f| f[p].map(|q| q[axis])).collect();
            let slow = slow_part(times, &values, breathing, CUTOFF_OF_BREATHING * breathing);
            for (f, s) in out.iter_mut().zip(slow) {
                if let Some(q) = &mut f[p] {
                    q[axis] -= s;
                }
            }
        }
    }
    out
}

/// What [`remove_sway`] returns: the frames in the trunk's frame and the sway removed.
#[derive(Clone, Debug, PartialEq)]
pub struct Desway {
    /// Per frame, per marker: the recorded point in the moving trunk frame.
    pub frames: Vec<Vec<Option<Point3<f64>>>>,
    /// The sway removed (or why none was).
    pub sway: Sway,
}

/// Removes the sway of `frames` (per frame, per marker, recorded frame, uniformly sampled
/// at `times`) estimated from the markers `reference` (indices; `labels` name every
/// marker). See the module doc; `chosen_by` says how the reference was chosen. With
/// `drift` (the fit projects each marker's drift out, [`super::drift`]) the part of the
/// sway the drift spline spans is left to that projection.
pub fn remove_sway(
    times: &[f64],
    frames: &[Vec<Option<Point3<f64>>>],
    labels: &[String],
    reference: &[usize],
    chosen_by: &'static str,
    drift: bool,
) -> Result<Desway> {
    let points = frames.first().map_or(0, Vec::len);
    let names: Vec<String> = reference.iter().map(|&k| labels[k].clone()).collect();
    let keep = |note: String| {
        Ok(Desway {
            frames: frames.to_vec(),
            sway: Sway::none(note, names.clone(), chosen_by),
        })
    };
    if points <= MAX_MARKERS_WITHOUT_SWAY {
        return keep(format!(
            "{points} markers, {MAX_MARKERS_WITHOUT_SWAY} or fewer leave no rigid reference beside the markers that breathe"
        ));
    }
    if reference.len() < MIN_REFERENCE {
        return keep(format!(
            "{} reference markers over the back (at least {MIN_REFERENCE} needed; a front-only set cannot tell forward sway \
             from breathing; name quasi-rigid markers with --reference LABELS)",
            reference.len()
        ));
    }
    if times.len() < 16 {
        return Err(Error::invalid(
            "recording frames",
            times.len(),
            "at least 16 for sway removal",
        ));
    }
    let breathing = breathing_frequency(times, frames)?;
    let breaths = (times[times.len() - 1] - times[0]) * breathing;
    if breaths < MIN_BREATHS {
        return keep(format!(
            "the recording spans {breaths:.1} breaths: sway slower than the breath is told from it in {MIN_BREATHS} or more"
        ));
    }
    let cutoff = CUTOFF_OF_BREATHING * breathing;
    let (transforms, shape, reference_rms) = procrustes(frames, reference);
    let registered = transforms.iter().filter(|t| t.is_some()).count();
    if registered < times.len() / 2 {
        return keep(format!(
            "the reference markers ({}) are tracked together ({MIN_REFERENCE} or more, off a line) in {registered} of {} frames, under half",
            names.join(", "),
            times.len()
        ));
    }
    let centroid =
        Point3::from(shape.iter().map(|p| p.coords).sum::<Vector3<f64>>() / shape.len() as f64);
    // Six numbers per frame: rotation vector, recorded point mapping to the centroid.
    let mut series: Vec<Vec<Option<f64>>> =
        (0..6).map(|_| Vec::with_capacity(times.len())).collect();
    for t in &transforms {
        let (r, p) = match t {
            Some(t) => (
                Some(t.rotation.scaled_axis()),
                Some(t.apply_inverse(&centroid).coords),
            ),
            None => (None, None),
        };
        for a in 0..3 {
            series[a].push(r.map(|r| r[a]));
            series[3 + a].push(p.map(|p| p[a]));
        }
    }
    let mut slow: Vec<Vec<f64>> = series
        .iter()
        .map(|s| slow_part(times, s, breathing, cutoff))
        .collect();
    // With each marker's drift projected out by the fit, the sway's part the drift spline
    // spans is left to it: the reference markers' own drifts read as a slow rigid motion,
    // and removing it would add their drift to every other marker.
    if drift {
        let t0 = times[0];
        let relative: Vec<f64> = times.iter().map(|t| t - t0).collect();
        let basis = super::drift::DriftBasis::new(&relative, breathing);
        for s in slow.iter_mut() {
            // The drift's variation only: each number's mean (the trunk frame's mean pose)
            // stays.
            let values: Vec<Option<f64>> = s.iter().map(|v| Some(*v)).collect();
            let fitted = basis.fit_series(&values);
            let mean = fitted.iter().sum::<f64>() / fitted.len().max(1) as f64;
            for (v, d) in s.iter_mut().zip(fitted) {
                *v -= d - mean;
            }
        }
    }
    // The slow transforms: recorded -> trunk, x -> R (x - p) + centroid.
    let smooth: Vec<RigidTransform> = (0..times.len())
        .map(|i| {
            let rotation =
                UnitQuaternion::from_scaled_axis(Vector3::new(slow[0][i], slow[1][i], slow[2][i]));
            let p = Vector3::new(slow[3][i], slow[4][i], slow[5][i]);
            RigidTransform {
                rotation,
                translation: centroid.coords - (rotation * p),
                scale: 1.0,
            }
        })
        .collect();
    let out: Vec<Vec<Option<Point3<f64>>>> = frames
        .iter()
        .zip(&smooth)
        .map(|(f, t)| f.iter().map(|q| q.map(|q| t.apply(&q))).collect())
        .collect();
    // The sway's size: each marker's mean trunk-frame position carried back by the sway.
    let mut mean = vec![Vector3::zeros(); points];
    let mut count = vec![0usize; points];
    for f in &out {
        for (p, q) in f.iter().enumerate() {
            if let Some(q) = q {
                mean[p] += q.coords;
                count[p] += 1;
            }
        }
    }
    let anchor: Vec<Point3<f64>> = mean
        .iter()
        .zip(&count)
        .map(|(m, &c)| Point3::from(m / c.max(1) as f64))
        .collect();
    let carried: Vec<Vec<Point3<f64>>> = smooth
        .iter()
        .map(|t| anchor.iter().map(|a| t.apply_inverse(a)).collect())
        .collect();
    let nf = times.len() as f64;
    let mut moved_mean = vec![Vector3::zeros(); points];
    for c in &carried {
        for (p, q) in c.iter().enumerate() {
            moved_mean[p] += q.coords / nf;
        }
    }
    let (mut ss, mut max) = (0.0, 0.0f64);
    let displacement: Vec<Vec<Vector3<f64>>> = carried
        .iter()
        .map(|c| {
            c.iter()
                .zip(&moved_mean)
                .map(|(q, m)| {
                    let d = q.coords - m;
                    ss += d.norm_squared();
                    max = max.max(d.norm());
                    d
                })
                .collect()
        })
        .collect();
    let displacement_rms = (ss / (nf * points.max(1) as f64)).sqrt();
    let rms_about_mean = |k: std::ops::Range<usize>| {
        let m: Vec<f64> = k
            .clone()
            .map(|a| slow[a].iter().sum::<f64>() / nf)
            .collect();
        let s: f64 = k
            .map(|a| slow[a].iter().map(|v| (v - m[a % 3]).powi(2)).sum::<f64>())
            .sum();
        (s / nf).sqrt()
    };
    let rotation_rms_deg = rms_about_mean(0..3).to_degrees();
    let translation_rms = rms_about_mean(3..6);
    // Spectrum at k / duration up to the breathing frequency.
    let t0 = times[0];
    let span = times[times.len() - 1] - t0;
    let bins = (breathing * span).floor() as usize;
    let spectrum: Vec<(f64, f64)> = (1..=bins.max(1))
        .map(|k| {
            let fk = k as f64 / span;
            let mut power = 0.0;
            for p in 0..points {
                for a in 0..3 {
                    let (mut re, mut im) = (0.0, 0.0);
                    for (t, d) in times.iter().zip(&displacement) {
                        let w = 2.0 * PI * fk * (t - t0);
                        re += d[p][a] * w.cos();
                        im += d[p][a] * w.sin();
                    }
                    power += (re * re + im * im) * (2.0 / nf).powi(2);
                }
            }
            (fk, (power / points.max(1) as f64).sqrt())
        })
        .collect();
    let peak_hz = spectrum
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(f64::NAN, |s| s.0);
    let share = explained(frames, &carried, f64::NAN).overall;
    Ok(Desway {
        frames: out,
        sway: Sway {
            removed: true,
            note: format!(
                "the trunk's rigid motion from {} reference markers ({}), its part below {:.3} Hz removed{}",
                names.len(),
                chosen_by,
                cutoff,
                if drift {
                    " (its part the drift spline spans left to the drift projection)"
                } else {
                    ""
                }
            ),
            reference: names,
            chosen_by,
            breathing_hz: breathing,
            cutoff_hz: cutoff,
            translation_rms_m: translation_rms,
            rotation_rms_deg,
            displacement_rms_m: displacement_rms,
            displacement_max_m: max,
            share,
            spectrum,
            peak_hz,
            reference_rms_m: reference_rms,
        },
    })
}
