//! The C types of the FMI 2.0 interface (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`),
//! spelled with the standard's names so that a generated declaration of our exported functions
//! can be compiled against the official headers: a typedef redefined with another type fails
//! the build (see `tests/fmi_headers.rs`).
//!
//! `fmi2Boolean` is a C `int`, enumerations are int-sized, and enumerations received from the
//! caller (`fmi2Type`, `fmi2StatusKind`) are taken as `c_int` and checked, so that an
//! out-of-range value from a foreign caller is an error rather than undefined behaviour.

#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use std::os::raw::{c_char, c_int, c_uint, c_void};

/// `fmi2Component`: the instance handle given to the master.
pub type fmi2Component = *mut c_void;
/// `fmi2ComponentEnvironment`: the master's pointer passed back to its callbacks.
pub type fmi2ComponentEnvironment = *mut c_void;
/// `fmi2FMUstate`: an opaque saved instance state.
pub type fmi2FMUstate = *mut c_void;
/// `fmi2ValueReference`.
pub type fmi2ValueReference = c_uint;
/// `fmi2Real`.
pub type fmi2Real = f64;
/// `fmi2Integer`.
pub type fmi2Integer = c_int;
/// `fmi2Boolean` (a C `int`: 0 false, anything else true).
pub type fmi2Boolean = c_int;
/// `fmi2Char`.
pub type fmi2Char = c_char;
/// `fmi2String`.
pub type fmi2String = *const fmi2Char;
/// `fmi2Byte`.
pub type fmi2Byte = c_char;

/// `fmi2True`.
pub const fmi2True: fmi2Boolean = 1;
/// `fmi2False`.
pub const fmi2False: fmi2Boolean = 0;

/// `fmi2Status`: the result of every function.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum fmi2Status {
    /// All well.
    fmi2OK = 0,
    /// Things are not quite right, but the computation can continue.
    fmi2Warning = 1,
    /// The step could not be completed (numerical failure); the instance stays at its last
    /// successful time.
    fmi2Discard = 2,
    /// The call failed; the logger was told why.
    fmi2Error = 3,
    /// The instance is unusable.
    fmi2Fatal = 4,
    /// An asynchronous step is still running (never returned here).
    fmi2Pending = 5,
}

/// `fmi2Type`, received as an `int` and checked.
pub type fmi2Type = c_int;
/// `fmi2StatusKind`, received as an `int` and checked.
pub type fmi2StatusKind = c_int;

/// `fmi2Type` value of a model-exchange instantiation (rejected: this FMU is co-simulation only).
pub const fmi2ModelExchange: fmi2Type = 0;
/// `fmi2Type` value of a co-simulation instantiation.
pub const fmi2CoSimulation: fmi2Type = 1;

/// `fmi2StatusKind` `fmi2DoStepStatus`.
pub const fmi2DoStepStatus: fmi2StatusKind = 0;
/// `fmi2StatusKind` `fmi2PendingStatus`.
pub const fmi2PendingStatus: fmi2StatusKind = 1;
/// `fmi2StatusKind` `fmi2LastSuccessfulTime`.
pub const fmi2LastSuccessfulTime: fmi2StatusKind = 2;
/// `fmi2StatusKind` `fmi2Terminated`.
pub const fmi2Terminated: fmi2StatusKind = 3;

/// `fmi2CallbackLogger`: printf-style and variadic. This crate always calls it with the format
/// `"%s"` and the message as the single argument.
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ),
>;
/// `fmi2CallbackAllocateMemory` (never called: the FMU declares
/// `canNotUseMemoryManagementFunctions`).
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
/// `fmi2CallbackFreeMemory` (never called).
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
/// `fmi2StepFinished` (never called: steps are synchronous).
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// `fmi2CallbackFunctions`, received by pointer in `fmi2Instantiate`.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct fmi2CallbackFunctions {
    /// The logger (may be null: then nothing is logged).
    pub logger: fmi2CallbackLogger,
    /// Memory allocation (unused).
    pub allocateMemory: fmi2CallbackAllocateMemory,
    /// Memory release (unused).
    pub freeMemory: fmi2CallbackFreeMemory,
    /// Asynchronous step completion (unused).
    pub stepFinished: fmi2StepFinished,
    /// The master's environment pointer, passed back to the logger.
    pub componentEnvironment: fmi2ComponentEnvironment,
}
