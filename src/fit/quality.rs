//! What a fit's figures mean: the recording's noise floor, the share of the markers' motion
//! the fit explains, the drive parameters the search left at a bound, and a plain verdict.
//!
//! - **Noise floor.** Each marker coordinate is fitted locally by a cubic over a window of
//!   an eighth of a breath (Savitzky & Golay 1964; at least 7 samples), where breathing is
//!   smooth: a sine's cubic fit over an eighth of its period leaves (pi/4)^4/120 = 0.3 % of
//!   its amplitude, 16 um of a 5 mm motion. The residual at the window's centre has
//!   variance sigma^2 (1 - h0) for white noise of standard deviation sigma (h0: the
//!   smoother's centre weight, the hat matrix's diagonal), so sigma = 1.4826 MAD / sqrt(1 -
//!   h0) (robust against the odd glitch), and the mean length of the 3-D noise vector, the
//!   cost a perfect fit reaches, is sigma sqrt(8 / pi).
//! - **Pre-filtered data.** The second difference of consecutive samples sees only the
//!   highest frequencies; on white noise it gives the same sigma (variance 6 sigma^2), on
//!   data low-pass filtered before export far less (a recording whose second differences
//!   gave 3.3 um made "cost = 2048 x noise floor"). When the second-difference sigma is
//!   under half the smoother's, the spectrum falls away at high frequency: the recording is
//!   flagged as filtered and its floor is a lower bound of the measurement noise.
//! - **Variance explained.** Of the recorded motion about each marker's mean, the share the
//!   fitted markers' motion (about theirs) explains: overall, per marker, and above the
//!   noise (the noise's 3 sigma^2 per sample taken out of both sums). When the fit removed
//!   each marker's drift ([`super::drift`]), the drift's share of the motion is reported and
//!   the drive's share is of the motion left after the drift; sway is not removed by this
//!   fit (null).
//! - **Verdict.** When the drive explains under half of the motion above the noise left
//!   after the drift, the report says "the model does not explain this recording";
//!   "converged" describes the search only.

use super::Fit;
use nalgebra::{Matrix4, Point3, Vector3, Vector4};

/// The noise of a recording, estimated from the recording alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseFloor {
    /// Standard deviation per coordinate from the local cubic fits [m].
    pub sigma_m: f64,
    /// Mean length of the 3-D noise vector, sigma sqrt(8 / pi) [m]: the cost a perfect fit
    /// reaches.
    pub floor_m: f64,
    /// Standard deviation per coordinate from second differences [m].
    pub second_difference_sigma_m: f64,
    /// Whether the high-frequency spectrum falls away (second-difference sigma under half
    /// of `sigma_m`): the data were probably low-pass filtered, and `floor_m` is a lower
    /// bound.
    pub prefiltered: bool,
    /// Window of the local fits [samples].
    pub window: usize,
    /// Residuals used.
    pub samples: usize,
}

/// Ratio of the second-difference sigma to the local-fit sigma under which a recording
/// counts as filtered (the highest frequencies' noise under half of that just above the
/// breath's band).
pub const PREFILTER_RATIO: f64 = 0.5;

/// Centre weights of the least-squares cubic over samples -m..m: the smoother's weights c
/// (fit at 0 = sum c_j x_j) and its centre weight h0 = c_0.
fn cubic_weights(m: usize) -> Vec<f64> {
    let mut xtx = Matrix4::<f64>::zeros();
    for j in -(m as i64)..=(m as i64) {
        let x = Vector4::new(1.0, j as f64, (j * j) as f64, (j * j * j) as f64);
        xtx += x * x.transpose();
    }
    let inv = xtx.try_inverse().unwrap_or_else(Matrix4::zeros);
    let row = inv.row(0).into_owned();
    (-(m as i64)..=(m as i64))
        .map(|j| {
            let x = Vector4::new(1.0, j as f64, (j * j) as f64, (j * j * j) as f64);
            (row * x)[0]
        })
        .collect()
}

fn median_abs(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.abs().total_cmp(&b.abs()));
    m.abs()
}

