//! The FMI 3.0 functions (common and co-simulation), exported unmangled from the same cdylib
//! as the FMI 2.0 ones. Each is a thin translation over the same version-neutral [`Instance`]
//! and the same guard ([`crate::fmi::guard`]: panics caught, pointers checked, the call
//! checked against the state machine's mask, `logCalls` tracing): value references are
//! translated through the FMI 3.0 view of the table ([`super::view`]: the marker array expands
//! to its 180 elements, Enumerations are read and set as `Int64`), the instance is told the
//! FMI 3.0 name of the function it serves, and the neutral status becomes `fmi3Status`.
//!
//! Not provided, each one line of [`not_provided!`] returning `fmi3Error` with a log line
//! saying so: event mode, the configuration mode (no structural parameters), output
//! derivatives, directional and adjoint derivatives, `fmi3GetVariableDependencies` (the
//! dependencies are in `<ModelStructure>`), clocks, and the functions of model exchange and
//! scheduled execution (exported all the same: importers resolve every function of the
//! standard when they load the library); model exchange and scheduled execution instantiate
//! nothing (NULL, with a log line). The getters and setters of types without variables are one
//! line each of [`no_variables!`].

#![allow(non_snake_case)]

use super::types::*;
use super::view::{Type3, expand, with_article};
use crate::fmi::guard::{
    self, null_argument, show, show_strings, slice, slice_mut, string, with_instance,
};
use crate::fmi::instance::{Instance, LogSink, Phase, mask};
use crate::fmi::status::{FMI3, Status};
use crate::fmi::variables::table;
use std::ffi::CString;
use std::os::raw::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

/// An FMI 3.0 function this FMU does not provide: `fmi3Error`, logged with `why`, in any
/// state.
///
/// # Safety
/// `instance` must be null or a pointer returned by [`fmi3InstantiateCoSimulation`] and not
/// freed.
unsafe fn not_provided(instance: fmi3Instance, function: &str, why: &str) -> fmi3Status {
    unsafe {
        with_instance(instance, function, mask::ANY, String::new, |inst| {
            inst.error(&format!("{function}: not provided: {why}"))
        })
    }
}

/// Exports FMI 3.0 functions this FMU does not provide, one line each:
/// `name(arguments after the instance) => why;`. Each logs `name: not provided: why` and
/// returns `fmi3Error` ([`not_provided`]). The arguments are spelled as the standard's header
/// declares them, so that the exported symbol has the standard's signature
/// (`tests/fmi3_headers.rs` compiles the same lines against the official header).
macro_rules! not_provided {
    ($($name:ident($($arg:ident: $ty:ty),*) => $why:expr;)*) => {$(
        #[doc = concat!("`", stringify!($name), "`: not provided; `fmi3Error` with a log line ",
            "saying why.\n\n# Safety\nFMI 3.0 calling conventions.")]
        #[unsafe(no_mangle)]
        #[allow(clippy::too_many_arguments)]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, $($arg: $ty),*) -> fmi3Status {
            $(let _ = $arg;)*
            unsafe { not_provided(instance, stringify!($name), $why) }
        }
    )*};
}

/// Getters and setters of a type this FMU has no variable of: no value reference is valid.
///
/// # Safety
/// FMI 3.0 calling conventions.
unsafe fn no_variables_of(
    instance: fmi3Instance,
    function: &str,
    ty: &str,
    mask: u8,
    vr: *const fmi3ValueReference,
    nvr: usize,
) -> fmi3Status {
    unsafe {
        let args = || format!("vr={}, nvr={nvr}", show(vr, nvr));
        with_instance(instance, function, mask, args, |inst| {
            match slice(vr, nvr) {
                None => null_argument(inst, function, "valueReferences[]"),
                Some([]) => Status::Ok,
                Some([first, ..]) => inst.error(&format!(
                    "{function}: value reference {first} is not {} variable: this FMU has none",
                    with_article(ty)
                )),
            }
        })
    }
}

