//! One FMU instance, the same for FMI 2.0 and FMI 3.0: the explicit co-simulation state
//! machine, the per-function masks of the states each function may be called in, value
//! access through the variable table, the communication step and the FMU state. Everything
//! here is safe Rust and version-neutral: calls answer a [`Status`], and each takes the name
//! of the exported function it serves, which its log messages start with; the functions it
//! mentions otherwise are named in the caller's version ([`Api`]). The exported C functions
//! ([`super::ffi`], [`super::fmi3::ffi`]) only check pointers, catch panics, translate and
//! forward. The function names in the documentation below are FMI 2.0's.
//!
//! Status policy: a rejected call (illegal call sequence, unknown value reference, a value
//! out of range or not finite, a fixed parameter after initialization) returns
//! [`Status::Error`] with a log message naming the function and the variable, and leaves the
//! instance exactly as it was. A numerical failure or an unphysiological state inside
//! `fmi2DoStep` returns [`Status::Discard`], keeps the model at its last successful time and
//! moves to [`Phase::StepFailed`]. Any other internal failure moves to [`Phase::Error`], from
//! which only `fmi2SetFMUstate`, `fmi2Reset` and `fmi2FreeInstance` lead out.

use super::status::{Api, Status};
use super::variables::{
    Causality, Input, LOG_CATEGORIES, Parameter, Role, ScalarType, Table, Value, Variable,
    start_config, table,
};
use crate::model::{AdvanceOptions, Config, Snapshot, Torso};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::ffi::CString;
use std::path::{Path, PathBuf};

/// The states of an instance (FMI 2.0 co-simulation state machine). `StepInProgress` and
/// `StepCanceled` are never entered: steps are synchronous.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// After `fmi2Instantiate` or `fmi2Reset`: start values and the experiment may be set.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode,
    /// Ready for `fmi2DoStep`.
    StepComplete,
    /// The last step was discarded (numerical failure); the model is at its last good time.
    StepFailed,
    /// After `fmi2Terminate`.
    Terminated,
    /// An internal failure: only set state, reset or free may follow.
    Error,
}

impl Phase {
    /// The bit of this phase in a [`mask`].
    pub fn bit(self) -> u8 {
        match self {
            Phase::Instantiated => mask::INSTANTIATED,
            Phase::InitializationMode => mask::INITIALIZATION_MODE,
            Phase::StepComplete => mask::STEP_COMPLETE,
            Phase::StepFailed => mask::STEP_FAILED,
            Phase::Terminated => mask::TERMINATED,
            Phase::Error => mask::ERROR,
        }
    }
}

/// Per-function masks of the phases a function may be called in (FMI 2.0 section 4.2.4,
/// co-simulation state machine).
pub mod mask {
    /// [`super::Phase::Instantiated`].
    pub const INSTANTIATED: u8 = 1;
    /// [`super::Phase::InitializationMode`].
    pub const INITIALIZATION_MODE: u8 = 2;
    /// [`super::Phase::StepComplete`].
    pub const STEP_COMPLETE: u8 = 4;
    /// [`super::Phase::StepFailed`].
    pub const STEP_FAILED: u8 = 8;
    /// [`super::Phase::Terminated`].
    pub const TERMINATED: u8 = 16;
    /// [`super::Phase::Error`].
    pub const ERROR: u8 = 32;
    /// Every phase.
    pub const ANY: u8 =
        INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR;

    /// `fmi2SetDebugLogging`.
    pub const SET_DEBUG_LOGGING: u8 = ANY;
    /// `fmi2FreeInstance`.
    pub const FREE_INSTANCE: u8 = ANY;
    /// `fmi2SetupExperiment`.
    pub const SETUP_EXPERIMENT: u8 = INSTANTIATED;
    /// `fmi2EnterInitializationMode`.
    pub const ENTER_INITIALIZATION_MODE: u8 = INSTANTIATED;
    /// `fmi2ExitInitializationMode`.
    pub const EXIT_INITIALIZATION_MODE: u8 = INITIALIZATION_MODE;
    /// `fmi2Terminate`.
    pub const TERMINATE: u8 = STEP_COMPLETE | STEP_FAILED;
    /// `fmi2Reset`.
    pub const RESET: u8 = ANY;
    /// `fmi2GetReal`, `fmi2GetInteger`, `fmi2GetBoolean`, `fmi2GetString`.
    pub const GET_VALUES: u8 =
        INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR;
    /// `fmi2SetReal`, `fmi2SetInteger`, `fmi2SetBoolean`, `fmi2SetString` (fixed parameters
    /// are further restricted to the first two phases).
    pub const SET_VALUES: u8 = INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE;
    /// `fmi2GetFMUstate` (never in [`super::Phase::Error`]: a saved state is consistent).
    pub const GET_FMU_STATE: u8 = ANY & !ERROR;
    /// `fmi2SetFMUstate`.
    pub const SET_FMU_STATE: u8 = ANY;
    /// `fmi2FreeFMUstate`, `fmi2SerializedFMUstateSize`, `fmi2SerializeFMUstate`,
    /// `fmi2DeSerializeFMUstate`.
    pub const FMU_STATE_MEMORY: u8 = ANY;
    /// `fmi2GetDirectionalDerivative` (not provided).
    pub const GET_DIRECTIONAL_DERIVATIVE: u8 =
        INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR;
    /// `fmi2SetRealInputDerivatives` (not provided).
    pub const SET_REAL_INPUT_DERIVATIVES: u8 = INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE;
    /// `fmi2GetRealOutputDerivatives` (not provided).
    pub const GET_REAL_OUTPUT_DERIVATIVES: u8 = STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR;
    /// `fmi2DoStep`.
    pub const DO_STEP: u8 = STEP_COMPLETE;
    /// `fmi2CancelStep`: only while a step is in progress, which never happens.
    pub const CANCEL_STEP: u8 = 0;
    /// `fmi2GetStatus` and the typed variants.
    pub const GET_STATUS: u8 = STEP_COMPLETE | STEP_FAILED | TERMINATED;
}

