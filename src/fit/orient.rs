//! The pose of a recorded marker set on the body, from the body: its shape and its breathing.
//!
//! A trunk is nearly symmetric, so the shape of a marker cloud alone leaves near ties: the
//! pose turned 180 degrees about the long axis (the front markers on the model's back), or
//! upside down, fits the skin almost as well as the right one. The choice here:
//!
//! 1. **Shape.** Every distinct pose whose registration score is within a margin of the
//!    best ([`register_candidates`]: the markers' principal axes put onto the skin's in all
//!    24 axis orders, each turned about the long axis, refined by trimmed closest-point
//!    fitting). Nothing is assumed of the laboratory's axes: Y-up, Z-up or X-up, standing
//!    or supine (the lab's vertical the body's antero-posterior axis) are all among the
//!    starts.
//! 2. **Front from the breathing motion.** The breathing frequency is estimated with each
//!    frame's rigid motion of the whole set taken out, and the motion kept is the breathing
//!    band ([`super::sway::breathing_band`]: each marker coordinate's part slower than the
//!    breath, the trunk's sway and drift, removed). Its principal displacement (the
//!    motion common to all markers, [`principal_displacement`]) is signed, in each pose, so
//!    that the markers move out of the skin on inspiration (the front and sides expand,
//!    the back barely moves); the inspiratory motion then points to the front, and
//!    cranially (the sternum moves ventrally and cranially on inspiration: Wilson et al.
//!    1987, "Geometry and respiratory displacement of human ribs", J Appl Physiol 62:1872;
//!    on the recordings of tests/fit_orientation.rs a fifth to three fifths of the summed
//!    inspiratory motion points forwards and three fifths or more cranially). This verdict
//!    ranks the registration's starts before the finalists are chosen, so that the poses it
//!    favours are refined even when the shape prefers another. A pose whose inspiratory
//!    motion points backwards (front markers on the model's back) is dropped, and one where
//!    it points caudally (upside down) too when any pose remains. The direction of least
//!    motion is never used: upper-chest markers move mostly cranially. With `--anterior LABELS` the named markers must instead sit on the front
//!    of the skin (outward normal pointing forwards).
//! 3. **Cost after a short fit.** Each pose left is fitted by the linearised model (the
//!    fit's own start, [`linearised_fit`]: two model runs shared by all poses), and the one
//!    with the smallest residual wins. Poses within [`TIE_MARGIN`] of that residual are a
//!    tie the short fit cannot break (on a patch of markers on the front, poses turned
//!    20-50 degrees in the patch's plane fit the motion alike): the one that fits the skin
//!    best of them is chosen, and a warning names both residuals and what was done.

use super::TorsoMarkers;
use super::fitting::{LinearFit, linear_basis, linearised_fit};
use super::principal::principal_displacement;
use crate::anatomy::skin::{
    MIN_SURFACE_MARKERS, MarkerSet, Skin, SurfaceOptions, SurfaceRegistration, register_candidates,
};
use crate::model::{Torso, Wave};
use crate::recording::{Markers, Recording};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::sync::Arc;

/// Two poses whose short-fit residuals are within this fraction of each other are a tie
/// worth a warning (the 35 %).
pub const TIE_MARGIN: f64 = 0.35;

/// What the user says about the pose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseOptions {
    /// Labels of markers on the front of the trunk (`--anterior`): only poses that bind
    /// each of them to skin facing forwards qualify; the breathing motion's front is then
    /// not used.
    pub anterior: Vec<String>,
}

/// One candidate pose and what the choice saw of it.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseCandidate {
    /// The registration (recorded frame -> model frame) and the markers it binds.
    pub registration: SurfaceRegistration,
    /// Share of the inspiratory motion pointing forwards in this pose, in [-1, 1]: the sum
    /// over the bound markers of the inspiratory displacement's anterior component over the
    /// sum of its lengths (> 0: the markers that move most are on the front).
    pub front: f64,
    /// Share of the inspiratory motion pointing cranially in this pose, in [-1, 1] (the
    /// same sums over the superior component).
    pub up: f64,
    /// Whether every `--anterior` marker is bound to skin facing forwards (None: none named).
    pub anterior_ok: Option<bool>,
    /// The linearised fit of the recording in this pose.
    pub short_fit: LinearFit,
    /// Rotation from the chosen pose [deg].
    pub from_chosen_deg: f64,
}

/// The pose chosen for a recording of a marker set.
#[derive(Clone, Debug, PartialEq)]
pub struct Orientation {
    /// Index of the chosen pose in `candidates`.
    pub chosen: usize,
    /// Every candidate pose, in the registration's order (best shape score first).
    pub candidates: Vec<PoseCandidate>,
    /// Breathing frequency used by the short fits [Hz].
    pub frequency_hz: f64,
    /// What the choice found doubtful and what it did, one sentence each.
    pub warnings: Vec<String>,
}