/// Exports the getters and setters of types this FMU has no variable of, one line each:
/// `name(arguments after the value references) => MASK, "Type";` ([`no_variables_of`]: an
/// empty list of value references is fine, any value reference an error naming the type).
macro_rules! no_variables {
    ($($name:ident($($arg:ident: $ty:ty),*) => $mask:ident, $type_name:literal;)*) => {$(
        #[doc = concat!("`", stringify!($name), "`: this FMU has no ", $type_name,
            " variables.\n\n# Safety\nFMI 3.0 calling conventions.")]
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(
            instance: fmi3Instance,
            valueReferences: *const fmi3ValueReference,
            nValueReferences: usize,
            $($arg: $ty),*
        ) -> fmi3Status {
            $(let _ = $arg;)*
            unsafe {
                no_variables_of(
                    instance,
                    stringify!($name),
                    $type_name,
                    mask::$mask,
                    valueReferences,
                    nValueReferences,
                )
            }
        }
    )*};
}

fn make_sink(
    logger: unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String),
    env: fmi3InstanceEnvironment,
) -> LogSink {
    Box::new(move |status: Status, category: &str, message: &str| {
        let category = CString::new(category).unwrap_or_default();
        let message = CString::new(message.replace('\0', "")).unwrap_or_default();
        // SAFETY: the importer's logger, with two NUL-terminated strings.
        unsafe { logger(env, status.into(), category.as_ptr(), message.as_ptr()) };
    })
}

/// Logs once through `logger`, outside any instance (instantiation failures).
///
/// # Safety
/// `logger`, if any, must be callable with `env`.
unsafe fn log_without_instance(
    logger: fmi3LogMessageCallback,
    env: fmi3InstanceEnvironment,
    message: &str,
) {
    if let Some(logger) = logger {
        let message = CString::new(message.replace('\0', "")).unwrap_or_default();
        // SAFETY: as documented by the caller.
        unsafe {
            logger(
                env,
                fmi3Status::fmi3Error,
                c"logStatusError".as_ptr(),
                message.as_ptr(),
            )
        };
    }
}

// ---------------------------------------------------------------------------------------------
// Inquire version; logging

/// `fmi3GetVersion`: `"3.0"`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// `fmi3SetDebugLogging`: switches the named categories (all when `nCategories` is 0).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    nCategories: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    const F: &str = "fmi3SetDebugLogging";
    unsafe {
        let args = || {
            format!(
                "loggingOn={loggingOn}, nCategories={nCategories}, categories={}",
                show_strings(categories, nCategories)
            )
        };
        with_instance(instance, F, mask::SET_DEBUG_LOGGING, args, |inst| {
            guard::set_debug_logging(inst, F, loggingOn, categories, nCategories)
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Creation and destruction

/// `fmi3InstantiateModelExchange`: NULL (co-simulation only), logged.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    let _ = (
        instanceName,
        instantiationToken,
        resourcePath,
        visible,
        loggingOn,
    );
    let _ = catch_unwind(AssertUnwindSafe(|| unsafe {
        log_without_instance(
            logMessage,
            instanceEnvironment,
            "fmi3InstantiateModelExchange: this FMU supports co-simulation only",
        )
    }));
    std::ptr::null_mut()
}

/// `fmi3InstantiateScheduledExecution`: NULL (co-simulation only), logged.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    clockUpdate: fmi3ClockUpdateCallback,
    lockPreemption: fmi3LockPreemptionCallback,
    unlockPreemption: fmi3UnlockPreemptionCallback,
) -> fmi3Instance {
    let _ = (
        instanceName,
        instantiationToken,
        resourcePath,
        visible,
        loggingOn,
    );
    let _ = (clockUpdate, lockPreemption, unlockPreemption);
    let _ = catch_unwind(AssertUnwindSafe(|| unsafe {
        log_without_instance(
            logMessage,
            instanceEnvironment,
            "fmi3InstantiateScheduledExecution: this FMU supports co-simulation only",
        )
    }));
    std::ptr::null_mut()
}

