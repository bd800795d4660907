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
//!   the drive's share is of the motion left after the drift. When the trunk's sway was
//!   removed before the fit ([`super::sway`]), its share of the recorded motion is reported
//!   beside them (null when none was removed, with the reason in the notes).
//! - **Cardiac motion** ([`cardiac_peak`]): the heartbeat moves the chest wall by a few
//!   tenths of a millimetre at 0.8-2.5 Hz (48-150 beats/min). It is not fitted; it is
//!   reported when the residual (recorded minus fitted, after the drift) has a spectral peak
//!   there: the residual's periodogram summed over every marker coordinate, each bin against
//!   the mean of the band's other bins, is an F(2M, 2M(K - 1)) variate for white noise (M
//!   coordinates, K bins); a peak whose probability times K (Bonferroni) is under 1 % is
//!   reported. Bins within one frequency step of a harmonic h of the breath, widened by h
//!   times the recording's breath-to-breath variation of period (the coefficient of
//!   variation of its breaths' Ttot), are left out: the fitted breath's harmonics differ
//!   from a varying recorded one's, and the difference spreads over that band.
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

/// The band searched for a cardiac peak [Hz]: 48-150 beats/min, resting to exercising
/// adults.
pub const CARDIAC_BAND_HZ: (f64, f64) = (0.8, 2.5);
/// False-alarm probability of a reported cardiac peak over the whole band.
pub const CARDIAC_FALSE_ALARM: f64 = 0.01;

/// A spectral peak of the residual in the cardiac band.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CardiacPeak {
    /// Frequency of the peak [Hz].
    pub frequency_hz: f64,
    /// Root mean square over the markers of the 3-D amplitude of the residual at the peak
    /// [m].
    pub amplitude_rms_m: f64,
    /// Largest 3-D amplitude of one marker at the peak [m] and that marker (index).
    pub amplitude_max_m: f64,
    /// Index of the marker with the largest amplitude.
    pub marker: usize,
    /// The peak bin's power over the mean of the band's other bins.
    pub ratio: f64,
    /// Probability of so high a bin in white noise, times the number of bins.
    pub false_alarm: f64,
}

