//! The built-in periodic drive, so that a fit can run on parameters alone: the sine of
//! thesis eq. 2.4, or the same wave with a shorter inspiration (an inspiratory fraction).
//!
//! Thesis eq. 2.4 modulates each element's rest-length ratio as
//! r(t) = alpha - beta/2 (sin(2 pi f t + phi) + 1). Here the same wave is expressed as an
//! activation a(t) = A/2 (sin(2 pi f t + phi) + 1) in [0, A], with A the fraction of the
//! maximal reachable activation (the thesis's A_ribs, A_diaphragm, Table 4.3); the element
//! then contracts as r = 1 - beta_max g a (see `dynamics`). The applied activation of a
//! group is clamp(input + drive + tone, 0, 1), the tone the abdominal wall's standing tone
//! under the hill law (`Params::abdominal_tone`). Supine under the hill law the internal
//! intercostals take the abdominal family's wave instead of the rib family's, since quiet
//! expiration is passive there (`Params::expiration_with_abdominals`).
//!
//! Real breathing is not a sine: quiet inspiration takes about 0.4 of the breath (Tobin et
//! al. 1983, "Breathing patterns. 1. Normal subjects", Chest 84:202; see docs/drive.md). The
//! drive therefore has an inspiratory fraction F = Ti/Ttot. With the cycle phase
//! u = ((2 pi f t + phi + pi/2) / 2 pi) mod 1 (u = 0 where the sine is at its minimum), the
//! waveform is two raised-cosine halves joined at the peak u = F:
//! w(u) = (1 - cos(pi u / F)) / 2 on [0, F] and w(u) = (1 + cos(pi (u - F) / (1 - F))) / 2
//! on [F, 1), so that a(t) = A w(u). Both halves have zero slope at their ends, so w is C1
//! (its second derivative jumps at u = 0 and u = F unless F = 1/2). At F = 1/2 the halves are
//! the two halves of (1 + sin(2 pi f t + phi)) / 2, which is then evaluated as that sine
//! itself, so the default drive is eq. 2.4 bit for bit. The expiratory groups take 1 - w(u),
//! which at F = 1/2 is the sine in antiphase (phi + pi) of eq. 2.4.
//!
//! Depth and rate also change from breath to breath. [`Breaths`] is a schedule of breaths
//! (start time, period, depth scale): time -> breath index -> cycle phase within the breath.
//! It is turned into a piecewise-constant drive, one [`Drive`] per breath
//! ([`Breaths::schedule`]), whose waves start each breath at their inspiration onset, so the
//! dynamics only ever see a fixed-shape drive.

use crate::anatomy::MuscleGroup;
use crate::dynamics::muscle::MuscleLaw;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// One sinusoidal wave: amplitude in [0, 1] (fraction of the maximal activation) and phase.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
pub struct Wave {
    /// Amplitude A in [0, 1].
    pub amplitude: f64,
    /// Phase phi [rad], in [-2 pi, 2 pi].
    pub phase: f64,
}

/// The drive of the three muscle families: ribs (external intercostals and scalenes; the
/// internal intercostals are driven in antiphase, thesis 2.4.1, except supine under the hill
/// law, where they take the abdominals' wave, [`crate::dynamics::expiration_with_abdominals`]),
/// diaphragm, abdominals (the four abdominal wall muscles, in antiphase with inspiration:
/// they help expiration).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Drive {
    /// Whether the drive runs (FMI `drive.enabled`); off, the muscles follow the activation
    /// inputs alone whatever the amplitudes. Saved states without the field had it on.
    #[serde(default = "drive_on")]
    pub enabled: bool,
    /// Breathing frequency f_b [Hz], in [0.05, 2].
    pub frequency: f64,
    /// Inspiratory fraction Ti/Ttot of every family's wave (FMI
    /// `drive.inspiratory_fraction`), in [0.2, 0.8]; 0.5 is the sine of eq. 2.4. Saved
    /// states without the field had the sine.
    #[serde(default = "sine_fraction")]
    pub inspiratory_fraction: f64,
    /// Rib-cage family.
    pub ribs: Wave,
    /// Diaphragm.
    pub diaphragm: Wave,
    /// Abdominal wall muscles.
    pub abdominals: Wave,
}