/// `fmi3InstantiateCoSimulation`: NULL (after logging why) on a wrong instantiation token, a
/// missing name, event mode requested (`hasEventMode` is false), intermediate variables
/// requested (`providesIntermediateUpdate` is false), or an internal failure.
/// `resourcePath` is the native path of the FMU's `resources/` folder (may be NULL).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    earlyReturnAllowed: fmi3Boolean,
    requiredIntermediateVariables: *const fmi3ValueReference,
    nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    intermediateUpdate: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    let _ = (requiredIntermediateVariables, intermediateUpdate);
    let result = catch_unwind(AssertUnwindSafe(|| unsafe {
        let name = string(instanceName).unwrap_or_default();
        let fail = |message: String| {
            log_without_instance(
                logMessage,
                instanceEnvironment,
                &format!("fmi3InstantiateCoSimulation: {message}"),
            );
            std::ptr::null_mut()
        };
        if name.is_empty() {
            return fail("instanceName must be a non-empty string".into());
        }
        let token = string(instantiationToken);
        if token.as_deref() != Some(table().guid()) {
            return fail(format!(
                "instantiationToken {} does not match this FMU's {}: the model description and the binary differ",
                token.as_deref().unwrap_or("(null)"),
                table().guid()
            ));
        }
        if eventModeUsed {
            return fail(
                "eventModeUsed = true, but this FMU has no event mode (hasEventMode=\"false\")"
                    .into(),
            );
        }
        if nRequiredIntermediateVariables > 0 {
            return fail(format!(
                "{nRequiredIntermediateVariables} intermediate variables requested, but this FMU provides no intermediate update (providesIntermediateUpdate=\"false\")"
            ));
        }
        let resources = string(resourcePath)
            .filter(|p| !p.is_empty())
            .map(PathBuf::from);
        let sink = logMessage.map(|l| make_sink(l, instanceEnvironment));
        let mut inst = Instance::new(&FMI3, &name, resources.clone(), sink, loggingOn);
        inst.trace(|| {
            format!(
                "fmi3InstantiateCoSimulation(instanceName={name:?}, instantiationToken={:?}, resourcePath={resources:?}, visible={visible}, loggingOn={loggingOn}, eventModeUsed={eventModeUsed}, earlyReturnAllowed={earlyReturnAllowed}, nRequiredIntermediateVariables={nRequiredIntermediateVariables})",
                token.as_deref().unwrap_or_default()
            )
        });
        Box::into_raw(Box::new(inst)) as fmi3Instance
    }));
    result.unwrap_or(std::ptr::null_mut())
}

/// `fmi3FreeInstance`: releases the instance and the FMU states it still holds.
///
/// # Safety
/// `instance` must be null or an instance not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    if instance.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: created by Box::into_raw in fmi3InstantiateCoSimulation.
        let mut inst = unsafe { Box::from_raw(instance as *mut Instance) };
        inst.trace(|| "fmi3FreeInstance()".into());
        guard::free_states(&mut inst);
    }));
}

// ---------------------------------------------------------------------------------------------
// Initialization, termination, reset

/// `fmi3EnterInitializationMode`: the experiment (tolerance, start and stop time, as
/// `fmi2SetupExperiment` takes them), then initialization mode.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    toleranceDefined: fmi3Boolean,
    tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3EnterInitializationMode";
    unsafe {
        let args = || {
            format!(
                "toleranceDefined={toleranceDefined}, tolerance={tolerance}, startTime={startTime}, stopTimeDefined={stopTimeDefined}, stopTime={stopTime}"
            )
        };
        with_instance(instance, F, mask::ENTER_INITIALIZATION_MODE, args, |inst| {
            let tol = toleranceDefined.then_some(tolerance);
            let stop = stopTimeDefined.then_some(stopTime);
            let experiment = inst.setup_experiment(F, tol, startTime, stop);
            if experiment > Status::Warning {
                return experiment;
            }
            experiment.max(inst.enter_initialization_mode())
        })
    }
}

/// `fmi3ExitInitializationMode`: builds the model and enters step mode.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with_instance(
            instance,
            "fmi3ExitInitializationMode",
            mask::EXIT_INITIALIZATION_MODE,
            String::new,
            |inst| inst.exit_initialization_mode("fmi3ExitInitializationMode"),
        )
    }
}

/// `fmi3Terminate`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with_instance(
            instance,
            "fmi3Terminate",
            mask::TERMINATE,
            String::new,
            Instance::terminate,
        )
    }
}

/// `fmi3Reset`: back to the freshly instantiated state.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with_instance(
            instance,
            "fmi3Reset",
            mask::RESET,
            String::new,
            Instance::reset,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Getting and setting variable values

