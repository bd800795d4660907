//! The FMI 3.0 functions (common and co-simulation), exported unmangled from the same cdylib
//! as the FMI 2.0 ones. Each is a thin layer over the same [`Instance`] and the same guard as
//! [`crate::fmi::ffi`] (panics caught, pointers checked, the call checked against the state
//! machine's mask, `logCalls` tracing): value references are translated through the FMI 3.0
//! view of the table ([`super::view`]: the marker array expands to its 180 elements,
//! Enumerations are read and set as `Int64`), and the FMI 2.0 status becomes the FMI 3.0 one.
//!
//! Not provided, each returning `fmi3Error` with a log line saying so: event mode, the
//! configuration mode (no structural parameters), output derivatives, directional and adjoint
//! derivatives, `fmi3GetVariableDependencies` (the dependencies are in `<ModelStructure>`),
//! early return, intermediate update, clocks, and the functions of model exchange and
//! scheduled execution (exported all the same: importers resolve every function of the
//! standard when they load the library); model exchange and scheduled execution instantiate
//! nothing (NULL, with a log line).
//!
//! Messages of the shared instance layer name the FMI 2.0 function they were written for; the
//! logger given to `fmi3InstantiateCoSimulation` receives them with that name replaced by the
//! FMI 3.0 function being called.

#![allow(non_snake_case)]

use super::types::*;
use super::view::{Type3, expand, with_article};
use crate::fmi::ffi::{
    free_states, known, null_argument, show, show_strings, slice, slice_mut, store_state, string,
    with_instance,
};
use crate::fmi::instance::{FmuState, Instance, LogSink, Phase, mask};
use crate::fmi::types::fmi2Status;
use crate::fmi::variables::table;
use std::cell::Cell;
use std::ffi::CString;
use std::os::raw::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

use fmi2Status::{fmi2OK, fmi2Warning};

thread_local! {
    /// The FMI 3.0 function running on this thread (calls are synchronous), which the logger
    /// names in place of the FMI 2.0 name of the shared instance layer.
    static CURRENT: Cell<&'static str> = const { Cell::new("") };
}

/// FMI 2.0 functions the shared instance layer names inside its messages (as what to call
/// next), with their FMI 3.0 counterparts.
const COUNTERPARTS: [(&str, &str); 5] = [
    ("fmi2ExitInitializationMode", "fmi3ExitInitializationMode"),
    ("fmi2SetFMUstate", "fmi3SetFMUState"),
    ("fmi2Reset", "fmi3Reset"),
    ("fmi2Instantiate", "fmi3InstantiateCoSimulation"),
    ("fmi2SetupExperiment", "fmi3EnterInitializationMode"),
];

/// `message` with a leading FMI 2.0 function name replaced by the running FMI 3.0 function,
/// and the FMI 2.0 functions it mentions by their FMI 3.0 counterparts.
fn renamed(message: &str) -> String {
    let current = CURRENT.with(Cell::get);
    let mut out = match message.strip_prefix("fmi2") {
        Some(rest) if !current.is_empty() => {
            let end = rest
                .find(|c: char| !c.is_ascii_alphanumeric())
                .unwrap_or(rest.len());
            format!("{current}{}", &rest[end..])
        }
        _ => message.to_string(),
    };
    if !current.is_empty() {
        for (two, three) in COUNTERPARTS {
            out = out.replace(two, three);
        }
    }
    out
}

/// [`with_instance`] under an FMI 3.0 function name, with the FMI 3.0 status.
///
/// # Safety
/// `c` must be null or a pointer returned by [`fmi3InstantiateCoSimulation`] and not freed.
unsafe fn with3(
    c: fmi3Instance,
    function: &'static str,
    mask: u8,
    args: impl FnOnce() -> String,
    body: impl FnOnce(&mut Instance) -> fmi2Status,
) -> fmi3Status {
    CURRENT.with(|f| f.set(function));
    let status = unsafe { with_instance(c, function, mask, args, body) };
    CURRENT.with(|f| f.set(""));
    status.into()
}