fn drive_on() -> bool {
    true
}

fn sine_fraction() -> f64 {
    SINE_FRACTION
}

/// The inspiratory fraction at which the waveform is the sine of eq. 2.4.
pub const SINE_FRACTION: f64 = 0.5;
/// Allowed range of the inspiratory fraction Ti/Ttot: wide enough for quiet breathing
/// (about 0.4, Tobin et al. 1983) and the short inspirations of exercise or obstruction,
/// narrow enough that neither raised-cosine half becomes a step for the solver.
pub const INSPIRATORY_FRACTION_RANGE: (f64, f64) = (0.2, 0.8);

/// The periodic waveform w in [0, 1] at cycle phase `u` (any real; taken modulo 1, u = 0 the
/// start of inspiration) with inspiratory fraction `fraction` in (0, 1): a raised-cosine
/// rise over [0, F] to 1 at u = F, then a raised-cosine fall over [F, 1) (module doc).
pub fn waveform(u: f64, fraction: f64) -> f64 {
    let u = u.rem_euclid(1.0);
    if u < fraction {
        0.5 * (1.0 - (PI * u / fraction).cos())
    } else {
        0.5 * (1.0 + (PI * (u - fraction) / (1.0 - fraction)).cos())
    }
}

/// No drive: every amplitude 0 (the `rest` scenario).
impl Default for Drive {
    fn default() -> Self {
        Drive {
            enabled: true,
            frequency: 0.25,
            inspiratory_fraction: SINE_FRACTION,
            ribs: Wave::default(),
            diaphragm: Wave::default(),
            abdominals: Wave::default(),
        }
    }
}

/// Peak activation of the diaphragm in quiet breathing under the passive-and-active muscle law
/// ([`MuscleLaw::Hill`], where an activation is a fraction of the maximal force): the crural
/// diaphragm's EMG in quiet breathing as a fraction of its maximum in maximal inspiratory
/// manoeuvres, 7.5 (2) % in 15 healthy adults (Reilly et al. 2011, Thorax 66:240, the controls
/// of a cystic-fibrosis study; 9.0 +- 3.4 % in 100 healthy subjects, Jolley et al. 2009, Eur
/// Respir J 33:289). EMG is taken as proportional to force (the diaphragm's Pdi-EMG relation
/// is near linear); not fitted: with it the quiet tidal volume is an outcome. The choice of
/// source matters: at Jolley et al.'s 9.0 % the default man standing breathes 0.786 L (10.5
/// mL/kg) with a 44.9 % rib-cage share, against 0.707 L (9.4 mL/kg, also above 7 mL/kg + 25 %)
/// and 54.7 % at Reilly et al.'s 7.5 % (`torso simulate --muscle-law hill --diaphragm-amplitude 0.09
/// --ribs-amplitude 0.058 --duration 16`, and 0.075; measured before the passive wall's
/// compartments were fitted apart, with which the standing breath is 0.683 L and its rib-cage
/// share 76.2 %); Reilly et al. is taken because it measured both families in the same
/// subjects.
pub const HILL_QUIET_DIAPHRAGM: f64 = 0.075;