/// The cardiac peak of `residual` (per frame, per marker; `times` from the first frame),
/// with the breath at `breathing` Hz varying from breath to breath by `spread` (coefficient
/// of variation of the breath's period); None when there is none (see the module doc), or
/// the recording is too short or too slowly sampled, or the breath's spread harmonics cover
/// the band (fewer than 4 bins left).
pub fn cardiac_peak(
    times: &[f64],
    residual: &[Vec<Option<Vector3<f64>>>],
    breathing: f64,
    spread: f64,
) -> Option<CardiacPeak> {
    let n = times.len();
    if n < 16 {
        return None;
    }
    let span = times[n - 1] - times[0];
    let rate = (n - 1) as f64 / span;
    let step = 1.0 / span;
    let (lo, hi) = CARDIAC_BAND_HZ;
    let hi = hi.min(0.45 * rate);
    let bins: Vec<f64> = ((lo / step).ceil() as usize..=(hi / step).floor() as usize)
        .map(|k| k as f64 * step)
        .filter(|f| {
            // Every harmonic h of the breath, spread by h times the breath-to-breath
            // variation of the breathing frequency, and one step either side.
            (1..=(f / breathing * (1.0 + spread) + 1.0) as usize).all(|h| {
                let fh = h as f64 * breathing;
                (f - fh).abs() > step + fh * spread
            })
        })
        .collect();
    if bins.len() < 4 {
        return None;
    }
    let points = residual.first().map_or(0, Vec::len);
    // Each coordinate about its mean over its tracked samples.
    let mut columns: Vec<(usize, Vec<(f64, f64)>)> = Vec::new();
    for p in 0..points {
        for a in 0..3 {
            let v: Vec<(f64, f64)> = residual
                .iter()
                .zip(times)
                .filter_map(|(r, &t)| r[p].map(|d| (t - times[0], d[a])))
                .collect();
            if v.len() < n / 2 {
                continue;
            }
            let mean = v.iter().map(|x| x.1).sum::<f64>() / v.len() as f64;
            columns.push((p, v.into_iter().map(|(t, x)| (t, x - mean)).collect()));
        }
    }
    let m = columns.len();
    if m == 0 {
        return None;
    }
    // Per bin: the summed power and each marker's squared amplitude.
    let mut power = vec![0.0; bins.len()];
    let mut amplitude2 = vec![vec![0.0; points]; bins.len()];
    for (p, v) in &columns {
        for (b, f) in bins.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let (mut re, mut im) = (0.0, 0.0);
            for (t, x) in v {
                re += x * (w * t).cos();
                im += x * (w * t).sin();
            }
            let x2 = re * re + im * im;
            power[b] += x2 / v.len() as f64;
            amplitude2[b][*p] += 4.0 * x2 / (v.len() * v.len()) as f64;
        }
    }
    let k = bins.len();
    let (best, &top) = power.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let others = (power.iter().sum::<f64>() - top) / (k - 1) as f64;
    if others <= 0.0 {
        return None;
    }
    let ratio = top / others;
    let d1 = 2.0 * m as f64;
    let false_alarm =
        (crate::stats::special::f_sf(ratio, d1, d1 * (k - 1) as f64) * k as f64).min(1.0);
    if false_alarm >= CARDIAC_FALSE_ALARM {
        return None;
    }
    let amps: Vec<f64> = amplitude2[best].iter().map(|a| a.sqrt()).collect();
    let (marker, &amax) = amps.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let tracked: Vec<f64> = columns
        .iter()
        .map(|c| c.0)
        .fold(Vec::new(), |mut u, p| {
            if !u.contains(&p) {
                u.push(p);
            }
            u
        })
        .into_iter()
        .map(|p| amplitude2[best][p])
        .collect();
    Some(CardiacPeak {
        frequency_hz: bins[best],
        amplitude_rms_m: (tracked.iter().sum::<f64>() / tracked.len().max(1) as f64).sqrt(),
        amplitude_max_m: amax,
        marker,
        ratio,
        false_alarm,
    })
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
    /// With sway removed: the sway's share of the recorded motion about the means (before
    /// the sway was removed).
    pub sway_share: Option<f64>,
    /// A spectral peak of the residual in the cardiac band, reported, not fitted.
    pub cardiac: Option<CardiacPeak>,
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
    let basis = fit
        .drift_knots
        .as_ref()
        .map(|_| super::drift::DriftBasis::new(&fit.times, fit.drive.frequency));
    let drift_of = basis
        .as_ref()
        .map(|b| b.drift(&fit.fitted.markers, &fit.recorded));
    let residual: Vec<Vec<Option<Vector3<f64>>>> = fit
        .recorded
        .iter()
        .zip(&fit.fitted.markers)
        .enumerate()
        .map(|(i, (r, m))| {
            r.iter()
                .zip(m)
                .enumerate()
                .map(|(p, (q, a))| {
                    q.map(|q| {
                        let d = drift_of.as_ref().map_or(Vector3::zeros(), |d| d[i][p]);
                        q - a - d
                    })
                })
                .collect()
        })
        .collect();
    let periods: Vec<f64> = fit.breathing.breaths.iter().map(|b| b.ttot).collect();
    let spread = if periods.len() > 1 {
        let m = periods.iter().sum::<f64>() / periods.len() as f64;
        let v = periods.iter().map(|p| (p - m).powi(2)).sum::<f64>() / (periods.len() - 1) as f64;
        v.sqrt() / m
    } else {
        0.0
    };
    let cardiac = cardiac_peak(&fit.times, &residual, fit.drive.frequency, spread);
    let (drift_share, after_drift) = match drift_of {
        None => (None, None),
        Some(drift) => {
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
    let sway_share = fit.sway.as_ref().filter(|s| s.removed).map(|s| s.share);
    let mut notes = Vec::new();
    if !explains {
        notes.push(format!(
            "the model does not explain this recording: the drive explains {:.0} % of the markers' \
             motion above the noise{} (under {:.0} %); {}",
            100.0 * share,
            if after_drift.is_some() {
                " left after the drift"
            } else {
                " (drift not removed)"
            },
            100.0 * EXPLAINS_AT_LEAST,
            if sway_share.is_some() {
                "the trunk's sway was removed before"
            } else {
                "sway is not removed by this fit"
            }
        ));
    }
    if let Some(c) = &cardiac {
        notes.push(format!(
            "cardiac motion: a peak of the residual at {:.2} Hz ({:.0} beats/min), {:.3} mm rms over the markers \
             (largest {:.3} mm), {:.1} x the band's other bins: reported, not fitted",
            c.frequency_hz,
            60.0 * c.frequency_hz,
            c.amplitude_rms_m * 1e3,
            c.amplitude_max_m * 1e3,
            c.ratio
        ));
    }
    if let Some(s) = fit.sway.as_ref().filter(|s| !s.removed) {
        notes.push(format!("sway not removed: {}", s.note));
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
        sway_share,
        cardiac,
        after_drift,
        at_bounds,
        explains,
        notes,
    }
}