/// An FMI 3.0 function this FMU does not provide: `fmi3Error`, logged with `why`.
///
/// # Safety
/// As for [`with3`].
unsafe fn not_provided(c: fmi3Instance, function: &'static str, why: &str) -> fmi3Status {
    unsafe {
        with3(c, function, mask::ANY, String::new, |inst| {
            inst.error(&format!("{function}: not provided: {why}"))
        })
    }
}

fn make_sink(
    logger: unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String),
    env: fmi3InstanceEnvironment,
) -> LogSink {
    Box::new(move |status: fmi2Status, category: &str, message: &str| {
        let category = CString::new(category).unwrap_or_default();
        let message = CString::new(renamed(message).replace('\0', "")).unwrap_or_default();
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
        with3(instance, F, mask::SET_DEBUG_LOGGING, args, |inst| {
            let Some(ptrs) = slice(categories, nCategories) else {
                return null_argument(inst, F, "categories[]");
            };
            let mut names = Vec::with_capacity(ptrs.len());
            for &p in ptrs {
                match string(p) {
                    Some(s) => names.push(s),
                    None => return inst.error(&format!("{F}: a category is NULL or not UTF-8")),
                }
            }
            let refs: Vec<&str> = names.iter().map(String::as_str).collect();
            inst.set_debug_logging(loggingOn, &refs)
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
        let mut inst = Instance::new(&name, resources.clone(), sink, loggingOn);
        CURRENT.with(|f| f.set("fmi3InstantiateCoSimulation"));
        inst.trace(|| {
            format!(
                "fmi3InstantiateCoSimulation(instanceName={name:?}, instantiationToken={:?}, resourcePath={resources:?}, visible={visible}, loggingOn={loggingOn}, eventModeUsed={eventModeUsed}, earlyReturnAllowed={earlyReturnAllowed}, nRequiredIntermediateVariables={nRequiredIntermediateVariables})",
                token.as_deref().unwrap_or_default()
            )
        });
        CURRENT.with(|f| f.set(""));
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
        free_states(&mut inst);
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
    unsafe {
        let args = || {
            format!(
                "toleranceDefined={toleranceDefined}, tolerance={tolerance}, startTime={startTime}, stopTimeDefined={stopTimeDefined}, stopTime={stopTime}"
            )
        };
        with3(
            instance,
            "fmi3EnterInitializationMode",
            mask::ENTER_INITIALIZATION_MODE,
            args,
            |inst| {
                let tol = toleranceDefined.then_some(tolerance);
                let stop = stopTimeDefined.then_some(stopTime);
                let experiment = inst.setup_experiment(tol, startTime, stop);
                if experiment > fmi2Warning {
                    return experiment;
                }
                experiment.max(inst.enter_initialization_mode())
            },
        )
    }
}

/// `fmi3ExitInitializationMode`: builds the model and enters step mode.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with3(
            instance,
            "fmi3ExitInitializationMode",
            mask::EXIT_INITIALIZATION_MODE,
            String::new,
            Instance::exit_initialization_mode,
        )
    }
}

/// `fmi3EnterEventMode`: not provided (`hasEventMode` is false).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        not_provided(
            instance,
            "fmi3EnterEventMode",
            "the model has no events (hasEventMode=\"false\")",
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
        with3(
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
        with3(
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
    get: impl FnOnce(&mut Instance, &[u32], &mut [U]) -> fmi2Status,
    convert: impl Fn(U) -> T,
) -> fmi3Status {
    unsafe {
        let args = || format!("vr={}, nvr={nvr}, nValues={nValues}", show(vr, nvr));
        with3(instance, function, mask::GET_VALUES, args, |inst| {
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
            let status = get(inst, &flat, &mut buffer);
            if status == fmi2OK {
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
    set: impl FnOnce(&mut Instance, &[u32], &[U]) -> fmi2Status,
) -> fmi3Status {
    unsafe {
        let args = || {
            format!(
                "vr={}, nvr={nvr}, values={}, nValues={nValues}",
                show(vr, nvr),
                show(values, nValues)
            )
        };
        with3(instance, function, mask::SET_VALUES, args, |inst| {
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
            set(inst, &flat, &converted)
        })
    }
}

/// Getters and setters of a type this FMU has no variable of: no value reference is valid.
///
/// # Safety
/// FMI 3.0 calling conventions.
unsafe fn no_variables_of(
    instance: fmi3Instance,
    function: &'static str,
    ty: &str,
    mask: u8,
    vr: *const fmi3ValueReference,
    nvr: usize,
) -> fmi3Status {
    unsafe {
        let args = || format!("vr={}, nvr={nvr}", show(vr, nvr));
        with3(instance, function, mask, args, |inst| {
            match slice(vr, nvr) {
                None => null_argument(inst, function, "valueReferences[]"),
                Some([]) => fmi2OK,
                Some([first, ..]) => inst.error(&format!(
                    "{function}: value reference {first} is not {} variable: this FMU has none",
                    with_article(ty)
                )),
            }
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

/// `fmi3GetFloat32`: no Float32 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetFloat32",
            "Float32",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetFloat32`: no Float32 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetFloat32",
            "Float32",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3GetInt8`: no Int8 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetInt8",
            "Int8",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetInt8`: no Int8 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetInt8",
            "Int8",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3GetUInt8`: no UInt8 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetUInt8",
            "UInt8",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetUInt8`: no UInt8 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetUInt8",
            "UInt8",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3GetInt16`: no Int16 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetInt16",
            "Int16",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetInt16`: no Int16 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetInt16",
            "Int16",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3GetUInt16`: no UInt16 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetUInt16",
            "UInt16",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetUInt16`: no UInt16 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetUInt16",
            "UInt16",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3GetUInt32`: no UInt32 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetUInt32",
            "UInt32",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetUInt32`: no UInt32 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetUInt32",
            "UInt32",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3GetUInt64`: no UInt64 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt64,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetUInt64",
            "UInt64",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetUInt64`: no UInt64 variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt64,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetUInt64",
            "UInt64",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3GetBinary`: no Binary variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    valueSizes: *mut usize,
    values: *mut fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    let _ = (valueSizes, values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3GetBinary",
            "Binary",
            mask::GET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

/// `fmi3SetBinary`: no Binary variables.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    valueSizes: *const usize,
    values: *const fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    let _ = (valueSizes, values, nValues);
    unsafe {
        no_variables_of(
            instance,
            "fmi3SetBinary",
            "Binary",
            mask::SET_VALUES,
            valueReferences,
            nValueReferences,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Dependencies, configuration, derivatives (not provided)

/// `fmi3GetNumberOfVariableDependencies`: not provided (see `<ModelStructure>`).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
    instance: fmi3Instance,
    valueReference: fmi3ValueReference,
    nDependencies: *mut usize,
) -> fmi3Status {
    let _ = (valueReference, nDependencies);
    unsafe {
        not_provided(
            instance,
            "fmi3GetNumberOfVariableDependencies",
            "the dependencies are declared in <ModelStructure> of modelDescription.xml",
        )
    }
}

/// `fmi3GetVariableDependencies`: not provided (see `<ModelStructure>`).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetVariableDependencies(
    instance: fmi3Instance,
    dependent: fmi3ValueReference,
    elementIndicesOfDependent: *mut usize,
    independents: *mut fmi3ValueReference,
    elementIndicesOfIndependents: *mut usize,
    dependencyKinds: *mut fmi3DependencyKind,
    nDependencies: usize,
) -> fmi3Status {
    let _ = (dependent, elementIndicesOfDependent, independents);
    let _ = (elementIndicesOfIndependents, dependencyKinds, nDependencies);
    unsafe {
        not_provided(
            instance,
            "fmi3GetVariableDependencies",
            "the dependencies are declared in <ModelStructure> of modelDescription.xml",
        )
    }
}

/// `fmi3GetDirectionalDerivative`: not provided (`providesDirectionalDerivatives` is false).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: usize,
    knowns: *const fmi3ValueReference,
    nKnowns: usize,
    seed: *const fmi3Float64,
    nSeed: usize,
    sensitivity: *mut fmi3Float64,
    nSensitivity: usize,
) -> fmi3Status {
    let _ = (unknowns, nUnknowns, knowns, nKnowns, seed, nSeed);
    let _ = (sensitivity, nSensitivity);
    unsafe {
        not_provided(
            instance,
            "fmi3GetDirectionalDerivative",
            "providesDirectionalDerivatives is false",
        )
    }
}

/// `fmi3GetAdjointDerivative`: not provided (`providesAdjointDerivatives` is false).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: usize,
    knowns: *const fmi3ValueReference,
    nKnowns: usize,
    seed: *const fmi3Float64,
    nSeed: usize,
    sensitivity: *mut fmi3Float64,
    nSensitivity: usize,
) -> fmi3Status {
    let _ = (unknowns, nUnknowns, knowns, nKnowns, seed, nSeed);
    let _ = (sensitivity, nSensitivity);
    unsafe {
        not_provided(
            instance,
            "fmi3GetAdjointDerivative",
            "providesAdjointDerivatives is false",
        )
    }
}

/// `fmi3EnterConfigurationMode`: not provided (no structural parameters).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        not_provided(
            instance,
            "fmi3EnterConfigurationMode",
            "the model has no structural parameters",
        )
    }
}

/// `fmi3ExitConfigurationMode`: not provided (no structural parameters).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        not_provided(
            instance,
            "fmi3ExitConfigurationMode",
            "the model has no structural parameters",
        )
    }
}

/// `fmi3EnterStepMode`: not provided (without event mode an instance is in step mode after
/// `fmi3ExitInitializationMode`).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        not_provided(
            instance,
            "fmi3EnterStepMode",
            "the model has no event mode; it is in step mode after fmi3ExitInitializationMode",
        )
    }
}