/// Log categories, by index in [`LOG_CATEGORIES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    /// `logEvents`.
    Events = 0,
    /// `logStatusWarning`.
    Warning = 1,
    /// `logStatusDiscard`.
    Discard = 2,
    /// `logStatusError`.
    Error = 3,
    /// `logStatusFatal`.
    Fatal = 4,
    /// `logCalls`.
    Calls = 5,
}

impl Category {
    /// The category's name in `modelDescription.xml`.
    pub fn name(self) -> &'static str {
        LOG_CATEGORIES[self as usize].0
    }
}

/// The receiver of log messages: (status, category name, message).
pub type LogSink = Box<dyn FnMut(Status, &str, &str)>;

/// Categories enabled when the master instantiates with `loggingOn = fmi2False`: the messages
/// of every call that returns a status other than `fmi2OK` (warnings, discarded steps,
/// errors), so that a master always learns why; `fmi2SetDebugLogging` may still switch them
/// off.
const STATUS_ONLY: u32 = (1 << Category::Warning as u32)
    | (1 << Category::Error as u32)
    | (1 << Category::Fatal as u32)
    | (1 << Category::Discard as u32);
const ALL_CATEGORIES: u32 = (1 << 6) - 1;

/// Seconds of relative tolerance when comparing the master's communication point with the
/// instance's time.
pub const TIME_TOLERANCE: f64 = 1e-9;

/// An FMU instance.
pub struct Instance {
    name: String,
    /// The names of the functions of the interface that created the instance, for messages.
    api: &'static Api,
    /// The variables of the FMU this instance belongs to: the generic table or a personalised
    /// one ([`Table::personalised`]).
    table: &'static Table,
    /// The configuration the start values describe, which the instance starts from and
    /// `fmi2Reset` returns to. Like `config`, it holds `slp.reference` and
    /// `subject.mesh_dir` as given ([`Instance::resolved`]).
    start: Config,
    resources: Option<PathBuf>,
    sink: Option<LogSink>,
    categories: u32,
    phase: Phase,
    /// The parameters' values. `slp.reference` and `subject.mesh_dir` are kept as given (a
    /// relative path stays relative to the FMU's `resources/`), so that the configuration,
    /// and a state saved from it, means the same in every unpack folder; they are resolved
    /// against this instance's resources when the model is built ([`Instance::resolved`]).
    config: Config,
    rtol_explicit: bool,
    inputs: [f64; Input::COUNT],
    /// The model, built from [`Instance::resolved`] `config` (its configuration holds the
    /// resolved paths).
    torso: Option<Torso>,
    /// Snapshot of `torso` taken right after it was built (its fresh state).
    fresh: Option<Snapshot>,
    /// The model of the instance before the last `fmi2Reset`, with its fresh snapshot: the
    /// next initialisation restores it instead of rebuilding when the fixed configuration
    /// is unchanged (a fit resets and re-initialises the instance for every evaluation).
    spare: Option<(Torso, Snapshot)>,
    start_time: f64,
    stop_time: Option<f64>,
    tolerance: Option<f64>,
    time: f64,
    last_successful_time: f64,
    last_step_status: Status,
    strings: Vec<CString>,
    /// Whether the explicit solver's stiffness flag has been logged.
    stiffness_logged: bool,
    /// Addresses of the FMU states handed out and not yet freed (managed by the C layer).
    pub(crate) fmu_states: std::collections::HashSet<usize>,
}

/// A saved instance state (`fmi2FMUstate`): plain data, no pointers into the instance.
#[derive(Clone, Debug, PartialEq)]
pub struct FmuState {
    saved: Saved,
    snapshot: Option<Snapshot>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Saved {
    guid: String,
    phase: Phase,
    config: Config,
    rtol_explicit: bool,
    /// The inputs in [`Input::all`] order (states saved before `airway.occluded` existed have
    /// one fewer: the airway open).
    inputs: Vec<f64>,
    start_time: f64,
    stop_time: Option<f64>,
    tolerance: Option<f64>,
    time: f64,
    last_successful_time: f64,
    last_step_discarded: bool,
    /// Whether a model snapshot follows (a truncated state is thus refused).
    has_snapshot: bool,
}

const STATE_MAGIC: &[u8; 8] = b"BTFMUST\0";
/// Format version of serialised FMU states.
pub const FMU_STATE_VERSION: u32 = 1;

impl FmuState {
    /// Serialises: magic, version, length of the instance part, the instance part (JSON), then
    /// the model snapshot ([`Snapshot::to_bytes`]), if any.
    pub fn to_bytes(&self) -> Vec<u8> {
        let json = serde_json::to_vec(&self.saved).unwrap_or_default();
        let mut out = STATE_MAGIC.to_vec();
        out.extend_from_slice(&FMU_STATE_VERSION.to_le_bytes());
        out.extend_from_slice(&(json.len() as u64).to_le_bytes());
        out.extend_from_slice(&json);
        if let Some(s) = &self.snapshot {
            out.extend_from_slice(&s.to_bytes());
        }
        out
    }

    /// Parses bytes written by [`FmuState::to_bytes`] by the generic FMU; anything else is an
    /// error, never a panic.
    pub fn from_bytes(bytes: &[u8]) -> Result<FmuState> {
        FmuState::from_bytes_for(bytes, table())
    }