/// Peak activation of the rib-cage inspiratory muscles in quiet breathing under the
/// passive-and-active law: the parasternal intercostals' surface EMG, 5.8 (3) % of its
/// maximum, in the same 15 subjects as [`HILL_QUIET_DIAPHRAGM`] (Reilly et al. 2011; 5.88
/// (3.63) % in 43 healthy adults, MacBean et al. 2014, Thorax 69 Suppl 2:A170). The drive's
/// rib family also drives the scalenes, for which no quiet-breathing fraction of maximum was
/// found, at the same fraction, and, upright, the internal intercostals at it in antiphase (the
/// drive's structure, thesis 2.4.1): the rib cage's expiratory muscles are active in quiet
/// expiration standing (the triangularis sterni in 15 of 20 adults, Estenne, Ninane & De
/// Troyer 1988, Respir Physiol 74:151), at a magnitude no source gave, so 5.8 % of their
/// maximal force in expiration is uncited. Supine, where quiet expiration is passive, they
/// follow the abdominal family instead ([`crate::dynamics::expiration_with_abdominals`]).
/// Measured (`torso bench physiology --muscle-law hill`, before the passive wall's compartments
/// were fitted apart): the upright rib-cage share of quiet breathing, 54.7 % with this
/// expiratory wave, rests on it (12.7 % without it, the internal intercostals silent standing,
/// the drive applied by hand: `cargo run --release --example diaphragm_pressure`); with the
/// compartments fitted apart it is 76.2 %.
pub const HILL_QUIET_RIBS: f64 = 0.058;

/// The factor that carries the thesis-law drives' amplitudes to the passive-and-active law:
/// the quiet diaphragm's cited activation over the thesis-law quiet amplitude,
/// [`HILL_QUIET_DIAPHRAGM`] / 0.24. [`Drive::forced`]'s amplitudes times this factor are the
/// forced drive under that law (no EMG fraction of maximum was found for deep breathing short
/// of a maximal one); its tidal volume is then a check against deep breathing's 1.5-3 L.
pub const HILL_DRIVE_SCALE: f64 = HILL_QUIET_DIAPHRAGM / 0.24;

/// Allowed range of the drive frequency [Hz].
pub const FREQUENCY_RANGE: (f64, f64) = (0.05, 2.0);
/// Allowed range of a phase [rad].
pub const PHASE_RANGE: (f64, f64) = (-2.0 * PI, 2.0 * PI);

impl Drive {
    /// Quiet breathing: 15 breaths/min, the diaphragm fired slightly first (thesis Table 4.3:
    /// in 7 of 9 quiet breaths). The amplitudes are this model's: A_ribs 0.096 and
    /// A_diaphragm 0.24 give the default upright subject (75 kg) a 0.526 L tidal volume, the
    /// 7 mL/kg of quiet breathing (about 0.5 L, 12-16 breaths/min; e.g. West, Respiratory
    /// Physiology: The Essentials), with upper-chest skin moving a few millimetres and the
    /// skin near the umbilicus moving mostly ventrally, as measured on seated subjects (De
    /// Groote et al. 1997). Their ratio, 0.4, is the one the drive had when the lungs were
    /// read as 0.75 of the thorax; the lung now follows the thoracic volume one to one and
    /// both amplitudes were scaled by 0.8 to keep the breath quiet (`torso simulate
    /// --diaphragm-amplitude 0.24 --ribs-amplitude 0.096`). The thesis's own fitted upright
    /// quiet amplitudes (Table 4.3: A_ribs 0.12-0.25, A_diaphragm 0.13-0.31, ratio 0.64 on
    /// average) belong to its model and are, as it notes in 4.3.2, simulation-dependent.
    pub fn quiet() -> Self {
        Drive {
            enabled: true,
            frequency: 0.25,
            inspiratory_fraction: SINE_FRACTION,
            ribs: Wave {
                amplitude: 0.096,
                phase: 0.0,
            },
            diaphragm: Wave {
                amplitude: 0.24,
                phase: 0.1,
            },
            abdominals: Wave::default(),
        }
    }

    /// Forced (deep) breathing: 12 breaths/min, the rib cage fired slightly first (thesis
    /// Table 4.3: in 7 of 9 forced breaths), the abdominal muscles helping expiration, as in
    /// deep breathing. A_ribs 0.28, A_diaphragm 0.48 and A_abdominals 0.4 move the default
    /// subject's markers about three times as far as [`Drive::quiet`] (Kaneko & Horie 2012:
    /// about 3x for deep breathing) with a 1.71 L tidal volume (deep breathing 1.5-3 L). They
    /// are the amplitudes calibrated that way when the lungs were read as 0.75 of the thorax
    /// (0.35 / 0.6 / 0.5), scaled by the same 0.8 as the quiet drive (thesis Table 4.3,
    /// forced: A_ribs 0.12-0.38, A_diaphragm 0.23-0.51).
    pub fn forced() -> Self {
        Drive {
            enabled: true,
            frequency: 0.2,
            inspiratory_fraction: SINE_FRACTION,
            ribs: Wave {
                amplitude: 0.28,
                phase: 0.0,
            },
            diaphragm: Wave {
                amplitude: 0.48,
                phase: -0.1,
            },
            abdominals: Wave {
                amplitude: 0.4,
                phase: 0.0,
            },
        }
    }

