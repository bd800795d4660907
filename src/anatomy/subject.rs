//! The subject: who the model is personalised to.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Biological sex, which selects the anthropometric regressions and rib shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Sex {
    /// Male (FMI `subject.sex` = 0).
    #[default]
    Male,
    /// Female (FMI `subject.sex` = 1).
    Female,
}

impl Sex {
    /// The FMI code of this sex (0 male, 1 female).
    pub fn code(self) -> i32 {
        match self {
            Sex::Male => 0,
            Sex::Female => 1,
        }
    }
    /// Parses the FMI code (0 male, 1 female).
    pub fn from_code(code: i64) -> Result<Self> {
        match code {
            0 => Ok(Sex::Male),
            1 => Ok(Sex::Female),
            _ => Err(Error::invalid(
                "subject.sex",
                code,
                "0 (male) or 1 (female)",
            )),
        }
    }
}

/// Body posture: changes the direction of gravity and the abdominal compliance, not the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Posture {
    /// Standing upright (FMI `posture` = 0).
    #[default]
    Standing,
    /// Sitting upright (FMI `posture` = 1).
    Sitting,
    /// Lying on the back (FMI `posture` = 2).
    Supine,
}

impl Posture {
    /// The FMI code of this posture.
    pub fn code(self) -> i32 {
        match self {
            Posture::Standing => 0,
            Posture::Sitting => 1,
            Posture::Supine => 2,
        }
    }
    /// Parses the FMI code (0 standing, 1 sitting, 2 supine).
    pub fn from_code(code: i64) -> Result<Self> {
        match code {
            0 => Ok(Posture::Standing),
            1 => Ok(Posture::Sitting),
            2 => Ok(Posture::Supine),
            _ => Err(Error::invalid(
                "posture",
                code,
                "0 (standing), 1 (sitting) or 2 (supine)",
            )),
        }
    }
    /// Parses a name (`standing`, `sitting`, `supine`).
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "standing" => Ok(Posture::Standing),
            "sitting" => Ok(Posture::Sitting),
            "supine" | "lying" => Ok(Posture::Supine),
            _ => Err(Error::invalid(
                "posture",
                name,
                "standing, sitting or supine",
            )),
        }
    }
}

/// The person the model is built for. Defaults: male, 30 y, 1.75 m, 75 kg, standing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Subject {
    /// Biological sex.
    pub sex: Sex,
    /// Age [years], adult range 18-90.
    pub age: f64,
    /// Stature [m], 1.40-2.10.
    pub stature: f64,
    /// Body mass [kg], 40-160.
    pub mass: f64,
    /// Breast size, 0 (none) to 1 (large); used by the skin of female subjects.
    pub breast_size: f64,
    /// Posture.
    pub posture: Posture,
}

impl Default for Subject {
    fn default() -> Self {
        Subject {
            sex: Sex::Male,
            age: 30.0,
            stature: 1.75,
            mass: 75.0,
            breast_size: 0.0,
            posture: Posture::Standing,
        }
    }
}

/// Allowed ranges of the subject's numeric fields: (FMI name, min, max).
/// Numerical: the input domain the model accepts, not a property of a body.
pub const SUBJECT_RANGES: [(&str, f64, f64); 4] = [
    ("subject.age", 18.0, 90.0),
    ("subject.stature", 1.40, 2.10),
    ("subject.mass", 40.0, 160.0),
    ("subject.breast_size", 0.0, 1.0),
];

impl Subject {
    /// Checks every field against the adult ranges of [`SUBJECT_RANGES`] and a plausible body
    /// mass index (13-60 kg/m^2); the error names the field and its allowed range.
    pub fn validate(&self) -> Result<()> {
        let values = [self.age, self.stature, self.mass, self.breast_size];
        for ((name, lo, hi), v) in SUBJECT_RANGES.iter().zip(values) {
            if !v.is_finite() || v < *lo || v > *hi {
                return Err(Error::invalid(*name, v, format!("[{lo}, {hi}]")));
            }
        }
        let bmi = self.mass / (self.stature * self.stature);
        if !(13.0..=60.0).contains(&bmi) {
            return Err(Error::invalid(
                "subject.mass",
                self.mass,
                format!(
                    "a body mass index of 13-60 kg/m^2 at stature {} m (got {bmi:.1})",
                    self.stature
                ),
            ));
        }
        Ok(())
    }

    /// ECSC/ERS 1993 (Quanjer) functional residual capacity [L] for this subject.
    /// Source: Quanjer et al. 1993, Eur Respir J 6 Suppl 16:5-40 (ECSC/ERS): men
    /// 2.34 H + 0.009 A - 1.09, women 2.24 H + 0.001 A - 1.00 (agrees: copied).
    pub fn frc_ecsc(&self) -> f64 {
        let (h, a) = (self.stature, self.age);
        match self.sex {
            Sex::Male => 2.34 * h + 0.009 * a - 1.09,
            Sex::Female => 2.24 * h + 0.001 * a - 1.00,
        }
    }

    /// ECSC/ERS 1993 vital capacity [L].
    /// Source: Quanjer et al. 1993 (ECSC/ERS): men 6.10 H - 0.028 A - 4.65, women
    /// 4.66 H - 0.026 A - 3.28 (agrees: copied).
    pub fn vc_ecsc(&self) -> f64 {
        let (h, a) = (self.stature, self.age);
        match self.sex {
            Sex::Male => 6.10 * h - 0.028 * a - 4.65,
            Sex::Female => 4.66 * h - 0.026 * a - 3.28,
        }
    }

    /// ECSC/ERS 1993 residual volume [L] (Quanjer et al. 1993, Eur Respir J 6 Suppl 16:5-40,
    /// stature H in m, age A in years): men 1.31 H + 0.022 A - 1.23, women
    /// 1.81 H + 0.016 A - 2.00.
    /// Source: Quanjer et al. 1993 (ECSC/ERS), as above (agrees: copied).
    pub fn rv_ecsc(&self) -> f64 {
        let (h, a) = (self.stature, self.age);
        match self.sex {
            Sex::Male => 1.31 * h + 0.022 * a - 1.23,
            Sex::Female => 1.81 * h + 0.016 * a - 2.00,
        }
    }

    /// ECSC/ERS 1993 total lung capacity [L].
    /// Source: Quanjer et al. 1993 (ECSC/ERS): men 7.99 H - 7.08, women 6.60 H - 5.79 (agrees:
    /// copied).
    pub fn tlc_ecsc(&self) -> f64 {
        let h = self.stature;
        match self.sex {
            Sex::Male => 7.99 * h - 7.08,
            Sex::Female => 6.60 * h - 5.79,
        }
    }
}