    /// Parses bytes written by [`FmuState::to_bytes`] by an FMU whose variables are `table`
    /// (the GUID must be that table's).
    pub fn from_bytes_for(bytes: &[u8], table: &Table) -> Result<FmuState> {
        let bad =
            |m: String| Error::State(format!("not a serialized BreathingTorso FMU state: {m}"));
        if bytes.len() < 20 || &bytes[..8] != STATE_MAGIC {
            return Err(bad("missing header".into()));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version != FMU_STATE_VERSION {
            return Err(bad(format!(
                "format version {version}, this FMU reads {FMU_STATE_VERSION}"
            )));
        }
        let mut len = [0u8; 8];
        len.copy_from_slice(&bytes[12..20]);
        let len = usize::try_from(u64::from_le_bytes(len))
            .map_err(|_| bad("length out of range".into()))?;
        let body = bytes.get(20..).unwrap_or_default();
        if len > body.len() {
            return Err(bad(format!("truncated: {} of {len} bytes", body.len())));
        }
        let saved: Saved = serde_json::from_slice(&body[..len]).map_err(|e| bad(e.to_string()))?;
        if saved.guid != table.guid() {
            return Err(bad(format!(
                "saved by an FMU with GUID {}, this one is {}",
                saved.guid,
                table.guid()
            )));
        }
        // The paths are checked when the restoring instance resolves them against its own
        // resources (a relative subject mesh folder means nothing in the working folder).
        let mut paths_aside = saved.config.clone();
        paths_aside.subject_mesh_dir = None;
        paths_aside.validate()?;
        let mut saved = saved;
        // States saved before the occlusion (9 inputs) or the sternocleidomastoids (10)
        // existed: the inputs added since, last in value-reference order, read 0.
        if (Input::COUNT - 2..Input::COUNT).contains(&saved.inputs.len()) {
            saved.inputs.resize(Input::COUNT, 0.0);
        }
        if saved.inputs.len() != Input::COUNT {
            return Err(bad(format!(
                "{} inputs, this FMU has {}",
                saved.inputs.len(),
                Input::COUNT
            )));
        }
        for (input, &v) in Input::all().into_iter().zip(&saved.inputs) {
            if input == Input::AirwayOccluded && v != 0.0 && v != 1.0 {
                return Err(Error::invalid(
                    "airway.occluded",
                    v,
                    "0 (open) or 1 (occluded)",
                ));
            }
            if let Some(var) = table.by_vr(input.vr()) {
                var.check(v)?;
            }
        }
        let rest = &body[len..];
        let snapshot = match (saved.has_snapshot, rest.is_empty()) {
            (true, false) => Some(Snapshot::from_bytes(rest)?),
            (false, true) => None,
            (true, true) => return Err(bad("truncated: the model snapshot is missing".into())),
            (false, false) => return Err(bad("trailing bytes after the state".into())),
        };
        Ok(FmuState { saved, snapshot })
    }
}

/// Whether two configurations build the same model: equal but for the (tunable) drive.
fn same_fixed_config(a: &Config, b: &Config) -> bool {
    let mut a = a.clone();
    a.drive = b.drive;
    a == *b
}

/// The fixed parameters in which `ours` and `theirs` differ, as `name: ours here, theirs in
/// the state`; settings without an FMI variable (constants of the dynamics) are named as such.
fn fixed_differences(table: &Table, ours: &Config, theirs: &Config) -> String {
    let show = |v: Value| match v {
        Value::Real(x) => format!("{x}"),
        Value::Integer(i) => format!("{i}"),
        Value::Boolean(b) => format!("{b}"),
        Value::String(s) => format!("{s:?}"),
    };
    let mut out: Vec<String> = table
        .variables()
        .iter()
        .filter_map(|var| match var.role {
            Role::Parameter(p) if !p.is_tunable() && p.get(ours) != p.get(theirs) => Some(format!(
                "`{}` {} here, {} in the state",
                var.name,
                show(p.get(ours)),
                show(p.get(theirs))
            )),
            _ => None,
        })
        .collect();
    if out.is_empty() {
        out.push("the constants of the dynamics".into());
    }
    out.join(", ")
}

fn type_name(t: ScalarType) -> &'static str {
    match t {
        ScalarType::Real => "Real",
        ScalarType::Integer => "Integer",
        ScalarType::Boolean => "Boolean",
        ScalarType::String => "String",
    }
}

/// A pending change collected by a setter before it is committed.
enum Change {
    Input(Input, f64),
    /// A parameter and its value; for `slp.reference` and `subject.mesh_dir` the value is
    /// the resolved path (which the setter checks) and the string the value as given (which
    /// the configuration keeps).
    Parameter(Parameter, Value, Option<String>),
}

/// The configuration's field of a path parameter (`slp.reference`, `subject.mesh_dir`).
fn path_field(config: &mut Config, p: Parameter) -> Option<&mut Option<PathBuf>> {
    match p {
        Parameter::SlpReference => Some(&mut config.scene.slp_reference),
        Parameter::MeshDir => Some(&mut config.subject_mesh_dir),
        _ => None,
    }
}

/// Puts a path parameter's value as given into `config` (the empty string: none).
fn keep_given(config: &mut Config, p: Parameter, given: &str) {
    if let Some(field) = path_field(config, p) {
        *field = (!given.is_empty()).then(|| PathBuf::from(given));
    }
}

impl Instance {
    /// A fresh instance. `resources` is the decoded `fmuResourceLocation`; `logging_on`
    /// enables every log category (otherwise only the messages of calls that return a status
    /// other than `fmi2OK`).
    pub fn new(
        api: &'static Api,
        name: &str,
        resources: Option<PathBuf>,
        sink: Option<LogSink>,
        logging_on: bool,
    ) -> Instance {
        Instance::fresh(
            api,
            name,
            resources,
            sink,
            logging_on,
            table(),
            start_config(),
        )
    }