/// Shared body of the typed getters: the value references are expanded through the FMI 3.0
/// view, `nValues` must be the number of values they hold, `get` reads them into a buffer of
/// the instance layer's type, `convert` writes them out.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[allow(clippy::too_many_arguments)]
unsafe fn get3<T, U: Clone>(
    instance: fmi3Instance,
    function: &'static str,
    ty: Type3,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    nValues: usize,
    init: U,
    get: impl FnOnce(&mut Instance, &str, &[u32], &mut [U]) -> Status,
    convert: impl Fn(U) -> T,
) -> fmi3Status {
    unsafe {
        let args = || format!("vr={}, nvr={nvr}, nValues={nValues}", show(vr, nvr));
        with_instance(instance, function, mask::GET_VALUES, args, |inst| {
            let Some(vrs) = slice(vr, nvr) else {
                return null_argument(inst, function, "valueReferences[]");
            };
            let flat = match expand(vrs, ty) {
                Ok(f) => f,
                Err(e) => return inst.error(&format!("{function}: {e}")),
            };
            if flat.len() != nValues {
                return inst.error(&format!(
                    "{function}: nValues = {nValues}, but the {nvr} value references hold {} values",
                    flat.len()
                ));
            }
            let Some(out) = slice_mut(values, nValues) else {
                return null_argument(inst, function, "values[]");
            };
            let mut buffer = vec![init; nValues];
            let status = get(inst, function, &flat, &mut buffer);
            if status == Status::Ok {
                for (o, b) in out.iter_mut().zip(buffer) {
                    *o = convert(b);
                }
            }
            status
        })
    }
}

/// Shared body of the typed setters, the mirror of [`get3`]; `convert` may refuse a value
/// (the message names the variable) before anything is set.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[allow(clippy::too_many_arguments)]
unsafe fn set3<T: Copy + std::fmt::Debug, U>(
    instance: fmi3Instance,
    function: &'static str,
    ty: Type3,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    nValues: usize,
    convert: impl Fn(u32, T) -> Result<U, String>,
    set: impl FnOnce(&mut Instance, &str, &[u32], &[U]) -> Status,
) -> fmi3Status {
    unsafe {
        let args = || {
            format!(
                "vr={}, nvr={nvr}, values={}, nValues={nValues}",
                show(vr, nvr),
                show(values, nValues)
            )
        };
        with_instance(instance, function, mask::SET_VALUES, args, |inst| {
            let Some(vrs) = slice(vr, nvr) else {
                return null_argument(inst, function, "valueReferences[]");
            };
            let flat = match expand(vrs, ty) {
                Ok(f) => f,
                Err(e) => return inst.error(&format!("{function}: {e}")),
            };
            if flat.len() != nValues {
                return inst.error(&format!(
                    "{function}: nValues = {nValues}, but the {nvr} value references hold {} values",
                    flat.len()
                ));
            }
            let Some(given) = slice(values, nValues) else {
                return null_argument(inst, function, "values[]");
            };
            let mut converted = Vec::with_capacity(nValues);
            for (&vr, &v) in flat.iter().zip(given) {
                match convert(vr, v) {
                    Ok(u) => converted.push(u),
                    Err(e) => {
                        return inst.error(&format!("{function}: {e}; nothing was set"));
                    }
                }
            }
            set(inst, function, &flat, &converted)
        })
    }
}

fn same<T>(_: u32, v: T) -> Result<T, String> {
    Ok(v)
}

/// `fmi3GetFloat64`: Float64 variables and the marker array (180 values, row-major).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get3(
            instance,
            "fmi3GetFloat64",
            Type3::Float64,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            0.0,
            Instance::get_real,
            |x| x,
        )
    }
}

/// `fmi3SetFloat64`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set3(
            instance,
            "fmi3SetFloat64",
            Type3::Float64,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            same,
            Instance::set_real,
        )
    }
}

/// `fmi3GetInt32`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get3(
            instance,
            "fmi3GetInt32",
            Type3::Int32,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            0,
            Instance::get_integer,
            |x| x,
        )
    }
}

/// `fmi3SetInt32`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set3(
            instance,
            "fmi3SetInt32",
            Type3::Int32,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            same,
            Instance::set_integer,
        )
    }
}

/// `fmi3GetInt64`: the Enumerations (sex, posture, solver method), by code.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get3(
            instance,
            "fmi3GetInt64",
            Type3::Enumeration(0),
            valueReferences,
            nValueReferences,
            values,
            nValues,
            0,
            Instance::get_integer,
            i64::from,
        )
    }
}

