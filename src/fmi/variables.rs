//! The one table of every FMI variable of the BreathingTorso FMU: name, value reference, type,
//! causality, variability, initial, unit, range, start value, description and the model
//! quantity or configuration field it maps to.
//!
//! Everything else is generated from this table: `modelDescription.xml` (and the FMU's copy),
//! `documentation/index.html`, the value-reference constants of `include/breathing_torso.h`,
//! the range checks of `fmi2SetReal`/`fmi2SetInteger`, and the GUID (a hash of the interface
//! part of the table, so that it changes exactly when the interface changes).
//!
//! Value references are unique across types and grouped: 0 time, 1-8 activation inputs, 9 the
//! airway-opening pressure input, 100-199 Real parameters, 200-299 Integer parameters, 300 the String parameter, 1000-1099
//! Real outputs, 2000-2767 markers (`2000 + 3 (i - 1) + axis`; the generic FMU's 60 use
//! 2000-2179), 3000-3002 Integer outputs.
//!
//! Ranges: the table's min/max are what the FMI layer checks first (and what masters see);
//! [`crate::Config::validate`] stays the final check. A test checks that both agree at every
//! bound.

use crate::anatomy::skin::MarkerSet;
use crate::anatomy::{MuscleGroup, SUBJECT_RANGES, Side};
use crate::model::{Config, Quantity, Torso, Wave};
use crate::solver::Method;
use crate::{Error, Result};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// The FMU's model identifier (name of the shared library and of the `.fmu`).
pub const MODEL_IDENTIFIER: &str = "BreathingTorso";
/// Number of marker outputs of the generic FMU (`marker[1]` .. `marker[60]`): the markers of
/// the default SLP grid, 10 rows x 6 columns (the model's default `grid_rows` x `grid_cols`,
/// the grid of the thesis's SLP recordings). A grid with more markers is refused by the generic
/// FMU; a personalised FMU ([`Table::personalised`]) has its own grid's or marker set's
/// markers, up to [`MAX_MARKER_OUTPUTS`].
pub const MARKER_SLOTS: u16 = 60;
/// Most marker outputs an FMU can have (the largest grid, 16 x 16, and any marker set):
/// value references 2000-2767.
pub const MAX_MARKER_OUTPUTS: u16 = crate::observe::markers::MAX_MARKERS as u16;
/// Value reference of `time`.
pub const VR_TIME: u32 = 0;
/// First value reference of the activation inputs (in [`MuscleGroup::ALL`] order).
pub const VR_ACTIVATION: u32 = 1;
/// Value reference of `pressure.airway_opening`, the input after the activations.
pub const VR_AIRWAY_OPENING: u32 = 9;
/// Value reference of `marker[1].x`; `marker[i].<axis>` is `VR_MARKER + 3 (i - 1) + axis`.
pub const VR_MARKER: u32 = 2000;

/// FMI base type of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ScalarType {
    /// `fmi2Real`.
    Real,
    /// `fmi2Integer`.
    Integer,
    /// `fmi2Boolean`.
    Boolean,
    /// `fmi2String`.
    String,
}

/// FMI causality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// The independent variable (time).
    Independent,
    /// A parameter.
    Parameter,
    /// An input.
    Input,
    /// An output.
    Output,
}

/// FMI variability.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    /// Set before initialization only.
    Fixed,
    /// May change between communication steps.
    Tunable,
    /// Discrete in time (changes only at communication points).
    Discrete,
    /// Continuous in time.
    Continuous,
}

/// FMI `initial` attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    /// The start value is used as is.
    Exact,
    /// Computed by the model during initialization (no start value).
    Calculated,
}

/// A start value.
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// No start value (independent and calculated variables).
    None,
    /// A Real start value.
    Real(f64),
    /// An Integer start value.
    Integer(i32),
    /// A Boolean start value.
    Boolean(bool),
    /// A String start value.
    String(String),
}

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
            SolverRtol => Value::Real(config.solver.rtol),
            SolverAtol => Value::Real(config.solver.atol),
            SolverMaxStep => Value::Real(config.solver.max_step),
        }
    }

    /// Writes `value` into `config`. The caller has range-checked it against the table
    /// ([`Variable::check`]); codes are converted through the facade's parsers, whose errors
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

/// An input of the model: a muscle group's activation or the pressure at the airway opening.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// The activation input of a muscle group, in [0, 1].
    Activation(MuscleGroup),
    /// The pressure at the airway opening relative to the body surface [Pa].
    AirwayOpening,
}

impl Input {
    /// Number of inputs.
    pub const COUNT: usize = 9;

    /// Every input, in value-reference order (the activations in [`MuscleGroup::ALL`] order,
    /// then the airway opening).
    pub fn all() -> [Input; Input::COUNT] {
        let mut all = [Input::AirwayOpening; Input::COUNT];
        for (slot, g) in all.iter_mut().zip(MuscleGroup::ALL) {
            *slot = Input::Activation(g);
        }
        all
    }

    /// Position in [`Input::all`].
    pub fn index(self) -> usize {
        match self {
            Input::Activation(g) => g.index(),
            Input::AirwayOpening => Input::COUNT - 1,
        }
    }

