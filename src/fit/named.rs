//! Fitting recordings of any marker set (markers anywhere on the trunk, labelled or not):
//! the first frame is registered to the model's rest skin without correspondences, in the
//! pose the body's shape and breathing motion choose ([`super::orient`]), each marker
//! within 3 cm of the skin is
//! bound to its nearest skin point and carried by the skinning like the grid's markers, the
//! others are reported and left out, and the bound markers are fitted with the grid's cost
//! and optimiser ([`super::fitting::fit_marker_frames`]).

use super::fitting::{Fit, FitOptions, fit_marker_frames};
use super::orient::{Orientation, PoseOptions, orient};
use super::{Markers, Recording, TorsoMarkers};
use crate::anatomy::skin::{MarkerSet, Skin, SkinOptions, SurfaceOptions, SurfaceRegistration};
use crate::model::Torso;
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
    Ok(BoundRecording {
        set,
        registration,
        orientation,
        recording,
        excluded,
    })
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
/// the model's motion must not try to explain.
pub fn fit_any_markers(
    config: crate::Config,
    markers: &Markers,
    surface: &SurfaceOptions,
    pose: &PoseOptions,
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<MarkerSetFit> {
    let mut torso = Torso::new_at_rest(config)?;
    let bound = bind_recording(&torso, markers, surface, pose)?;
    torso.set_marker_set(Some(Arc::new(bound.set.clone())));
    let mut source = TorsoMarkers::from_torso(torso)?;
    let options = FitOptions {
        marker_offsets: true,
        ..options.clone()
    };
    let fit = fit_marker_frames(&mut source, &bound.recording, &options, progress)?;
    Ok(MarkerSetFit { fit, bound })
}
