//! Fitting the model to structured-light plethysmography (SLP) recordings (thesis 3.4 and
//! 4.3), read by [`crate::recording`]: synthetic recordings with known parameters, the breathing
//! frequency of a recording, derivative-free optimisers, the fit loop and its report.
//!
//! | file | owns |
//! |---|---|
//! | [`named`] | recordings of any marker set: registration to the skin without correspondences, binding, fit |
//! | [`principal`] | principal displacement of the grid (PCA) and the breathing frequency |
//! | [`quality`] | what a fit's figures mean: noise floor (local cubic fits, pre-filter check), motion explained, bounds, verdict |
//! | [`breathing`] | breath-by-breath Ti, Te, Ttot of a recording from its principal displacement |
//! | [`clinical`] | per-breath report of the fitted model: Ti, Te, IE50, VT, rib-cage share, phase angle |
//! | [`clean`] | label swaps and ghost markers (jumps against neighbours) repaired, gaps over a breath left out |
//! | [`sway`] | the whole trunk's sway: rigid motion of reference markers, its part slower than the breath removed |
//! | [`drift`] | each marker's slow drift (linear spline, knots three breaths apart) projected out of the cost |
//! | [`figure`] | the PNG/SVG report: lung volume, compartments, markers, front view of residuals |
//! | [`orient`] | the pose of a marker set on the body: shape candidates, front from the breathing motion, short fits |
//! | [`source`] | the [`MarkerSource`] a fit runs: one [`crate::Torso`] reused by snapshot/restore |
//! | [`fitting`] | registration, frequency, the search over amplitudes and phases (eq. 3.1) |
//! | [`synth`] | synthetic recordings: camera pose, noise, variability, dropped points |
//! | [`sweep`] | the acceptance sweep: six synthetic recordings fitted back, errors against truth |
//! | [`mismatch`] | the acceptance under model mismatch: recordings of another model fitted, judged against it |
//! | [`size`] | the subject's stature and mass from a recording's first frame (registration residual) |
//! | [`report`] | result JSON with FMI names, fitted lung-volume CSV, PNG report |

pub mod breathing;
pub mod clean;
pub mod clinical;
pub mod drift;
pub mod figure;
pub mod fitting;
pub mod mismatch;
pub mod named;
pub mod orient;
pub mod principal;
pub mod quality;
pub mod report;
pub mod size;
pub mod source;
pub mod sway;
pub mod sweep;
pub mod synth;

pub use fitting::{Fit, FitOptions, Method, fit_marker_frames, fit_recording};
pub use named::{BoundRecording, MarkerSetFit, bind_recording, bind_with_radius, fit_any_markers};
pub use orient::{Orientation, PoseOptions};
pub use source::{MarkerSource, TorsoMarkers, Trajectory};
pub use synth::{Camera, SynthOptions, Synthetic, synthesize};
