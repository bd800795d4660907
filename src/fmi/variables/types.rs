//! The vocabulary of the variable table: a variable's FMI attributes (base type, causality,
//! variability, `initial`, start value), what it stands for in the model ([`Role`]), the
//! [`Variable`] row itself with its range check, the units declared in `<UnitDefinitions>`
//! ([`UNITS`]) and the log categories ([`LOG_CATEGORIES`]).

use super::mapping::{Input, Parameter};
use crate::model::Quantity;
use crate::{Error, Result};

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
        name: "m/s2",
        base: &[("m", 1), ("s", -2)],
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