/// The noise floor of `frames` (per frame, per marker; uniformly spaced `times`) breathing
/// at `frequency` Hz (see the module doc). NaN fields with fewer than 30 residuals.
pub fn noise_floor(
    times: &[f64],
    frames: &[Vec<Option<Point3<f64>>>],
    frequency: f64,
) -> NoiseFloor {
    let n = times.len();
    let rate = if n > 1 {
        (n - 1) as f64 / (times[n - 1] - times[0])
    } else {
        0.0
    };
    let half = ((rate / (8.0 * frequency.max(1e-3))) / 2.0)
        .floor()
        .max(3.0) as usize;
    let weights = cubic_weights(half);
    let h0 = weights[half];
    let points = frames.first().map_or(0, Vec::len);
    let uniform = |k: usize| {
        let h = times[k] - times[k - 1];
        h > 0.0 && ((h * rate) - 1.0).abs() <= 0.01
    };
    let (mut residuals, mut second) = (Vec::new(), Vec::new());
    for p in 0..points {
        for axis in 0..3 {
            let value = |k: usize| frames[k].get(p).copied().flatten().map(|q| q[axis]);
            for k in half..n.saturating_sub(half) {
                let window: Option<Vec<f64>> = (k - half..=k + half).map(value).collect();
                let Some(window) = window else { continue };
                if !(k - half + 1..=k + half).all(uniform) {
                    continue;
                }
                let fit: f64 = window.iter().zip(&weights).map(|(x, c)| x * c).sum();
                residuals.push(window[half] - fit);
                second.push(window[half - 1] - 2.0 * window[half] + window[half + 1]);
            }
        }
    }
    if residuals.len() < 30 {
        return NoiseFloor {
            sigma_m: f64::NAN,
            floor_m: f64::NAN,
            second_difference_sigma_m: f64::NAN,
            prefiltered: false,
            window: 2 * half + 1,
            samples: residuals.len(),
        };
    }
    let samples = residuals.len();
    let sigma = 1.4826 * median_abs(residuals) / (1.0 - h0).sqrt();
    let sigma2 = 1.4826 * median_abs(second) / 6f64.sqrt();
    NoiseFloor {
        sigma_m: sigma,
        floor_m: sigma * (8.0 / std::f64::consts::PI).sqrt(),
        second_difference_sigma_m: sigma2,
        prefiltered: sigma2 < PREFILTER_RATIO * sigma,
        window: 2 * half + 1,
        samples,
    }
}

/// Shares of the recorded motion the fit explains.
#[derive(Clone, Debug, PartialEq)]
pub struct Explained {
    /// Of the recorded motion about each marker's mean, the share the fitted motion
    /// explains: 1 - sum |residual|^2 / sum |recorded - mean|^2.
    pub overall: f64,
    /// The same with the noise's 3 sigma^2 per sample taken out of both sums (NaN when the
    /// motion does not rise above the noise).
    pub above_noise: f64,
    /// Per marker, the share of its own motion explained (NaN for a marker tracked in fewer
    /// than two frames or not moving).
    pub per_marker: Vec<f64>,
    /// Recorded motion about the means, root mean square per sample [m].
    pub motion_rms_m: f64,
    /// Residual about the means, root mean square per sample [m].
    pub residual_rms_m: f64,
}

/// The shares of the motion of `recorded` (per frame, per marker) that `fitted` (the
/// model's markers at the same frames, same frame of reference) explains; `sigma` is the
/// noise per coordinate [m] (see [`Explained`]).
pub fn explained(
    recorded: &[Vec<Option<Point3<f64>>>],
    fitted: &[Vec<Point3<f64>>],
    sigma: f64,
) -> Explained {
    let points = recorded.first().map_or(0, Vec::len);
    let mut mean_q = vec![Vector3::zeros(); points];
    let mut mean_m = vec![Vector3::zeros(); points];
    let mut count = vec![0usize; points];
    for (r, m) in recorded.iter().zip(fitted) {
        for (p, q) in r.iter().enumerate() {
            if let Some(q) = q {
                mean_q[p] += q.coords;
                mean_m[p] += m[p].coords;
                count[p] += 1;
            }
        }
    }
    for p in 0..points {
        let c = count[p].max(1) as f64;
        mean_q[p] /= c;
        mean_m[p] /= c;
    }
    let mut sst = vec![0.0; points];
    let mut ssr = vec![0.0; points];
    for (r, m) in recorded.iter().zip(fitted) {
        for (p, q) in r.iter().enumerate() {
            if let Some(q) = q {
                let d = q.coords - mean_q[p];
                sst[p] += d.norm_squared();
                ssr[p] += (d - (m[p].coords - mean_m[p])).norm_squared();
            }
        }
    }
    let (tst, tsr): (f64, f64) = (sst.iter().sum(), ssr.iter().sum());
    let total: usize = count.iter().sum();
    let noise = if sigma.is_finite() {
        3.0 * sigma * sigma * total as f64
    } else {
        0.0
    };
    let share = |sr: f64, st: f64| if st > 0.0 { 1.0 - sr / st } else { f64::NAN };
    Explained {
        overall: share(tsr, tst),
        above_noise: if tst > noise {
            share((tsr - noise).max(0.0), tst - noise)
        } else {
            f64::NAN
        },
        per_marker: (0..points)
            .map(|p| {
                if count[p] > 1 {
                    share(ssr[p], sst[p])
                } else {
                    f64::NAN
                }
            })
            .collect(),
        motion_rms_m: (tst / total.max(1) as f64).sqrt(),
        residual_rms_m: (tsr / total.max(1) as f64).sqrt(),
    }
}

