//! Data preparation before comparing a simulated lung volume with a spirogram (thesis 4.2):
//!
//! 1. a flow spirogram [L/s] is integrated to volume (cumulative trapezoid rule) and the
//!    least-squares straight line is removed from the result: a constant flow offset (the
//!    sensor's zero error) integrates to a linear ramp, which this removes exactly; the
//!    assumption is that the record holds whole breaths with no net volume change on
//!    average. A volume spirogram is detrended the same way only on request;
//! 2. the spirogram is resampled to the simulation's rate by the polyphase filter of
//!    [`resample`](super::resample) (100 -> 56 Hz is 14/25), and the samples at each end
//!    that the filter's zero padding reaches ([`edge_samples`], 10 at 14/25) are dropped;
//! 3. the simulated volume is multiplied by the lung ratio, for a simulation whose lungs
//!    change as a fraction of its thoracic volume (the thesis's 0.75, section 4.2; 1 for this
//!    model, whose lung and thoracic volumes change one to one);
//! 4. the two time columns are read as one clock: simulation sample `i` at `t_i` meets the
//!    spirogram at `t_i + lag / fs`, and the lag in `[-max_lag, max_lag]` frames maximising
//!    the normalised cross-correlation (Pearson correlation over the overlapping samples of
//!    the mean-removed series) is found; the pair is cut to the overlap. With the thesis's
//!    +-100 frames at 56 Hz (about half a breath) the search can lock onto a neighbouring
//!    breath: the correlation at every lag is reported for inspection;
//! 5. the spirogram, which starts at zero, is offset to the simulation's mean. The thesis
//!    adds the simulation mean; here the spirogram's own mean is removed first, so the two
//!    means are equal exactly, which the equality tests assume.
//!
//! Positive lags mean the spirogram's clock is read `lag` frames later than the
//! simulation's: a spirometer export whose time column starts at 0 s like the
//! simulation's, but which was started `d` seconds after the simulation's first sample,
//! gives a lag of `-d fs`.
//!
//! Refused with a message naming the file and the figure: a flat series (nothing to
//! compare), records that do not overlap on the clock, and a `max_lag` that reaches beyond
//! half the overlap (the lag search compares at least half the records at every lag).

use super::io::Series;
use super::resample::{gcd, rate_ratio, resample_poly};
use crate::{Error, Result};
use serde::Serialize;

/// What the spirometry column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SpiroKind {
    /// Volume [L].
    Volume,
    /// Flow [L/s], integrated.
    Flow,
}

/// Options of [`prepare`].
#[derive(Debug, Clone, Copy, Serialize)]
pub struct PrepareOptions {
    /// Factor applied to the simulated volume (1 when it already is a lung volume).
    pub lung_ratio: f64,
    /// Largest lag searched, in frames of the simulation's rate.
    pub max_lag: usize,
    /// Remove the linear trend from a volume spirogram too.
    pub detrend_volume: bool,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        PrepareOptions {
            lung_ratio: 1.0,
            max_lag: 100,
            detrend_volume: false,
        }
    }
}

/// The prepared, aligned pair.
#[derive(Debug, Clone, Serialize)]
pub struct Prepared {
    /// Common sampling rate (the simulation's) [Hz].
    pub rate_hz: f64,
    /// Spirometry rate [Hz].
    pub spiro_rate_hz: f64,
    /// Resampling ratio up / down applied to the spirogram.
    pub resample_ratio: (usize, usize),
    /// Lung ratio applied to the simulation.
    pub lung_ratio: f64,
    /// Chosen lag [frames].
    pub lag_frames: i64,
    /// Chosen lag [s].
    pub lag_seconds: f64,
    /// Normalised cross-correlation at the chosen lag.
    pub max_correlation: f64,
    /// True when the chosen lag is at the edge of the search window: the true lag may lie
    /// outside it (increase `max_lag`).
    pub lag_at_search_limit: bool,
    /// Normalised cross-correlation for lags -max_lag..=max_lag (NaN where not computed).
    pub correlation_by_lag: Vec<f64>,
    /// Constant added to the spirogram after alignment [L].
    pub spiro_offset: f64,
    /// Slope removed from the spirometer volume [L/s] (0 when not detrended).
    pub drift_removed_l_per_s: f64,
    /// Times of the aligned samples (simulation clock) [s].
    #[serde(skip)]
    pub time: Vec<f64>,
    /// Simulated lung volume [L].
    #[serde(skip)]
    pub sim: Vec<f64>,
    /// Spirometer lung volume [L], resampled, aligned and offset.
    #[serde(skip)]
    pub spiro: Vec<f64>,
    /// The whole resampled spirogram before edge trimming, alignment and offset [L].
    #[serde(skip)]
    pub spiro_resampled: Vec<f64>,
}