/// `fmi3GetOutputDerivatives`: not provided (`maxOutputDerivativeOrder` is 0).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, orders, values, nValues);
    unsafe {
        not_provided(
            instance,
            "fmi3GetOutputDerivatives",
            "maxOutputDerivativeOrder is 0",
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
        with3(instance, F, mask::GET_FMU_STATE, args, |inst| {
            if FMUState.is_null() {
                return null_argument(inst, F, "FMUState");
            }
            let state = inst.get_fmu_state();
            store_state(inst, F, FMUState, state)
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
        with3(instance, F, mask::SET_FMU_STATE, args, |inst| {
            if !known(inst, FMUState) {
                return inst.error(&format!("{F}: FMUState is not a state of this instance"));
            }
            // SAFETY: a live FmuState of this instance; cloned so the instance may change freely.
            let state = (*(FMUState as *const FmuState)).clone();
            inst.set_fmu_state(&state)
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
        with3(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            if FMUState.is_null() {
                return null_argument(inst, F, "FMUState");
            }
            let p = *FMUState;
            if p.is_null() {
                return fmi2OK;
            }
            if !inst.fmu_states.remove(&(p as usize)) {
                return inst.error(&format!("{F}: *FMUState is not a state of this instance"));
            }
            drop(Box::from_raw(p as *mut FmuState));
            *FMUState = std::ptr::null_mut();
            fmi2OK
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
        with3(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            if size.is_null() {
                return null_argument(inst, F, "size");
            }
            if !known(inst, FMUState) {
                return inst.error(&format!("{F}: FMUState is not a state of this instance"));
            }
            *size = (*(FMUState as *const FmuState)).to_bytes().len();
            fmi2OK
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
        with3(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            if !known(inst, FMUState) {
                return inst.error(&format!("{F}: FMUState is not a state of this instance"));
            }
            let bytes = (*(FMUState as *const FmuState)).to_bytes();
            if size < bytes.len() {
                return inst.error(&format!(
                    "{F}: buffer of {size} bytes, {} needed",
                    bytes.len()
                ));
            }
            let Some(out) = slice_mut(serializedState, bytes.len()) else {
                return null_argument(inst, F, "serializedState");
            };
            out.copy_from_slice(&bytes);
            fmi2OK
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
        with3(instance, F, mask::FMU_STATE_MEMORY, args, |inst| {
            if FMUState.is_null() {
                return null_argument(inst, F, "FMUState");
            }
            let Some(bytes) = slice(serializedState, size) else {
                return null_argument(inst, F, "serializedState");
            };
            match FmuState::from_bytes(bytes) {
                Ok(state) => store_state(inst, F, FMUState, state),
                Err(e) => inst.error(&format!("{F}: {e}")),
            }
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
        with3(instance, F, mask::DO_STEP, args, |inst| {
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
            let status = inst.do_step(currentCommunicationPoint, communicationStepSize);
            *eventHandlingNeeded = false;
            *earlyReturn = false;
            *terminateSimulation = inst.phase() == Phase::StepFailed;
            *lastSuccessfulTime = inst.time();
            status
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Clocks, model exchange and scheduled execution: not provided. Exported because importers
// (fmpy among them) resolve every function of the standard when they load the library.

/// `fmi3GetClock`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, values);
    unsafe { not_provided(instance, "fmi3GetClock", NO_CLOCKS) }
}

/// `fmi3SetClock`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, values);
    unsafe { not_provided(instance, "fmi3SetClock", NO_CLOCKS) }
}

const NO_CLOCKS: &str = "the model has no clocks";
const NO_MODEL_EXCHANGE: &str = "this FMU supports co-simulation only";

/// `fmi3GetIntervalDecimal`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetIntervalDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    intervals: *mut fmi3Float64,
    qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, intervals, qualifiers);
    unsafe { not_provided(instance, "fmi3GetIntervalDecimal", NO_CLOCKS) }
}

/// `fmi3GetIntervalFraction`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetIntervalFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *mut fmi3UInt64,
    resolutions: *mut fmi3UInt64,
    qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    let _ = (
        valueReferences,
        nValueReferences,
        counters,
        resolutions,
        qualifiers,
    );
    unsafe { not_provided(instance, "fmi3GetIntervalFraction", NO_CLOCKS) }
}

/// `fmi3GetShiftDecimal`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetShiftDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    shifts: *mut fmi3Float64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, shifts);
    unsafe { not_provided(instance, "fmi3GetShiftDecimal", NO_CLOCKS) }
}

/// `fmi3GetShiftFraction`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetShiftFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *mut fmi3UInt64,
    resolutions: *mut fmi3UInt64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, counters, resolutions);
    unsafe { not_provided(instance, "fmi3GetShiftFraction", NO_CLOCKS) }
}

/// `fmi3SetIntervalDecimal`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetIntervalDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    intervals: *const fmi3Float64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, intervals);
    unsafe { not_provided(instance, "fmi3SetIntervalDecimal", NO_CLOCKS) }
}

/// `fmi3SetIntervalFraction`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetIntervalFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *const fmi3UInt64,
    resolutions: *const fmi3UInt64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, counters, resolutions);
    unsafe { not_provided(instance, "fmi3SetIntervalFraction", NO_CLOCKS) }
}

/// `fmi3SetShiftDecimal`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetShiftDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    shifts: *const fmi3Float64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, shifts);
    unsafe { not_provided(instance, "fmi3SetShiftDecimal", NO_CLOCKS) }
}

/// `fmi3SetShiftFraction`: not provided (no clocks).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetShiftFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *const fmi3UInt64,
    resolutions: *const fmi3UInt64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, counters, resolutions);
    unsafe { not_provided(instance, "fmi3SetShiftFraction", NO_CLOCKS) }
}