    /// A fresh instance of the FMU whose variables are `table` (a personalised FMU's): its
    /// configuration starts from the table's start values, a relative `slp.reference` or
    /// `subject.mesh_dir` being looked up in `resources` first. An error names the parameter
    /// whose start value cannot be used (e.g. a file missing from the FMU's resources/).
    pub fn with_table(
        api: &'static Api,
        name: &str,
        resources: Option<PathBuf>,
        sink: Option<LogSink>,
        logging_on: bool,
        table: &'static Table,
    ) -> Result<Instance> {
        let mut inst = Instance::fresh(
            api,
            name,
            resources,
            sink,
            logging_on,
            table,
            start_config(),
        );
        // Resolved to check that every start value can be used (files present, mesh readable),
        // then kept as given.
        let mut start = table.start_config_with(&mut |p, value| inst.resolve_path(p, value))?;
        for (name, value) in table.personalisation().map_or(&[][..], |p| &p.starts[..]) {
            if let (Some(var), Value::String(given)) = (table.by_name(name), value)
                && let Role::Parameter(p) = var.role
            {
                keep_given(&mut start, p, given);
            }
        }
        inst.config = start.clone();
        inst.start = start;
        Ok(inst)
    }

    /// The variables of the FMU this instance belongs to.
    pub fn table(&self) -> &'static Table {
        self.table
    }

    fn fresh(
        api: &'static Api,
        name: &str,
        resources: Option<PathBuf>,
        sink: Option<LogSink>,
        logging_on: bool,
        table: &'static Table,
        start: Config,
    ) -> Instance {
        Instance {
            name: name.to_string(),
            api,
            table,
            resources,
            sink,
            categories: if logging_on {
                ALL_CATEGORIES
            } else {
                STATUS_ONLY
            },
            phase: Phase::Instantiated,
            config: start.clone(),
            start,
            rtol_explicit: false,
            stiffness_logged: false,
            inputs: [0.0; Input::COUNT],
            torso: None,
            fresh: None,
            spare: None,
            start_time: 0.0,
            stop_time: None,
            tolerance: None,
            time: 0.0,
            last_successful_time: 0.0,
            last_step_status: Status::Ok,
            strings: Vec::new(),
            fmu_states: Default::default(),
        }
    }

    /// The instance name given at instantiation.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Current phase of the state machine.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Current communication time [s].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The configuration the model is (or will be) built from.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Sends a message to the logger if its category is enabled.
    pub fn log(&mut self, status: Status, category: Category, message: &str) {
        if self.categories & (1 << category as u32) != 0
            && let Some(sink) = self.sink.as_mut()
        {
            sink(status, category.name(), message);
        }
    }

    /// Records an internal failure: the instance moves to [`Phase::Error`].
    pub fn fail(&mut self, message: &str) -> Status {
        self.phase = Phase::Error;
        self.error(message)
    }

    /// Logs an error and returns [`Status::Error`].
    pub fn error(&mut self, message: &str) -> Status {
        self.log(Status::Error, Category::Error, message);
        Status::Error
    }

    /// Logs a call when `logCalls` is enabled; `args` is only formatted then.
    pub fn trace(&mut self, args: impl FnOnce() -> String) {
        if self.categories & (1 << Category::Calls as u32) != 0 {
            let message = args();
            self.log(Status::Ok, Category::Calls, &message);
        }
    }

    /// Checks that `function` may be called in the current phase; logs "illegal call sequence"
    /// otherwise.
    pub fn allowed(&mut self, function: &str, mask: u8) -> bool {
        if self.phase.bit() & mask != 0 {
            return true;
        }
        let phase = self.phase;
        self.error(&format!(
            "{function}: illegal call sequence: not allowed in state {phase:?}"
        ));
        false
    }

    /// `fmi2SetDebugLogging`: no categories sets all of them; unknown names are an error (and
    /// change nothing).
    pub fn set_debug_logging(&mut self, function: &str, on: bool, names: &[&str]) -> Status {
        let mut bits = 0u32;
        for name in names {
            match LOG_CATEGORIES.iter().position(|(c, _)| c == name) {
                Some(i) => bits |= 1 << i,
                None => {
                    let known: Vec<&str> = LOG_CATEGORIES.iter().map(|c| c.0).collect();
                    return self.error(&format!(
                        "{function}: unknown log category \"{name}\" (known: {})",
                        known.join(", ")
                    ));
                }
            }
        }
        if names.is_empty() {
            bits = ALL_CATEGORIES;
        }
        if on {
            self.categories |= bits;
        } else {
            self.categories &= !bits;
        }
        Status::Ok
    }

