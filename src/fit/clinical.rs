//! The per-breath report a clinician reads off a fit: the fitted model run over the
//! recording's time span ([`fitted_compartments`]: lung volume and the volumes displaced by
//! the rib cage and by the abdomen), its lung volume cut into breaths, and per breath
//! ([`breath_indices`]) the timing indices of the SLP literature, the tidal volume, the
//! rib-cage share and the thoraco-abdominal phase angle, with their means and SDs
//! ([`BreathReport`]), as JSON and as a text table.
//!
//! - Breaths: trough -> peak -> trough of the fitted lung volume
//!   ([`crate::stats::breaths::segment_breaths`], hysteresis 0.3 of the range, extrema at
//!   least 0.1 breathing periods apart as for the recording ([`super::breathing`]), no
//!   smoothing: the model's trajectory carries no noise).
//! - The recording's ends: the fit puts its first frame at end-expiration, so a breath
//!   often starts on the first frame and ends on the last, where a splitter cannot confirm
//!   a trough. The fitted model is deterministic and noise-free, so [`BreathReport::of_fit`]
//!   runs it half a breathing period ([`END_PADDING_PERIODS`]) before the first frame (the
//!   fit settles one period before it) and after the last, cuts that longer series, and
//!   keeps the breaths whose starting and ending troughs lie within the recording's span
//!   ([`breaths_within`]). A trough up to one frame interval outside an end counts as on
//!   it: a trough found on samples places the curve's minimum only within a frame either
//!   side of its sample, and a fitted model whose troughs sit a fraction of a frame off the
//!   recording's (a 1-frame shift is 1.6 deg of phase at 0.25 Hz and 56 Hz) would otherwise
//!   lose a whole breath at either end.
//! - Ti (trough to peak), Te (peak to next trough), Ttot = Ti + Te, Ti/Ttot, and
//!   IE50 = TIF50 / TEF50, the tidal inspiratory flow at 50 % of the inspired volume over
//!   the tidal expiratory flow at 50 % of the expired volume: the indices by which SLP is
//!   compared with pneumotachography (Motamedi-Fakhr et al. 2017, Physiol. Rep.
//!   5:e13124); the tidal flows at 50 % of the tidal volume are those of the ERS/ATS
//!   standard for tidal breath analysis (Bates et al. 2000, Eur. Respir. J. 16:1180-1192).
//! - VT: lung volume at the peak minus at the starting trough [L].
//! - Rib-cage share and phase angle over the breath's samples (starting trough up to, not
//!   including, the next one, so that the loop closes):
//!   [`crate::stats::thoracoabdominal`] (Konno & Mead 1967; Lissajous method, Agostoni &
//!   Mognoni 1966, Prisk, Hammer & Newth 2002), positive when the abdomen leads.
//! - Summary: the mean and sample SD of each index over the breaths, except the phase
//!   angle, an angle on the circle where +179 and -179 deg are 2 deg apart: its mean is the
//!   circular mean direction and its spread the circular standard deviation
//!   ([`circular_mean_sd_deg`]; Fisher 1993, Statistical Analysis of Circular Data, ch. 2;
//!   Mardia & Jupp 2000, Directional Statistics, ch. 2).

use super::Fit;
use crate::model::{Config, Quantity, Torso};
use crate::stats::breaths::{BreathDetector, segment_breaths};
use crate::stats::thoracoabdominal::{lissajous_phase_deg, rib_cage_share};
use crate::{Error, Result};
use serde::Serialize;
use serde_json::{Value, json};

/// The fitted model's volumes at the recording's times.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Compartments {
    /// Times relative to the recording's first frame [s].
    pub times: Vec<f64>,
    /// Lung volume [L].
    pub lung: Vec<f64>,
    /// Volume displaced by the rib cage since rest [L].
    pub rib_cage: Vec<f64>,
    /// Volume displaced by the abdominal wall since rest [L].
    pub abdomen: Vec<f64>,
}

/// Breathing periods the per-breath report runs the fitted model before the recording's
/// first frame and after its last (module doc): half a period reaches the expiration that
/// ends on a trough at the first frame, and the inspiration that confirms a trough on the
/// last.
pub const END_PADDING_PERIODS: f64 = 0.5;