    /// Applies `value` to `torso` (range-checked there; a rejected value changes nothing).
    pub fn apply(self, torso: &mut Torso, value: f64) -> Result<()> {
        match self {
            Input::Activation(g) => torso.set_activation(g, value),
            Input::AirwayOpening => torso.set_airway_opening(value),
        }
    }

    /// The value `torso` holds.
    pub fn value(self, torso: &Torso) -> f64 {
        match self {
            Input::Activation(g) => torso.activation_input(g),
            Input::AirwayOpening => torso.airway_opening(),
        }
    }
}

/// What a variable stands for in the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Role {
    /// Simulated time.
    Time,
    /// An input.
    Input(Input),
    /// A configuration field.
    Parameter(Parameter),
    /// A quantity read off the model.
    Output(Quantity),
}

/// One FMI scalar variable.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    /// Structured name, e.g. `volume.lung`, `marker[12].x`.
    pub name: String,
    /// Value reference (unique across types in this model).
    pub vr: u32,
    /// Base type.
    pub ty: ScalarType,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// `initial` attribute, where one is written.
    pub initial: Option<Initial>,
    /// Unit (declared in [`UNITS`]).
    pub unit: Option<&'static str>,
    /// Preferred display unit (declared in [`UNITS`]).
    pub display_unit: Option<&'static str>,
    /// Smallest allowed value (Real and Integer).
    pub min: Option<f64>,
    /// Largest allowed value (Real and Integer).
    pub max: Option<f64>,
    /// Start value.
    pub start: Start,
    /// Description.
    pub description: String,
    /// What the variable maps to.
    pub role: Role,
    /// For outputs, the inputs (value references, ascending) the output depends on directly:
    /// those whose new value changes the output at the same communication point, without a
    /// step. Empty for an output read off the model's state, which every output but two is
    /// (activations act on the state through the dynamics, not on the outputs); the alveolar
    /// and pleural pressures depend on the airway-opening pressure at once (measured by
    /// `python/tests/test_fmu_structure.py` and `tests/fmi_structure.rs`). `None` for the
    /// other causalities. Written as the `dependencies` of `<ModelStructure>`.
    pub input_dependencies: Option<Vec<u32>>,
}

impl Variable {
    /// Checks a value against the variable's range: finite and within [min, max]. The error
    /// names the variable and the range.
    pub fn check(&self, v: f64) -> Result<()> {
        let lo = self.min.unwrap_or(f64::NEG_INFINITY);
        let hi = self.max.unwrap_or(f64::INFINITY);
        if v.is_finite() && v >= lo && v <= hi {
            return Ok(());
        }
        let range = match (self.min, self.max) {
            (Some(a), Some(b)) => format!("[{a}, {b}]"),
            (Some(a), None) => format!(">= {a}"),
            (None, Some(b)) => format!("<= {b}"),
            (None, None) => "finite".to_string(),
        };
        Err(Error::invalid(&self.name, v, range))
    }
}

/// A unit declared in `<UnitDefinitions>`: SI base-unit exponents, factor to the base unit,
/// and display units (name, factor: display = factor x value).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    /// Unit name as used in `unit=`.
    pub name: &'static str,
    /// SI exponents as (attribute, exponent), e.g. `("m", 3)`.
    pub base: &'static [(&'static str, i32)],
    /// value in base units = factor x value in this unit.
    pub factor: f64,
    /// Display units: (name, factor).
    pub display: &'static [(&'static str, f64)],
}

/// Pascal per cmH2O (conventional: 1 cmH2O = 98.0665 Pa).
pub const PA_PER_CMH2O: f64 = 98.0665;
/// Seconds per (Julian) year.
pub const SECONDS_PER_YEAR: f64 = 31_557_600.0;

/// Every unit used by the table.
pub const UNITS: &[Unit] = &[
    Unit {
        name: "s",
        base: &[("s", 1)],
        factor: 1.0,
        display: &[],
    },
    Unit {
        name: "L",
        base: &[("m", 3)],
        factor: 0.001,
        display: &[],
    },
    Unit {
        name: "m",
        base: &[("m", 1)],
        factor: 1.0,
        display: &[("mm", 1000.0)],
    },
    Unit {
        name: "Pa",
        base: &[("kg", 1), ("m", -1), ("s", -2)],
        factor: 1.0,
        display: &[("cmH2O", 1.0 / PA_PER_CMH2O)],
    },
    Unit {
        name: "L/s",
        base: &[("m", 3), ("s", -1)],
        factor: 0.001,
        display: &[],
    },
    Unit {
        name: "Hz",
        base: &[("s", -1)],
        factor: 1.0,
        display: &[],
    },
    Unit {
        name: "rad",
        base: &[("rad", 1)],
        factor: 1.0,
        display: &[],
    },
    Unit {
        name: "kg",
        base: &[("kg", 1)],
        factor: 1.0,
        display: &[],
    },
    Unit {
        name: "y",
        base: &[("s", 1)],
        factor: SECONDS_PER_YEAR,
        display: &[],
    },
];

