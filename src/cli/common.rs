//! Options shared by several subcommands: the subject, the solver and the drive, the names
//! of their flags in errors, the marker grid option, and where output folders may be created.

use crate::anatomy::{Posture, Sex, Subject};
use crate::model::{Config, Drive};
use crate::solver::Method;
use crate::{Error, Result};
use clap::Args;
use std::path::{Component, Path};

/// The level of detail when `--lod` is not given.
pub const DEFAULT_LOD: u32 = 1;

/// Who the model is built for, and the level of detail it is built at.
#[derive(Args, Debug, Clone)]
pub struct SubjectArgs {
    /// Sex: male or female.
    #[arg(long, default_value = "male")]
    pub sex: String,
    /// Age [years].
    #[arg(long, default_value_t = 30.0)]
    pub age: f64,
    /// Stature [m] [default: 1.75; `torso fit`: estimated from the recording when neither
    /// --stature nor --mass is given].
    #[arg(long)]
    pub stature: Option<f64>,
    /// Body mass [kg] [default: 75; `torso fit`: estimated from the recording when neither
    /// --stature nor --mass is given].
    #[arg(long)]
    pub mass: Option<f64>,
    /// Breast size, 0-1.
    #[arg(long, default_value_t = 0.0)]
    pub breast_size: f64,
    /// Posture: standing, sitting or supine.
    #[arg(long, default_value = "standing")]
    pub posture: String,
    /// Level of detail 0, 1 or 2 [default: 1; `torso fit`: the recording's, when it names
    /// one].
    #[arg(long)]
    pub lod: Option<u32>,
    /// Muscle law: thesis (the seed thesis's shortening linear spring) or hill (passive and
    /// active parts, the passive wall fitted to the adult chest wall's compliance).
    #[arg(long, default_value = "thesis")]
    pub muscle_law: String,
    /// Gravitational acceleration [m/s^2], 0 (weightless) to 3 x 9.81.
    #[arg(long, default_value_t = crate::dynamics::GRAVITY)]
    pub gravity: f64,
    /// How gravity loads the model: preloaded (preloads cancel it at each posture's rest, the
    /// posture effects from tables) or acting (the abdominal contents' hydrostatic pressure,
    /// the rest found under the loads).
    #[arg(long, default_value = "preloaded")]
    pub gravity_loads: String,
    /// The posture's tonic muscle activity: on (standing under the hill law the abdominal
    /// wall's tone, 0.017 of the maximal force, Cholewicki et al. 1997) or off (a relaxed
    /// subject, as in a relaxation manoeuvre).
    #[arg(long, default_value = "on")]
    pub postural_tone: String,
}

impl SubjectArgs {
    /// Whether the subject's size was given (`--stature` or `--mass`).
    pub fn size_given(&self) -> bool {
        self.stature.is_some() || self.mass.is_some()
    }

    /// The subject described by the options; an error names the flag.
    pub fn subject(&self) -> Result<Subject> {
        let sex = match self.sex.as_str() {
            "male" | "m" | "M" => Sex::Male,
            "female" | "f" | "F" => Sex::Female,
            other => return Err(Error::invalid("--sex", other, "male or female")),
        };
        let s = Subject {
            sex,
            age: self.age,
            stature: self.stature.unwrap_or(Subject::default().stature),
            mass: self.mass.unwrap_or(Subject::default().mass),
            breast_size: self.breast_size,
            posture: Posture::from_name(&self.posture).map_err(flag_error)?,
        };
        s.validate().map_err(flag_error)?;
        Ok(s)
    }