/// Output samples at each end of a polyphase resampling that the zero padding reaches:
/// the filter's half length `10 max(up, down)` in input-rate-times-up units, over `down`.
pub fn edge_samples(up: usize, down: usize) -> usize {
    let g = gcd(up, down);
    let (up, down) = (up / g, down / g);
    (10 * up.max(down)).div_ceil(down)
}

/// Cumulative trapezoid integral of `y(t)`, starting at zero.
pub fn integrate(t: &[f64], y: &[f64]) -> Vec<f64> {
    let mut v = Vec::with_capacity(y.len());
    let mut acc = 0.0;
    v.push(0.0);
    for k in 1..y.len() {
        acc += 0.5 * (y[k] + y[k - 1]) * (t[k] - t[k - 1]);
        v.push(acc);
    }
    v
}

/// Removes the least-squares line in time; returns (detrended, slope per second).
pub fn remove_linear_drift(t: &[f64], v: &[f64]) -> (Vec<f64>, f64) {
    let n = v.len() as f64;
    let tm = t.iter().sum::<f64>() / n;
    let vm = v.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in t.iter().zip(v) {
        sxy += (a - tm) * (b - vm);
        sxx += (a - tm) * (a - tm);
    }
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    // Keep the first sample's level so the volume still starts near zero.
    let out = t
        .iter()
        .zip(v)
        .map(|(a, b)| b - slope * (a - t[0]))
        .collect();
    (out, slope)
}

/// Pearson correlation of `a[i]` with `b[i + lag]` over the overlap; NaN when the overlap
/// is shorter than `min_overlap` or a side is constant.
pub fn lagged_correlation(a: &[f64], b: &[f64], lag: i64, min_overlap: usize) -> f64 {
    let i0 = if lag < 0 { (-lag) as usize } else { 0 };
    let i1 = (a.len() as i64).min(b.len() as i64 - lag);
    if i1 <= i0 as i64 || ((i1 - i0 as i64) as usize) < min_overlap {
        return f64::NAN;
    }
    let i1 = i1 as usize;
    let m = (i1 - i0) as f64;
    let bs = |i: usize| b[(i as i64 + lag) as usize];
    let ma = a[i0..i1].iter().sum::<f64>() / m;
    let mb = (i0..i1).map(bs).sum::<f64>() / m;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (i, ai) in a.iter().enumerate().take(i1).skip(i0) {
        let (x, y) = (ai - ma, bs(i) - mb);
        sab += x * y;
        saa += x * x;
        sbb += y * y;
    }
    if saa == 0.0 || sbb == 0.0 {
        f64::NAN
    } else {
        sab / (saa * sbb).sqrt()
    }
}

/// Lag in `[-max_lag, max_lag]` maximising [`lagged_correlation`], with the whole curve.
pub fn best_lag(a: &[f64], b: &[f64], max_lag: usize) -> Result<(i64, f64, Vec<f64>)> {
    best_lag_around(a, b, 0, max_lag)
}