    /// A named scenario: `quiet`, `forced` or `rest` (no drive), calibrated for the thesis's
    /// muscle law (the default; [`Drive::scenario_for`] for another law).
    pub fn scenario(name: &str) -> Result<Self> {
        match name {
            "quiet" => Ok(Self::quiet()),
            "forced" => Ok(Self::forced()),
            "rest" => Ok(Self::default()),
            _ => Err(Error::invalid("scenario", name, "quiet, forced or rest")),
        }
    }

    /// The named scenario for `law`: the thesis's amplitudes under its law; under the
    /// passive-and-active law the quiet drive of [`Drive::quiet_for`] and the others' amplitudes
    /// times [`HILL_DRIVE_SCALE`] (frequency, phases and inspiratory fraction unchanged).
    pub fn scenario_for(name: &str, law: MuscleLaw) -> Result<Self> {
        match (name, law) {
            ("quiet", _) => Ok(Self::quiet_for(law)),
            (_, MuscleLaw::Thesis) => Self::scenario(name),
            (_, MuscleLaw::Hill) => {
                let mut d = Self::scenario(name)?;
                for w in [&mut d.ribs, &mut d.diaphragm, &mut d.abdominals] {
                    w.amplitude *= HILL_DRIVE_SCALE;
                }
                Ok(d)
            }
        }
    }

    /// Quiet breathing for `law`: [`Drive::quiet`] under the thesis's law; under the
    /// passive-and-active law the same timing with the diaphragm and rib-cage families at
    /// their cited fractions of maximum ([`HILL_QUIET_DIAPHRAGM`], [`HILL_QUIET_RIBS`]).
    pub fn quiet_for(law: MuscleLaw) -> Self {
        let mut d = Self::quiet();
        if law == MuscleLaw::Hill {
            d.diaphragm.amplitude = HILL_QUIET_DIAPHRAGM;
            d.ribs.amplitude = HILL_QUIET_RIBS;
        }
        d
    }

    /// Checks every field; the error names the FMI parameter.
    pub fn validate(&self) -> Result<()> {
        check("drive.frequency", self.frequency, FREQUENCY_RANGE)?;
        check(
            "drive.inspiratory_fraction",
            self.inspiratory_fraction,
            INSPIRATORY_FRACTION_RANGE,
        )?;
        for (family, w) in [
            ("ribs", self.ribs),
            ("diaphragm", self.diaphragm),
            ("abdominals", self.abdominals),
        ] {
            check(
                &format!("drive.{family}.amplitude"),
                w.amplitude,
                (0.0, 1.0),
            )?;
            check(&format!("drive.{family}.phase"), w.phase, PHASE_RANGE)?;
        }
        Ok(())
    }

