//! Fitting recordings of any marker set (markers anywhere on the trunk, labelled or not):
//! the first frame is registered to the model's rest skin without correspondences, in the
//! pose the body's shape and breathing motion choose ([`super::orient`]), each marker
//! within 3 cm of the skin is
//! bound to its nearest skin point and carried by the skinning like the grid's markers, the
//! others are reported and left out, and the bound markers are fitted with the grid's cost
//! and optimiser ([`super::fitting::fit_marker_frames`]).

use super::TorsoMarkers;
use super::fitting::{Fit, FitOptions, fit_marker_frames};
use super::orient::{Orientation, PoseOptions, orient};
use crate::anatomy::skin::{MarkerSet, Skin, SkinOptions, SurfaceOptions, SurfaceRegistration};
use crate::model::Torso;
use crate::recording::{Markers, Recording};
use crate::{Error, Result};
use std::sync::Arc;

/// A recording's markers registered to and bound on a model's rest skin.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundRecording {
    /// The bound markers (labels from the recording, bindings on the rest skin).
    pub set: MarkerSet,
    /// The registration of the first frame (the chosen pose's).
    pub registration: SurfaceRegistration,
    /// How the pose was chosen: every candidate pose, the chosen one, the warnings.
    pub orientation: Orientation,
    /// The recording of the bound markers, in the set's order, `grid = (markers, 1)`.
    pub recording: Recording,
    /// Markers left out: label and distance to the registered skin [m] (NaN: not tracked
    /// in the first frame).
    pub excluded: Vec<(String, f64)>,
    /// The bound markers over the back (indices into `set`): skin whose outward normal points
    /// backwards ([`super::sway::back_markers`]), the sway's default reference.
    pub back: Vec<usize>,
    /// Outward unit normal of the rest skin at each bound marker (model frame, in `set`'s
    /// order).
    pub normals: Vec<nalgebra::Vector3<f64>>,
    /// Marker radius taken off the recorded markers along those normals [m] (0: the
    /// recorded points are taken as skin points).
    pub radius_m: f64,
}

/// Registers the first frame of `markers` (any labels, any frame, metres) to the rest skin
/// of `torso`'s anatomy in the pose [`orient`] chooses and binds the markers within
/// `options.max_distance` of it. The torso is not changed; see [`fit_any_markers`].
pub fn bind_recording(
    torso: &Torso,
    markers: &Markers,
    options: &SurfaceOptions,
    pose: &PoseOptions,
) -> Result<BoundRecording> {
    markers.validate()?;
    if torso.config().scene.slp_reference.is_some() {
        return Err(Error::invalid(
            "slp.reference",
            "set",
            "unset for a marker set other than the grid (the skin is fitted to the grid only)",
        ));
    }
    let skin = Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default())?;
    let orientation = orient(torso, &skin, markers, options, pose)?;
    let registration = orientation.registration().clone();
    let set = MarkerSet {
        name: "recording".into(),
        labels: registration
            .attached
            .iter()
            .map(|a| markers.labels[a.index].clone())
            .collect(),
        bindings: registration.attached.iter().map(|a| a.binding).collect(),
    };
    let order: Vec<usize> = registration.attached.iter().map(|a| a.index).collect();
    let recording = Recording {
        grid: (order.len(), 1),
        times: markers.times.clone(),
        frames: markers
            .frames
            .iter()
            .map(|f| order.iter().map(|&k| f[k]).collect())
            .collect(),
        units: markers.units,
        provenance: markers
            .provenance
            .iter()
            .filter(|(k, _)| k != "grid" && k != "units")
            .cloned()
            .collect(),
    };
    recording.validate_frames()?;
    let excluded = registration
        .excluded
        .iter()
        .map(|&(k, d)| (markers.labels[k].clone(), d))
        .collect();
    let back = super::sway::back_markers(&skin, &set.bindings);
    let normals = set
        .bindings
        .iter()
        .map(|b| super::sway::binding_normal(&skin, b))
        .collect();
    Ok(BoundRecording {
        set,
        registration,
        orientation,
        recording,
        excluded,
        back,
        normals,
        radius_m: 0.0,
    })
}

/// Largest marker radius accepted [m]: the largest motion-capture markers are 25-30 mm
/// across; a radius over 25 mm is a unit mistake.
pub const MAX_MARKER_RADIUS_M: f64 = 0.025;