/// `fmi3EvaluateDiscreteStates`: not provided (`providesEvaluateDiscreteStates` is false).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        not_provided(
            instance,
            "fmi3EvaluateDiscreteStates",
            "providesEvaluateDiscreteStates is false",
        )
    }
}

/// `fmi3UpdateDiscreteStates`: not provided (no event mode).
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    discreteStatesNeedUpdate: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
    valuesOfContinuousStatesChanged: *mut fmi3Boolean,
    nextEventTimeDefined: *mut fmi3Boolean,
    nextEventTime: *mut fmi3Float64,
) -> fmi3Status {
    let _ = (discreteStatesNeedUpdate, terminateSimulation);
    let _ = (
        nominalsOfContinuousStatesChanged,
        valuesOfContinuousStatesChanged,
    );
    let _ = (nextEventTimeDefined, nextEventTime);
    unsafe {
        not_provided(
            instance,
            "fmi3UpdateDiscreteStates",
            "the model has no event mode",
        )
    }
}

/// `fmi3EnterContinuousTimeMode`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    unsafe { not_provided(instance, "fmi3EnterContinuousTimeMode", NO_MODEL_EXCHANGE) }
}

/// `fmi3CompletedIntegratorStep`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    enterEventMode: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
) -> fmi3Status {
    let _ = (
        noSetFMUStatePriorToCurrentPoint,
        enterEventMode,
        terminateSimulation,
    );
    unsafe { not_provided(instance, "fmi3CompletedIntegratorStep", NO_MODEL_EXCHANGE) }
}