/// Log categories declared in `<LogCategories>` and honoured by `fmi2SetDebugLogging`.
pub const LOG_CATEGORIES: &[(&str, &str)] = &[
    ("logEvents", "State changes and informational messages"),
    ("logStatusWarning", "Messages with status fmi2Warning"),
    (
        "logStatusDiscard",
        "Messages with status fmi2Discard (numerical failures)",
    ),
    (
        "logStatusError",
        "Messages with status fmi2Error (on unless switched off)",
    ),
    (
        "logStatusFatal",
        "Messages with status fmi2Fatal (on unless switched off)",
    ),
    (
        "logCalls",
        "Every call of an FMI function, with its arguments",
    ),
];

/// The table and its indexes.
#[derive(Debug)]
pub struct Table {
    variables: Vec<Variable>,
    /// Position in `variables` of each value reference, indexed by the reference itself
    /// (`u32::MAX`: none). The references are a few thousand at most, and `fmi2GetReal` of
    /// the 60 markers looks up 184 of them per communication step: a direct index costs a
    /// load where a hash map's lookup cost some 40 ns.
    by_vr: Vec<u32>,
    by_name: HashMap<String, usize>,
    guid: String,
    personalisation: Option<Personalisation>,
}

impl Table {
    /// All variables, in `<ModelVariables>` order.
    pub fn variables(&self) -> &[Variable] {
        &self.variables
    }

    /// The variable with value reference `vr`.
    pub fn by_vr(&self, vr: u32) -> Option<&Variable> {
        self.position(vr).map(|i| &self.variables[i])
    }

    fn position(&self, vr: u32) -> Option<usize> {
        match self.by_vr.get(vr as usize) {
            Some(&i) if i != u32::MAX => Some(i as usize),
            _ => None,
        }
    }

    /// The variable called `name`.
    pub fn by_name(&self, name: &str) -> Option<&Variable> {
        self.by_name.get(name).map(|&i| &self.variables[i])
    }

    /// 1-based index of a variable in `<ModelVariables>`.
    pub fn index_of(&self, vr: u32) -> Option<usize> {
        self.position(vr).map(|i| i + 1)
    }

    /// The GUID: `{...}` formatted 128-bit FNV-1a hash of the interface.
    pub fn guid(&self) -> &str {
        &self.guid
    }
}

impl Table {
    /// Indexes `variables`; the GUID hashes their interface and `extra` (empty for the
    /// generic table).
    fn indexed(
        variables: Vec<Variable>,
        extra: &str,
        personalisation: Option<Personalisation>,
    ) -> Table {
        let size = variables
            .iter()
            .map(|v| v.vr as usize + 1)
            .max()
            .unwrap_or(0);
        let mut by_vr = vec![u32::MAX; size];
        for (i, v) in variables.iter().enumerate() {
            by_vr[v.vr as usize] = i as u32;
        }
        let by_name = variables
            .iter()
            .enumerate()
            .map(|(i, v)| (v.name.clone(), i))
            .collect();
        let text = interface_text(&variables) + extra;
        let guid = format_guid(fnv1a_128(text.as_bytes()));
        Table {
            variables,
            by_vr,
            by_name,
            guid,
            personalisation,
        }
    }