/// Runs the fitted drive of `fit` on a model built from `config` from rest and reads the
/// lung, rib-cage and abdominal volumes at the recording's times. The fit's time convention
/// ([`super::fitting`]): the recording's first frame is model time 1/f.
pub fn fitted_compartments(config: &Config, fit: &Fit) -> Result<Compartments> {
    fitted_compartments_at(config, fit, &fit.times)
}

/// [`fitted_compartments`] at `times` (relative to the recording's first frame, increasing,
/// none earlier than one breathing period before it, where the fitted run starts).
pub fn fitted_compartments_at(config: &Config, fit: &Fit, times: &[f64]) -> Result<Compartments> {
    let mut c = config.clone();
    c.drive = fit.drive;
    c.drive.enabled = true;
    let settle = 1.0 / c.drive.frequency;
    if let Some(&t) = times
        .first()
        .filter(|&&t| !(settle + t).is_finite() || settle + t < 0.0)
    {
        return Err(Error::invalid(
            "time of the fitted model's run",
            t,
            format!("at least -{settle} s (one breathing period before the first frame)"),
        ));
    }
    let mut torso = Torso::new(c)?;
    let n = times.len();
    let mut out = Compartments {
        times: times.to_vec(),
        lung: Vec::with_capacity(n),
        rib_cage: Vec::with_capacity(n),
        abdomen: Vec::with_capacity(n),
    };
    for &t in times {
        torso.advance_to(settle + t)?;
        out.lung.push(torso.read(Quantity::LungVolume)?);
        out.rib_cage.push(torso.read(Quantity::RibCageDisplaced)?);
        out.abdomen.push(torso.read(Quantity::AbdomenDisplaced)?);
    }
    Ok(out)
}

/// `times` (uniformly spaced, at least two) extended by `pad` [s] on both sides at their
/// own spacing; also the number of times added before the first.
pub fn padded_times(times: &[f64], pad: f64) -> Result<(Vec<f64>, usize)> {
    let n = times.len();
    if n < 2 {
        return Err(Error::invalid(
            "recording frames",
            n,
            "at least 2 for a per-breath report",
        ));
    }
    let (t0, t1) = (times[0], times[n - 1]);
    let h = (t1 - t0) / (n - 1) as f64;
    if !(h > 0.0 && h.is_finite()) {
        return Err(Error::invalid(
            "recording times",
            format!("{t0} s to {t1} s"),
            "increasing times",
        ));
    }
    let k = (pad / h).ceil().max(0.0) as usize;
    let mut out = Vec::with_capacity(n + 2 * k);
    out.extend((1..=k).rev().map(|i| t0 - i as f64 * h));
    out.extend_from_slice(times);
    out.extend((1..=k).map(|i| t1 + i as f64 * h));
    Ok((out, k))
}

/// The indices of one breath (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BreathIndices {
    /// Onset (starting trough) relative to the recording's first frame [s].
    pub onset_s: f64,
    /// Inspiratory time [s].
    pub ti_s: f64,
    /// Expiratory time [s].
    pub te_s: f64,
    /// Total breath time [s].
    pub ttot_s: f64,
    /// Duty cycle Ti / Ttot.
    pub ti_ttot: f64,
    /// TIF50 / TEF50 (NaN when a half-volume crossing is missing).
    pub ie50: f64,
    /// Tidal volume [L].
    pub tidal_volume_l: f64,
    /// Rib-cage share of the displaced volume.
    pub rib_cage_share: f64,
    /// Thoraco-abdominal phase angle [deg], positive when the abdomen leads (NaN when the
    /// loop is degenerate).
    pub phase_angle_deg: f64,
}

/// One index of a breath: JSON name, table header with unit, accessor.
pub type Index = (&'static str, &'static str, fn(&BreathIndices) -> f64);

/// The names, units and accessors of the indices, in table order.
pub const INDICES: [Index; 8] = [
    ("ti_s", "Ti [s]", |b| b.ti_s),
    ("te_s", "Te [s]", |b| b.te_s),
    ("ttot_s", "Ttot [s]", |b| b.ttot_s),
    ("ti_ttot", "Ti/Ttot", |b| b.ti_ttot),
    ("ie50", "IE50", |b| b.ie50),
    ("tidal_volume_l", "VT [L]", |b| b.tidal_volume_l),
    ("rib_cage_share", "RC share [%]", |b| b.rib_cage_share),
    ("phase_angle_deg", "phase [deg]", |b| b.phase_angle_deg),
];