/// Share of the motion above the noise under which the report says the model does not
/// explain the recording (the half).
pub const EXPLAINS_AT_LEAST: f64 = 0.5;

/// The quality of a fit: the noise floor, the shares explained, the parameters at a bound
/// and the verdict.
#[derive(Clone, Debug, PartialEq)]
pub struct Quality {
    /// The recording's noise.
    pub noise: NoiseFloor,
    /// The shares of the motion the fitted markers explain (without the drift).
    pub explained: Explained,
    /// With drift removed: the drift's share of the motion about the means.
    pub drift_share: Option<f64>,
    /// With drift removed: the shares of the motion left after the drift that the drive
    /// explains.
    pub after_drift: Option<Explained>,
    /// Drive parameters the search left at a bound, e.g. `drive.ribs.amplitude = 0`.
    pub at_bounds: Vec<String>,
    /// Whether the drive explains at least half of the motion above the noise.
    pub explains: bool,
    /// Plain sentences for the report: the verdict and what the figures mean.
    pub notes: Vec<String>,
}

/// Amplitudes within this of a bound of [`super::fitting::AMPLITUDE_RANGE`] are at it.
const AT_BOUND: f64 = 1e-3;

/// The quality of `fit` (see the module doc).
pub fn quality(fit: &Fit) -> Quality {
    let noise = noise_floor(&fit.times, &fit.recorded, fit.drive.frequency);
    let whole = explained(&fit.recorded, &fit.fitted.markers, noise.sigma_m);
    let (drift_share, after_drift) = match &fit.drift_knots {
        None => (None, None),
        Some(_) => {
            let basis = super::drift::DriftBasis::new(&fit.times, fit.drive.frequency);
            let drift = basis.drift(&fit.fitted.markers, &fit.recorded);
            let less: Vec<Vec<Option<Point3<f64>>>> = fit
                .recorded
                .iter()
                .zip(&drift)
                .map(|(r, d)| r.iter().zip(d).map(|(q, e)| q.map(|q| q - e)).collect())
                .collect();
            // The drift's share: what the drift alone explains of the motion about the means.
            let drift_points: Vec<Vec<Point3<f64>>> = drift
                .iter()
                .map(|d| d.iter().map(|e| Point3::from(*e)).collect())
                .collect();
            let alone = explained(&fit.recorded, &drift_points, f64::NAN);
            (
                Some(alone.overall),
                Some(explained(&less, &fit.fitted.markers, noise.sigma_m)),
            )
        }
    };
    let explained = whole;
    let (lo, hi) = super::fitting::AMPLITUDE_RANGE;
    let mut at_bounds = Vec::new();
    for (name, a) in [
        ("drive.ribs.amplitude", fit.drive.ribs.amplitude),
        ("drive.diaphragm.amplitude", fit.drive.diaphragm.amplitude),
    ] {
        if a <= lo + AT_BOUND {
            at_bounds.push(format!("{name} = {lo} (its lower bound)"));
        } else if a >= hi - AT_BOUND {
            at_bounds.push(format!("{name} = {hi} (its upper bound)"));
        }
    }
    let judged = after_drift.as_ref().unwrap_or(&explained);
    let share = if judged.above_noise.is_finite() {
        judged.above_noise
    } else {
        judged.overall
    };
    let explains = share >= EXPLAINS_AT_LEAST;
    let mut notes = Vec::new();
    if !explains {
        notes.push(format!(
            "the model does not explain this recording: the drive explains {:.0} % of the markers' \
             motion above the noise{} (under {:.0} %); sway is not removed by this fit",
            100.0 * share,
            if after_drift.is_some() {
                " left after the drift"
            } else {
                " (drift not removed)"
            },
            100.0 * EXPLAINS_AT_LEAST
        ));
    }
    if noise.prefiltered {
        notes.push(format!(
            "the recording looks low-pass filtered before export (second-difference noise {:.3} mm \
             against {:.3} mm from local fits): its noise floor {:.3} mm is a lower bound",
            noise.second_difference_sigma_m * 1e3,
            noise.sigma_m * 1e3,
            noise.floor_m * 1e3
        ));
    }
    for b in &at_bounds {
        notes.push(format!(
            "{b}: the search ended on the bound, the data may want a value outside the drive's range"
        ));
    }
    Quality {
        noise,
        explained,
        drift_share,
        after_drift,
        at_bounds,
        explains,
        notes,
    }
}
