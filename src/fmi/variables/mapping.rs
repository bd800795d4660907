//! What a variable maps to in the model: the configuration fields exposed as parameters
//! ([`Parameter`], read from and written to a [`Config`] as a [`Value`]), the drive's families
//! ([`Family`]), the inputs ([`Input`], applied to and read from a [`Torso`]) and the
//! configuration the parameters' start values come from ([`start_config`]).

use crate::anatomy::{MuscleGroup, Side};
use crate::model::{Config, Torso, Wave};
use crate::solver::Method;
use crate::{Error, Result};
use std::path::PathBuf;

/// A family of the built-in drive (thesis eq. 2.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Rib-cage muscles.
    Ribs,
    /// Diaphragm.
    Diaphragm,
    /// Abdominal wall muscles.
    Abdominals,
}

impl Family {
    /// All families, in table order.
    pub const ALL: [Family; 3] = [Family::Ribs, Family::Diaphragm, Family::Abdominals];

    /// Name used in `drive.<family>.*`.
    pub fn name(self) -> &'static str {
        match self {
            Family::Ribs => "ribs",
            Family::Diaphragm => "diaphragm",
            Family::Abdominals => "abdominals",
        }
    }

    fn wave(self, config: &Config) -> Wave {
        match self {
            Family::Ribs => config.drive.ribs,
            Family::Diaphragm => config.drive.diaphragm,
            Family::Abdominals => config.drive.abdominals,
        }
    }

    fn wave_mut(self, config: &mut Config) -> &mut Wave {
        match self {
            Family::Ribs => &mut config.drive.ribs,
            Family::Diaphragm => &mut config.drive.diaphragm,
            Family::Abdominals => &mut config.drive.abdominals,
        }
    }
}

/// A configuration field exposed as an FMI parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// `subject.sex` (Integer: 0 male, 1 female).
    Sex,
    /// `subject.age` [y].
    Age,
    /// `subject.stature` [m].
    Stature,
    /// `subject.mass` [kg].
    Mass,
    /// `subject.breast_size` [0-1].
    BreastSize,
    /// `posture` (Integer: 0 standing, 1 sitting, 2 supine).
    Posture,
    /// `drive.enabled` (Boolean): the built-in drive runs.
    DriveEnabled,
    /// `drive.frequency` [Hz].
    DriveFrequency,
    /// `drive.inspiratory_fraction`: Ti/Ttot of every family's wave.
    DriveInspiratoryFraction,
    /// `drive.<family>.amplitude`.
    DriveAmplitude(Family),
    /// `drive.<family>.phase` [rad].
    DrivePhase(Family),
    /// `lung.ratio`.
    LungRatio,
    /// `gain.left`.
    GainLeft,
    /// `gain.right`.
    GainRight,
    /// `gain.<group>.left|right`: one group's gain on one side.
    GroupGain(MuscleGroup, Side),
    /// `scene.level_of_detail` (Integer).
    LevelOfDetail,
    /// `grid.rows` (Integer).
    GridRows,
    /// `grid.cols` (Integer).
    GridCols,
    /// `slp.reference` (String).
    SlpReference,
    /// `subject.mesh_dir` (String): a prepared subject mesh directory.
    MeshDir,
    /// `solver.method` (Integer).
    SolverMethod,
    /// `muscle_law` (Integer: 0 thesis, 1 hill).
    MuscleLaw,
    /// `gravity` [m/s^2].
    Gravity,
    /// `gravity_loads` (Integer: 0 preloaded, 1 acting).
    GravityLoads,
    /// `postural_tone` (Integer: 0 off, 1 on).
    PosturalTone,
    /// `solver.rtol`.
    SolverRtol,
    /// `solver.atol`.
    SolverAtol,
    /// `solver.max_step` [s].
    SolverMaxStep,
}

/// A value of any FMI type, as read from or written to a [`Config`].
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// Real.
    Real(f64),
    /// Integer.
    Integer(i32),
    /// Boolean.
    Boolean(bool),
    /// String.
    String(String),
}

impl Parameter {
    /// Whether the parameter may change between communication steps (the drive).
    pub fn is_tunable(self) -> bool {
        matches!(
            self,
            Parameter::DriveEnabled
                | Parameter::DriveFrequency
                | Parameter::DriveInspiratoryFraction
                | Parameter::DriveAmplitude(_)
                | Parameter::DrivePhase(_)
        )
    }

