//! The status of an FMU call in neither version's spelling: the instance layer
//! ([`super::instance`]) answers with a [`Status`], and each interface's exported functions
//! translate it into their own (`fmi2Status` in [`super::ffi`], `fmi3Status` in
//! [`super::fmi3::ffi`]). The five values and their order are those both standards share.

use super::fmi3::types::fmi3Status;
use super::types::fmi2Status;

/// The result of a call on an instance, ordered from best to worst (so that the worse of two
/// statuses is their `max`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// All well.
    Ok,
    /// Things are not quite right, but the computation can continue.
    Warning,
    /// The step could not be completed; the instance stays at its last successful time.
    Discard,
    /// The call failed; the logger was told why.
    Error,
    /// The instance is unusable.
    Fatal,
}

impl From<Status> for fmi2Status {
    fn from(s: Status) -> fmi2Status {
        match s {
            Status::Ok => fmi2Status::fmi2OK,
            Status::Warning => fmi2Status::fmi2Warning,
            Status::Discard => fmi2Status::fmi2Discard,
            Status::Error => fmi2Status::fmi2Error,
            Status::Fatal => fmi2Status::fmi2Fatal,
        }
    }
}

impl From<Status> for fmi3Status {
    fn from(s: Status) -> fmi3Status {
        match s {
            Status::Ok => fmi3Status::fmi3OK,
            Status::Warning => fmi3Status::fmi3Warning,
            Status::Discard => fmi3Status::fmi3Discard,
            Status::Error => fmi3Status::fmi3Error,
            Status::Fatal => fmi3Status::fmi3Fatal,
        }
    }
}

/// The names an interface gives the functions the instance layer mentions in its messages
/// (what to call next, or what was not called), so that a message reads in the caller's
/// version of the standard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Api {
    /// The function that creates a co-simulation instance.
    pub instantiate: &'static str,
    /// The function that ends initialization.
    pub exit_initialization_mode: &'static str,
    /// The function that resets an instance.
    pub reset: &'static str,
}

/// FMI 2.0's names.
pub const FMI2: Api = Api {
    instantiate: "fmi2Instantiate",
    exit_initialization_mode: "fmi2ExitInitializationMode",
    reset: "fmi2Reset",
};

/// FMI 3.0's names.
pub const FMI3: Api = Api {
    instantiate: "fmi3InstantiateCoSimulation",
    exit_initialization_mode: "fmi3ExitInitializationMode",
    reset: "fmi3Reset",
};
