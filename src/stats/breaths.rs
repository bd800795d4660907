//! Breath segmentation of a volume curve and breath-by-breath pairing of two curves.
//!
//! Samples of one time series are not independent, so agreement is also reported per breath
//! (per-breath tidal volume, inspiratory and expiratory time), as the SLP literature does
//! (e.g. de Boer et al. 2010). Extrema are found with a hysteresis detector: a peak is
//! confirmed once the signal has fallen `h` below the running maximum, a trough once it has
//! risen `h` above the running minimum, with `h` a fraction (default 0.3) of the 5-95 %
//! range of the detrended signal, so noise smaller than `h` never creates a breath. Extrema
//! closer than a minimum distance (default 0.3 breathing periods) are merged, keeping the
//! more extreme one, and an extremum on the first sample (a record starting mid-breath) is
//! dropped. Extrema are located on a centred moving average over 0.05 breathing periods,
//! which keeps the noise out of the per-breath volumes. A breath runs trough -> peak -> trough.
//!
//! Per breath, the timing indices the SLP validation against pneumotachography compares
//! (Motamedi-Fakhr et al. 2017, Physiol. Rep. 5(3):e13124): inspiratory time Ti (trough to
//! peak), expiratory time Te (peak to next trough), total time Ttot = Ti + Te, the duty
//! cycle Ti/Ttot, and IE50 = TIF50 / TEF50, the inspiratory flow when half the tidal volume
//! has been inspired over the expiratory flow when half the expired volume has been
//! expired. Each flow is the slope of the smoothed volume over the sample interval in
//! which the curve crosses its half-volume level (first crossing in the phase).

use super::frequency::detrend_linear;
use serde::Serialize;

/// One breath: trough, peak, next trough.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Breath {
    /// Sample index of the starting trough.
    pub start: usize,
    /// Sample index of the peak (end of inspiration).
    pub peak: usize,
    /// Sample index of the ending trough.
    pub end: usize,
    /// Time of the peak [s].
    pub peak_time: f64,
    /// Inspired volume v(peak) - v(start) [L].
    pub tidal_volume: f64,
    /// Expired volume v(peak) - v(end) [L].
    pub expired_volume: f64,
    /// Inspiratory time [s].
    pub ti: f64,
    /// Expiratory time [s].
    pub te: f64,
    /// Total breath time Ti + Te [s].
    pub ttot: f64,
    /// Duty cycle Ti / Ttot.
    pub ti_ttot: f64,
    /// TIF50 / TEF50 (see the module doc); NaN when a half-volume crossing is missing.
    pub ie50: f64,
}

/// Slope of `v` over the first sample interval in `from..to` where it crosses `level`
/// (upwards when `rising`), in units of v per second; None without a crossing.
fn slope_at_level(
    t: &[f64],
    v: &[f64],
    from: usize,
    to: usize,
    level: f64,
    rising: bool,
) -> Option<f64> {
    (from..to).find_map(|k| {
        let crosses = if rising {
            v[k] < level && v[k + 1] >= level
        } else {
            v[k] > level && v[k + 1] <= level
        };
        (crosses && t[k + 1] > t[k]).then(|| (v[k + 1] - v[k]) / (t[k + 1] - t[k]))
    })
}

/// Settings of [`segment_breaths`].
#[derive(Debug, Clone, Copy)]
pub struct BreathDetector {
    /// Hysteresis as a fraction of the 5-95 % range of the detrended signal.
    pub hysteresis_fraction: f64,
    /// Minimum distance between consecutive extrema [s].
    pub min_distance_s: f64,
    /// Width of the centred moving average applied before locating extrema [s].
    pub smoothing_s: f64,
}

impl BreathDetector {
    /// Defaults for a breathing period `period_s`: hysteresis 0.3, minimum distance 0.3
    /// periods, smoothing over 0.05 periods.
    pub fn for_period(period_s: f64) -> Self {
        BreathDetector {
            hysteresis_fraction: 0.3,
            min_distance_s: 0.3 * period_s,
            smoothing_s: 0.05 * period_s,
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Peak,
    Trough,
}

/// Percentile (linear interpolation) of unsorted data.
pub fn percentile(x: &[f64], q: f64) -> f64 {
    let mut s = x.to_vec();
    s.sort_by(f64::total_cmp);
    let pos = q / 100.0 * (s.len() - 1) as f64;
    let i = pos.floor() as usize;
    let frac = pos - i as f64;
    if i + 1 < s.len() {
        s[i] * (1.0 - frac) + s[i + 1] * frac
    } else {
        s[i]
    }
}

fn extrema(v: &[f64], h: f64) -> Vec<(usize, Kind)> {
    let mut out = Vec::new();
    let (mut max_i, mut min_i) = (0usize, 0usize);
    let mut state: Option<Kind> = None; // Some(Peak) = looking for a peak (rising)
    for i in 1..v.len() {
        match state {
            None => {
                if v[i] > v[max_i] {
                    max_i = i;
                }
                if v[i] < v[min_i] {
                    min_i = i;
                }
                if v[i] >= v[min_i] + h {
                    out.push((min_i, Kind::Trough));
                    state = Some(Kind::Peak);
                    max_i = i;
                } else if v[i] <= v[max_i] - h {
                    out.push((max_i, Kind::Peak));
                    state = Some(Kind::Trough);
                    min_i = i;
                }
            }
            Some(Kind::Peak) => {
                if v[i] > v[max_i] {
                    max_i = i;
                }
                if v[i] <= v[max_i] - h {
                    out.push((max_i, Kind::Peak));
                    state = Some(Kind::Trough);
                    min_i = i;
                }
            }
            Some(Kind::Trough) => {
                if v[i] < v[min_i] {
                    min_i = i;
                }
                if v[i] >= v[min_i] + h {
                    out.push((min_i, Kind::Trough));
                    state = Some(Kind::Peak);
                    max_i = i;
                }
            }
        }
    }
    out
}

/// Centred moving average over `half` samples on each side (shrinking at the ends).
pub fn moving_average(v: &[f64], half: usize) -> Vec<f64> {
    let n = v.len();
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(0.0);
    for x in v {
        prefix.push(prefix.last().copied().unwrap_or(0.0) + x);
    }
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(half), (i + half + 1).min(n));
            (prefix[b] - prefix[a]) / (b - a) as f64
        })
        .collect()
}