    /// Drive activation of `group` at time `t`: A w(u) for the family's wave (module doc),
    /// A (1 - w(u)) for the expiratory groups (internal intercostals, abdominal wall muscles);
    /// with the inspiratory fraction 1/2, A/2 (sin(2 pi f t + phi) + 1) and its antiphase
    /// (phi + pi) exactly as eq. 2.4; 0 when the drive is off, and 0 always for the
    /// sternocleidomastoids, which no breathing drive recruits.
    pub fn activation(&self, group: MuscleGroup, t: f64) -> f64 {
        let (wave, antiphase) = match group {
            // Accessory muscles: silent in quiet breathing in healthy people (Raper et al.
            // 1966, J Appl Physiol 21:497), moved by their activation input only.
            MuscleGroup::Sternocleidomastoids => return 0.0,
            MuscleGroup::ExternalIntercostals | MuscleGroup::Scalenes => (self.ribs, false),
            MuscleGroup::InternalIntercostals => (self.ribs, true),
            MuscleGroup::Diaphragm => (self.diaphragm, false),
            MuscleGroup::TransversusAbdominis
            | MuscleGroup::RectusAbdominis
            | MuscleGroup::ExternalObliques
            | MuscleGroup::InternalObliques => (self.abdominals, true),
        };
        if !self.enabled || wave.amplitude == 0.0 {
            return 0.0;
        }
        let theta = 2.0 * PI * self.frequency * t + wave.phase;
        if self.inspiratory_fraction == SINE_FRACTION {
            let shift = if antiphase { PI } else { 0.0 };
            return 0.5 * wave.amplitude * ((theta + shift).sin() + 1.0);
        }
        let w = waveform(self.cycle_phase(theta), self.inspiratory_fraction);
        wave.amplitude * if antiphase { 1.0 - w } else { w }
    }

    /// Cycle phase u in [0, 1) of a wave at angle `theta` = 2 pi f t + phi: 0 at the start of
    /// inspiration (where the sine of eq. 2.4 is at its minimum, theta = -pi/2 mod 2 pi).
    pub fn cycle_phase(&self, theta: f64) -> f64 {
        ((theta + 0.5 * PI) / (2.0 * PI)).rem_euclid(1.0)
    }
}

/// One breath of a [`Breaths`] schedule.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Breath {
    /// Time at which the breath starts [s]: the rib-cage family's inspiration onset.
    pub start: f64,
    /// Its period Ttot [s].
    pub period: f64,
    /// Its depth: every family's amplitude scale (1: the nominal drive's).
    pub depth: f64,
}

/// A schedule of consecutive breaths, each with its own period and depth, in increasing
/// start time; each breath ends where the next starts, the last one repeats with its period.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Breaths(pub Vec<Breath>);

impl Breaths {
    /// The breath running at time `t` and the cycle phase u in [0, 1) within it (u = 0 at its
    /// start); `None` before the first breath or for an empty schedule. After the last
    /// breath, the last breath repeats (u wraps).
    pub fn locate(&self, t: f64) -> Option<(usize, f64)> {
        let k = self.0.partition_point(|b| b.start <= t).checked_sub(1)?;
        let b = self.0[k];
        let u = ((t - b.start) / b.period).rem_euclid(1.0);
        Some((k, u))
    }

    /// The piecewise-constant drive of the schedule, `(start time, drive)` segments: `base`
    /// until the first breath, then per breath `base` with frequency 1 / period, every
    /// amplitude times the depth (at most 1), the rib-cage phase set so that its wave starts
    /// inspiration (u = 0) at the breath's start, and the other families keeping their
    /// phase offsets from the rib cage.
    pub fn schedule(&self, base: &Drive) -> Vec<(f64, Drive)> {
        let mut segments = vec![(0.0, *base)];
        for b in &self.0 {
            let fk = 1.0 / b.period;
            let mut d = *base;
            d.frequency = fk;
            d.ribs.phase = wrap(-PI / 2.0 - 2.0 * PI * fk * b.start);
            d.diaphragm.phase = wrap(d.ribs.phase + base.diaphragm.phase - base.ribs.phase);
            d.abdominals.phase = wrap(d.ribs.phase + base.abdominals.phase - base.ribs.phase);
            d.ribs.amplitude = (base.ribs.amplitude * b.depth).min(1.0);
            d.diaphragm.amplitude = (base.diaphragm.amplitude * b.depth).min(1.0);
            d.abdominals.amplitude = (base.abdominals.amplitude * b.depth).min(1.0);
            segments.push((b.start, d));
        }
        segments
    }
}

/// An angle wrapped to (-pi, pi].
fn wrap(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI { w + 2.0 * PI } else { w }
}

