//! The C types of the FMI 3.0 interface (`fmi3PlatformTypes.h`, `fmi3FunctionTypes.h`),
//! spelled with the standard's names so that a generated declaration of the exported
//! `fmi3*` functions compiles against the official headers (see `tests/fmi3_headers.rs`).
//!
//! `fmi3Boolean` is C99 `bool` (one byte). Boolean arrays received from the caller are read
//! as bytes (any non-zero byte is true), so that a foreign caller's byte other than 0 or 1
//! is not undefined behaviour here.

#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use std::os::raw::{c_char, c_void};

/// `fmi3Instance`: the instance handle given to the importer.
pub type fmi3Instance = *mut c_void;
/// `fmi3InstanceEnvironment`: the importer's pointer passed back to its callbacks.
pub type fmi3InstanceEnvironment = *mut c_void;
/// `fmi3FMUState`: an opaque saved instance state.
pub type fmi3FMUState = *mut c_void;
/// `fmi3ValueReference`.
pub type fmi3ValueReference = u32;
/// `fmi3Float32`.
pub type fmi3Float32 = f32;
/// `fmi3Float64`.
pub type fmi3Float64 = f64;
/// `fmi3Int8`.
pub type fmi3Int8 = i8;
/// `fmi3UInt8`.
pub type fmi3UInt8 = u8;
/// `fmi3Int16`.
pub type fmi3Int16 = i16;
/// `fmi3UInt16`.
pub type fmi3UInt16 = u16;
/// `fmi3Int32`.
pub type fmi3Int32 = i32;
/// `fmi3UInt32`.
pub type fmi3UInt32 = u32;
/// `fmi3Int64`.
pub type fmi3Int64 = i64;
/// `fmi3UInt64`.
pub type fmi3UInt64 = u64;
/// `fmi3Boolean` (C99 `bool`).
pub type fmi3Boolean = bool;
/// `fmi3Char`.
pub type fmi3Char = c_char;
/// `fmi3String`.
pub type fmi3String = *const fmi3Char;
/// `fmi3Byte`.
pub type fmi3Byte = u8;
/// `fmi3Binary`.
pub type fmi3Binary = *const fmi3Byte;

/// `fmi3Status`: the result of every function.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum fmi3Status {
    /// All well.
    fmi3OK = 0,
    /// Things are not quite right, but the computation can continue.
    fmi3Warning = 1,
    /// The step could not be completed (numerical failure).
    fmi3Discard = 2,
    /// The call failed; the logger was told why.
    fmi3Error = 3,
    /// The instance is unusable.
    fmi3Fatal = 4,
}

/// `fmi3DependencyKind`, written by `fmi3GetVariableDependencies` (which this FMU does not
/// provide: its dependencies are in `<ModelStructure>`); taken as an `int`.
pub type fmi3DependencyKind = std::os::raw::c_int;

/// `fmi3LogMessageCallback`.
pub type fmi3LogMessageCallback =
    Option<unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String)>;

/// `fmi3IntermediateUpdateCallback` (never called: `providesIntermediateUpdate` is false).
pub type fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        fmi3InstanceEnvironment,
        fmi3Float64,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        *mut fmi3Boolean,
        *mut fmi3Float64,
    ),
>;

/// `fmi3ClockUpdateCallback` (scheduled execution, not provided).
pub type fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(fmi3InstanceEnvironment)>;
/// `fmi3LockPreemptionCallback` (scheduled execution, not provided).
pub type fmi3LockPreemptionCallback = Option<unsafe extern "C" fn()>;
/// `fmi3UnlockPreemptionCallback` (scheduled execution, not provided).
pub type fmi3UnlockPreemptionCallback = Option<unsafe extern "C" fn()>;

/// `fmi3Clock` (C99 `bool`; the model has no clocks).
pub type fmi3Clock = bool;

/// `fmi3IntervalQualifier`, taken as an `int` (the model has no clocks).
pub type fmi3IntervalQualifier = std::os::raw::c_int;