    /// The table of a personalised FMU: the generic table with `p`'s start values (each
    /// checked against its variable's type and range), `grid.rows` and `grid.cols` fixed at
    /// their start values (min = max), and as outputs the markers of the subject's marker set:
    /// with no named set, that grid's `rows x cols` markers `marker[i].x|y|z`, numbered as in
    /// the generic FMU; with a named set ([`Personalisation::markers`]), its markers in its
    /// order, named by their labels (`marker.<label>.x|y|z`, see [`marker_label_name`]), at
    /// the same value references as the grid's. Its GUID differs from the generic one and
    /// follows the set's labels and bindings. An error names the variable that cannot take
    /// its value, or the set that cannot be an FMU's.
    pub fn personalised(p: &Personalisation) -> Result<Table> {
        let markers = match &p.markers {
            None => None,
            Some(set) => {
                if set.len() > usize::from(MAX_MARKER_OUTPUTS) {
                    return Err(Error::invalid(
                        format!("marker set `{}`", set.name),
                        format!("{} markers", set.len()),
                        format!(
                            "at most {MAX_MARKER_OUTPUTS} markers (the FMU's marker value references)"
                        ),
                    ));
                }
                if set.is_empty() {
                    return Err(Error::invalid(
                        format!("marker set `{}`", set.name),
                        "no marker",
                        "at least one marker",
                    ));
                }
                Some(set)
            }
        };
        let mut variables = build(&MarkerOutputs::Grid(0));
        for (name, value) in &p.starts {
            let var = variables
                .iter_mut()
                .find(|v| &v.name == name)
                .ok_or_else(|| Error::invalid("parameter name", name, "a parameter of the FMU"))?;
            if !matches!(var.role, Role::Parameter(_)) {
                return Err(Error::invalid(
                    name,
                    format!("{value:?}"),
                    "a value for a parameter only (this variable is not one)",
                ));
            }
            let numeric = match value {
                Value::Real(x) => Some(*x),
                Value::Integer(i) => Some(f64::from(*i)),
                _ => None,
            };
            if let Some(x) = numeric {
                var.check(x)?;
            }
            var.start = match (var.ty, value) {
                (ScalarType::Real, Value::Real(x)) => Start::Real(*x),
                (ScalarType::Integer, Value::Integer(i)) => Start::Integer(*i),
                (ScalarType::Boolean, Value::Boolean(b)) => Start::Boolean(*b),
                (ScalarType::String, Value::String(s)) => Start::String(s.clone()),
                (ty, v) => {
                    return Err(Error::invalid(
                        name,
                        format!("{v:?}"),
                        format!("a {ty:?} value"),
                    ));
                }
            };
        }
        let grid = |name: &str, variables: &mut [Variable]| -> usize {
            let v = variables.iter_mut().find(|v| v.name == name);
            match v {
                Some(v) => {
                    let n = match v.start {
                        Start::Integer(n) => n.max(0),
                        _ => 0,
                    };
                    v.min = Some(f64::from(n));
                    v.max = Some(f64::from(n));
                    n as usize
                }
                None => 0,
            }
        };
        let rows = grid("grid.rows", &mut variables);
        let cols = grid("grid.cols", &mut variables);
        let (outputs, extra) = match markers {
            // The grid's range (1-16 each) keeps rows x cols within MAX_MARKER_OUTPUTS.
            None => (
                MarkerOutputs::Grid((rows * cols).min(usize::from(MAX_MARKER_OUTPUTS)) as u16),
                format!("personalised|{rows}x{cols}\n"),
            ),
            Some(set) => {
                let mut extra = format!("personalised|{rows}x{cols}|set|{}\n", set.name);
                for (label, b) in set.labels.iter().zip(&set.bindings) {
                    use std::fmt::Write;
                    let _ = writeln!(
                        extra,
                        "{label}|{}|{:?}|{:?}|{:?}",
                        b.triangle, b.barycentric[0], b.barycentric[1], b.barycentric[2]
                    );
                }
                (MarkerOutputs::Named(set), extra)
            }
        };
        let mut markers = marker_rows(&outputs);
        let at = variables
            .iter()
            .position(|v| v.name == "solver.steps")
            .unwrap_or(variables.len());
        variables.splice(at..at, markers.drain(..));
        Ok(Table::indexed(variables, &extra, Some(p.clone())))
    }

    /// The named marker set whose markers are this table's marker outputs (`None`: the grid's).
    pub fn marker_set(&self) -> Option<&Arc<MarkerSet>> {
        self.personalisation
            .as_ref()
            .and_then(|p| p.markers.as_ref())
    }

    /// Number of marker outputs (`marker[i]` or `marker.<label>`, three scalars each).
    pub fn marker_outputs(&self) -> usize {
        self.variables
            .iter()
            .filter(|v| matches!(v.role, Role::Output(Quantity::Marker { axis: 0, .. })))
            .count()
    }

    /// The personalisation this table was made with (`None`: the generic table).
    pub fn personalisation(&self) -> Option<&Personalisation> {
        self.personalisation.as_ref()
    }

    /// The configuration the table's start values describe: [`start_config`] with the
    /// personalisation's values set (`resolve` turns a String parameter's value into the
    /// path the instance uses, e.g. a path relative to the FMU's `resources/`). An error
    /// names the parameter.
    pub fn start_config_with(
        &self,
        resolve: &mut dyn FnMut(Parameter, &str) -> Result<String>,
    ) -> Result<Config> {
        let mut config = start_config();
        if let Some(p) = &self.personalisation {
            for (name, value) in &p.starts {
                let Some(Variable {
                    role: Role::Parameter(par),
                    ..
                }) = self.by_name(name)
                else {
                    continue;
                };
                let value = match value {
                    Value::String(s) if !s.is_empty() => Value::String(resolve(*par, s)?),
                    v => v.clone(),
                };
                par.set(&mut config, value)
                    .map_err(|e| Error::State(format!("`{name}`: {e}")))?;
            }
        }
        Ok(config)
    }
}

/// A subject baked into an FMU ([`Table::personalised`]): parameters with the start values
/// that replace the generic ones, in the order given, and the subject's marker set when it
/// is not the grid.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Personalisation {
    /// (FMI parameter name, start value).
    pub starts: Vec<(String, Value)>,
    /// A named marker set (labels and bindings on the rest skin) whose markers are the FMU's
    /// marker outputs instead of the grid's; `None`: the grid.
    pub markers: Option<Arc<MarkerSet>>,
}

/// The table (built once; immutable and shared by every instance and thread).
pub fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(|| Table::indexed(build(&MarkerOutputs::Grid(MARKER_SLOTS)), "", None))
}

/// The table of a personalisation, built once per distinct personalisation and kept for
/// the life of the process (an FMU's instances share it, as they share [`table`]).
pub fn personalised_table(p: &Personalisation) -> Result<&'static Table> {
    static TABLES: OnceLock<Mutex<Vec<&'static Table>>> = OnceLock::new();
    let tables = TABLES.get_or_init(|| Mutex::new(Vec::new()));
    let mut tables = tables.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(t) = tables
        .iter()
        .find(|t| t.personalisation.as_ref() == Some(p))
    {
        return Ok(t);
    }
    let t: &'static Table = Box::leak(Box::new(Table::personalised(p)?));
    tables.push(t);
    Ok(t)
}