    /// Reads the parameter's value from `config`.
    pub fn get(self, config: &Config) -> Value {
        use Parameter::*;
        let s = &config.subject;
        match self {
            Sex => Value::Integer(s.sex.code()),
            Age => Value::Real(s.age),
            Stature => Value::Real(s.stature),
            Mass => Value::Real(s.mass),
            BreastSize => Value::Real(s.breast_size),
            Posture => Value::Integer(s.posture.code()),
            DriveEnabled => Value::Boolean(config.drive.enabled),
            DriveFrequency => Value::Real(config.drive.frequency),
            DriveInspiratoryFraction => Value::Real(config.drive.inspiratory_fraction),
            DriveAmplitude(f) => Value::Real(f.wave(config).amplitude),
            DrivePhase(f) => Value::Real(f.wave(config).phase),
            LungRatio => Value::Real(config.lung_ratio),
            GainLeft => Value::Real(config.gain_left),
            GainRight => Value::Real(config.gain_right),
            GroupGain(g, side) => Value::Real(match side {
                Side::Right => config.group_gains.right[g.index()],
                Side::Left => config.group_gains.left[g.index()],
            }),
            LevelOfDetail => Value::Integer(config.scene.level_of_detail as i32),
            GridRows => Value::Integer(config.scene.grid_rows as i32),
            GridCols => Value::Integer(config.scene.grid_cols as i32),
            SlpReference => Value::String(
                config
                    .scene
                    .slp_reference
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default(),
            ),
            MeshDir => Value::String(
                config
                    .subject_mesh_dir
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default(),
            ),
            SolverMethod => Value::Integer(config.solver.method.code()),
            MuscleLaw => Value::Integer(config.muscle_law.code()),
            Gravity => Value::Real(config.gravity),
            GravityLoads => Value::Integer(config.gravity_loads.code()),
            PosturalTone => Value::Integer(crate::model::postural_tone_code(config.postural_tone)),
            SolverRtol => Value::Real(config.solver.rtol),
            SolverAtol => Value::Real(config.solver.atol),
            SolverMaxStep => Value::Real(config.solver.max_step),
        }
    }

    /// Writes `value` into `config`. The caller has range-checked it against the table
    /// ([`Variable::check`](super::Variable::check)); codes are converted through the facade's parsers, whose errors
    /// name the variable.
    pub fn set(self, config: &mut Config, value: Value) -> Result<()> {
        use Parameter::*;
        let s = &mut config.subject;
        match (self, value) {
            (Sex, Value::Integer(v)) => s.sex = crate::anatomy::Sex::from_code(v.into())?,
            (Age, Value::Real(v)) => s.age = v,
            (Stature, Value::Real(v)) => s.stature = v,
            (Mass, Value::Real(v)) => s.mass = v,
            (BreastSize, Value::Real(v)) => s.breast_size = v,
            (Posture, Value::Integer(v)) => {
                s.posture = crate::anatomy::Posture::from_code(v.into())?
            }
            (DriveEnabled, Value::Boolean(v)) => config.drive.enabled = v,
            (DriveFrequency, Value::Real(v)) => config.drive.frequency = v,
            (DriveInspiratoryFraction, Value::Real(v)) => config.drive.inspiratory_fraction = v,
            (DriveAmplitude(f), Value::Real(v)) => f.wave_mut(config).amplitude = v,
            (DrivePhase(f), Value::Real(v)) => f.wave_mut(config).phase = v,
            (LungRatio, Value::Real(v)) => config.lung_ratio = v,
            (GainLeft, Value::Real(v)) => config.gain_left = v,
            (GainRight, Value::Real(v)) => config.gain_right = v,
            (GroupGain(g, side), Value::Real(v)) => match side {
                Side::Right => config.group_gains.right[g.index()] = v,
                Side::Left => config.group_gains.left[g.index()] = v,
            },
            (LevelOfDetail, Value::Integer(v)) => {
                config.scene.level_of_detail = non_negative(v)? as u32
            }
            (GridRows, Value::Integer(v)) => config.scene.grid_rows = non_negative(v)?,
            (GridCols, Value::Integer(v)) => config.scene.grid_cols = non_negative(v)?,
            (SlpReference, Value::String(v)) => {
                config.scene.slp_reference = if v.is_empty() {
                    None
                } else {
                    Some(PathBuf::from(v))
                }
            }
            (MeshDir, Value::String(v)) => {
                config.subject_mesh_dir = if v.is_empty() {
                    None
                } else {
                    // Read and checked now, so that a bad directory is refused when set.
                    crate::anatomy::SubjectMesh::load(&v)?;
                    Some(PathBuf::from(v))
                }
            }
            (SolverMethod, Value::Integer(v)) => {
                config.solver.method = Method::from_code(v.into()).ok_or_else(|| {
                    Error::invalid("solver.method", v, format!("0..{}", Method::ALL.len() - 1))
                })?
            }
            (MuscleLaw, Value::Integer(v)) => {
                config.muscle_law = crate::dynamics::muscle::MuscleLaw::from_code(v.into())?
            }
            (Gravity, Value::Real(v)) => config.gravity = v,
            (GravityLoads, Value::Integer(v)) => {
                config.gravity_loads = crate::dynamics::GravityLoads::from_code(v.into())?
            }
            (PosturalTone, Value::Integer(v)) => {
                config.postural_tone = crate::model::postural_tone_from_code(v.into())?
            }
            (SolverRtol, Value::Real(v)) => config.solver.rtol = v,
            (SolverAtol, Value::Real(v)) => config.solver.atol = v,
            (SolverMaxStep, Value::Real(v)) => config.solver.max_step = v,
            (p, v) => return Err(Error::State(format!("parameter {p:?} cannot take {v:?}"))),
        }
        Ok(())
    }
}

