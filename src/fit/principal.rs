//! The principal displacement of a recording and the breathing frequency read off it
//! (thesis 4.3 fixes the frequency before optimising).
//!
//! Each tracked coordinate of every grid point is one column of a frames x 3P matrix;
//! untracked samples are filled by linear interpolation in time between the point's tracked
//! samples (the nearest one at the ends); each column's least-squares linear trend is
//! removed. The principal displacement is the projection on the first principal axis (the
//! leading eigenvector of the 3P x 3P covariance, Jolliffe 2002, section 1.1): the motion
//! common to the whole grid, i.e. the breath. Its frequency comes from
//! [`crate::stats::frequency::estimate_frequency`] (Hann-windowed DFT with two-bin
//! interpolation, autocorrelation cross-check).

use crate::recording::Recording;
use crate::stats::frequency::{FrequencyEstimate, detrend_linear, estimate_frequency};
use crate::{Error, Result};
use nalgebra::{DMatrix, Vector3};

/// The breath signal of a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipalDisplacement {
    /// Projection of each frame on the first principal axis [m] (detrended).
    pub signal: Vec<f64>,
    /// Per grid point, its loading on the axis (unit vector over all coordinates, split
    /// into 3-vectors); zero for points never tracked.
    pub loadings: Vec<Vector3<f64>>,
    /// Fraction of the detrended variance on the axis.
    pub explained: f64,
}

/// Linear interpolation of a series with gaps; `None` when fewer than two samples exist.
fn fill(times: &[f64], values: &[Option<f64>]) -> Option<Vec<f64>> {
    let known: Vec<usize> = (0..values.len()).filter(|&i| values[i].is_some()).collect();
    if known.len() < 2 {
        return None;
    }
    let at = |i: usize| values[i].unwrap_or(0.0);
    let mut out = vec![0.0; values.len()];
    let mut k = 0;
    for (i, o) in out.iter_mut().enumerate() {
        while k + 1 < known.len() && known[k + 1] <= i {
            k += 1;
        }
        *o = if i <= known[0] {
            at(known[0])
        } else if i >= known[known.len() - 1] {
            at(known[known.len() - 1])
        } else {
            let (a, b) = (known[k], known[k + 1]);
            let s = (times[i] - times[a]) / (times[b] - times[a]);
            at(a) + s * (at(b) - at(a))
        };
    }
    Some(out)
}

/// The principal displacement of `recording` (see the module doc).
pub fn principal_displacement(recording: &Recording) -> Result<PrincipalDisplacement> {
    principal_displacement_without(recording, &[])
}

/// [`principal_displacement`] leaving out the points `left_out` (e.g. those with a gap
/// longer than a breath, which interpolation would draw a line across); their loadings
/// are zero. When that leaves no point, none is left out.
pub fn principal_displacement_without(
    recording: &Recording,
    left_out: &[usize],
) -> Result<PrincipalDisplacement> {
    let nf = recording.frames.len();
    let np = recording.points();
    let left_out: &[usize] = if left_out.len() >= np { &[] } else { left_out };
    let mut columns: Vec<(usize, usize, Vec<f64>)> = Vec::new();
    for p in (0..np).filter(|p| !left_out.contains(p)) {
        for axis in 0..3 {
            let values: Vec<Option<f64>> = recording
                .frames
                .iter()
                .map(|f| f[p].map(|q| q[axis]))
                .collect();
            if let Some(v) = fill(&recording.times, &values) {
                columns.push((p, axis, detrend_linear(&v)));
            }
        }
    }
    if columns.is_empty() {
        return Err(Error::invalid(
            "recording",
            "no grid point tracked in two frames",
            "at least one point tracked in two or more frames",
        ));
    }
    let m = columns.len();
    let x = DMatrix::from_fn(nf, m, |i, j| columns[j].2[i]);
    let cov = x.transpose() * &x;
    let total = cov.trace();
    // Below 0.1 um RMS per frame the grid does not breathe (rounding of a constant file).
    if total <= nf as f64 * 1e-14 {
        return Err(Error::invalid(
            "recording",
            "grid points that do not move",
            "a breathing recording",
        ));
    }
    let eig = cov.symmetric_eigen();
    let (k, lead) =
        eig.eigenvalues
            .iter()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |b, (i, &v)| if v > b.1 { (i, v) } else { b },
            );
    let axis = eig.eigenvectors.column(k).into_owned();
    let signal: Vec<f64> = (x * &axis).iter().copied().collect();
    let mut loadings = vec![Vector3::zeros(); np];
    for (j, (p, a, _)) in columns.iter().enumerate() {
        loadings[*p][*a] = axis[j];
    }
    Ok(PrincipalDisplacement {
        signal,
        loadings,
        explained: lead / total,
    })
}

/// Breathing frequency of `recording`: its principal displacement fed to
/// [`estimate_frequency`] at the recording's mean frame rate.
pub fn recording_frequency(recording: &Recording) -> Result<FrequencyEstimate> {
    let pd = principal_displacement(recording)?;
    estimate_frequency(&pd.signal, recording.rate())
}