/// `fmi3SetInt64`: the Enumerations, by code (a value outside the enumeration's items is
/// refused, naming the variable and its items' range).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set3(
            instance,
            "fmi3SetInt64",
            Type3::Enumeration(0),
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |vr, v: i64| {
                i32::try_from(v).map_err(|_| {
                    let var = table().by_vr(vr);
                    let name = var.map(|v| v.name.as_str()).unwrap_or_default();
                    let (lo, hi) = var.map_or((0.0, 0.0), |v| {
                        (v.min.unwrap_or_default(), v.max.unwrap_or_default())
                    });
                    format!("`{name}` = {v} is not one of its enumeration's codes [{lo}, {hi}]")
                })
            },
            Instance::set_integer,
        )
    }
}

/// `fmi3GetBoolean`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get3(
            instance,
            "fmi3GetBoolean",
            Type3::Boolean,
            valueReferences,
            nValueReferences,
            values as *mut u8,
            nValues,
            0,
            Instance::get_boolean,
            |x| u8::from(x != 0),
        )
    }
}

/// `fmi3SetBoolean` (the values are read as bytes: any non-zero byte is true).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set3(
            instance,
            "fmi3SetBoolean",
            Type3::Boolean,
            valueReferences,
            nValueReferences,
            values as *const u8,
            nValues,
            |_, v: u8| Ok(i32::from(v != 0)),
            Instance::set_boolean,
        )
    }
}

/// `fmi3GetString`: the pointers stay valid until the next string-returning call on the
/// instance.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3String,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get3(
            instance,
            "fmi3GetString",
            Type3::String,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            std::ptr::null(),
            Instance::get_string,
            |x| x,
        )
    }
}

/// `fmi3SetString` (the strings are copied).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3String,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set3(
            instance,
            "fmi3SetString",
            Type3::String,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |vr, p: fmi3String| {
                string(p).ok_or_else(|| {
                    let name = table()
                        .by_vr(vr)
                        .map(|v| v.name.as_str())
                        .unwrap_or_default();
                    format!("the value of `{name}` is NULL or not UTF-8")
                })
            },
            Instance::set_string,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// FMU state

/// `fmi3GetFMUState`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    const F: &str = "fmi3GetFMUState";
    unsafe {
        let args = || format!("FMUState={FMUState:?}");
        with_instance(instance, F, mask::GET_FMU_STATE, args, |inst| {
            guard::get_state(inst, F, "FMUState", FMUState)
        })
    }
}

/// `fmi3SetFMUState`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
) -> fmi3Status {
    const F: &str = "fmi3SetFMUState";
    unsafe {
        let args = || format!("FMUState={FMUState:?}");
        with_instance(instance, F, mask::SET_FMU_STATE, args, |inst| {
            guard::set_state(inst, F, "FMUState", FMUState)
        })
    }
}

/// `fmi3FreeFMUState`: frees `*FMUState` and sets it to NULL.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    const F: &str = "fmi3FreeFMUState";
    unsafe {
        let args = || format!("FMUState={FMUState:?}");
        with_instance(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            guard::free_state(inst, F, "FMUState", FMUState)
        })
    }
}

/// `fmi3SerializedFMUStateSize`.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    const F: &str = "fmi3SerializedFMUStateSize";
    unsafe {
        let args = || format!("FMUState={FMUState:?}");
        with_instance(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            guard::serialized_size(inst, F, "FMUState", FMUState, size)
        })
    }
}

/// `fmi3SerializeFMUState`: the same self-contained, versioned byte form as FMI 2.0's.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    serializedState: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    const F: &str = "fmi3SerializeFMUState";
    unsafe {
        let args = || format!("FMUState={FMUState:?}, size={size}");
        with_instance(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            guard::serialize(inst, F, "FMUState", FMUState, serializedState, size)
        })
    }
}