impl Orientation {
    /// The chosen pose's registration.
    pub fn registration(&self) -> &SurfaceRegistration {
        &self.candidates[self.chosen].registration
    }
}

/// Outward unit normal of triangle `t` of the skin.
fn triangle_normal(skin: &Skin, t: u32) -> Vector3<f64> {
    let [a, b, c] = skin.triangles[t as usize].map(|k| skin.vertices[k as usize]);
    (b - a)
        .cross(&(c - a))
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::zeros)
}

/// The shares of the inspiratory motion pointing forwards and cranially (see
/// [`PoseCandidate::front`], [`PoseCandidate::up`]): `loadings` are the recording's
/// principal-displacement loadings per marker (recorded frame), signed here so that the
/// bound markers move out of the skin.
fn motion_shares(skin: &Skin, r: &SurfaceRegistration, loadings: &[Vector3<f64>]) -> (f64, f64) {
    let rotation = r.to_model.rotation;
    let moved: Vec<(Vector3<f64>, Vector3<f64>)> = r
        .attached
        .iter()
        .map(|a| {
            (
                rotation * loadings[a.index],
                triangle_normal(skin, a.binding.triangle),
            )
        })
        .collect();
    let outward: f64 = moved.iter().map(|(l, n)| l.dot(n)).sum();
    let sign = if outward < 0.0 { -1.0 } else { 1.0 };
    let length: f64 = moved.iter().map(|(l, _)| l.norm()).sum();
    if length <= 0.0 {
        return (0.0, 0.0);
    }
    let sum = moved.iter().fold(Vector3::zeros(), |a, (l, _)| a + l) * sign / length;
    (sum.x, sum.y)
}