/// [`bind_recording`] for markers whose centres stand `radius` [m] off the skin (half a
/// marker's diameter plus its base): the first binding gives each marker's outward skin
/// normal, every recorded position of the marker is moved by `radius` along it, inwards,
/// and the markers are registered and bound again. The assumption: each marker stands off
/// its skin point along the rest skin's outward normal there, by the same distance in every
/// frame (the skin's rotation over a breath, a few degrees, moves a 7 mm offset by a few
/// tenths of a millimetre). A radius of 0 is [`bind_recording`].
pub fn bind_with_radius(
    torso: &Torso,
    markers: &Markers,
    options: &SurfaceOptions,
    pose: &PoseOptions,
    radius: f64,
) -> Result<BoundRecording> {
    if !(0.0..=MAX_MARKER_RADIUS_M).contains(&radius) {
        return Err(Error::invalid(
            "--marker-radius [m]",
            radius,
            format!("0 to {MAX_MARKER_RADIUS_M} (a marker's centre off the skin)"),
        ));
    }
    let first = bind_recording(torso, markers, options, pose)?;
    if radius == 0.0 {
        return Ok(first);
    }
    let back = first.registration.to_model.rotation.inverse();
    let mut moved = markers.clone();
    for (a, n) in first.registration.attached.iter().zip(&first.normals) {
        let offset = back * n * radius;
        for f in moved.frames.iter_mut() {
            f[a.index] = f[a.index].map(|q| q - offset);
        }
    }
    let mut bound = bind_recording(torso, &moved, options, pose)?;
    bound.radius_m = radius;
    Ok(bound)
}

/// A fit of a recording of any marker set.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerSetFit {
    /// The fit (its `grid` is (bound markers, 1); `recorded` in the bound set's order).
    pub fit: Fit,
    /// The registration and binding.
    pub bound: BoundRecording,
}

/// Fits a recording of any marker set on a fresh torso built from `config`: pose,
/// registration and binding ([`bind_recording`]), then the grid's fit over the bound markers with each
/// marker's constant offset left out of the cost ([`FitOptions::marker_offsets`]): a
/// marker bound to its nearest skin point stands off it by its height above the skin and
/// the registration's residual (the first frame is not the rest pose the skin is in), which
/// the model's motion must not try to explain. With [`FitOptions::clean`] label swaps and
/// ghost markers are repaired first ([`super::clean`]). With [`FitOptions::sway`] the trunk's sway
/// is removed first ([`super::sway`]), from the markers [`FitOptions::reference`] names or
/// those over the back.
pub fn fit_any_markers(
    config: crate::Config,
    markers: &Markers,
    surface: &SurfaceOptions,
    pose: &PoseOptions,
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<MarkerSetFit> {
    let mut torso = Torso::new_at_rest(config)?;
    let cleaned = if options.clean {
        Some(super::clean::clean(
            &markers.times,
            &markers.labels,
            &markers.frames,
        )?)
    } else {
        None
    };
    let repaired;
    let markers = match &cleaned {
        Some(c) => {
            repaired = Markers {
                frames: c.frames.clone(),
                ..markers.clone()
            };
            &repaired
        }
        None => markers,
    };
    let notes = cleaned.map(|c| c.notes).unwrap_or_default();
    let finish = |mut fit: Fit, bound: BoundRecording| {
        fit.repairs.splice(0..0, notes.iter().cloned());
        fit.note_long_gaps(&bound.set.labels);
        MarkerSetFit { fit, bound }
    };
    let bound = bind_with_radius(&torso, markers, surface, pose, options.marker_radius)?;
    torso.set_marker_set(Some(Arc::new(bound.set.clone())));
    let mut source = TorsoMarkers::from_torso(torso)?;
    let options = FitOptions {
        marker_offsets: true,
        ..options.clone()
    };
    if !options.sway {
        let fit = fit_marker_frames(&mut source, &bound.recording, &options, progress)?;
        return Ok(finish(fit, bound));
    }
    let (reference, chosen_by) = if options.reference.is_empty() {
        (bound.back.clone(), "back")
    } else {
        let mut k = Vec::with_capacity(options.reference.len());
        for label in &options.reference {
            match bound.set.labels.iter().position(|l| l == label) {
                Some(i) => k.push(i),
                None => {
                    return Err(Error::invalid(
                        "--reference",
                        label,
                        format!(
                            "labels of markers bound to the skin (the recording's {}: {})",
                            if markers.labels.contains(label) {
                                "marker is left out of the fit, too far from the skin; bound are"
                            } else {
                                "markers"
                            },
                            bound.set.labels.join(", ")
                        ),
                    ));
                }
            }
        }
        (k, "named")
    };
    let rec = &bound.recording;
    let desway = super::sway::remove_sway(
        &rec.times,
        &rec.frames,
        &bound.set.labels,
        &reference,
        chosen_by,
        options.drift,
    )?;
    let recording = Recording {
        frames: desway.frames,
        ..rec.clone()
    };
    let mut fit = fit_marker_frames(&mut source, &recording, &options, progress)?;
    fit.sway = Some(desway.sway);
    Ok(finish(fit, bound))
}
