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

/// Runs the fitted drive of `fit` on a model built from `config` from rest and reads the
/// lung, rib-cage and abdominal volumes at the recording's times. The fit's time convention
/// ([`super::fitting`]): the recording's first frame is model time 1/f.
pub fn fitted_compartments(config: &Config, fit: &Fit) -> Result<Compartments> {
    let mut c = config.clone();
    c.drive = fit.drive;
    c.drive.enabled = true;
    let settle = 1.0 / c.drive.frequency;
    let mut torso = Torso::new(c)?;
    let n = fit.times.len();
    let mut out = Compartments {
        times: fit.times.clone(),
        lung: Vec::with_capacity(n),
        rib_cage: Vec::with_capacity(n),
        abdomen: Vec::with_capacity(n),
    };
    for &t in &fit.times {
        torso.advance_to(settle + t)?;
        out.lung.push(torso.read(Quantity::LungVolume)?);
        out.rib_cage.push(torso.read(Quantity::RibCageDisplaced)?);
        out.abdomen.push(torso.read(Quantity::AbdomenDisplaced)?);
    }
    Ok(out)
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

/// The per-breath report of a fit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BreathReport {
    /// The fitted model's volumes at the recording's times.
    pub compartments: Compartments,
    /// One entry per whole breath of the fitted lung volume.
    pub breaths: Vec<BreathIndices>,
}

impl BreathReport {
    /// Runs the fitted model ([`fitted_compartments`]) and analyses its breaths.
    pub fn of_fit(config: &Config, fit: &Fit) -> Result<BreathReport> {
        let compartments = fitted_compartments(config, fit)?;
        let breaths = breath_indices(&compartments, fit.drive.frequency)?;
        Ok(BreathReport {
            compartments,
            breaths,
        })
    }

    /// Mean and SD of each index of [`INDICES`].
    pub fn stats(&self) -> Vec<(&'static str, f64, f64)> {
        INDICES
            .iter()
            .map(|(name, _, get)| {
                let (m, sd) = mean_sd(self.breaths.iter().map(get));
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
            "source": "the fitted model run from rest with the fitted drive over the recording's time span; breaths trough-peak-trough of its lung volume",
            "count": self.breaths.len(),
            "mean": mean,
            "sd": sd,
            "definitions": {
                "ie50": "TIF50/TEF50: tidal inspiratory flow at 50 % of the inspired volume over tidal expiratory flow at 50 % of the expired volume",
                "rib_cage_share": "rib-cage swing / (rib-cage + abdominal swings) of the displaced volumes within the breath",
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

    /// A raised-cosine breath: inspiration of `ti` s, expiration of `te` s, tidal volume
    /// `vt`, sampled at `rate` Hz for `breaths` breaths between a quarter-breath lead-in
    /// (the end of an expiration) and a quarter-breath tail. Flow at half volume: vt pi / (2 ti) in, vt pi / (2 te) out, so
    /// IE50 = te / ti.
    fn cosine_breaths(ti: f64, te: f64, vt: f64, rate: f64, breaths: usize) -> Compartments {
        let ttot = ti + te;
        let lead = 0.25 * ttot;
        let n = ((lead + breaths as f64 * ttot + lead) * rate) as usize;
        let times: Vec<f64> = (0..n).map(|k| k as f64 / rate).collect();
        // Before the first trough (t < lead) the signal is the end of an expiration.
        let shape = |t: f64| {
            let u = (t - lead).rem_euclid(ttot);
            if u < ti {
                0.5 * (1.0 - (PI * u / ti).cos())
            } else {
                0.5 * (1.0 + (PI * (u - ti) / te).cos())
            }
        };
        let lung: Vec<f64> = times.iter().map(|&t| 3.0 + vt * shape(t)).collect();
        // Rib cage 0.4 of the volume in phase, abdomen 0.6 of it lagging 0.1 breath.
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

    #[test]
    fn mismatched_lengths_and_bad_frequency_are_errors() {
        let mut c = cosine_breaths(1.5, 2.5, 0.5, 20.0, 2);
        assert!(breath_indices(&c, 0.0).is_err());
        c.abdomen.pop();
        let e = breath_indices(&c, 0.25).unwrap_err().to_string();
        assert!(e.contains("abdominal"), "{e}");
    }
}