/// Value reference of `marker[index + 1].<axis>` (index 0-based, axis 0 = x, 1 = y, 2 = z).
pub fn marker_vr(index: u16, axis: u8) -> u32 {
    VR_MARKER + 3 * u32::from(index) + u32::from(axis)
}

const AXES: [&str; 3] = ["x", "y", "z"];

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

/// Which markers a table has as outputs.
#[derive(Clone, Copy, Debug)]
enum MarkerOutputs<'a> {
    /// The first `n` markers of the grid, `marker[1]` .. `marker[n]`, row-major.
    Grid(u16),
    /// A named marker set's markers in its order, `marker.<label>`.
    Named(&'a MarkerSet),
}

/// The structured FMI name of a marker set's label: the label itself when it is an FMI
/// identifier (a letter or `_`, then letters, digits and `_`), otherwise quoted (`'...'`, with
/// `\` and `'` escaped), as the structured naming convention's q-names are (FMI 2.0
/// standard, section 2.2.9).
pub fn marker_label_name(label: &str) -> String {
    let plain = label
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && label.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if plain {
        label.to_string()
    } else {
        let escaped = label.replace('\\', "\\\\").replace('\'', "\\'");
        format!("'{escaped}'")
    }
}

/// The marker outputs' rows: `marker[<i>].<axis>` of the grid, `marker.<label>.<axis>` of a
/// named set, value references `2000 + 3 i + axis` (i 0-based) in both cases.
fn marker_rows(markers: &MarkerOutputs) -> Vec<Variable> {
    let count = match *markers {
        MarkerOutputs::Grid(n) => n,
        MarkerOutputs::Named(set) => set.len() as u16,
    };
    // (name stem, description) of marker `index`.
    let name = |index: u16| match *markers {
        MarkerOutputs::Grid(_) => (
            format!("marker[{}]", index + 1),
            format!(
                "Marker {} of the grid (row-major from the top row, column 1 on the subject's right; reads 0 when {} > grid.rows x grid.cols)",
                index + 1,
                index + 1
            ),
        ),
        MarkerOutputs::Named(set) => {
            let label = &set.labels[usize::from(index)];
            (
                format!("marker.{}", marker_label_name(label)),
                format!(
                    "Marker `{label}` of the subject's marker set `{}` (bound to the skin at barycentric coordinates of a skin triangle)",
                    set.name
                ),
            )
        }
    };
    let mut rows = Vec::with_capacity(3 * usize::from(count));
    for index in 0..count {
        let (stem, what) = name(index);
        for (axis, a) in AXES.iter().enumerate() {
            let axis = axis as u8;
            let row = Row::new(
                format!("{stem}.{a}"),
                marker_vr(index, axis),
                ScalarType::Real,
                Role::Output(Quantity::Marker { index, axis }),
                format!("{what}, {a} coordinate"),
            )
            .output(Variability::Continuous)
            .unit("m")
            .display("mm");
            rows.push(row.0);
        }
    }
    rows
}

/// A compact builder for table rows.
struct Row(Variable);

impl Row {
    fn new(
        name: impl Into<String>,
        vr: u32,
        ty: ScalarType,
        role: Role,
        description: impl Into<String>,
    ) -> Row {
        Row(Variable {
            name: name.into(),
            vr,
            ty,
            causality: Causality::Output,
            variability: Variability::Continuous,
            initial: None,
            unit: None,
            display_unit: None,
            min: None,
            max: None,
            start: Start::None,
            description: description.into(),
            role,
            input_dependencies: None,
        })
    }
    fn unit(mut self, unit: &'static str) -> Row {
        self.0.unit = Some(unit);
        self
    }
    fn display(mut self, unit: &'static str) -> Row {
        self.0.display_unit = Some(unit);
        self
    }
    fn range(mut self, lo: f64, hi: f64) -> Row {
        self.0.min = Some(lo);
        self.0.max = Some(hi);
        self
    }
    /// The range the anatomy declares for this subject field ([`SUBJECT_RANGES`]).
    fn subject_range(self) -> Row {
        match SUBJECT_RANGES.iter().find(|r| r.0 == self.0.name) {
            Some(&(_, lo, hi)) => self.range(lo, hi),
            None => self,
        }
    }
    fn output(mut self, variability: Variability) -> Row {
        self.0.causality = Causality::Output;
        self.0.variability = variability;
        self.0.initial = Some(Initial::Calculated);
        // Read off the state: no direct feedthrough from any input.
        self.0.input_dependencies = Some(Vec::new());
        self
    }
    /// An output that the inputs `vrs` reach at once, without a step (direct feedthrough).
    fn depends_on(mut self, vrs: &[u32]) -> Row {
        self.0.input_dependencies = Some(vrs.to_vec());
        self
    }
    /// A parameter whose start value is read from the default configuration.
    fn parameter(mut self, defaults: &Config) -> Row {
        let Role::Parameter(p) = self.0.role else {
            unreachable!("parameter rows carry a parameter role")
        };
        self.0.causality = Causality::Parameter;
        self.0.variability = if p.is_tunable() {
            Variability::Tunable
        } else {
            Variability::Fixed
        };
        self.0.initial = Some(Initial::Exact);
        self.0.start = match p.get(defaults) {
            Value::Real(v) => Start::Real(v),
            Value::Integer(v) => Start::Integer(v),
            Value::Boolean(v) => Start::Boolean(v),
            Value::String(v) => Start::String(v),
        };
        self
    }
}