/// Cuts `c.lung` into breaths for a breathing frequency `frequency` [Hz] and computes each
/// breath's indices (module doc).
pub fn breath_indices(c: &Compartments, frequency: f64) -> Result<Vec<BreathIndices>> {
    let n = c.times.len();
    if c.lung.len() != n || c.rib_cage.len() != n || c.abdomen.len() != n {
        return Err(Error::State(format!(
            "breath indices: {} times, {} lung, {} rib-cage and {} abdominal volumes",
            n,
            c.lung.len(),
            c.rib_cage.len(),
            c.abdomen.len()
        )));
    }
    if !(frequency.is_finite() && frequency > 0.0) {
        return Err(Error::invalid(
            "breathing frequency",
            frequency,
            "a frequency in Hz > 0",
        ));
    }
    let period = 1.0 / frequency;
    let detector = BreathDetector {
        min_distance_s: 0.1 * period,
        smoothing_s: 0.0,
        ..BreathDetector::for_period(period)
    };
    Ok(segment_breaths(&c.times, &c.lung, &detector)
        .iter()
        .map(|b| {
            let (rc, ab) = (&c.rib_cage[b.start..b.end], &c.abdomen[b.start..b.end]);
            BreathIndices {
                onset_s: c.times[b.start],
                ti_s: b.ti,
                te_s: b.te,
                ttot_s: b.ttot,
                ti_ttot: b.ti_ttot,
                ie50: b.ie50,
                tidal_volume_l: b.tidal_volume,
                rib_cage_share: rib_cage_share(rc, ab),
                phase_angle_deg: lissajous_phase_deg(rc, ab).unwrap_or(f64::NAN),
            }
        })
        .collect())
}

/// The breaths of `c` ([`breath_indices`]) whose starting and ending troughs lie within
/// `from..=to` [s], a trough up to one frame interval of `c` outside either end counting
/// as on it (module doc: the report's series runs beyond the recording; a sampled trough
/// locates the minimum within a frame).
pub fn breaths_within(
    c: &Compartments,
    frequency: f64,
    from: f64,
    to: f64,
) -> Result<Vec<BreathIndices>> {
    let n = c.times.len();
    let h = if n > 1 {
        (c.times[n - 1] - c.times[0]) / (n - 1) as f64
    } else {
        0.0
    };
    // One frame, and the rounding of times computed from it.
    let slack = h * (1.0 + 1e-9);
    Ok(breath_indices(c, frequency)?
        .into_iter()
        .filter(|b| b.onset_s >= from - slack && b.onset_s + b.ttot_s <= to + slack)
        .collect())
}

/// Mean and sample SD (n - 1) of the finite values; NaN when there are none (SD: fewer
/// than two).
pub fn mean_sd(x: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = x.filter(|v| v.is_finite()).collect();
    let n = v.len() as f64;
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let m = v.iter().sum::<f64>() / n;
    let sd = if v.len() > 1 {
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        f64::NAN
    };
    (m, sd)
}

/// Circular mean direction and circular standard deviation [deg] of the finite angles
/// `deg` [deg] (Fisher 1993, Statistical Analysis of Circular Data, Cambridge University
/// Press, ch. 2; Mardia & Jupp 2000, Directional Statistics, Wiley, ch. 2): with C and S
/// the means of the cosines and sines, the mean direction is atan2(S, C), in (-180, 180],
/// and the circular SD is sqrt(-2 ln R) with R = sqrt(C^2 + S^2) the mean resultant length
/// (for small spreads close to the linear SD). NaN when there are no angles or they cancel
/// (R = 0, no mean direction); the SD NaN for fewer than two, as [`mean_sd`].
pub fn circular_mean_sd_deg(deg: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = deg.filter(|v| v.is_finite()).map(f64::to_radians).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let n = v.len() as f64;
    let c = v.iter().map(|a| a.cos()).sum::<f64>() / n;
    let s = v.iter().map(|a| a.sin()).sum::<f64>() / n;
    let r = c.hypot(s);
    // Below 1e-12 the direction is rounding noise.
    if r < 1e-12 {
        return (f64::NAN, f64::NAN);
    }
    let mut mean = s.atan2(c).to_degrees();
    if mean <= -180.0 {
        mean += 360.0;
    }
    let sd = if v.len() > 1 {
        (-2.0 * r.min(1.0).ln()).sqrt().to_degrees()
    } else {
        f64::NAN
    };
    (mean, sd)
}