/// `fmi3DeserializeFMUState`: anything but a state written by this FMU is an error.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serializedState: *const fmi3Byte,
    size: usize,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    const F: &str = "fmi3DeserializeFMUState";
    unsafe {
        let args = || format!("size={size}");
        with_instance(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            guard::deserialize(inst, F, "FMUState", serializedState, size, FMUState)
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Co-simulation

/// `fmi3DoStep`: integrates from `currentCommunicationPoint` to exactly
/// `currentCommunicationPoint + communicationStepSize`. Never needs event handling nor
/// returns early; `terminateSimulation` is true after a discarded step (the model stays at
/// `lastSuccessfulTime` and cannot go on without `fmi3SetFMUState` or `fmi3Reset`).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3DoStep";
    unsafe {
        let args = || {
            format!(
                "currentCommunicationPoint={currentCommunicationPoint}, communicationStepSize={communicationStepSize}, noSetFMUStatePriorToCurrentPoint={noSetFMUStatePriorToCurrentPoint}"
            )
        };
        with_instance(instance, F, mask::DO_STEP, args, |inst| {
            for (p, name) in [
                (eventHandlingNeeded, "eventHandlingNeeded"),
                (terminateSimulation, "terminateSimulation"),
                (earlyReturn, "earlyReturn"),
            ] {
                if p.is_null() {
                    return null_argument(inst, F, name);
                }
            }
            if lastSuccessfulTime.is_null() {
                return null_argument(inst, F, "lastSuccessfulTime");
            }
            let status = inst.do_step(F, currentCommunicationPoint, communicationStepSize);
            *eventHandlingNeeded = false;
            *earlyReturn = false;
            *terminateSimulation = inst.phase() == Phase::StepFailed;
            *lastSuccessfulTime = inst.time();
            status
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Getters and setters of the types this FMU has no variable of, one line each:
// `name(arguments after the value references) => the state mask, the type`.

#[rustfmt::skip]
no_variables! {
    fmi3GetFloat32(values: *mut fmi3Float32, nValues: usize) => GET_VALUES, "Float32";
    fmi3SetFloat32(values: *const fmi3Float32, nValues: usize) => SET_VALUES, "Float32";
    fmi3GetInt8(values: *mut fmi3Int8, nValues: usize) => GET_VALUES, "Int8";
    fmi3SetInt8(values: *const fmi3Int8, nValues: usize) => SET_VALUES, "Int8";
    fmi3GetUInt8(values: *mut fmi3UInt8, nValues: usize) => GET_VALUES, "UInt8";
    fmi3SetUInt8(values: *const fmi3UInt8, nValues: usize) => SET_VALUES, "UInt8";
    fmi3GetInt16(values: *mut fmi3Int16, nValues: usize) => GET_VALUES, "Int16";
    fmi3SetInt16(values: *const fmi3Int16, nValues: usize) => SET_VALUES, "Int16";
    fmi3GetUInt16(values: *mut fmi3UInt16, nValues: usize) => GET_VALUES, "UInt16";
    fmi3SetUInt16(values: *const fmi3UInt16, nValues: usize) => SET_VALUES, "UInt16";
    fmi3GetUInt32(values: *mut fmi3UInt32, nValues: usize) => GET_VALUES, "UInt32";
    fmi3SetUInt32(values: *const fmi3UInt32, nValues: usize) => SET_VALUES, "UInt32";
    fmi3GetUInt64(values: *mut fmi3UInt64, nValues: usize) => GET_VALUES, "UInt64";
    fmi3SetUInt64(values: *const fmi3UInt64, nValues: usize) => SET_VALUES, "UInt64";
    fmi3GetBinary(valueSizes: *mut usize, values: *mut fmi3Binary, nValues: usize) => GET_VALUES, "Binary";
    fmi3SetBinary(valueSizes: *const usize, values: *const fmi3Binary, nValues: usize) => SET_VALUES, "Binary";
}

// ---------------------------------------------------------------------------------------------
// Not provided, one line each: `name(arguments after the instance) => why`. Exported all the
// same, because importers (fmpy among them) resolve every function of the standard when they
// load the library.

const NO_CLOCKS: &str = "the model has no clocks";
const NO_MODEL_EXCHANGE: &str = "this FMU supports co-simulation only";

#[rustfmt::skip]
not_provided! {
    fmi3EnterEventMode() => "the model has no events (hasEventMode=\"false\")";
    fmi3GetNumberOfVariableDependencies(valueReference: fmi3ValueReference, nDependencies: *mut usize) => "the dependencies are declared in <ModelStructure> of modelDescription.xml";
    fmi3GetVariableDependencies(dependent: fmi3ValueReference, elementIndicesOfDependent: *mut usize, independents: *mut fmi3ValueReference, elementIndicesOfIndependents: *mut usize, dependencyKinds: *mut fmi3DependencyKind, nDependencies: usize) => "the dependencies are declared in <ModelStructure> of modelDescription.xml";
    fmi3GetDirectionalDerivative(unknowns: *const fmi3ValueReference, nUnknowns: usize, knowns: *const fmi3ValueReference, nKnowns: usize, seed: *const fmi3Float64, nSeed: usize, sensitivity: *mut fmi3Float64, nSensitivity: usize) => "providesDirectionalDerivatives is false";
    fmi3GetAdjointDerivative(unknowns: *const fmi3ValueReference, nUnknowns: usize, knowns: *const fmi3ValueReference, nKnowns: usize, seed: *const fmi3Float64, nSeed: usize, sensitivity: *mut fmi3Float64, nSensitivity: usize) => "providesAdjointDerivatives is false";
    fmi3EnterConfigurationMode() => "the model has no structural parameters";
    fmi3ExitConfigurationMode() => "the model has no structural parameters";
    fmi3EnterStepMode() => "the model has no event mode; it is in step mode after fmi3ExitInitializationMode";
    fmi3GetOutputDerivatives(valueReferences: *const fmi3ValueReference, nValueReferences: usize, orders: *const fmi3Int32, values: *mut fmi3Float64, nValues: usize) => "maxOutputDerivativeOrder is 0";
    fmi3GetClock(valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Clock) => NO_CLOCKS;
    fmi3SetClock(valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Clock) => NO_CLOCKS;
    fmi3GetIntervalDecimal(valueReferences: *const fmi3ValueReference, nValueReferences: usize, intervals: *mut fmi3Float64, qualifiers: *mut fmi3IntervalQualifier) => NO_CLOCKS;
    fmi3GetIntervalFraction(valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64, qualifiers: *mut fmi3IntervalQualifier) => NO_CLOCKS;
    fmi3GetShiftDecimal(valueReferences: *const fmi3ValueReference, nValueReferences: usize, shifts: *mut fmi3Float64) => NO_CLOCKS;
    fmi3GetShiftFraction(valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64) => NO_CLOCKS;
    fmi3SetIntervalDecimal(valueReferences: *const fmi3ValueReference, nValueReferences: usize, intervals: *const fmi3Float64) => NO_CLOCKS;
    fmi3SetIntervalFraction(valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64) => NO_CLOCKS;
    fmi3SetShiftDecimal(valueReferences: *const fmi3ValueReference, nValueReferences: usize, shifts: *const fmi3Float64) => NO_CLOCKS;
    fmi3SetShiftFraction(valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64) => NO_CLOCKS;
    fmi3EvaluateDiscreteStates() => "providesEvaluateDiscreteStates is false";
    fmi3UpdateDiscreteStates(discreteStatesNeedUpdate: *mut fmi3Boolean, terminateSimulation: *mut fmi3Boolean, nominalsOfContinuousStatesChanged: *mut fmi3Boolean, valuesOfContinuousStatesChanged: *mut fmi3Boolean, nextEventTimeDefined: *mut fmi3Boolean, nextEventTime: *mut fmi3Float64) => "the model has no event mode";
    fmi3EnterContinuousTimeMode() => NO_MODEL_EXCHANGE;
    fmi3CompletedIntegratorStep(noSetFMUStatePriorToCurrentPoint: fmi3Boolean, enterEventMode: *mut fmi3Boolean, terminateSimulation: *mut fmi3Boolean) => NO_MODEL_EXCHANGE;
    fmi3SetTime(time: fmi3Float64) => NO_MODEL_EXCHANGE;
    fmi3SetContinuousStates(continuousStates: *const fmi3Float64, nContinuousStates: usize) => NO_MODEL_EXCHANGE;
    fmi3GetContinuousStateDerivatives(derivatives: *mut fmi3Float64, nContinuousStates: usize) => NO_MODEL_EXCHANGE;
    fmi3GetEventIndicators(eventIndicators: *mut fmi3Float64, nEventIndicators: usize) => NO_MODEL_EXCHANGE;
    fmi3GetContinuousStates(continuousStates: *mut fmi3Float64, nContinuousStates: usize) => NO_MODEL_EXCHANGE;
    fmi3GetNominalsOfContinuousStates(nominals: *mut fmi3Float64, nContinuousStates: usize) => NO_MODEL_EXCHANGE;
    fmi3GetNumberOfEventIndicators(nEventIndicators: *mut usize) => NO_MODEL_EXCHANGE;
    fmi3GetNumberOfContinuousStates(nContinuousStates: *mut usize) => NO_MODEL_EXCHANGE;
    fmi3ActivateModelPartition(clockReference: fmi3ValueReference, activationTime: fmi3Float64) => NO_MODEL_EXCHANGE;
}
