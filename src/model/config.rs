//! Configuration of a [`super::Torso`]: subject, scene, solver, drive and model constants.

use super::drive::{Drive, check};
use crate::anatomy::Subject;
use crate::solver::Method;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// What the scene contains and how finely it is resolved.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Level of detail 0, 1 or 2: abdominal surface of about 160 / 640 / 2,560 vertices and
    /// muscle element counts scaled by 1/4, 1/2 and 1 of the thesis's. Default 1.
    pub level_of_detail: u32,
    /// Marker grid rows (1-16, default 10).
    pub grid_rows: usize,
    /// Marker grid columns (1-16, default 6).
    pub grid_cols: usize,
    /// SLP recording whose first frame registers the marker grid; `None`: default grid.
    pub slp_reference: Option<PathBuf>,
}

impl Default for Scene {
    fn default() -> Self {
        Scene {
            level_of_detail: 1,
            grid_rows: 10,
            grid_cols: 6,
            slp_reference: None,
        }
    }
}

/// Integration settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverConfig {
    /// Method (default Dormand-Prince 5(4)).
    pub method: Method,
    /// Relative tolerance, in [1e-12, 1e-2] (default 1e-6).
    pub rtol: f64,
    /// Absolute tolerance on the state (m, rad, m/s, rad/s), in [1e-14, 1e-2] (default 1e-8).
    pub atol: f64,
    /// Largest internal step [s], in [1e-5, 1] (default 0.05).
    pub max_step: f64,
    /// Whether the methods step past the times the model is advanced to and read the state
    /// there from the step's continuous extension (default; the stiff method's restarts
    /// still end on the time), or end a step on each of them (`false`: every communication
    /// point costs at least one step). See [`crate::solver::Integrator::integrate_ahead`].
    #[serde(default = "step_past_outputs_default")]
    pub step_past_outputs: bool,
}

fn step_past_outputs_default() -> bool {
    true
}

impl Default for SolverConfig {
    fn default() -> Self {
        SolverConfig {
            method: Method::Dopri5,
            rtol: 1e-6,
            atol: 1e-8,
            max_step: 0.05,
            step_past_outputs: true,
        }
    }
}

/// Everything needed to build a [`super::Torso`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// The subject.
    pub subject: Subject,
    /// Scene contents and resolution.
    pub scene: Scene,
    /// Integrator settings.
    pub solver: SolverConfig,
    /// Sinusoidal drive (tunable while running).
    pub drive: Drive,
    /// Lung volume as a fraction of the thoracic cavity volume at rest (thesis 4.2: 0.75), in
    /// [0.3, 1]; the rest of the cavity (heart, great vessels, mediastinum) keeps its volume
    /// over a breath, so thoracic volume changes are lung volume changes one to one.
    pub lung_ratio: f64,
    /// Activation gain of the subject's left side, in [0, 2] (1: healthy).
    pub gain_left: f64,
    /// Activation gain of the subject's right side, in [0, 2].
    pub gain_right: f64,
    /// Activation gain of each muscle group on each side, on top of `gain_left` and
    /// `gain_right` (FMI `gain.<group>.left|right`, in [0, 2]; 1 healthy): 0 on the left
    /// diaphragm paralyses the left hemidiaphragm. Configurations written before it existed
    /// read all ones.
    #[serde(default)]
    pub group_gains: GroupGains,
    /// A subject mesh directory written by `torso mesh prepare` (FMI `subject.mesh_dir`): its
    /// `skin.obj` replaces the generated skin and its `abdomen.obj`, when present, the
    /// generated abdominal cavity (see [`crate::anatomy::prepared`]); `None`: generated
    /// geometry.
    #[serde(default)]
    pub subject_mesh_dir: Option<PathBuf>,
    /// Constants of the dynamics overriding the posture's defaults
    /// ([`crate::dynamics::Params::for_posture`]), for studies of stiff scenes (stiffer
    /// cartilage, a higher bulk modulus) and of sensitivity; `None`: the defaults.
    #[serde(default)]
    pub params: Option<crate::dynamics::Params>,
    /// The muscle law (FMI `muscle_law`, [`crate::dynamics::muscle::MuscleLaw`]) of the
    /// posture's defaults ([`crate::dynamics::Params::for_posture_and_law`]) when `params` is
    /// `None`; `params` carries its own. Configurations written before it existed read the
    /// thesis's law.
    #[serde(default)]
    pub muscle_law: crate::dynamics::muscle::MuscleLaw,
    /// Gravitational acceleration [m/s^2] (FMI `gravity`, [`crate::dynamics::Params::gravity`])
    /// of the posture's defaults when `params` is `None`; `params` carries its own.
    /// Configurations written before it existed read [`crate::dynamics::GRAVITY`].
    #[serde(default = "default_gravity")]
    pub gravity: f64,
    /// How gravity loads the model (FMI `gravity_loads`, [`crate::dynamics::GravityLoads`])
    /// when `params` is `None`; `params` carries its own. Configurations written before it
    /// existed read the preloaded model.
    #[serde(default)]
    pub gravity_loads: crate::dynamics::GravityLoads,
    /// Whether the posture's tonic muscle activity is applied (FMI `postural_tone`): `true`
    /// (the default), the abdominal wall's tone of the posture and muscle law
    /// ([`crate::dynamics::abdominal_tone`], [`crate::dynamics::STANDING_ABDOMINAL_TONE`]
    /// standing under the passive-and-active law); `false`, none, a relaxed subject as in a
    /// relaxation manoeuvre (Rahn et al. 1946), whose respiratory-system compliance is the
    /// passive one. Used when `params` is `None`; `params` carries its own tone.
    /// Configurations written before it existed read `true`.
    #[serde(default = "default_postural_tone")]
    pub postural_tone: bool,
}