/// Segments a volume curve `v` sampled at times `t` into breaths. Volumes and times are
/// read on the smoothed curve (see [`BreathDetector::smoothing_s`]).
pub fn segment_breaths(t: &[f64], v: &[f64], det: &BreathDetector) -> Vec<Breath> {
    if v.len() < 4 || t.len() != v.len() {
        return Vec::new();
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    let half = if dt > 0.0 {
        (0.5 * det.smoothing_s / dt).round() as usize
    } else {
        0
    };
    let smoothed = moving_average(v, half);
    let v = &smoothed[..];
    let d = detrend_linear(v);
    let h = det.hysteresis_fraction * (percentile(&d, 95.0) - percentile(&d, 5.0));
    if h <= 0.0 {
        return Vec::new();
    }
    let mut ext = extrema(v, h);
    if ext.first().is_some_and(|e| e.0 == 0) {
        ext.remove(0);
    }
    // Merge extrema closer than the minimum distance.
    let more_extreme = |a: (usize, Kind), b: (usize, Kind)| -> (usize, Kind) {
        match a.1 {
            Kind::Peak => {
                if v[b.0] > v[a.0] {
                    b
                } else {
                    a
                }
            }
            Kind::Trough => {
                if v[b.0] < v[a.0] {
                    b
                } else {
                    a
                }
            }
        }
    };
    let mut i = 0;
    while i + 1 < ext.len() {
        if t[ext[i + 1].0] - t[ext[i].0] < det.min_distance_s {
            if i + 2 < ext.len() && i > 0 {
                ext[i - 1] = more_extreme(ext[i - 1], ext[i + 1]);
                ext.drain(i..i + 2);
                i -= 1;
            } else if i == 0 {
                ext.remove(0);
            } else {
                ext.truncate(i + 1);
            }
        } else {
            i += 1;
        }
    }
    let mut breaths = Vec::new();
    for w in ext.windows(3) {
        if let [(s, Kind::Trough), (p, Kind::Peak), (e, Kind::Trough)] = *w {
            let (vt, ve) = (v[p] - v[s], v[p] - v[e]);
            let (ti, te) = (t[p] - t[s], t[e] - t[p]);
            let tif50 = slope_at_level(t, v, s, p, v[s] + 0.5 * vt, true);
            let tef50 = slope_at_level(t, v, p, e, v[p] - 0.5 * ve, false);
            let ie50 = match (tif50, tef50) {
                (Some(i), Some(x)) if x < 0.0 => i / -x,
                _ => f64::NAN,
            };
            breaths.push(Breath {
                start: s,
                peak: p,
                end: e,
                peak_time: t[p],
                tidal_volume: vt,
                expired_volume: ve,
                ti,
                te,
                ttot: ti + te,
                ti_ttot: ti / (ti + te),
                ie50,
            });
        }
    }
    breaths
}

/// Pairs breaths of two segmentations by nearest peak time (each breath used once, pairs
/// further apart than `max_gap_s` dropped). Returns index pairs (a, b).
pub fn pair_breaths(a: &[Breath], b: &[Breath], max_gap_s: f64) -> Vec<(usize, usize)> {
    let mut used = vec![false; b.len()];
    let mut pairs = Vec::new();
    for (i, ba) in a.iter().enumerate() {
        let best = b
            .iter()
            .enumerate()
            .filter(|(j, _)| !used[*j])
            .map(|(j, bb)| (j, (bb.peak_time - ba.peak_time).abs()))
            .min_by(|x, y| x.1.total_cmp(&y.1));
        if let Some((j, gap)) = best
            && gap <= max_gap_s
        {
            used[j] = true;
            pairs.push((i, j));
        }
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::Pcg64;
    use std::f64::consts::PI;

    #[test]
    fn counts_breaths_of_noisy_sine_with_drift() {
        let fs = 56.0;
        let f0 = 0.25;
        let mut g = Pcg64::new(1, 0);
        // 30.5 s, phase chosen so the record starts mid-inspiration: 7 full
        // trough-peak-trough cycles fit (troughs at 1 + 4 j s).
        let t: Vec<f64> = (0..(30.5 * fs) as usize).map(|i| i as f64 / fs).collect();
        let v: Vec<f64> = t
            .iter()
            .map(|&s| {
                2.0 + 0.25 * (1.0 - (2.0 * PI * f0 * (s - 1.0)).cos())
                    + 0.01 * s
                    + 0.02 * g.normal()
            })
            .collect();
        let b = segment_breaths(&t, &v, &BreathDetector::for_period(1.0 / f0));
        assert_eq!(b.len(), 7, "{b:?}");
        for br in &b {
            assert!(
                (br.ti - 2.0).abs() < 0.4 && (br.te - 2.0).abs() < 0.4,
                "{br:?}"
            );
            assert!((br.tidal_volume - 0.5).abs() < 0.06, "{br:?}");
        }
    }
}
