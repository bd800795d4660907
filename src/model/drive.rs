//! The built-in sinusoidal drive (thesis eq. 2.4), so that a fit can run on parameters alone.
//!
//! Thesis eq. 2.4 modulates each element's rest-length ratio as
//! r(t) = alpha - beta/2 (sin(2 pi f t + phi) + 1). Here the same wave is expressed as an
//! activation a(t) = A/2 (sin(2 pi f t + phi) + 1) in [0, A], with A the fraction of the
//! maximal reachable activation (the thesis's A_ribs, A_diaphragm, Table 4.3); the element
//! then contracts as r = 1 - beta_max g a (see `dynamics`). The applied activation of a
//! group is clamp(input + drive, 0, 1).

use crate::anatomy::MuscleGroup;
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
/// internal intercostals are driven in antiphase, thesis 2.4.1), diaphragm, abdominals (the
/// four abdominal wall muscles, in antiphase with inspiration: they help expiration).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Drive {
    /// Whether the drive runs (FMI `drive.enabled`); off, the muscles follow the activation
    /// inputs alone whatever the amplitudes. Saved states without the field had it on.
    #[serde(default = "drive_on")]
    pub enabled: bool,
    /// Breathing frequency f_b [Hz], in [0.05, 2].
    pub frequency: f64,
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

/// No drive: every amplitude 0 (the `rest` scenario).
impl Default for Drive {
    fn default() -> Self {
        Drive {
            enabled: true,
            frequency: 0.25,
            ribs: Wave::default(),
            diaphragm: Wave::default(),
            abdominals: Wave::default(),
        }
    }
}

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

    /// A named scenario: `quiet`, `forced` or `rest` (no drive).
    pub fn scenario(name: &str) -> Result<Self> {
        match name {
            "quiet" => Ok(Self::quiet()),
            "forced" => Ok(Self::forced()),
            "rest" => Ok(Self::default()),
            _ => Err(Error::invalid("scenario", name, "quiet, forced or rest")),
        }
    }

    /// Checks every field; the error names the FMI parameter.
    pub fn validate(&self) -> Result<()> {
        check("drive.frequency", self.frequency, FREQUENCY_RANGE)?;
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

    /// Drive activation of `group` at time `t`: A/2 (sin(2 pi f t + phi) + 1) for the family's
    /// wave, in antiphase (phi + pi) for the expiratory groups (internal intercostals,
    /// abdominal wall muscles); 0 when the drive is off.
    pub fn activation(&self, group: MuscleGroup, t: f64) -> f64 {
        let (wave, antiphase) = match group {
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
        let shift = if antiphase { PI } else { 0.0 };
        0.5 * wave.amplitude * ((2.0 * PI * self.frequency * t + wave.phase + shift).sin() + 1.0)
    }
}

/// Range check with a message naming the variable.
pub(crate) fn check(name: &str, v: f64, (lo, hi): (f64, f64)) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(Error::invalid(name, v, format!("[{lo}, {hi}]")))
    }
}