    /// A configuration for this subject with `drive` and the solver of `solver`; an error
    /// names the flag.
    pub fn config(&self, solver: &SolverArgs, drive: Drive) -> Result<Config> {
        let mut c = Config {
            subject: self.subject()?,
            drive,
            ..Config::default()
        };
        c.scene.level_of_detail = self.lod.unwrap_or(DEFAULT_LOD);
        c.solver.method = Method::from_name(&solver.solver).ok_or_else(|| {
            Error::invalid(
                "--solver",
                &solver.solver,
                "dopri5, bs3, high-order, rosenbrock or quasi-static",
            )
        })?;
        c.solver.rtol = solver.rtol;
        c.muscle_law = self.law()?;
        c.gravity = self.gravity;
        c.gravity_loads =
            crate::dynamics::GravityLoads::parse(&self.gravity_loads).map_err(|_| {
                Error::invalid(
                    "--gravity-loads",
                    &self.gravity_loads,
                    "preloaded or acting",
                )
            })?;
        c.postural_tone = crate::model::parse_postural_tone(&self.postural_tone)
            .map_err(|_| Error::invalid("--postural-tone", &self.postural_tone, "on or off"))?;
        c.validate().map_err(flag_error)?;
        Ok(c)
    }

    /// The muscle law named by `--muscle-law`.
    pub fn law(&self) -> Result<crate::dynamics::muscle::MuscleLaw> {
        crate::dynamics::muscle::MuscleLaw::parse(&self.muscle_law)
            .map_err(|_| Error::invalid("--muscle-law", &self.muscle_law, "thesis or hill"))
    }
}

/// The ODE solver of a run (FMI `solver.method`, `solver.rtol`). The option is `--solver` in
/// every subcommand; `simulate` and `render-skin` also take their former `--method`
/// (hidden, see [`MethodAlias`]). `fit` and `fit-sweep` keep `--method` for the search method.
#[derive(Args, Debug, Clone)]
pub struct SolverArgs {
    /// ODE solver: dopri5, bs3, high-order, rosenbrock (stiff scenes) or quasi-static (the chest
    /// wall in equilibrium at every instant, the lung volume the only state).
    #[arg(long, default_value = "dopri5")]
    pub solver: String,
    /// Relative tolerance of the ODE solver.
    #[arg(long, default_value_t = 1e-6)]
    pub rtol: f64,
}

/// The former name of `--solver` in `simulate` and `render-skin`, kept hidden so that old
/// scripts still run.
#[derive(Args, Debug, Clone)]
pub struct MethodAlias {
    /// Former name of --solver.
    #[arg(long = "method", hide = true, conflicts_with = "solver")]
    pub method: Option<String>,
}

impl SolverArgs {
    /// These options with `--solver` replaced by the former `--method` when that was given.
    pub fn with_alias(&self, alias: &MethodAlias) -> SolverArgs {
        SolverArgs {
            solver: alias.method.clone().unwrap_or_else(|| self.solver.clone()),
            rtol: self.rtol,
        }
    }
}

/// The command-line flag standing for a model or FMI parameter name (`subject.stature` ->
/// `--stature`), for the parameters the shared options set; `None` for others.
pub fn flag_for(name: &str) -> Option<&'static str> {
    Some(match name {
        "subject.sex" => "--sex",
        "subject.age" => "--age",
        "subject.stature" => "--stature",
        "subject.mass" => "--mass",
        "subject.breast_size" => "--breast-size",
        "posture" | "subject.posture" => "--posture",
        "scene.level_of_detail" => "--lod",
        "grid.rows" | "grid.cols" => "--grid",
        "solver.method" => "--solver",
        "muscle_law" => "--muscle-law",
        "gravity" => "--gravity",
        "gravity_loads" => "--gravity-loads",
        "postural_tone" => "--postural-tone",
        "solver.rtol" => "--rtol",
        "scenario" => "--scenario",
        "drive.frequency" => "--frequency",
        "drive.inspiratory_fraction" => "--ti-ttot",
        "drive.ribs.amplitude" => "--ribs-amplitude",
        "drive.ribs.phase" => "--ribs-phase",
        "drive.diaphragm.amplitude" => "--diaphragm-amplitude",
        "drive.diaphragm.phase" => "--diaphragm-phase",
        "drive.abdominals.amplitude" => "--abdominals-amplitude",
        "drive.abdominals.phase" => "--abdominals-phase",
        _ => return None,
    })
}

/// `e` with the parameter it names replaced by the flag the user typed (see [`flag_for`]).
pub fn flag_error(e: Error) -> Error {
    match e {
        Error::InvalidParameter { name, value, range } => Error::InvalidParameter {
            name: flag_for(&name).map_or(name, String::from),
            value,
            range,
        },
        other => other,
    }
}