/// Range check with a message naming the variable.
pub(crate) fn check(name: &str, v: f64, (lo, hi): (f64, f64)) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(Error::invalid(name, v, format!("[{lo}, {hi}]")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each law's scenario: the thesis's amplitudes under its law; under the passive-and-active
    /// law the quiet drive at its cited fractions of maximum and the others scaled, the timing
    /// untouched; `rest` stays off.
    #[test]
    fn scenarios_follow_the_muscle_law() {
        for name in ["quiet", "forced", "rest"] {
            let base = Drive::scenario(name).unwrap();
            assert_eq!(Drive::scenario_for(name, MuscleLaw::Thesis).unwrap(), base);
            let hill = Drive::scenario_for(name, MuscleLaw::Hill).unwrap();
            assert_eq!(
                (hill.enabled, hill.frequency, hill.inspiratory_fraction),
                (base.enabled, base.frequency, base.inspiratory_fraction)
            );
            for (h, b) in [
                (hill.ribs, base.ribs),
                (hill.diaphragm, base.diaphragm),
                (hill.abdominals, base.abdominals),
            ] {
                assert_eq!(h.phase, b.phase);
                if name != "quiet" {
                    assert_eq!(h.amplitude, b.amplitude * HILL_DRIVE_SCALE);
                }
            }
        }
        // the quiet drive at the cited fractions of maximum, the abdominals silent
        let quiet = Drive::quiet_for(MuscleLaw::Hill);
        assert_eq!(
            [
                quiet.diaphragm.amplitude,
                quiet.ribs.amplitude,
                quiet.abdominals.amplitude
            ],
            [HILL_QUIET_DIAPHRAGM, HILL_QUIET_RIBS, 0.0]
        );
        assert_eq!(Drive::quiet_for(MuscleLaw::Thesis), Drive::quiet());
        // the scale carries the thesis quiet diaphragm to its cited fraction
        assert!(
            (HILL_DRIVE_SCALE * Drive::quiet().diaphragm.amplitude - HILL_QUIET_DIAPHRAGM).abs()
                < 1e-15
        );
        assert_eq!(
            Drive::quiet_for(MuscleLaw::Hill),
            Drive::scenario_for("quiet", MuscleLaw::Hill).unwrap()
        );
        assert!(Drive::scenario_for("deep", MuscleLaw::Hill).is_err());
    }

    /// At F = 1/2 the raised-cosine halves are the sine of eq. 2.4 (to rounding), and the
    /// drive evaluates that sine itself, bit for bit.
    #[test]
    fn half_fraction_is_the_sine() {
        let mut worst: f64 = 0.0;
        for k in 0..=4000 {
            let theta = -PI + 2.0 * PI * k as f64 / 4000.0;
            let d = Drive::default();
            let w = waveform(d.cycle_phase(theta), 0.5);
            worst = worst.max((w - 0.5 * (theta.sin() + 1.0)).abs());
        }
        assert!(worst <= 1e-15, "raised cosine against sine: {worst:e}");
        let d = Drive::forced();
        for k in 0..500 {
            let t = 0.037 * k as f64;
            for (g, wave, shift) in [
                (MuscleGroup::Diaphragm, d.diaphragm, 0.0),
                (MuscleGroup::InternalIntercostals, d.ribs, PI),
                (MuscleGroup::RectusAbdominis, d.abdominals, PI),
            ] {
                let sine = 0.5
                    * wave.amplitude
                    * ((2.0 * PI * d.frequency * t + wave.phase + shift).sin() + 1.0);
                assert_eq!(d.activation(g, t).to_bits(), sine.to_bits());
            }
        }
    }

    /// The waveform peaks at u = F with value 1, is 0 at u = 0, stays in [0, 1], and is C1:
    /// its one-sided slopes agree at both joins (both are 0).
    #[test]
    fn waveform_shape() {
        for f in [0.2, 0.38, 0.42, 0.5, 0.8] {
            assert_eq!(waveform(f, f), 1.0);
            assert_eq!(waveform(0.0, f), 0.0);
            let h = 1e-6;
            for join in [0.0, f] {
                let left = (waveform(join, f) - waveform(join - h, f)) / h;
                let right = (waveform(join + h, f) - waveform(join, f)) / h;
                assert!(left.abs() < 1e-4 && right.abs() < 1e-4, "F {f} join {join}");
            }
            let mut peak = (0.0, -1.0);
            for k in 0..10000 {
                let u = k as f64 / 10000.0;
                let w = waveform(u, f);
                assert!((0.0..=1.0).contains(&w));
                if w > peak.1 {
                    peak = (u, w);
                }
            }
            assert!((peak.0 - f).abs() <= 1e-4, "F {f}: peak at {}", peak.0);
        }
    }

    /// Expiratory groups take 1 - w; inspiration starts where the sine had its minimum.
    #[test]
    fn expiratory_groups_mirror_and_phase_keeps_its_meaning() {
        let mut d = Drive::forced();
        d.inspiratory_fraction = 0.4;
        d.ribs.phase = 0.0;
        let f = d.frequency;
        // theta = -pi/2 at t = 3/4 period: inspiration onset; peak 0.4 period later.
        let onset = 0.75 / f;
        let peak = onset + 0.4 / f;
        let a = d.ribs.amplitude;
        assert!(d.activation(MuscleGroup::ExternalIntercostals, onset).abs() < 1e-12);
        assert!((d.activation(MuscleGroup::ExternalIntercostals, peak) - a).abs() < 1e-12);
        for t in [0.3, 1.7, onset, peak] {
            let ext = d.activation(MuscleGroup::ExternalIntercostals, t);
            let int = d.activation(MuscleGroup::InternalIntercostals, t);
            assert!((ext + int - a).abs() < 1e-12);
        }
    }

    #[test]
    fn fraction_is_range_checked() {
        let mut d = Drive::quiet();
        d.inspiratory_fraction = 0.9;
        let e = d.validate().unwrap_err().to_string();
        assert!(e.contains("drive.inspiratory_fraction"), "{e}");
        d.inspiratory_fraction = f64::NAN;
        assert!(d.validate().is_err());
    }

    /// Time -> breath index -> cycle phase, and each breath's drive starts its rib-cage
    /// inspiration at the breath's start with the breath's period and depth.
    #[test]
    fn breaths_locate_and_schedule() {
        let mut base = Drive::forced();
        base.inspiratory_fraction = 0.4;
        let breaths = Breaths(vec![
            Breath {
                start: 2.0,
                period: 4.0,
                depth: 1.0,
            },
            Breath {
                start: 6.0,
                period: 5.0,
                depth: 1.2,
            },
        ]);
        assert_eq!(breaths.locate(1.0), None);
        assert_eq!(breaths.locate(3.0), Some((0, 0.25)));
        assert_eq!(breaths.locate(8.5), Some((1, 0.5)));
        let (k, u) = breaths.locate(12.0).unwrap();
        assert!(k == 1 && (u - 0.2).abs() < 1e-15, "{k} {u}");
        let segments = breaths.schedule(&base);
        assert_eq!(segments.len(), 3);
        for (k, b) in breaths.0.iter().enumerate() {
            let d = segments[k + 1].1;
            assert_eq!(segments[k + 1].0, b.start);
            assert!((d.frequency - 1.0 / b.period).abs() < 1e-15);
            let ext = MuscleGroup::ExternalIntercostals;
            let amp = base.ribs.amplitude * b.depth;
            assert!(d.activation(ext, b.start).abs() < 1e-12);
            let peak = b.start + 0.4 * b.period;
            assert!((d.activation(ext, peak) - amp).abs() < 1e-12);
            let offset = wrap(d.diaphragm.phase - d.ribs.phase);
            assert!((offset - wrap(base.diaphragm.phase - base.ribs.phase)).abs() < 1e-12);
        }
    }

    /// States saved before the field existed read as the sine.
    #[test]
    fn old_states_read_as_the_sine() {
        let mut v = serde_json::to_value(Drive::quiet()).unwrap();
        v.as_object_mut().unwrap().remove("inspiratory_fraction");
        let d: Drive = serde_json::from_value(v).unwrap();
        assert_eq!(d, Drive::quiet());
    }
}