/// The per-breath report of a fit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BreathReport {
    /// The fitted model's volumes at the recording's times.
    pub compartments: Compartments,
    /// One entry per whole breath of the fitted lung volume within the recording's span.
    pub breaths: Vec<BreathIndices>,
}

impl BreathReport {
    /// Runs the fitted model from half a breathing period before the recording's first
    /// frame to half a period after its last ([`fitted_compartments_at`],
    /// [`END_PADDING_PERIODS`]), keeps the breaths within the recording's span
    /// ([`breaths_within`]) and the volumes at the recording's times.
    pub fn of_fit(config: &Config, fit: &Fit) -> Result<BreathReport> {
        let f = fit.drive.frequency;
        let (times, before) = padded_times(&fit.times, END_PADDING_PERIODS / f)?;
        let padded = fitted_compartments_at(config, fit, &times)?;
        let (from, to) = (fit.times[0], fit.times[fit.times.len() - 1]);
        let breaths = breaths_within(&padded, f, from, to)?;
        let span = before..before + fit.times.len();
        let compartments = Compartments {
            times: fit.times.clone(),
            lung: padded.lung[span.clone()].to_vec(),
            rib_cage: padded.rib_cage[span.clone()].to_vec(),
            abdomen: padded.abdomen[span].to_vec(),
        };
        Ok(BreathReport {
            compartments,
            breaths,
        })
    }

    /// Mean and SD of each index of [`INDICES`]; the phase angle's circular
    /// ([`circular_mean_sd_deg`]).
    pub fn stats(&self) -> Vec<(&'static str, f64, f64)> {
        INDICES
            .iter()
            .map(|(name, _, get)| {
                let values = self.breaths.iter().map(get);
                let (m, sd) = if *name == "phase_angle_deg" {
                    circular_mean_sd_deg(values)
                } else {
                    mean_sd(values)
                };
                (*name, m, sd)
            })
            .collect()
    }

    /// The `breaths` array of the result JSON (NaN written as null).
    pub fn json_breaths(&self) -> Value {
        Value::Array(
            self.breaths
                .iter()
                .map(|b| {
                    let mut m = serde_json::Map::new();
                    m.insert("onset_s".into(), num(b.onset_s));
                    for (name, _, get) in INDICES {
                        m.insert(name.into(), num(get(b)));
                    }
                    Value::Object(m)
                })
                .collect(),
        )
    }

    /// The `breaths_summary` object of the result JSON: count, means, SDs, definitions.
    pub fn json_summary(&self) -> Value {
        let stats = self.stats();
        let mean: serde_json::Map<String, Value> = stats
            .iter()
            .map(|(k, m, _)| (k.to_string(), num(*m)))
            .collect();
        let sd: serde_json::Map<String, Value> = stats
            .iter()
            .map(|(k, _, s)| (k.to_string(), num(*s)))
            .collect();
        json!({
            "source": "the fitted model run from rest with the fitted drive from half a breathing period before the recording's first frame to half a period after its last; breaths trough-peak-trough of its lung volume whose troughs lie within the recording's span (a trough on its first or last frame included)",
            "count": self.breaths.len(),
            "statistics": "mean and sample SD (n - 1) of the breaths' values; phase_angle_deg: circular mean direction atan2(mean sin, mean cos) and circular SD sqrt(-2 ln R), R the mean resultant length (Fisher 1993; Mardia & Jupp 2000)",
            "mean": mean,
            "sd": sd,
            "definitions": {
                "ie50": "TIF50/TEF50: tidal inspiratory flow at 50 % of the inspired volume over tidal expiratory flow at 50 % of the expired volume",
                "rib_cage_share": "rib-cage swing / (rib-cage + abdominal swings) of the displaced volumes within the breath, a fraction (0-1; the printed table shows it in %)",
                "phase_angle_deg": "Lissajous phase angle of the abdominal against the rib-cage displaced volume, sin(phi) = m/s (Agostoni & Mognoni 1966); positive: abdomen leads",
            },
        })
    }