/// Chooses the pose of `markers` (any labels, any frame, metres) on `skin`, the rest skin of
/// `torso` (see the module doc). `surface` sets the registration; the short fits run on a
/// copy of `torso` (sharing its compiled model) carrying every candidate's markers at once.
pub fn orient(
    torso: &Torso,
    skin: &Skin,
    markers: &Markers,
    surface: &SurfaceOptions,
    pose: &PoseOptions,
) -> Result<Orientation> {
    let mut anterior = Vec::with_capacity(pose.anterior.len());
    for label in &pose.anterior {
        match markers.labels.iter().position(|l| l == label) {
            Some(k) => anterior.push(k),
            None => {
                return Err(Error::invalid(
                    "--anterior",
                    label,
                    format!(
                        "labels of the recording's markers ({})",
                        markers.labels.join(", ")
                    ),
                ));
            }
        }
    }
    // The registration's own check first, so that too few markers is named as such rather
    // than as a motion too short to read.
    let tracked = markers.frames[0]
        .iter()
        .filter(|p| p.is_some_and(|p| p.coords.iter().all(|c| c.is_finite())))
        .count();
    if tracked < MIN_SURFACE_MARKERS {
        return Err(Error::invalid(
            "recording first frame",
            format!("{tracked} tracked markers"),
            format!("at least {MIN_SURFACE_MARKERS} markers on the trunk"),
        ));
    }
    // The breathing frequency with each frame's rigid motion of the whole set taken out,
    // and the motion's direction from the breathing band alone: the trunk's sway (slower
    // than the breath, super::sway) would otherwise pass for the breath.
    let f = super::sway::breathing_frequency(&markers.times, &markers.frames)?;
    crate::model::check(
        "drive.frequency (estimated from the recording)",
        f,
        (0.05, 2.0),
    )?;
    let all = Recording {
        grid: (markers.markers(), 1),
        times: markers.times.clone(),
        frames: super::sway::breathing_band(&markers.times, &markers.frames, f),
        units: markers.units,
        provenance: Vec::new(),
    };
    let pd = principal_displacement(&all)?;
    let registrations = register_candidates(
        &skin.vertices,
        &skin.triangles,
        &markers.frames[0],
        Some(&pd.loadings),
        surface,
    )?;
    // One model carrying every candidate's bound markers: two basis runs serve them all.
    let mut labels = Vec::new();
    let mut bindings = Vec::new();
    let mut ranges = Vec::with_capacity(registrations.len());
    for (c, r) in registrations.iter().enumerate() {
        let start = bindings.len();
        for a in &r.attached {
            labels.push(format!("pose{c}:{}", markers.labels[a.index]));
            bindings.push(a.binding);
        }
        ranges.push(start..bindings.len());
    }
    let mut copy = Torso::with_compiled_at_rest(torso.config().clone(), torso.compiled().clone())?;
    copy.set_marker_set(Some(Arc::new(MarkerSet {
        name: "pose candidates".into(),
        labels,
        bindings,
    })));
    let mut source = TorsoMarkers::from_torso(copy)?;
    let basis = linear_basis(
        &mut source,
        f,
        0.0,
        Wave::default(),
        crate::model::drive::SINE_FRACTION,
        markers.rate(),
    )?;
    let t0 = markers.times[0];
    let times: Vec<f64> = markers.times.iter().map(|t| t - t0).collect();
    let mut candidates = Vec::with_capacity(registrations.len());
    for (r, range) in registrations.into_iter().zip(ranges) {
        let columns: Vec<usize> = range.collect();
        let recorded: Vec<Vec<Option<Point3<f64>>>> = all
            .frames
            .iter()
            .map(|frame| {
                r.attached
                    .iter()
                    .map(|a| frame[a.index].map(|q| r.to_model.apply(&q)))
                    .collect()
            })
            .collect();
        let short_fit = linearised_fit(&basis.columns(&columns), &recorded, &times);
        let (front, up) = motion_shares(skin, &r, &pd.loadings);
        let anterior_ok = (!anterior.is_empty()).then(|| {
            anterior.iter().all(|k| {
                r.attached
                    .iter()
                    .find(|a| a.index == *k)
                    .is_some_and(|a| triangle_normal(skin, a.binding.triangle).x > 0.0)
            })
        });
        candidates.push(PoseCandidate {
            registration: r,
            front,
            up,
            anterior_ok,
            short_fit,
            from_chosen_deg: 0.0,
        });
    }
    let mut warnings = Vec::new();
    let mut eligible: Vec<usize> = if anterior.is_empty() {
        let forwards_up: Vec<usize> = (0..candidates.len())
            .filter(|&c| candidates[c].front > 0.0 && candidates[c].up > 0.0)
            .collect();
        if forwards_up.is_empty() {
            (0..candidates.len())
                .filter(|&c| candidates[c].front > 0.0)
                .collect()
        } else {
            forwards_up
        }
    } else {
        (0..candidates.len())
            .filter(|&c| candidates[c].anterior_ok == Some(true))
            .collect()
    };
    if eligible.is_empty() {
        if !anterior.is_empty() {
            return Err(Error::invalid(
                "--anterior",
                pose.anterior.join(","),
                format!(
                    "markers on the front of the trunk: no pose of the {} that fits the skin puts them all there",
                    candidates.len()
                ),
            ));
        }
        warnings.push(format!(
            "the breathing motion did not show which side is the front (in none of the {} poses \
             that fit the skin does the inspiratory motion point forwards); chose the pose by the \
             short fit alone; name markers on the front with --anterior LABELS to decide",
            candidates.len()
        ));
        eligible = (0..candidates.len()).collect();
    }
    eligible.sort_by(|&a, &b| {
        candidates[a]
            .short_fit
            .rms_m()
            .total_cmp(&candidates[b].short_fit.rms_m())
    });
    // Poses the short fit cannot separate (within the tie margin of the best) are told
    // apart by the shape: the one that fits the skin best of them.
    let best_rms = candidates[eligible[0]].short_fit.rms_m();
    let tied: Vec<usize> = eligible
        .iter()
        .copied()
        .filter(|&c| candidates[c].short_fit.rms_m() <= (1.0 + TIE_MARGIN) * best_rms)
        .collect();
    let chosen = tied
        .iter()
        .copied()
        .min_by(|&a, &b| {
            candidates[a]
                .registration
                .score
                .total_cmp(&candidates[b].registration.score)
        })
        .unwrap_or(eligible[0]);
    let chosen_rotation = candidates[chosen].registration.to_model.rotation;
    for c in &mut candidates {
        c.from_chosen_deg = (c.registration.to_model.rotation * chosen_rotation.inverse())
            .angle()
            .to_degrees();
    }
    if let Some(&other) = tied.iter().find(|&&c| c != chosen) {
        let (a, b) = (&candidates[chosen], &candidates[other]);
        warnings.push(format!(
            "two poses of the markers on the trunk fit within {:.0} % after a short fit: \
             residual {:.2} mm (chosen) and {:.2} mm (turned {:.0} deg from it); fitted the one \
             that fits the skin better (registration scores {:.0} and {:.0} mm^2); name markers \
             on the front with --anterior LABELS if it is the wrong one",
            100.0 * TIE_MARGIN,
            a.short_fit.rms_m() * 1e3,
            b.short_fit.rms_m() * 1e3,
            b.from_chosen_deg,
            a.registration.score * 1e6,
            b.registration.score * 1e6,
        ));
    }
    Ok(Orientation {
        chosen,
        candidates,
        frequency_hz: f,
        warnings,
    })
}