fn build(markers: &MarkerOutputs) -> Vec<Variable> {
    use Parameter as P;
    use ScalarType::{Boolean, Integer, Real, String as Str};
    let d = start_config();
    let mut rows: Vec<Variable> = Vec::with_capacity(900);

    rows.push(Variable {
        causality: Causality::Independent,
        initial: None,
        ..Row::new("time", VR_TIME, Real, Role::Time, "Simulated time")
            .unit("s")
            .0
    });

    for (k, g) in MuscleGroup::ALL.into_iter().enumerate() {
        let mut r = Row::new(
            format!("activation.{}", g.name()),
            VR_ACTIVATION + k as u32,
            Real,
            Role::Input(Input::Activation(g)),
            format!(
                "Activation input of the {} (added to the drive, applied clamped to [0, 1])",
                g.name().replace('_', " ")
            ),
        )
        .range(0.0, 1.0)
        .0;
        r.causality = Causality::Input;
        r.start = Start::Real(0.0);
        rows.push(r);
    }
    let (lo, hi) = crate::model::AIRWAY_OPENING_RANGE;
    let mut r = Row::new(
        "pressure.airway_opening",
        VR_AIRWAY_OPENING,
        Real,
        Role::Input(Input::AirwayOpening),
        "Pressure at the airway opening relative to the body surface (0: breathing air; a ventilator's pressure); reaches the alveoli through the airway resistance",
    )
    .unit("Pa")
    .display("cmH2O")
    .range(lo, hi)
    .0;
    r.causality = Causality::Input;
    r.start = Start::Real(0.0);
    rows.push(r);

    let methods = (Method::ALL.len() - 1) as f64;
    let par = |name: &str, vr: u32, ty: ScalarType, p: Parameter, desc: &str| {
        Row::new(name, vr, ty, Role::Parameter(p), desc)
    };
    let mut params: Vec<Row> = vec![
        par(
            "subject.sex",
            200,
            Integer,
            P::Sex,
            "Sex of the subject: 0 male, 1 female",
        )
        .range(0.0, 1.0),
        par("subject.age", 100, Real, P::Age, "Age of the subject")
            .unit("y")
            .subject_range(),
        par(
            "subject.stature",
            101,
            Real,
            P::Stature,
            "Stature of the subject",
        )
        .unit("m")
        .subject_range(),
        par(
            "subject.mass",
            102,
            Real,
            P::Mass,
            "Body mass of the subject (body mass index 13-60 kg/m2)",
        )
        .unit("kg")
        .subject_range(),
        par(
            "subject.breast_size",
            103,
            Real,
            P::BreastSize,
            "Breast size, 0 (none) to 1 (large)",
        )
        .subject_range(),
        par(
            "posture",
            201,
            Integer,
            P::Posture,
            "Posture: 0 standing, 1 sitting, 2 supine",
        )
        .range(0.0, 2.0),
        par(
            "drive.enabled",
            400,
            Boolean,
            P::DriveEnabled,
            "The built-in drive (drive.*, thesis eq. 2.4) runs; false: the muscles follow the activation inputs alone",
        ),
        par(
            "drive.frequency",
            110,
            Real,
            P::DriveFrequency,
            "Breathing frequency of the built-in drive",
        )
        .unit("Hz")
        .range(0.05, 2.0),
        par(
            "drive.inspiratory_fraction",
            401,
            Real,
            P::DriveInspiratoryFraction,
            "Inspiratory fraction Ti/Ttot of the built-in drive's waves (raised-cosine rise and fall, docs/drive.md); 0.5 is the sine of thesis eq. 2.4",
        )
        .range(0.2, 0.8),
    ];
    for (k, f) in Family::ALL.into_iter().enumerate() {
        let vr = 111 + 2 * k as u32;
        params.push(
            par(
                &format!("drive.{}.amplitude", f.name()),
                vr,
                Real,
                P::DriveAmplitude(f),
                &format!("Drive amplitude of the {} family (fraction of the maximal activation; thesis eq. 2.4)", f.name()),
            )
            .range(0.0, 1.0),
        );
        params.push(
            par(
                &format!("drive.{}.phase", f.name()),
                vr + 1,
                Real,
                P::DrivePhase(f),
                &format!("Drive phase of the {} family", f.name()),
            )
            .unit("rad")
            .range(-2.0 * PI, 2.0 * PI),
        );
    }
    params.extend([
        par("lung.ratio", 120, Real, P::LungRatio, "Lung volume as a fraction of the thoracic cavity volume at rest (thesis 4.2); the rest, heart and mediastinum, is constant over a breath")
            .range(0.3, 1.0),
        par("gain.left", 121, Real, P::GainLeft, "Activation gain of the subject's left side (1: healthy)").range(0.0, 2.0),
        par("gain.right", 122, Real, P::GainRight, "Activation gain of the subject's right side (1: healthy)").range(0.0, 2.0),
        par("scene.level_of_detail", 202, Integer, P::LevelOfDetail, "Level of detail: 0 coarse, 1 default, 2 the thesis's element counts")
            .range(0.0, 2.0),
        par("grid.rows", 203, Integer, P::GridRows, "Marker grid rows").range(1.0, 16.0),
        par("grid.cols", 204, Integer, P::GridCols, "Marker grid columns").range(1.0, 16.0),
        par(
            "slp.reference",
            300,
            Str,
            P::SlpReference,
            "SLP recording whose first frame registers the marker grid (absolute, or relative to the FMU's resources/); empty: default grid",
        ),
        par(
            "subject.mesh_dir",
            301,
            Str,
            P::MeshDir,
            "Subject mesh directory written by `torso mesh prepare` (skin.obj, optional abdomen.obj) replacing the generated skin and cavity; empty: generated geometry",
        ),
        par(
            "solver.method",
            205,
            Integer,
            P::SolverMethod,
            "Integration method: 0 Dormand-Prince 5(4), 1 Bogacki-Shampine 3(2), 2 high-order pair, 3 Rosenbrock-W (stiff), 4 quasi-static (chest wall in equilibrium, the lung volume integrated by Dormand-Prince 5(4))",
        )
        .range(0.0, methods),
        par("solver.rtol", 130, Real, P::SolverRtol, "Relative tolerance of the integrator").range(1e-12, 1e-2),
        par("solver.atol", 131, Real, P::SolverAtol, "Absolute tolerance of the integrator on the state").range(1e-14, 1e-2),
        par("solver.max_step", 132, Real, P::SolverMaxStep, "Largest internal integration step").unit("s").range(1e-5, 1.0),
    ]);
    // 140 + 2 k (right) and 141 + 2 k (left) for the k-th group of MuscleGroup::ALL.
    for (k, g) in MuscleGroup::ALL.into_iter().enumerate() {
        for (s, side) in [Side::Right, Side::Left].into_iter().enumerate() {
            let side_name = match side {
                Side::Right => "right",
                Side::Left => "left",
            };
            params.push(
                par(
                    &format!("gain.{}.{side_name}", g.name()),
                    140 + 2 * k as u32 + s as u32,
                    Real,
                    P::GroupGain(g, side),
                    &format!(
                        "Activation gain of the {} on the subject's {side_name} side, times gain.{side_name} (1: healthy, 0: paralysed)",
                        g.name().replace('_', " ")
                    ),
                )
                .range(0.0, 2.0),
            );
        }
    }
    rows.extend(params.into_iter().map(|r| r.parameter(&d).0));

    use Quantity as Q;
    let out = |name: &str, vr: u32, q: Quantity, unit: &'static str, desc: &str| {
        Row::new(name, vr, Real, Role::Output(q), desc)
            .unit(unit)
            .output(Variability::Continuous)
    };
    rows.extend([
        out(
            "volume.lung",
            1000,
            Q::LungVolume,
            "L",
            "Lung volume = thoracic volume - the constant non-lung volume (heart, mediastinum; lung.ratio of the thorax at rest)",
        )
        .0,
        out(
            "volume.thorax",
            1001,
            Q::ThoraxVolume,
            "L",
            "Thoracic cavity volume = trunk - abdomen",
        )
        .0,
        out(
            "volume.abdomen",
            1002,
            Q::AbdomenVolume,
            "L",
            "Abdominal cavity volume",
        )
        .0,
        out(
            "volume.trunk",
            1003,
            Q::TrunkVolume,
            "L",
            "Trunk cavity volume (rib-cage lining plus abdominal wall)",
        )
        .0,
        out(
            "volume.rib_cage_displaced",
            1004,
            Q::RibCageDisplaced,
            "L",
            "Volume displaced by the trunk wall above the lowest point of the costal margin (rib cage, as in optoelectronic plethysmography) since the start",
        )
        .0,
        out(
            "volume.abdomen_displaced",
            1005,
            Q::AbdomenDisplaced,
            "L",
            "Volume displaced by the trunk wall below the lowest point of the costal margin (abdomen, as in optoelectronic plethysmography) since the start",
        )
        .0,
        out(
            "pressure.abdomen",
            1006,
            Q::AbdominalPressure,
            "Pa",
            "Abdominal pressure above rest (thesis eq. 2.5)",
        )
        .display("cmH2O")
        .0,
        out(
            "diaphragm.displacement",
            1007,
            Q::DiaphragmDisplacement,
            "m",
            "Displacement of the diaphragm dome since the start, positive cranial",
        )
        .display("mm")
        .0,
        out(
            "pressure.pleural",
            1011,
            Q::PleuralPressure,
            "Pa",
            "Pleural pressure relative to the body surface: alveolar pressure less the lungs' elastic recoil (about -5 cmH2O at rest)",
        )
        .display("cmH2O")
        .depends_on(&[VR_AIRWAY_OPENING])
        .0,
        out(
            "pressure.alveolar",
            1012,
            Q::AlveolarPressure,
            "Pa",
            "Alveolar pressure relative to the body surface: the airway opening's less the drop across the airway resistance",
        )
        .display("cmH2O")
        .depends_on(&[VR_AIRWAY_OPENING])
        .0,
        out(
            "flow.airway",
            1013,
            Q::AirwayFlow,
            "L/s",
            "Airflow into the lungs (rate of the lung volume), positive in inspiration",
        )
        .0,
    ]);
    // 1014 + 2 k + side (0 right, 1 left) for lung, rib-cage and abdominal displaced
    // volumes and the hemidiaphragm.
    type Sided = (&'static str, fn(u8) -> Quantity, &'static str, &'static str);
    let sided: [Sided; 4] = [
        (
            "volume.lung",
            Q::LungVolumeSide,
            "L",
            "Volume of the {side} lung: its rest share of the lungs (right 53.3 %, CT volumetry) plus the change of its side of the thorax",
        ),
        (
            "volume.rib_cage_displaced",
            Q::RibCageDisplacedSide,
            "L",
            "Volume displaced by the {side} half of the rib-cage wall since the start",
        ),
        (
            "volume.abdomen_displaced",
            Q::AbdomenDisplacedSide,
            "L",
            "Volume displaced by the {side} half of the abdominal wall since the start",
        ),
        (
            "diaphragm.displacement",
            Q::DiaphragmDisplacementSide,
            "m",
            "Displacement of the {side} hemidiaphragm since the start, positive cranial",
        ),
    ];
    for (k, (name, q, unit, desc)) in sided.into_iter().enumerate() {
        for (s, side) in ["right", "left"].into_iter().enumerate() {
            let mut row = out(
                &format!("{name}.{side}"),
                1014 + 2 * k as u32 + s as u32,
                q(s as u8),
                unit,
                &desc.replace("{side}", side),
            );
            if unit == "m" {
                row = row.display("mm");
            }
            rows.push(row.0);
        }
    }
    for (axis, a) in AXES.iter().enumerate() {
        rows.push(
            out(
                &format!("sternum.displacement.{a}"),
                1008 + axis as u32,
                Q::SternumDisplacement(axis as u8),
                "m",
                &format!("Displacement of the sternum since the start along {a} (x anterior, y cranial, z right)"),
            )
            .display("mm")
            .0,
        );
    }
    rows.extend(marker_rows(markers));
    let int_out = |name: &str, vr: u32, q: Quantity, desc: &str| {
        Row::new(name, vr, Integer, Role::Output(q), desc)
            .output(Variability::Discrete)
            .0
    };
    rows.extend([
        int_out(
            "solver.steps",
            3000,
            Q::SolverSteps,
            "Accepted integration steps since the start",
        ),
        int_out(
            "solver.rejected_steps",
            3001,
            Q::SolverRejectedSteps,
            "Rejected integration steps since the start",
        ),
        int_out(
            "solver.rhs_evaluations",
            3002,
            Q::SolverRhsEvaluations,
            "Right-hand-side evaluations since the start",
        ),
    ]);
    rows
}