fn default_gravity() -> f64 {
    crate::dynamics::GRAVITY
}

fn default_postural_tone() -> bool {
    true
}

/// The code of a `postural_tone` setting (FMI `postural_tone`, `BtConfig.postural_tone`): 1
/// on, 0 off.
pub fn postural_tone_code(on: bool) -> i32 {
    i32::from(on)
}

/// The `postural_tone` setting of code `code`; the error names `postural_tone` and the codes.
pub fn postural_tone_from_code(code: i64) -> Result<bool> {
    match code {
        0 => Ok(false),
        1 => Ok(true),
        other => Err(Error::invalid("postural_tone", other, "0 off or 1 on")),
    }
}

/// The `postural_tone` setting named `name` (`on` or `off`).
pub fn parse_postural_tone(name: &str) -> Result<bool> {
    match name {
        "on" => Ok(true),
        "off" => Ok(false),
        other => Err(Error::invalid("postural_tone", other, "on or off")),
    }
}

impl Default for Config {
    fn default() -> Self {
        Config {
            subject: Subject::default(),
            scene: Scene::default(),
            solver: SolverConfig::default(),
            drive: Drive::default(),
            lung_ratio: crate::dynamics::REST_LUNG_FRACTION,
            gain_left: 1.0,
            gain_right: 1.0,
            group_gains: GroupGains::default(),
            subject_mesh_dir: None,
            params: None,
            muscle_law: crate::dynamics::muscle::MuscleLaw::Thesis,
            gravity: crate::dynamics::GRAVITY,
            gravity_loads: crate::dynamics::GravityLoads::Preloaded,
            postural_tone: true,
        }
    }
}

impl Config {
    /// Checks every field; the error names the FMI variable and its allowed range.
    pub fn validate(&self) -> Result<()> {
        self.subject.validate()?;
        self.drive.validate()?;
        if self.scene.level_of_detail > 2 {
            return Err(Error::invalid(
                "scene.level_of_detail",
                self.scene.level_of_detail,
                "0, 1 or 2",
            ));
        }
        for (name, v) in [
            ("grid.rows", self.scene.grid_rows),
            ("grid.cols", self.scene.grid_cols),
        ] {
            if !(1..=16).contains(&v) {
                return Err(Error::invalid(name, v, "1..16"));
            }
        }
        check("solver.rtol", self.solver.rtol, (1e-12, 1e-2))?;
        check("solver.atol", self.solver.atol, (1e-14, 1e-2))?;
        check("solver.max_step", self.solver.max_step, (1e-5, 1.0))?;
        check("lung.ratio", self.lung_ratio, (0.3, 1.0))?;
        check("gravity", self.gravity, (0.0, crate::dynamics::GRAVITY_MAX))?;
        check("gain.left", self.gain_left, (0.0, 2.0))?;
        check("gain.right", self.gain_right, (0.0, 2.0))?;
        for g in crate::anatomy::MuscleGroup::ALL {
            for (side, gains) in [
                ("right", &self.group_gains.right),
                ("left", &self.group_gains.left),
            ] {
                let name = format!("gain.{}.{side}", g.name());
                check(&name, gains[g.index()], (0.0, 2.0))?;
            }
        }
        if let Some(dir) = &self.subject_mesh_dir {
            crate::anatomy::prepared::check_dir(dir)?;
        }
        if let Some(p) = &self.params {
            p.validate()?;
        }
        Ok(())
    }
}

/// Activation gains per muscle group (in [`crate::anatomy::MuscleGroup::ALL`] order) and
/// side, each in [0, 2], multiplying the side's overall gain: a paralysed group has 0 on its
/// side, a healthy one 1.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GroupGains {
    /// Gains of the subject's right side.
    pub right: [f64; crate::anatomy::MuscleGroup::COUNT],
    /// Gains of the subject's left side.
    pub left: [f64; crate::anatomy::MuscleGroup::COUNT],
}

impl Default for GroupGains {
    fn default() -> Self {
        GroupGains {
            right: [1.0; crate::anatomy::MuscleGroup::COUNT],
            left: [1.0; crate::anatomy::MuscleGroup::COUNT],
        }
    }
}