/// `fmi3SetTime`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    let _ = time;
    unsafe { not_provided(instance, "fmi3SetTime", NO_MODEL_EXCHANGE) }
}

/// `fmi3SetContinuousStates`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *const fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    let _ = (continuousStates, nContinuousStates);
    unsafe { not_provided(instance, "fmi3SetContinuousStates", NO_MODEL_EXCHANGE) }
}

/// `fmi3GetContinuousStateDerivatives`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: fmi3Instance,
    derivatives: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    let _ = (derivatives, nContinuousStates);
    unsafe {
        not_provided(
            instance,
            "fmi3GetContinuousStateDerivatives",
            NO_MODEL_EXCHANGE,
        )
    }
}

/// `fmi3GetEventIndicators`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetEventIndicators(
    instance: fmi3Instance,
    eventIndicators: *mut fmi3Float64,
    nEventIndicators: usize,
) -> fmi3Status {
    let _ = (eventIndicators, nEventIndicators);
    unsafe { not_provided(instance, "fmi3GetEventIndicators", NO_MODEL_EXCHANGE) }
}

/// `fmi3GetContinuousStates`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    let _ = (continuousStates, nContinuousStates);
    unsafe { not_provided(instance, "fmi3GetContinuousStates", NO_MODEL_EXCHANGE) }
}