fn non_negative(v: i32) -> Result<usize> {
    usize::try_from(v).map_err(|_| Error::State(format!("negative value {v}")))
}

/// An input of the model: a muscle group's activation, the pressure at the airway opening or
/// the airway's occlusion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// The activation input of a muscle group, in [0, 1].
    Activation(MuscleGroup),
    /// The pressure at the airway opening relative to the body surface [Pa].
    AirwayOpening,
    /// The airway occluded at the mouth (a Boolean held as 1.0 true, 0.0 false).
    AirwayOccluded,
}

impl Input {
    /// Number of inputs.
    pub const COUNT: usize = MuscleGroup::COUNT + 2;

    /// Every input, in value-reference order: the thesis's eight activations (in
    /// [`MuscleGroup::ALL`] order), the airway opening, the occlusion, then the activations
    /// added after them (the sternocleidomastoids).
    pub fn all() -> [Input; Input::COUNT] {
        let mut all = [Input::AirwayOpening; Input::COUNT];
        for g in MuscleGroup::ALL {
            all[Input::Activation(g).index()] = Input::Activation(g);
        }
        all[Input::AirwayOccluded.index()] = Input::AirwayOccluded;
        all
    }

    /// Position in [`Input::all`] (value-reference order).
    pub fn index(self) -> usize {
        match self {
            Input::Activation(g) if g.index() < 8 => g.index(),
            Input::Activation(g) => g.index() + 2,
            Input::AirwayOpening => 8,
            Input::AirwayOccluded => 9,
        }
    }

    /// The input's value reference.
    pub fn vr(self) -> u32 {
        match self {
            Input::Activation(g) => super::activation_vr(g),
            Input::AirwayOpening => super::VR_AIRWAY_OPENING,
            Input::AirwayOccluded => super::VR_AIRWAY_OCCLUDED,
        }
    }

    /// Applies `value` to `torso` (range-checked there; a rejected value changes nothing).
    /// The occlusion takes 0 (open) or 1 (occluded).
    pub fn apply(self, torso: &mut Torso, value: f64) -> Result<()> {
        match self {
            Input::Activation(g) => torso.set_activation(g, value),
            Input::AirwayOpening => torso.set_airway_opening(value),
            Input::AirwayOccluded => match value {
                0.0 => torso.set_airway_occluded(false),
                1.0 => torso.set_airway_occluded(true),
                v => Err(crate::Error::invalid(
                    "airway.occluded",
                    v,
                    "0 (open) or 1 (occluded)",
                )),
            },
        }
    }

    /// The value `torso` holds (the occlusion as 1.0 or 0.0).
    pub fn value(self, torso: &Torso) -> f64 {
        match self {
            Input::Activation(g) => torso.activation_input(g),
            Input::AirwayOpening => torso.airway_opening(),
            Input::AirwayOccluded => f64::from(u8::from(torso.airway_occluded())),
        }
    }
}

/// The configuration an instance starts from, whose values are the parameters' start
/// values: the default subject (male, 30 y, 1.75 m, 75 kg, standing, level of detail 1)
/// breathing the quiet scenario ([`crate::model::Drive::quiet`]), as `torso simulate` does;
/// `drive.enabled = false` turns the built-in drive off for input-driven use.
pub fn start_config() -> Config {
    Config {
        drive: crate::model::Drive::quiet(),
        ..Config::default()
    }
}