    /// A compact table: one row per breath, then the mean and SD rows.
    pub fn table(&self) -> String {
        let mut s = format!("{:>6} {:>9}", "breath", "onset [s]");
        for (_, head, _) in INDICES {
            s.push_str(&format!(" {head:>11}"));
        }
        s.push('\n');
        let row = |label: &str, onset: String, values: Vec<f64>| {
            let mut r = format!("{label:>6} {onset:>9}");
            for ((name, _, _), v) in INDICES.iter().zip(values) {
                let text = if !v.is_finite() {
                    "-".to_string()
                } else if *name == "phase_angle_deg" && label != "SD" {
                    format!("{v:+.1}")
                } else if *name == "tidal_volume_l" {
                    format!("{v:.3}")
                } else if *name == "phase_angle_deg" {
                    format!("{v:.1}")
                } else if *name == "rib_cage_share" {
                    format!("{:.1}", 100.0 * v)
                } else {
                    format!("{v:.2}")
                };
                r.push_str(&format!(" {text:>11}"));
            }
            r + "\n"
        };
        for (k, b) in self.breaths.iter().enumerate() {
            s.push_str(&row(
                &(k + 1).to_string(),
                format!("{:.2}", b.onset_s),
                INDICES.iter().map(|(_, _, g)| g(b)).collect(),
            ));
        }
        let stats = self.stats();
        s.push_str(&row(
            "mean",
            String::new(),
            stats.iter().map(|x| x.1).collect(),
        ));
        s.push_str(&row(
            "SD",
            String::new(),
            stats.iter().map(|x| x.2).collect(),
        ));
        s
    }
}