/// `fmi3GetNominalsOfContinuousStates`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: fmi3Instance,
    nominals: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    let _ = (nominals, nContinuousStates);
    unsafe {
        not_provided(
            instance,
            "fmi3GetNominalsOfContinuousStates",
            NO_MODEL_EXCHANGE,
        )
    }
}

/// `fmi3GetNumberOfEventIndicators`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
    instance: fmi3Instance,
    nEventIndicators: *mut usize,
) -> fmi3Status {
    let _ = nEventIndicators;
    unsafe {
        not_provided(
            instance,
            "fmi3GetNumberOfEventIndicators",
            NO_MODEL_EXCHANGE,
        )
    }
}

/// `fmi3GetNumberOfContinuousStates`: model exchange, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
    instance: fmi3Instance,
    nContinuousStates: *mut usize,
) -> fmi3Status {
    let _ = nContinuousStates;
    unsafe {
        not_provided(
            instance,
            "fmi3GetNumberOfContinuousStates",
            NO_MODEL_EXCHANGE,
        )
    }
}

/// `fmi3ActivateModelPartition`: scheduled execution, not provided.
///
/// # Safety
/// FMI 3.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ActivateModelPartition(
    instance: fmi3Instance,
    clockReference: fmi3ValueReference,
    activationTime: fmi3Float64,
) -> fmi3Status {
    let _ = (clockReference, activationTime);
    unsafe { not_provided(instance, "fmi3ActivateModelPartition", NO_MODEL_EXCHANGE) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_fmi3_function() {
        CURRENT.with(|f| f.set("fmi3SetFloat64"));
        assert_eq!(
            renamed("fmi2SetReal: `posture` is out of range"),
            "fmi3SetFloat64: `posture` is out of range"
        );
        assert_eq!(renamed("reset"), "reset");
        assert_eq!(
            renamed("fmi2SetReal: `posture` cannot change after fmi2ExitInitializationMode"),
            "fmi3SetFloat64: `posture` cannot change after fmi3ExitInitializationMode"
        );
        CURRENT.with(|f| f.set(""));
        assert_eq!(renamed("fmi2DoStep: x"), "fmi2DoStep: x");
    }
}