/// Parses a marker grid `ROWSxCOLS` given as `flag` (1..16 each, as the FMU's and the C
/// ABI's `grid.rows` and `grid.cols`).
pub fn parse_grid_flag(flag: &str, s: &str) -> Result<(usize, usize)> {
    crate::recording::parse_grid(s).ok_or_else(|| {
        Error::invalid(
            flag,
            s,
            format!(
                "ROWSxCOLS with 1..{} each, e.g. 10x6",
                crate::recording::MAX_GRID_SIDE
            ),
        )
    })
}

/// Makes sure the folder of the output file `path` exists. A missing folder is created only
/// when it lies below the working directory (a relative path without `..`, or an absolute one
/// under the working directory); anywhere else the error asks the user to create it, so that
/// a mistyped absolute path does not leave folders at the filesystem root.
pub fn prepare_output_file(path: &Path) -> Result<()> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => {
            if !below_working_directory(dir) {
                return Err(missing_folder(dir));
            }
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
        }
        _ => Ok(()),
    }
}

/// Makes sure the output folder `dir` exists: it is created when its parent exists (as
/// `mkdir` would), with any missing parents only below the working directory (see
/// [`prepare_output_file`]).
pub fn prepare_output_dir(dir: &Path) -> Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    if below_working_directory(dir) {
        return std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e));
    }
    match dir.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(parent) if parent.is_dir() => std::fs::create_dir(dir).map_err(|e| Error::io(dir, e)),
        Some(parent) => Err(missing_folder(parent)),
        None => Err(missing_folder(dir)),
    }
}

/// Whether `dir` lies below the working directory: relative without `..`, or absolute under
/// the (canonical) working directory.
fn below_working_directory(dir: &Path) -> bool {
    if dir.components().any(|c| matches!(c, Component::ParentDir)) {
        return false;
    }
    dir.is_relative()
        || std::env::current_dir()
            .ok()
            .and_then(|cwd| std::fs::canonicalize(cwd).ok())
            .is_some_and(|cwd| dir.starts_with(&cwd) && dir != cwd)
}

/// The error for an output folder that is missing and outside the working directory.
fn missing_folder(dir: &Path) -> Error {
    Error::State(format!(
        "output folder {} does not exist; create it first (torso creates missing folders \
         only below the working directory)",
        dir.display()
    ))
}

/// The built-in drive: a named scenario, with optional overrides (thesis eq. 2.4; with
/// `--ti-ttot`, the raised-cosine wave of docs/drive.md).
#[derive(Args, Debug, Clone)]
pub struct DriveArgs {
    /// Scenario: quiet, forced or rest.
    #[arg(long, default_value = "quiet")]
    pub scenario: String,
    /// Breathing frequency [Hz].
    #[arg(long)]
    pub frequency: Option<f64>,
    /// Inspiratory fraction Ti/Ttot of the drive (0.2-0.8; 0.5, the default, is the sine of
    /// thesis eq. 2.4).
    #[arg(long, allow_hyphen_values = true)]
    pub ti_ttot: Option<f64>,
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
    /// The drive described by the options: the scenario for the muscle `law`
    /// ([`Drive::scenario_for`]), then each amplitude, phase or rate given, as given.
    pub fn drive(&self, law: crate::dynamics::muscle::MuscleLaw) -> Result<Drive> {
        let mut d = Drive::scenario_for(&self.scenario, law).map_err(flag_error)?;
        if let Some(v) = self.frequency {
            d.frequency = v;
        }
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut d.inspiratory_fraction, self.ti_ttot);
        set(&mut d.ribs.amplitude, self.ribs_amplitude);
        set(&mut d.ribs.phase, self.ribs_phase);
        set(&mut d.diaphragm.amplitude, self.diaphragm_amplitude);
        set(&mut d.diaphragm.phase, self.diaphragm_phase);
        set(&mut d.abdominals.amplitude, self.abdominals_amplitude);
        set(&mut d.abdominals.phase, self.abdominals_phase);
        d.validate().map_err(flag_error)?;
        Ok(d)
    }
}