/// Lag `l` in `[-max_lag, max_lag]` maximising the correlation of `a[i]` with
/// `b[i + center + l]`, with the curve over `l`.
pub fn best_lag_around(
    a: &[f64],
    b: &[f64],
    center: i64,
    max_lag: usize,
) -> Result<(i64, f64, Vec<f64>)> {
    let min_overlap = (a.len().min(b.len()) / 2).max(16);
    let curve: Vec<f64> = (-(max_lag as i64)..=max_lag as i64)
        .map(|l| lagged_correlation(a, b, center + l, min_overlap))
        .collect();
    let (idx, best) = curve
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .max_by(|x, y| x.1.total_cmp(y.1))
        .ok_or_else(|| {
            Error::invalid(
                "series overlap",
                format!("{} and {} samples", a.len(), b.len()),
                format!(
                    "an overlap of at least {min_overlap} samples at some lag within +-{max_lag}"
                ),
            )
        })?;
    Ok((idx as i64 - max_lag as i64, *best, curve))
}

/// Range (max - min) below which a series counts as flat: `1e-9 max(1, max |v|)`, i.e.
/// constant to within rounding of the values as written.
pub fn flat_tolerance(v: &[f64]) -> f64 {
    1e-9 * v.iter().fold(1.0f64, |m, x| m.max(x.abs()))
}

/// Errors when `series` is flat (see [`flat_tolerance`]): nothing to compare. `what`
/// describes the role ("simulation", "spirometry").
pub fn check_not_flat(series: &Series, what: &str, kind: Option<SpiroKind>) -> Result<()> {
    let (lo, hi) = series
        .values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    if hi - lo <= flat_tolerance(&series.values) {
        let unit = if kind == Some(SpiroKind::Flow) {
            "L/s"
        } else {
            "L"
        };
        let why = if kind == Some(SpiroKind::Flow) {
            "a constant flow integrates to a pure drift, which is removed, leaving no breathing"
        } else {
            "there is no breathing to compare"
        };
        return Err(Error::State(format!(
            "{}: the {what} column `{}` is flat ({} rows, all within {:.3e} {unit} of {}): {why}",
            series.source,
            series.column,
            series.len(),
            hi - lo,
            lo
        )));
    }
    Ok(())
}

/// The time interval [s] both records cover on their clocks, or an error naming both files
/// and their spans when they do not overlap.
pub fn clock_overlap(sim: &Series, spiro: &Series) -> Result<(f64, f64)> {
    let (s0, s1) = (sim.time[0], sim.time[sim.len() - 1]);
    let (p0, p1) = (spiro.time[0], spiro.time[spiro.len() - 1]);
    let (a, b) = (s0.max(p0), s1.min(p1));
    if b <= a {
        return Err(Error::State(format!(
            "{} covers {s0:.3}-{s1:.3} s and {} covers {p0:.3}-{p1:.3} s: the records do not \
             overlap in time. Both time columns must be on one clock (a spirometer export \
             starting at 0 s is compared from the simulation's start); shift one of them",
            sim.source, spiro.source
        )));
    }
    Ok((a, b))
}

