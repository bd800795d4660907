//! The variable table of a personalised FMU: a [`Personalisation`] (the subject's start
//! values and, for a named marker set, its markers) turned into a [`Table`] of its own
//! ([`Table::personalised`]), kept once per distinct personalisation
//! ([`personalised_table`]), and the configuration its start values describe
//! ([`Table::start_config_with`]). Reading a fit result into a personalisation is
//! [`crate::fmi::personal`]'s.

use super::mapping::{Parameter, Value, start_config};
use super::rows::{MarkerOutputs, build, marker_rows};
use super::types::{Role, ScalarType, Start, Variable};
use super::{MAX_MARKER_OUTPUTS, Table};
use crate::anatomy::skin::MarkerSet;
use crate::model::Config;
use crate::{Error, Result};
use std::sync::{Arc, Mutex, OnceLock};

impl Table {
    /// The table of a personalised FMU: the generic table with `p`'s start values (each
    /// checked against its variable's type and range), `grid.rows` and `grid.cols` fixed at
    /// their start values (min = max), and as outputs the markers of the subject's marker set:
    /// with no named set, that grid's `rows x cols` markers `marker[i].x|y|z`, numbered as in
    /// the generic FMU; with a named set ([`Personalisation::markers`]), its markers in its
    /// order, named by their labels (`marker.<label>.x|y|z`, see [`marker_label_name`](super::marker_label_name)), at
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

/// The table of a personalisation, built once per distinct personalisation and kept for
/// the life of the process (an FMU's instances share it, as they share [`table`](super::table)).
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