    /// `fmi2SetupExperiment`. A defined tolerance becomes `solver.rtol` unless `solver.rtol`
    /// was set explicitly; one outside the solver's range is ignored with a warning.
    pub fn setup_experiment(
        &mut self,
        function: &str,
        tolerance: Option<f64>,
        start: f64,
        stop: Option<f64>,
    ) -> Status {
        if !start.is_finite() {
            return self.error(&format!("{function}: startTime = {start} is not finite"));
        }
        if let Some(stop) = stop
            && !(stop.is_finite() && stop >= start)
        {
            return self.error(&format!(
                "{function}: stopTime = {stop} must be finite and >= startTime = {start}"
            ));
        }
        let mut status = Status::Ok;
        if let Some(tol) = tolerance {
            let rtol = self.table.by_name("solver.rtol").map(|v| v.check(tol));
            match rtol {
                Some(Ok(())) if !self.rtol_explicit => {
                    self.config.solver.rtol = tol;
                    self.tolerance = Some(tol);
                    self.torso = None;
                }
                Some(Err(e)) => {
                    self.log(
                        Status::Warning,
                        Category::Warning,
                        &format!("{function}: tolerance ignored: {e}"),
                    );
                    status = Status::Warning;
                }
                _ => {}
            }
        }
        self.start_time = start;
        self.stop_time = stop;
        self.time = start;
        self.last_successful_time = start;
        status
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Status {
        self.phase = Phase::InitializationMode;
        self.log(Status::Ok, Category::Events, "entered initialization mode");
        Status::Ok
    }

    /// `fmi2ExitInitializationMode`: builds the model (the configuration's final check); a
    /// bad configuration is an error naming the variable, and the instance stays in
    /// initialization mode so that the master may correct it.
    pub fn exit_initialization_mode(&mut self, function: &str) -> Status {
        let start = match self.ensure_torso() {
            Err(e) => return self.error(&format!("{function}: {e}")),
            // the start state: the static equilibrium of the inputs set during initialisation
            // and the drive's start (cached per compiled model and activations)
            Ok(torso) => {
                let start = torso.start_at_equilibrium();
                // drive parameters changed from here on act as steps, like the inputs
                torso.fix_start();
                (start, torso.config().solver.rtol)
            }
        };
        if !start.0.converged {
            let message = format!(
                "{function}: the start state's solve did not settle: relative imbalance {:.1e} after {} Newton iterations and {:.0} s of relaxation (tolerance solver.rtol {:.0e}); the run starts there",
                start.0.relative_residual(),
                start.0.newton_iterations,
                start.0.relaxation_time,
                start.1
            );
            self.log(Status::Ok, Category::Events, &message);
        }
        self.phase = Phase::StepComplete;
        self.last_successful_time = self.time;
        self.log(Status::Ok, Category::Events, "initialization done");
        Status::Ok
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Status {
        self.phase = Phase::Terminated;
        Status::Ok
    }

    /// `fmi2Reset`: back to the freshly instantiated state (start values, time, model, solver
    /// memory and statistics); the name, resources and logging settings stay. The built model
    /// is kept aside with the snapshot of its fresh state, so that an initialisation with the
    /// same fixed parameters restores that snapshot rather than rebuilding the model and its
    /// skin weights (see [`Instance::exit_initialization_mode`]).
    pub fn reset(&mut self) -> Status {
        let fmu_states = std::mem::take(&mut self.fmu_states);
        let spare = match (self.torso.take(), self.fresh.take()) {
            (Some(torso), Some(fresh)) => Some((torso, fresh)),
            _ => self.spare.take(),
        };
        let instance = Instance::fresh(
            self.api,
            &self.name,
            self.resources.take(),
            self.sink.take(),
            false,
            self.table,
            self.start.clone(),
        );
        let categories = self.categories;
        *self = Instance {
            categories,
            fmu_states,
            spare,
            ..instance
        };
        self.log(Status::Ok, Category::Events, "reset");
        Status::Ok
    }

    /// The path a String parameter's value stands for: a relative `slp.reference` (a file) or
    /// `subject.mesh_dir` (a folder) is looked up in the FMU's resources/ first, then as
    /// given. Other parameters and the empty string are returned unchanged. An error names
    /// the parameter and where it was looked for.
    fn resolve_path(&self, p: Parameter, value: &str) -> Result<String> {
        let (name, wants_dir, what) = match p {
            Parameter::SlpReference => ("slp.reference", false, "an existing SLP recording file"),
            Parameter::MeshDir => ("subject.mesh_dir", true, "an existing subject mesh folder"),
            _ => return Ok(value.to_string()),
        };
        if value.is_empty() {
            return Ok(String::new());
        }
        let exists = |p: &Path| if wants_dir { p.is_dir() } else { p.is_file() };
        let path = Path::new(value);
        let candidate = match (&self.resources, path.is_relative()) {
            (Some(r), true) if exists(&r.join(path)) => r.join(path),
            _ => path.to_path_buf(),
        };
        if !exists(&candidate) {
            let where_ = match (&self.resources, path.is_relative()) {
                (Some(r), _) => format!(" (also looked in {})", r.display()),
                (None, true) => format!(
                    " (not looked for in the FMU's resources/: {} was given no usable resource location)",
                    self.api.instantiate
                ),
                (None, false) => String::new(),
            };
            return Err(Error::invalid(name, value, format!("{what}{where_}")));
        }
        Ok(candidate.display().to_string())
    }

    /// `config` with its `slp.reference` and `subject.mesh_dir` resolved against this
    /// instance's resources ([`Instance::resolve_path`]): the configuration a model is built
    /// from. An error names the parameter and where its file was looked for.
    fn resolved(&self, config: &Config) -> Result<Config> {
        let mut out = config.clone();
        for p in [Parameter::SlpReference, Parameter::MeshDir] {
            let given = path_field(&mut out, p)
                .and_then(|f| f.as_ref())
                .map(|path| path.to_string_lossy().into_owned());
            if let Some(given) = given {
                let path = self.resolve_path(p, &given)?;
                keep_given(&mut out, p, &path);
            }
        }
        Ok(out)
    }

    /// A model of `config` (paths resolved) whose markers are this FMU's marker outputs: a
    /// personalised FMU's named marker set, else the grid. A grid with more markers than the
    /// FMU has marker outputs is refused, naming the grid and how to get an FMU with them.
    fn new_torso(&self, config: Config) -> Result<Torso> {
        let set = self.table.marker_set().cloned();
        if set.is_none() {
            let (rows, cols) = (config.scene.grid_rows, config.scene.grid_cols);
            let outputs = self.table.marker_outputs();
            if rows * cols > outputs {
                return Err(Error::invalid(
                    "grid.rows x grid.cols",
                    format!("{rows} x {cols} = {} markers", rows * cols),
                    format!(
                        "at most {outputs} markers, this FMU's marker outputs (a personalised FMU, \
                         `torso fmu build --subject FIT.json` of a fit made with `--grid {rows}x{cols}`, \
                         has that grid's markers as outputs)"
                    ),
                ));
            }
        }
        let mut torso = Torso::new(config)?;
        if set.is_some() {
            torso.set_marker_set(set);
        }
        Ok(torso)
    }

    /// Builds the model from the configuration if it is not built yet; a model kept by
    /// `fmi2Reset` whose fixed configuration (everything but the drive) is the current one is
    /// restored to its fresh state instead, which gives the same state as a rebuild.
    fn ensure_torso(&mut self) -> Result<&mut Torso> {
        if self.torso.is_none() {
            let config = self.resolved(&self.config)?;
            let reused = match self.spare.take() {
                Some((mut torso, fresh)) if same_fixed_config(torso.config(), &config) => {
                    torso.restore(&fresh).ok().map(|_| (torso, fresh))
                }
                _ => None,
            };
            let (mut torso, fresh) = match reused {
                Some(pair) => pair,
                None => {
                    let torso = self.new_torso(config)?;
                    let fresh = torso.snapshot();
                    (torso, fresh)
                }
            };
            torso.set_drive(self.config.drive)?;
            for input in Input::all() {
                input.apply(&mut torso, self.inputs[input.index()])?;
            }
            self.fresh = Some(fresh);
            self.torso = Some(torso);
        }
        self.torso
            .as_mut()
            .ok_or_else(|| Error::State("model not built".into()))
    }

    fn variable(
        &mut self,
        function: &str,
        vr: u32,
        ty: ScalarType,
    ) -> std::result::Result<&'static Variable, Status> {
        match self.table.by_vr(vr) {
            Some(v) if v.ty == ty => Ok(v),
            Some(v) => Err(self.error(&format!(
                "{function}: value reference {vr} is `{}`, a {}, not a {}",
                v.name,
                type_name(v.ty),
                type_name(ty)
            ))),
            None => Err(self.error(&format!("{function}: unknown value reference {vr}"))),
        }
    }

    fn get_value(
        &mut self,
        function: &str,
        vr: u32,
        ty: ScalarType,
    ) -> std::result::Result<Value, Status> {
        let var = self.variable(function, vr, ty)?;
        let value = match var.role {
            Role::Time => Ok(Value::Real(self.time)),
            Role::Input(Input::AirwayOccluded) => Ok(Value::Boolean(
                self.inputs[Input::AirwayOccluded.index()] != 0.0,
            )),
            Role::Input(input) => Ok(Value::Real(self.inputs[input.index()])),
            Role::Parameter(p) => Ok(p.get(&self.config)),
            Role::Output(q) => self
                .ensure_torso()
                .and_then(|t| t.read_output(&var.name, q))
                .map(|x| match var.ty {
                    ScalarType::Integer => Value::Integer(x.min(i32::MAX as f64) as i32),
                    _ => Value::Real(x),
                }),
        };
        value.map_err(|e| self.error(&format!("{function}: {e}")))
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, function: &str, vrs: &[u32], out: &mut [f64]) -> Status {
        for (vr, o) in vrs.iter().zip(out.iter_mut()) {
            match self.get_value(function, *vr, ScalarType::Real) {
                Ok(Value::Real(x)) => *o = x,
                Ok(_) => return self.error(&format!("{function}: internal type mismatch")),
                Err(s) => return s,
            }
        }
        Status::Ok
    }

    /// `fmi2GetInteger`.
    pub fn get_integer(&mut self, function: &str, vrs: &[u32], out: &mut [i32]) -> Status {
        for (vr, o) in vrs.iter().zip(out.iter_mut()) {
            match self.get_value(function, *vr, ScalarType::Integer) {
                Ok(Value::Integer(x)) => *o = x,
                Ok(_) => return self.error(&format!("{function}: internal type mismatch")),
                Err(s) => return s,
            }
        }
        Status::Ok
    }

    /// `fmi2GetBoolean` (`fmi2Boolean` values: 1 true, 0 false).
    pub fn get_boolean(&mut self, function: &str, vrs: &[u32], out: &mut [i32]) -> Status {
        for (vr, o) in vrs.iter().zip(out.iter_mut()) {
            match self.get_value(function, *vr, ScalarType::Boolean) {
                Ok(Value::Boolean(x)) => *o = i32::from(x),
                Ok(_) => return self.error(&format!("{function}: internal type mismatch")),
                Err(s) => return s,
            }
        }
        Status::Ok
    }

    /// `fmi2GetString`: the returned pointers stay valid until the next call on this instance
    /// that returns strings.
    pub fn get_string(
        &mut self,
        function: &str,
        vrs: &[u32],
        out: &mut [*const std::os::raw::c_char],
    ) -> Status {
        let mut strings = Vec::with_capacity(vrs.len());
        for vr in vrs {
            match self.get_value(function, *vr, ScalarType::String) {
                Ok(Value::String(s)) => {
                    strings.push(CString::new(s.replace('\0', "")).unwrap_or_default())
                }
                Ok(_) => return self.error(&format!("{function}: internal type mismatch")),
                Err(s) => return s,
            }
        }
        self.strings = strings;
        for (o, s) in out.iter_mut().zip(&self.strings) {
            *o = s.as_ptr();
        }
        Status::Ok
    }

    /// Checks one assignment and turns it into a [`Change`]; nothing is modified yet.
    fn check_set(
        &mut self,
        function: &str,
        vr: u32,
        ty: ScalarType,
        value: Value,
    ) -> std::result::Result<Change, Status> {
        let var = self.variable(function, vr, ty)?;
        let numeric = match &value {
            Value::Real(x) => Some(*x),
            Value::Integer(i) => Some(f64::from(*i)),
            Value::Boolean(b) => Some(f64::from(u8::from(*b))),
            Value::String(_) => None,
        };
        if let Some(x) = numeric
            && let Err(e) = var.check(x)
        {
            return Err(self.error(&format!("{function}: {e}; the value was not applied")));
        }
        match var.role {
            Role::Input(Input::AirwayOccluded)
                if numeric == Some(1.0)
                    && self.config.solver.method == crate::solver::Method::QuasiStatic =>
            {
                Err(self.error(&format!(
                    "{function}: `airway.occluded` = true is refused under solver.method 4 \
                     (quasi-static): an occluded airway is simulated by the inertial methods \
                     (0-3) only; the value was not applied"
                )))
            }
            Role::Input(input) => Ok(Change::Input(input, numeric.unwrap_or_default())),
            Role::Parameter(p) => {
                let before_run =
                    matches!(self.phase, Phase::Instantiated | Phase::InitializationMode);
                if !p.is_tunable() && !before_run {
                    return Err(self.error(&format!(
                        "{function}: `{}` is a fixed parameter: it cannot change after {}",
                        var.name, self.api.exit_initialization_mode
                    )));
                }
                // A path is resolved now, so that a missing file is refused when set, and
                // kept as given.
                let (value, given) = match (p, value) {
                    (Parameter::SlpReference | Parameter::MeshDir, Value::String(s)) => {
                        match self.resolve_path(p, &s) {
                            Ok(path) => (Value::String(path), Some(s)),
                            Err(e) => return Err(self.error(&format!("{function}: {e}"))),
                        }
                    }
                    (_, v) => (v, None),
                };
                Ok(Change::Parameter(p, value, given))
            }
            Role::Time | Role::Output(_) => {
                let what = if var.causality == Causality::Output {
                    "an output"
                } else {
                    "the independent variable"
                };
                Err(self.error(&format!(
                    "{function}: `{}` is {what} and cannot be set",
                    var.name
                )))
            }
        }
    }

    /// Applies checked changes all together: the configuration and the inputs are updated on
    /// copies, validated, then committed, so that a failure changes nothing.
    fn commit(&mut self, function: &str, changes: Vec<Change>) -> Status {
        let mut config = self.config.clone();
        let mut inputs = self.inputs;
        let mut rtol_explicit = self.rtol_explicit;
        let mut fixed_changed = false;
        let mut drive_changed = false;
        for change in changes {
            match change {
                Change::Input(input, v) => inputs[input.index()] = v,
                Change::Parameter(p, v, given) => {
                    if let Err(e) = p.set(&mut config, v) {
                        return self.error(&format!("{function}: {e}"));
                    }
                    if let Some(given) = given {
                        keep_given(&mut config, p, &given);
                    }
                    rtol_explicit |= p == Parameter::SolverRtol;
                    if p.is_tunable() {
                        drive_changed = true;
                    } else {
                        fixed_changed = true;
                    }
                }
            }
        }
        if drive_changed && let Err(e) = config.drive.validate() {
            return self.error(&format!("{function}: {e}"));
        }
        if fixed_changed {
            self.torso = None;
        } else if let Some(torso) = self.torso.as_mut() {
            let mut result = Ok(());
            if drive_changed {
                result = torso.set_drive(config.drive);
            }
            for input in Input::all() {
                let i = input.index();
                if result.is_ok() && inputs[i] != self.inputs[i] {
                    result = input.apply(torso, inputs[i]);
                }
            }
            if let Err(e) = result {
                self.phase = Phase::Error;
                return self.error(&format!("{function}: {e}"));
            }
        }
        self.config = config;
        self.inputs = inputs;
        self.rtol_explicit = rtol_explicit;
        Status::Ok
    }

    fn set_values<T: Copy>(
        &mut self,
        function: &str,
        ty: ScalarType,
        vrs: &[u32],
        values: &[T],
        wrap: impl Fn(T) -> Value,
    ) -> Status {
        let mut changes = Vec::with_capacity(vrs.len());
        for (vr, v) in vrs.iter().zip(values) {
            match self.check_set(function, *vr, ty, wrap(*v)) {
                Ok(c) => changes.push(c),
                Err(s) => return s,
            }
        }
        self.commit(function, changes)
    }

    /// `fmi2SetReal`.
    pub fn set_real(&mut self, function: &str, vrs: &[u32], values: &[f64]) -> Status {
        self.set_values(function, ScalarType::Real, vrs, values, Value::Real)
    }

    /// `fmi2SetInteger`.
    pub fn set_integer(&mut self, function: &str, vrs: &[u32], values: &[i32]) -> Status {
        self.set_values(function, ScalarType::Integer, vrs, values, Value::Integer)
    }

    /// `fmi2SetBoolean` (any non-zero `fmi2Boolean` is true).
    pub fn set_boolean(&mut self, function: &str, vrs: &[u32], values: &[i32]) -> Status {
        self.set_values(function, ScalarType::Boolean, vrs, values, |v| {
            Value::Boolean(v != 0)
        })
    }

    /// `fmi2SetString` (the strings are copied).
    pub fn set_string(&mut self, function: &str, vrs: &[u32], values: &[String]) -> Status {
        let mut changes = Vec::with_capacity(vrs.len());
        for (vr, v) in vrs.iter().zip(values) {
            match self.check_set(function, *vr, ScalarType::String, Value::String(v.clone())) {
                Ok(c) => changes.push(c),
                Err(s) => return s,
            }
        }
        self.commit(function, changes)
    }

    /// `fmi2DoStep`: integrates from `t` to exactly `t + h` with the inputs held.
    pub fn do_step(&mut self, function: &str, t: f64, h: f64) -> Status {
        if !(h.is_finite() && h > 0.0) {
            return self.error(&format!(
                "{function}: communicationStepSize = {h} must be finite and > 0"
            ));
        }
        let tolerance = TIME_TOLERANCE * self.time.abs().max(t.abs()).max(h);
        if !t.is_finite() || (t - self.time).abs() > tolerance {
            let now = self.time;
            return self.error(&format!(
                "{function}: currentCommunicationPoint = {t} is not the instance's current time {now} (tolerance {tolerance:e})"
            ));
        }
        let target = t + h;
        if let Some(stop) = self.stop_time
            && target > stop + TIME_TOLERANCE * stop.abs().max(h)
        {
            return self.error(&format!(
                "{function}: t + h = {target} is beyond stopTime = {stop}"
            ));
        }
        let start = self.start_time;
        let torso = match self.ensure_torso() {
            Ok(t) => t,
            Err(e) => {
                self.phase = Phase::Error;
                return self.error(&format!("{function}: {e}"));
            }
        };
        // `t` may lie up to the tolerance before the instance's time, and a tiny step may then
        // end before the model's time: the model stays where it is (it cannot step back), the
        // instance's time becomes `t + h`. A step that leaves the physiological bounds is
        // rolled back by the model and discarded here.
        let model_target = (target - start).max(torso.time());
        let options = AdvanceOptions {
            check_physiology: true,
        };
        let advanced = torso.advance_to_with(model_target, options);
        let stiff = match &advanced {
            Err(Error::Unphysiological {
                stiffness_detected, ..
            }) => *stiffness_detected,
            _ => torso.stiffness_detected(),
        };
        if stiff && !self.stiffness_logged {
            self.stiffness_logged = true;
            // A hint, not a warning: the step succeeded and returns Status::Ok.
            self.log(
                Status::Ok,
                Category::Events,
                &format!(
                    "{function}: the explicit solver detected stiffness near t = {target}; a stiff \
                     method is available (parameter solver.method = {}, Rosenbrock-W with a sparse \
                     Jacobian), worth trying on stiff scenes (stiff cartilage, high bulk modulus)",
                    crate::solver::Method::Rosenbrock.code()
                ),
            );
        }
        match advanced {
            Ok(_) => {
                self.time = target;
                self.last_successful_time = target;
                self.last_step_status = Status::Ok;
                Status::Ok
            }
            Err(Error::Unphysiological { reason, .. }) => self.discard(
                function,
                t,
                target,
                t,
                &format!("at t = {target}: {reason}"),
            ),
            Err(Error::Numerical { time, reason }) => {
                self.discard(function, t, target, start + time, &reason)
            }
            Err(e) => {
                self.phase = Phase::Error;
                self.error(&format!("{function}: {e}"))
            }
        }
    }

    /// Ends a step with [`Status::Discard`]: the model stays at `at`, the reason is logged.
    fn discard(&mut self, function: &str, t: f64, target: f64, at: f64, reason: &str) -> Status {
        self.time = at;
        self.last_successful_time = at;
        self.last_step_status = Status::Discard;
        self.phase = Phase::StepFailed;
        let message = format!(
            "{function}: step from {t} to {target} discarded: {reason}; the model stays at its last successful time {at}"
        );
        self.log(Status::Discard, Category::Discard, &message);
        Status::Discard
    }

    /// The status of the last communication step: [`Status::Discard`] after a discarded
    /// step, else [`Status::Ok`] (FMI 2.0's `fmi2DoStepStatus`).
    pub fn last_step_status(&self) -> Status {
        self.last_step_status
    }

    /// The time the model last reached successfully [s] (FMI 2.0's
    /// `fmi2LastSuccessfulTime`).
    pub fn last_successful_time(&self) -> f64 {
        self.last_successful_time
    }

    /// A saved state of the whole instance.
    pub fn get_fmu_state(&mut self) -> FmuState {
        FmuState {
            saved: Saved {
                guid: self.table.guid().to_string(),
                phase: self.phase,
                config: self.config.clone(),
                rtol_explicit: self.rtol_explicit,
                inputs: self.inputs.to_vec(),
                start_time: self.start_time,
                stop_time: self.stop_time,
                tolerance: self.tolerance,
                time: self.time,
                last_successful_time: self.last_successful_time,
                last_step_discarded: self.last_step_status == Status::Discard,
                has_snapshot: self.torso.is_some(),
            },
            snapshot: self.torso.as_ref().map(Torso::snapshot),
        }
    }

    /// Restores a saved state. Once initialised, an instance refuses ([`Status::Error`], nothing
    /// changes) a state saved with other fixed parameters, as it refuses setting them: the
    /// model is the one its parameters built. Before `fmi2ExitInitializationMode`, when fixed
    /// parameters may still be set, the state's are taken and the model is rebuilt when they
    /// differ. A state holds `slp.reference` and `subject.mesh_dir` as they were given, so a
    /// state saved by an instance unpacked in one folder applies in an instance unpacked in
    /// another: a relative path names the file in this instance's resources.
    pub fn set_fmu_state(&mut self, function: &str, state: &FmuState) -> Status {
        let s = &state.saved;
        let initialised = !matches!(self.phase, Phase::Instantiated | Phase::InitializationMode);
        if initialised && !same_fixed_config(&self.config, &s.config) {
            let differences = fixed_differences(self.table, &self.config, &s.config);
            let (exit, reset) = (self.api.exit_initialization_mode, self.api.reset);
            return self.error(&format!(
                "{function}: the state was saved by an instance with other fixed parameters \
                 ({differences}); fixed parameters cannot change after \
                 {exit} ({reset} first, or instantiate with the state's \
                 parameters): the state was not applied"
            ));
        }
        let mut rebuilt_fresh = None;
        let torso = match &state.snapshot {
            None => None,
            Some(snapshot) => {
                // The state's paths are resolved against this instance's resources.
                let resolved = match self.resolved(&s.config) {
                    Ok(c) => c,
                    Err(e) => return self.error(&format!("{function}: {e}")),
                };
                let reuse =
                    matches!(&self.torso, Some(t) if same_fixed_config(t.config(), &resolved));
                let mut torso = match (reuse, self.torso.take()) {
                    (true, Some(t)) => t,
                    (_, current) => {
                        self.torso = current;
                        match self.new_torso(resolved) {
                            Ok(t) => {
                                rebuilt_fresh = Some(t.snapshot());
                                t
                            }
                            Err(e) => return self.error(&format!("{function}: {e}")),
                        }
                    }
                };
                if let Err(e) = torso.restore(snapshot) {
                    // The facade leaves a model whose restore failed as it was.
                    if reuse {
                        self.torso = Some(torso);
                    }
                    return self.error(&format!("{function}: {e}"));
                }
                Some(torso)
            }
        };
        self.torso = torso;
        if rebuilt_fresh.is_some() {
            // The fresh snapshot kept for fmi2Reset must be the rebuilt model's.
            self.fresh = rebuilt_fresh;
        }
        self.phase = s.phase;
        self.config = s.config.clone();
        self.rtol_explicit = s.rtol_explicit;
        self.inputs.copy_from_slice(&s.inputs);
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.tolerance = s.tolerance;
        self.time = s.time;
        self.last_successful_time = s.last_successful_time;
        self.last_step_status = if s.last_step_discarded {
            Status::Discard
        } else {
            Status::Ok
        };
        Status::Ok
    }
}