/// Runs steps 1-5 of the module doc on a simulation series and a spirometry series.
pub fn prepare(
    sim: &Series,
    spiro: &Series,
    kind: SpiroKind,
    opts: &PrepareOptions,
) -> Result<Prepared> {
    if !(opts.lung_ratio > 0.0 && opts.lung_ratio <= 2.0) {
        return Err(Error::invalid("lung ratio", opts.lung_ratio, "(0, 2]"));
    }
    check_not_flat(sim, "simulation", None)?;
    check_not_flat(spiro, "spirometry", Some(kind))?;
    let (o0, o1) = clock_overlap(sim, spiro)?;
    let fs = sim.rate();
    let fs_spiro = spiro.rate();
    let overlap_frames = ((o1 - o0) * fs).floor() as usize + 1;
    if 2 * opts.max_lag >= overlap_frames {
        return Err(Error::State(format!(
            "--max-lag {} frames ({:.2} s at {:.3} Hz) reaches beyond the overlap of {} and {}: \
             {overlap_frames} frames ({:.2} s, {o0:.3}-{o1:.3} s). Every lag tried must leave \
             half the overlap to compare: at most {} frames here",
            opts.max_lag,
            opts.max_lag as f64 / fs,
            fs,
            sim.source,
            spiro.source,
            o1 - o0,
            (overlap_frames - 1) / 2
        )));
    }
    let (mut vol, drift) = match kind {
        SpiroKind::Flow => {
            let v = integrate(&spiro.time, &spiro.values);
            remove_linear_drift(&spiro.time, &v)
        }
        SpiroKind::Volume if opts.detrend_volume => remove_linear_drift(&spiro.time, &spiro.values),
        SpiroKind::Volume => (spiro.values.clone(), 0.0),
    };
    let (up, down) = rate_ratio(fs_spiro, fs)?;
    let mut trimmed = 0i64;
    let mut resampled = Vec::new();
    if up != down {
        vol = resample_poly(&vol, up, down)?;
        resampled = vol.clone();
        let trim = edge_samples(up, down);
        if vol.len() <= 2 * trim + 32 {
            return Err(Error::invalid(
                "spirometry samples after resampling",
                vol.len(),
                format!("more than {}", 2 * trim + 32),
            ));
        }
        vol = vol[trim..vol.len() - trim].to_vec();
        trimmed = trim as i64;
    }
    let simv: Vec<f64> = sim.values.iter().map(|v| v * opts.lung_ratio).collect();
    // Index of the (trimmed) spirogram sample on the simulation's clock at lag 0:
    // simulation sample i pairs with spirogram sample i + clock - trimmed + lag.
    let clock = ((sim.time[0] - spiro.time[0]) * fs).round() as i64;
    let center = clock - trimmed;
    let (lag, max_correlation, curve) = best_lag_around(&simv, &vol, center, opts.max_lag)?;
    let shift = center + lag;
    let i0 = if shift < 0 { (-shift) as usize } else { 0 };
    let i1 = ((simv.len() as i64).min(vol.len() as i64 - shift)) as usize;
    let time = sim.time[i0..i1].to_vec();
    let simv = simv[i0..i1].to_vec();
    let mut spv: Vec<f64> = (i0..i1).map(|i| vol[(i as i64 + shift) as usize]).collect();
    let m_sim = simv.iter().sum::<f64>() / simv.len() as f64;
    let m_sp = spv.iter().sum::<f64>() / spv.len() as f64;
    let offset = m_sim - m_sp;
    for v in &mut spv {
        *v += offset;
    }
    Ok(Prepared {
        rate_hz: fs,
        spiro_rate_hz: fs_spiro,
        resample_ratio: (up, down),
        lung_ratio: opts.lung_ratio,
        lag_frames: lag,
        lag_seconds: lag as f64 / fs,
        max_correlation,
        lag_at_search_limit: lag.unsigned_abs() as usize == opts.max_lag,
        correlation_by_lag: curve,
        spiro_offset: offset,
        drift_removed_l_per_s: drift,
        time,
        sim: simv,
        spiro: spv,
        spiro_resampled: if resampled.is_empty() { vol } else { resampled },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_known_lag_exactly() {
        let f = |i: i64| {
            let t = i as f64 / 56.0;
            (2.0 * std::f64::consts::PI * 0.27 * t).sin()
                + 0.3 * (2.0 * std::f64::consts::PI * 0.61 * t).cos()
        };
        let a: Vec<f64> = (0..1000).map(f).collect();
        for lag in [-37i64, 0, 5, 64] {
            let b: Vec<f64> = (0..1000).map(|i| 2.0 * f(i - lag) + 1.0).collect();
            let (l, r, _) = best_lag(&a, &b, 100).unwrap();
            assert_eq!(l, lag);
            assert!((r - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn flow_offset_is_removed() {
        let t: Vec<f64> = (0..2000).map(|i| i as f64 / 100.0).collect();
        let w = 2.0 * std::f64::consts::PI * 0.25;
        let flow: Vec<f64> = t.iter().map(|&s| 0.25 * w * (w * s).sin() + 0.05).collect();
        let v = integrate(&t, &flow);
        let (d, slope) = remove_linear_drift(&t, &v);
        assert!((slope - 0.05).abs() < 2e-3, "{slope}");
        let span = d.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - d.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((span - 0.5).abs() < 0.03, "{span}");
    }
}