/// The part of the model description that makes up the interface: identifier, capability
/// flags, units, and every variable's name, reference, type, causality, variability, initial,
/// unit, range, start and input dependencies (descriptions excluded).
fn interface_text(variables: &[Variable]) -> String {
    use std::fmt::Write;
    let mut s = format!(
        "fmi2|{MODEL_IDENTIFIER}|cs|{}\n",
        crate::fmi::xml::CAPABILITY_FLAGS.join(",")
    );
    for u in UNITS {
        let _ = writeln!(
            s,
            "unit|{}|{:?}|{:?}|{:?}",
            u.name, u.base, u.factor, u.display
        );
    }
    for v in variables {
        let _ = writeln!(
            s,
            "{}|{}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
            v.name,
            v.vr,
            v.ty,
            v.causality,
            v.variability,
            v.initial,
            v.unit,
            v.display_unit,
            v.min,
            v.max,
            v.start,
            v.input_dependencies
        );
    }
    s
}

/// 128-bit FNV-1a (Fowler-Noll-Vo) hash.
pub fn fnv1a_128(bytes: &[u8]) -> u128 {
    const OFFSET: u128 = 0x6c62272e07bb014262b821756295c58d;
    const PRIME: u128 = 0x0000000001000000000000000000013B;
    bytes
        .iter()
        .fold(OFFSET, |h, &b| (h ^ u128::from(b)).wrapping_mul(PRIME))
}

fn format_guid(h: u128) -> String {
    let x = format!("{h:032x}");
    format!(
        "{{{}-{}-{}-{}-{}}}",
        &x[0..8],
        &x[8..12],
        &x[12..16],
        &x[16..20],
        &x[20..32]
    )
}
