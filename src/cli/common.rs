//! Options shared by several subcommands: the subject, the scene and the drive.

use crate::anatomy::{Posture, Sex, Subject};
use crate::model::{Config, Drive};
use crate::solver::Method;
use crate::{Error, Result};
use clap::Args;

/// Who the model is built for.
#[derive(Args, Debug, Clone)]
pub struct SubjectArgs {
    /// Sex: male or female.
    #[arg(long, default_value = "male")]
    pub sex: String,
    /// Age [years].
    #[arg(long, default_value_t = 30.0)]
    pub age: f64,
    /// Stature [m].
    #[arg(long, default_value_t = 1.75)]
    pub stature: f64,
    /// Body mass [kg].
    #[arg(long, default_value_t = 75.0)]
    pub mass: f64,
    /// Breast size, 0-1.
    #[arg(long, default_value_t = 0.0)]
    pub breast_size: f64,
    /// Posture: standing, sitting or supine.
    #[arg(long, default_value = "standing")]
    pub posture: String,
    /// Level of detail 0, 1 or 2.
    #[arg(long, default_value_t = 1)]
    pub lod: u32,
    /// Solver method: dopri5, bs3, high-order or rosenbrock (stiff scenes).
    #[arg(long, default_value = "dopri5")]
    pub method: String,
    /// Relative tolerance.
    #[arg(long, default_value_t = 1e-6)]
    pub rtol: f64,
}

impl SubjectArgs {
    /// The subject described by the options.
    pub fn subject(&self) -> Result<Subject> {
        let sex = match self.sex.as_str() {
            "male" | "m" | "M" => Sex::Male,
            "female" | "f" | "F" => Sex::Female,
            other => return Err(Error::invalid("--sex", other, "male or female")),
        };
        let s = Subject {
            sex,
            age: self.age,
            stature: self.stature,
            mass: self.mass,
            breast_size: self.breast_size,
            posture: Posture::from_name(&self.posture)?,
        };
        s.validate()?;
        Ok(s)
    }

    /// A configuration for this subject with `drive`.
    pub fn config(&self, drive: Drive) -> Result<Config> {
        let mut c = Config {
            subject: self.subject()?,
            drive,
            ..Config::default()
        };
        c.scene.level_of_detail = self.lod;
        c.solver.method = Method::from_name(&self.method).ok_or_else(|| {
            Error::invalid(
                "--method",
                &self.method,
                "dopri5, bs3, high-order or rosenbrock",
            )
        })?;
        c.solver.rtol = self.rtol;
        c.validate()?;
        Ok(c)
    }
}

/// The sinusoidal drive: a named scenario, with optional overrides (thesis eq. 2.4).
#[derive(Args, Debug, Clone)]
pub struct DriveArgs {
    /// Scenario: quiet, forced or rest.
    #[arg(long, default_value = "quiet")]
    pub scenario: String,
    /// Breathing frequency [Hz].
    #[arg(long)]
    pub frequency: Option<f64>,
    /// Rib-cage amplitude (0-1).
    #[arg(long)]
    pub ribs_amplitude: Option<f64>,
    /// Rib-cage phase [rad].
    #[arg(long, allow_hyphen_values = true)]
    pub ribs_phase: Option<f64>,
    /// Diaphragm amplitude (0-1).
    #[arg(long)]
    pub diaphragm_amplitude: Option<f64>,
    /// Diaphragm phase [rad].
    #[arg(long, allow_hyphen_values = true)]
    pub diaphragm_phase: Option<f64>,
    /// Abdominal muscles amplitude (0-1).
    #[arg(long)]
    pub abdominals_amplitude: Option<f64>,
    /// Abdominal muscles phase [rad].
    #[arg(long, allow_hyphen_values = true)]
    pub abdominals_phase: Option<f64>,
}

impl DriveArgs {
    /// The drive described by the options.
    pub fn drive(&self) -> Result<Drive> {
        let mut d = Drive::scenario(&self.scenario)?;
        if let Some(v) = self.frequency {
            d.frequency = v;
        }
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut d.ribs.amplitude, self.ribs_amplitude);
        set(&mut d.ribs.phase, self.ribs_phase);
        set(&mut d.diaphragm.amplitude, self.diaphragm_amplitude);
        set(&mut d.diaphragm.phase, self.diaphragm_phase);
        set(&mut d.abdominals.amplitude, self.abdominals_amplitude);
        set(&mut d.abdominals.phase, self.abdominals_phase);
        d.validate()?;
        Ok(d)
    }
}