/// A JSON number, or null for NaN and infinities.
fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Raised-cosine breaths at `times`: inspiration of `ti` s, expiration of `te` s, tidal
    /// volume `vt`, a trough at `first_trough` and every ti + te from it (before it, the
    /// end of an expiration). Flow at half volume: vt pi / (2 ti) in, vt pi / (2 te) out,
    /// so IE50 = te / ti. Rib cage 0.4 of the volume in phase, abdomen 0.6 of it lagging
    /// 0.1 breath.
    fn cosine_compartments(
        ti: f64,
        te: f64,
        vt: f64,
        times: Vec<f64>,
        first_trough: f64,
    ) -> Compartments {
        let ttot = ti + te;
        let shape = |t: f64| {
            let u = (t - first_trough).rem_euclid(ttot);
            if u < ti {
                0.5 * (1.0 - (PI * u / ti).cos())
            } else {
                0.5 * (1.0 + (PI * (u - ti) / te).cos())
            }
        };
        let lung: Vec<f64> = times.iter().map(|&t| 3.0 + vt * shape(t)).collect();
        let rib_cage = times.iter().map(|&t| 0.4 * vt * shape(t)).collect();
        let abdomen = times
            .iter()
            .map(|&t| 0.6 * vt * shape(t - 0.1 * ttot))
            .collect();
        Compartments {
            times,
            lung,
            rib_cage,
            abdomen,
        }
    }

    /// [`cosine_compartments`] sampled at `rate` Hz for `breaths` breaths between a
    /// quarter-breath lead-in (the end of an expiration) and a quarter-breath tail.
    fn cosine_breaths(ti: f64, te: f64, vt: f64, rate: f64, breaths: usize) -> Compartments {
        let lead = 0.25 * (ti + te);
        let n = ((lead + breaths as f64 * (ti + te) + lead) * rate) as usize;
        let times: Vec<f64> = (0..n).map(|k| k as f64 / rate).collect();
        cosine_compartments(ti, te, vt, times, lead)
    }

    #[test]
    fn asymmetric_breaths_give_their_timing_ie50_and_volume() {
        let (ti, te, vt, rate) = (1.5, 2.5, 0.5, 50.0);
        let c = cosine_breaths(ti, te, vt, rate, 5);
        let b = breath_indices(&c, 1.0 / (ti + te)).unwrap();
        assert_eq!(b.len(), 5, "{b:?}");
        for (k, x) in b.iter().enumerate() {
            // Extrema are samples: timing within one sample interval.
            let h = 1.0 / rate;
            assert!((x.ti_s - ti).abs() <= h, "{x:?}");
            assert!((x.te_s - te).abs() <= h, "{x:?}");
            assert!((x.ttot_s - (ti + te)).abs() <= h, "{x:?}");
            assert!((x.ti_ttot - ti / (ti + te)).abs() < 0.01, "{x:?}");
            assert!(
                (x.onset_s - (0.25 + k as f64) * (ti + te)).abs() <= h,
                "{x:?}"
            );
            // IE50 = te / ti for raised-cosine halves; slope over one sample interval at
            // the inflection point errs by O(h^2).
            assert!((x.ie50 - te / ti).abs() < 0.01 * te / ti, "{x:?}");
            assert!((x.tidal_volume_l - vt).abs() < 1e-3 * vt, "{x:?}");
            // Swings 0.4 vt and 0.6 vt.
            assert!((x.rib_cage_share - 0.4).abs() < 1e-3, "{x:?}");
            // The abdomen lags 0.1 breath; for this non-sinusoidal waveform the Lissajous
            // angle is not exactly 36 deg, but must be negative (abdomen lagging) and of
            // that order.
            assert!(
                x.phase_angle_deg < -20.0 && x.phase_angle_deg > -60.0,
                "{x:?}"
            );
        }
    }

    #[test]
    fn sinusoidal_compartments_give_their_phase_and_share() {
        let (f, rate) = (0.25, 30.0);
        for lag_deg in [15.0_f64, -40.0, 150.0] {
            let lag = lag_deg.to_radians();
            let times: Vec<f64> = (0..(30.0 * rate) as usize)
                .map(|k| k as f64 / rate)
                .collect();
            let w = 2.0 * PI * f;
            let rib_cage: Vec<f64> = times.iter().map(|t| 0.2 * (w * t).sin()).collect();
            let abdomen: Vec<f64> = times.iter().map(|t| 0.3 * (w * t + lag).sin()).collect();
            let lung = rib_cage
                .iter()
                .zip(&abdomen)
                .map(|(r, a)| 3.0 + r + a)
                .collect();
            let c = Compartments {
                times,
                lung,
                rib_cage,
                abdomen,
            };
            let b = breath_indices(&c, f).unwrap();
            assert!(b.len() >= 6, "{b:?}");
            for x in &b {
                assert!(
                    (x.phase_angle_deg - lag_deg).abs() < 1.0,
                    "{lag_deg}: {x:?}"
                );
                assert!((x.rib_cage_share - 0.4).abs() < 2e-3, "{x:?}");
                assert!((x.ttot_s - 4.0).abs() <= 1.0 / rate, "{x:?}");
            }
        }
    }

    #[test]
    fn report_json_and_table_carry_every_breath() {
        let c = cosine_breaths(1.6, 2.4, 0.45, 28.0, 4);
        let r = BreathReport {
            breaths: breath_indices(&c, 0.25).unwrap(),
            compartments: c,
        };
        let j = r.json_breaths();
        assert_eq!(j.as_array().unwrap().len(), 4);
        assert!((j[2]["ti_s"].as_f64().unwrap() - 1.6).abs() < 0.04);
        let s = r.json_summary();
        assert_eq!(s["count"], 4);
        assert!((s["mean"]["tidal_volume_l"].as_f64().unwrap() - 0.45).abs() < 1e-3);
        assert!(s["sd"]["ti_s"].as_f64().unwrap() < 0.04);
        let t = r.table();
        assert_eq!(t.lines().count(), 1 + 4 + 2, "{t}");
        assert!(t.contains("Ti [s]") && t.contains("VT [L]") && t.contains("phase [deg]"));
    }

    /// A recording that starts and ends on a trough (as a fit's first frame, at
    /// end-expiration): five whole breaths in 0..=5 Ttot. The series runs half a breath
    /// beyond both ends, as the report's run of the fitted model, and every breath is kept,
    /// the first starting on the first frame and the last ending on the last.
    #[test]
    fn breaths_starting_and_ending_on_the_recording_ends_are_all_kept() {
        let (ti, te, vt, rate) = (1.6, 2.4, 0.5, 28.0_f64);
        let ttot: f64 = ti + te;
        let recording: Vec<f64> = (0..=(5.0 * ttot * rate).round() as usize)
            .map(|k| k as f64 / rate)
            .collect();
        let (times, before) = padded_times(&recording, 0.5 * ttot).unwrap();
        assert_eq!(before, (0.5 * ttot * rate).ceil() as usize);
        assert_eq!(times.len(), recording.len() + 2 * before);
        assert!((times[before] - 0.0).abs() < 1e-12);
        let c = cosine_compartments(ti, te, vt, times, 0.0);
        let b = breaths_within(&c, 1.0 / ttot, 0.0, 5.0 * ttot).unwrap();
        assert_eq!(b.len(), 5, "{b:?}");
        for (k, x) in b.iter().enumerate() {
            assert!((x.onset_s - k as f64 * ttot).abs() < 1e-9, "{x:?}");
            assert!((x.ttot_s - ttot).abs() < 1e-9, "{x:?}");
            assert!((x.tidal_volume_l - vt).abs() < 1e-3 * vt, "{x:?}");
        }
        // A trough one frame outside an end still counts (a sampled trough places the
        // minimum within a frame); two frames outside, the breath is not whole.
        let h = 1.0 / rate;
        for (from, to, count) in [
            (h, 5.0 * ttot - h, 5),
            (2.0 * h, 5.0 * ttot, 4),
            (0.0, 5.0 * ttot - 2.0 * h, 4),
            (2.0 * h, 5.0 * ttot - 2.0 * h, 3),
        ] {
            let b = breaths_within(&c, 1.0 / ttot, from, to).unwrap();
            assert_eq!(b.len(), count, "{from} {to}: {b:?}");
        }
        let b = breaths_within(&c, 1.0 / ttot, 2.0 * h, 5.0 * ttot).unwrap();
        assert!((b[0].onset_s - ttot).abs() < 1e-9, "{b:?}");
        assert!(padded_times(&[0.0], 1.0).is_err());
        assert!(padded_times(&[1.0, 1.0], 1.0).is_err());
    }

    #[test]
    fn phase_angles_are_averaged_on_the_circle() {
        // Paradoxical breaths either side of 180 deg: the plain mean would read 0
        // (synchronous); on the circle they are 2 deg from 180.
        let (m, sd) = circular_mean_sd_deg([178.0, -178.0, 178.0, -178.0].into_iter());
        assert!((m.abs() - 180.0).abs() < 1e-9, "{m}");
        // Each 2 deg from the mean: R = cos 2 deg, sqrt(-2 ln R) = 2.0001 deg.
        assert!((sd - 2.0).abs() < 0.01, "{sd}");
        // Small spreads: the circular SD is close to the root mean square deviation
        // (8.165 deg for 10, 20, 30).
        let (m, sd) = circular_mean_sd_deg([10.0, 20.0, 30.0, f64::NAN].into_iter());
        assert!((m - 20.0).abs() < 1e-9, "{m}");
        assert!((sd - (200.0_f64 / 3.0).sqrt()).abs() < 0.05, "{sd}");
        let (m, sd) = circular_mean_sd_deg([-170.0].into_iter());
        assert!((m + 170.0).abs() < 1e-9 && sd.is_nan());
        let (m, _) = circular_mean_sd_deg([90.0, -90.0].into_iter());
        assert!(m.is_nan());
        assert!(circular_mean_sd_deg(std::iter::empty()).0.is_nan());
        // The report's summary takes the circular statistics for the phase angle only.
        let c = cosine_breaths(1.6, 2.4, 0.45, 28.0, 4);
        let mut breaths = breath_indices(&c, 0.25).unwrap();
        for (k, b) in breaths.iter_mut().enumerate() {
            b.phase_angle_deg = if k % 2 == 0 { 178.0 } else { -178.0 };
        }
        let r = BreathReport {
            breaths,
            compartments: c,
        };
        let s = r.json_summary();
        let phase = s["mean"]["phase_angle_deg"].as_f64().unwrap();
        assert!((phase.abs() - 180.0).abs() < 1e-9, "{s}");
        assert!((s["sd"]["phase_angle_deg"].as_f64().unwrap() - 2.0).abs() < 0.01);
        assert!((s["mean"]["ti_s"].as_f64().unwrap() - 1.6).abs() < 0.04);
        let t = r.table();
        let mean_row = t
            .lines()
            .find(|l| l.trim_start().starts_with("mean"))
            .unwrap();
        assert!(mean_row.trim_end().ends_with("180.0"), "{t}");
    }

    #[test]
    fn mismatched_lengths_and_bad_frequency_are_errors() {
        let mut c = cosine_breaths(1.5, 2.5, 0.5, 20.0, 2);
        assert!(breath_indices(&c, 0.0).is_err());
        c.abdomen.pop();
        let e = breath_indices(&c, 0.25).unwrap_err().to_string();
        assert!(e.contains("abdominal"), "{e}");
    }
}
