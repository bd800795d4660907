//! The 34 functions of FMI 2.0 (common and co-simulation), exported unmangled from the cdylib.
//!
//! Each is a thin translation: it runs behind the shared guard ([`super::guard`]: a panic
//! becomes `fmi2Error`, is logged, and moves the instance to its error state; nothing unwinds
//! into the master; the instance's state is checked against the function's mask,
//! [`super::instance::mask`]), reads its C arguments, forwards to the version-neutral
//! [`Instance`] with its own name, and spells the neutral [`Status`] as `fmi2Status`. Strings
//! received are copied; the logger is always called with the format `"%s"`.

#![allow(non_snake_case)]
// The FMI status-kind constants keep the standard's spelling, also in match patterns.
#![allow(non_upper_case_globals)]

use super::guard::{
    self, null_argument, show, show_strings, slice, slice_mut, string, with_instance,
};
use super::instance::{Instance, LogSink, Phase, mask};
use super::status::{FMI2, Status};
use super::types::*;
use super::uri::file_uri_to_path;
use super::variables::table;
use std::ffi::CString;
use std::os::raw::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

use fmi2Status::fmi2Error;

// ---------------------------------------------------------------------------------------------
// Inquire platform and version; logging

/// `fmi2GetTypesPlatform`: `"default"`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// `fmi2GetVersion`: `"2.0"`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// `fmi2SetDebugLogging`: switches the named categories (all when `nCategories` is 0).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2SetDebugLogging";
    unsafe {
        let args = || {
            format!(
                "loggingOn={loggingOn}, nCategories={nCategories}, categories={}",
                show_strings(categories, nCategories)
            )
        };
        with_instance(c, F, mask::SET_DEBUG_LOGGING, args, |inst| {
            guard::set_debug_logging(inst, F, loggingOn != fmi2False, categories, nCategories)
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Creation and destruction

/// Calls a C logger once, outside any instance (used when instantiation fails).
///
/// # Safety
/// `functions`, if non-null, must point to valid callbacks.
unsafe fn log_without_instance(functions: *const fmi2CallbackFunctions, name: &str, message: &str) {
    if functions.is_null() {
        return;
    }
    // SAFETY: non-null pointer to the master's callback struct.
    let f = unsafe { &*functions };
    if let Some(logger) = f.logger {
        let name = CString::new(name.replace('\0', "")).unwrap_or_default();
        let message = CString::new(message.replace('\0', "")).unwrap_or_default();
        // SAFETY: a printf-style logger given "%s" and one string argument.
        unsafe {
            logger(
                f.componentEnvironment,
                name.as_ptr(),
                fmi2Error,
                c"logStatusError".as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            )
        };
    }
}

fn make_sink(functions: &fmi2CallbackFunctions, name: &str) -> Option<LogSink> {
    let logger = functions.logger?;
    let env = functions.componentEnvironment;
    let name = CString::new(name.replace('\0', "")).unwrap_or_default();
    Some(Box::new(
        move |status: Status, category: &str, message: &str| {
            let category = CString::new(category).unwrap_or_default();
            let message = CString::new(message.replace('\0', "")).unwrap_or_default();
            // SAFETY: the master's logger, called with the "%s" format and one string argument.
            unsafe {
                logger(
                    env,
                    name.as_ptr(),
                    status.into(),
                    category.as_ptr(),
                    c"%s".as_ptr(),
                    message.as_ptr(),
                )
            };
        },
    ))
}

/// `fmi2Instantiate`: returns NULL (after logging why) on a wrong GUID, a model-exchange
/// request, a missing name or callbacks, or an internal failure.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let result = catch_unwind(AssertUnwindSafe(|| unsafe {
        let name = string(instanceName).unwrap_or_default();
        // Notes on the way (e.g. an unusable resource location) are logged before a failure's
        // message, since they often explain it.
        let mut notes: Vec<String> = Vec::new();
        let fail = |notes: &[String], message: String| {
            for note in notes {
                log_without_instance(functions, &name, note);
            }
            log_without_instance(functions, &name, &format!("fmi2Instantiate: {message}"));
            std::ptr::null_mut::<c_void>()
        };
        if functions.is_null() {
            return std::ptr::null_mut();
        }
        if name.is_empty() {
            return fail(&notes, "instanceName must be a non-empty string".into());
        }
        if fmuType != fmi2CoSimulation {
            return fail(
                &notes,
                format!(
                    "fmuType = {fmuType}: this FMU supports co-simulation (fmi2CoSimulation = 1) only"
                ),
            );
        }
        let guid = string(fmuGUID);
        let resources = match string(fmuResourceLocation) {
            None => None,
            Some(uri) => match file_uri_to_path(&uri) {
                Ok(p) => Some(p),
                Err(e) => {
                    notes.push(format!("fmi2Instantiate: resources unavailable: {e}"));
                    None
                }
            },
        };
        // A personalised FMU carries its parameter set in its resources; its variables, and
        // so its GUID, follow from it.
        let fmu_table = match super::personal::table_in(resources.as_deref()) {
            Ok(t) => t,
            Err(e) => return fail(&notes, e.to_string()),
        };
        if guid.as_deref() != Some(fmu_table.guid()) {
            let given = guid.as_deref().unwrap_or("(null)");
            return fail(
                &notes,
                guid_mismatch(given, resources.as_deref(), fmu_table),
            );
        }
        let sink = make_sink(&*functions, &name);
        let logging = loggingOn != fmi2False;
        let mut inst = if std::ptr::eq(fmu_table, table()) {
            Instance::new(&FMI2, &name, resources, sink, logging)
        } else {
            match Instance::with_table(&FMI2, &name, resources, sink, logging, fmu_table) {
                Ok(inst) => inst,
                Err(e) => return fail(&notes, e.to_string()),
            }
        };
        inst.trace(|| {
            format!(
                "fmi2Instantiate(instanceName={name:?}, fmuType={fmuType}, fmuGUID={:?}, fmuResourceLocation={:?}, visible={visible}, loggingOn={loggingOn})",
                guid.as_deref().unwrap_or_default(),
                string(fmuResourceLocation)
            )
        });
        // fmi2Instantiate returns no status, so these are logged as events, not as warnings
        // (a warning belongs to a call that returns fmi2Warning); a relative `slp.reference`
        // that needed the resources is refused later with an error saying so.
        for w in notes {
            inst.log(Status::Ok, super::instance::Category::Events, &w);
        }
        Box::into_raw(Box::new(inst)) as fmi2Component
    }));
    result.unwrap_or(std::ptr::null_mut())
}

/// The message of a GUID that is not the FMU's: which GUID the library computed and from
/// what, i.e. whether a personalised FMU's parameter set was looked for, where, and what it
/// gave (`table` is the table the library found).
fn guid_mismatch(
    given: &str,
    resources: Option<&std::path::Path>,
    table: &super::variables::Table,
) -> String {
    let ours = table.guid();
    let set = resources.map(|r| r.join(super::personal::PARAMETERS));
    let source = match &set {
        Some(path) if table.personalisation().is_some() => format!(
            "the parameter set {} makes this a personalised FMU with GUID {ours}: the model \
             description and that parameter set differ (was the set edited, or copied from \
             another personalised FMU?)",
            path.display()
        ),
        Some(path) => format!(
            "no parameter set was found at {}, so this is the generic FMU, GUID {ours}; a \
             personalised FMU needs its resources/{} (is it missing from the unpacked FMU?)",
            path.display(),
            super::personal::PARAMETERS
        ),
        None => format!(
            "no parameter set was looked for (no usable resource location), so this is the \
             generic FMU, GUID {ours}; a personalised FMU reads its resources/{}",
            super::personal::PARAMETERS
        ),
    };
    format!("GUID {given} does not match: {source}")
}

/// `fmi2FreeInstance`: releases the instance and the FMU states it still holds.
///
/// # Safety
/// `c` must be null or an instance not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: created by Box::into_raw in fmi2Instantiate.
        let mut inst = unsafe { Box::from_raw(c as *mut Instance) };
        inst.trace(|| "fmi2FreeInstance()".into());
        guard::free_states(&mut inst);
    }));
}

// ---------------------------------------------------------------------------------------------
// Initialization, termination, reset

/// `fmi2SetupExperiment`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    unsafe {
        let args = || {
            format!(
                "toleranceDefined={toleranceDefined}, tolerance={tolerance}, startTime={startTime}, stopTimeDefined={stopTimeDefined}, stopTime={stopTime}"
            )
        };
        with_instance(
            c,
            "fmi2SetupExperiment",
            mask::SETUP_EXPERIMENT,
            args,
            |inst| {
                let tol = (toleranceDefined != fmi2False).then_some(tolerance);
                let stop = (stopTimeDefined != fmi2False).then_some(stopTime);
                inst.setup_experiment("fmi2SetupExperiment", tol, startTime, stop)
            },
        )
    }
}

/// `fmi2EnterInitializationMode`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    unsafe {
        with_instance(
            c,
            "fmi2EnterInitializationMode",
            mask::ENTER_INITIALIZATION_MODE,
            String::new,
            Instance::enter_initialization_mode,
        )
    }
}

/// `fmi2ExitInitializationMode`: builds the model.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    unsafe {
        with_instance(
            c,
            "fmi2ExitInitializationMode",
            mask::EXIT_INITIALIZATION_MODE,
            String::new,
            |inst| inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        )
    }
}

/// `fmi2Terminate`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    unsafe {
        with_instance(
            c,
            "fmi2Terminate",
            mask::TERMINATE,
            String::new,
            Instance::terminate,
        )
    }
}

/// `fmi2Reset`: back to the freshly instantiated state.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    unsafe { with_instance(c, "fmi2Reset", mask::RESET, String::new, Instance::reset) }
}

// ---------------------------------------------------------------------------------------------
// Getting and setting variable values

/// Shared body of the typed getters.
///
/// # Safety
/// FMI 2.0 calling conventions.
unsafe fn get_values<T>(
    c: fmi2Component,
    function: &str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut T,
    get: impl FnOnce(&mut Instance, &str, &[u32], &mut [T]) -> Status,
) -> fmi2Status {
    unsafe {
        let args = || format!("vr={}, nvr={nvr}", show(vr, nvr));
        with_instance(c, function, mask::GET_VALUES, args, |inst| {
            let Some(vrs) = slice(vr, nvr) else {
                return null_argument(inst, function, "vr[]");
            };
            let Some(out) = slice_mut(value, nvr) else {
                return null_argument(inst, function, "value[]");
            };
            get(inst, function, vrs, out)
        })
    }
}

/// `fmi2GetReal`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe { get_values(c, "fmi2GetReal", vr, nvr, value, Instance::get_real) }
}

/// `fmi2GetInteger`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe { get_values(c, "fmi2GetInteger", vr, nvr, value, Instance::get_integer) }
}

/// `fmi2GetString`: the pointers stay valid until the next string-returning call on the
/// instance.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    unsafe { get_values(c, "fmi2GetString", vr, nvr, value, Instance::get_string) }
}

/// `fmi2GetBoolean` (`drive.enabled`).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe { get_values(c, "fmi2GetBoolean", vr, nvr, value, Instance::get_boolean) }
}

/// Shared body of the typed setters.
///
/// # Safety
/// FMI 2.0 calling conventions.
unsafe fn set_values<T: std::fmt::Debug>(
    c: fmi2Component,
    function: &str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
    set: impl FnOnce(&mut Instance, &str, &[u32], &[T]) -> Status,
) -> fmi2Status {
    unsafe {
        let args = || {
            format!(
                "vr={}, nvr={nvr}, value={}",
                show(vr, nvr),
                show(value, nvr)
            )
        };
        with_instance(c, function, mask::SET_VALUES, args, |inst| {
            let Some(vrs) = slice(vr, nvr) else {
                return null_argument(inst, function, "vr[]");
            };
            let Some(values) = slice(value, nvr) else {
                return null_argument(inst, function, "value[]");
            };
            set(inst, function, vrs, values)
        })
    }
}

/// `fmi2SetReal`: inputs and parameters; a value out of range or not finite is an error
/// naming the variable, and nothing is changed.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    unsafe { set_values(c, "fmi2SetReal", vr, nvr, value, Instance::set_real) }
}

/// `fmi2SetInteger`: Integer parameters (all fixed).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    unsafe { set_values(c, "fmi2SetInteger", vr, nvr, value, Instance::set_integer) }
}

/// `fmi2SetBoolean` (`drive.enabled`, tunable).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    unsafe { set_values(c, "fmi2SetBoolean", vr, nvr, value, Instance::set_boolean) }
}

/// `fmi2SetString`: the strings are copied.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    unsafe {
        let args = || {
            format!(
                "vr={}, nvr={nvr}, value={}",
                show(vr, nvr),
                show_strings(value, nvr)
            )
        };
        with_instance(c, "fmi2SetString", mask::SET_VALUES, args, |inst| {
            let Some(vrs) = slice(vr, nvr) else {
                return null_argument(inst, "fmi2SetString", "vr[]");
            };
            let Some(ptrs) = slice(value, nvr) else {
                return null_argument(inst, "fmi2SetString", "value[]");
            };
            let mut values = Vec::with_capacity(nvr);
            for &p in ptrs {
                match string(p) {
                    Some(s) => values.push(s),
                    None => return inst.error("fmi2SetString: a value is NULL or not UTF-8"),
                }
            }
            inst.set_string("fmi2SetString", vrs, &values)
        })
    }
}

// ---------------------------------------------------------------------------------------------
// FMU state

/// `fmi2GetFMUstate`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    const F: &str = "fmi2GetFMUstate";
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}");
        with_instance(c, F, mask::GET_FMU_STATE, args, |inst| {
            guard::get_state(inst, F, "FMUstate", FMUstate)
        })
    }
}

/// `fmi2SetFMUstate`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    const F: &str = "fmi2SetFMUstate";
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}");
        with_instance(c, F, mask::SET_FMU_STATE, args, |inst| {
            guard::set_state(inst, F, "FMUstate", FMUstate)
        })
    }
}

/// `fmi2FreeFMUstate`: frees `*FMUstate` and sets it to NULL.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    const F: &str = "fmi2FreeFMUstate";
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}");
        with_instance(c, F, mask::FMU_STATE_MEMORY, args, |inst| {
            guard::free_state(inst, F, "FMUstate", FMUstate)
        })
    }
}

/// `fmi2SerializedFMUstateSize`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    const F: &str = "fmi2SerializedFMUstateSize";
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}");
        with_instance(c, F, mask::FMU_STATE_MEMORY, args, |inst| {
            guard::serialized_size(inst, F, "FMUstate", FMUstate, size)
        })
    }
}

/// `fmi2SerializeFMUstate`: writes the self-contained, versioned byte form.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    const F: &str = "fmi2SerializeFMUstate";
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}, size={size}");
        with_instance(c, F, mask::FMU_STATE_MEMORY, args, |inst| {
            let out = serializedState as *mut u8;
            guard::serialize(inst, F, "FMUstate", FMUstate, out, size)
        })
    }
}

/// `fmi2DeSerializeFMUstate`: anything but a state written by this FMU is an error.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    const F: &str = "fmi2DeSerializeFMUstate";
    unsafe {
        let args = || format!("size={size}");
        with_instance(c, F, mask::FMU_STATE_MEMORY, args, |inst| {
            let bytes = serializedState as *const u8;
            guard::deserialize(inst, F, "FMUstate", bytes, size, FMUstate)
        })
    }
}

/// `fmi2GetDirectionalDerivative`: not provided (`providesDirectionalDerivative` is false).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    vUnknown_ref: *const fmi2ValueReference,
    nUnknown: usize,
    vKnown_ref: *const fmi2ValueReference,
    nKnown: usize,
    dvKnown: *const fmi2Real,
    dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    let _ = (
        vUnknown_ref,
        nUnknown,
        vKnown_ref,
        nKnown,
        dvKnown,
        dvUnknown,
    );
    unsafe {
        with_instance(
            c,
            "fmi2GetDirectionalDerivative",
            mask::GET_DIRECTIONAL_DERIVATIVE,
            || format!("nUnknown={nUnknown}, nKnown={nKnown}"),
            |inst| {
                inst.error("fmi2GetDirectionalDerivative: not provided by this FMU (providesDirectionalDerivative=false)")
            },
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Co-simulation

/// `fmi2SetRealInputDerivatives`: not supported (`canInterpolateInputs` is false).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    let _ = (vr, nvr, order, value);
    unsafe {
        with_instance(
            c,
            "fmi2SetRealInputDerivatives",
            mask::SET_REAL_INPUT_DERIVATIVES,
            || format!("vr={}, nvr={nvr}", show(vr, nvr)),
            |inst| {
                inst.error("fmi2SetRealInputDerivatives: inputs are held constant over a step (canInterpolateInputs=false)")
            },
        )
    }
}

/// `fmi2GetRealOutputDerivatives`: not supported (`maxOutputDerivativeOrder` is 0).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    let _ = (vr, nvr, order, value);
    unsafe {
        with_instance(
            c,
            "fmi2GetRealOutputDerivatives",
            mask::GET_REAL_OUTPUT_DERIVATIVES,
            || format!("vr={}, nvr={nvr}", show(vr, nvr)),
            |inst| {
                inst.error("fmi2GetRealOutputDerivatives: output derivatives are not provided (maxOutputDerivativeOrder=0)")
            },
        )
    }
}

/// `fmi2DoStep`: integrates from `currentCommunicationPoint` to exactly
/// `currentCommunicationPoint + communicationStepSize`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    let _ = noSetFMUStatePriorToCurrentPoint;
    unsafe {
        let args = || {
            format!(
                "currentCommunicationPoint={currentCommunicationPoint}, communicationStepSize={communicationStepSize}, noSetFMUStatePriorToCurrentPoint={noSetFMUStatePriorToCurrentPoint}"
            )
        };
        with_instance(c, "fmi2DoStep", mask::DO_STEP, args, |inst| {
            inst.do_step(
                "fmi2DoStep",
                currentCommunicationPoint,
                communicationStepSize,
            )
        })
    }
}

/// `fmi2CancelStep`: steps are synchronous, so there is never a step to cancel.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    unsafe {
        with_instance(c, "fmi2CancelStep", mask::CANCEL_STEP, String::new, |_| {
            Status::Ok
        })
    }
}

/// Shared body of the status getters: `get` answers the value of a status kind, or the
/// reason it has none.
///
/// # Safety
/// FMI 2.0 calling conventions.
unsafe fn status_value<T>(
    c: fmi2Component,
    function: &str,
    kind: fmi2StatusKind,
    value: *mut T,
    get: impl FnOnce(&mut Instance) -> Result<T, String>,
) -> fmi2Status {
    unsafe {
        let args = || format!("s={kind}");
        with_instance(c, function, mask::GET_STATUS, args, |inst| {
            if value.is_null() {
                return null_argument(inst, function, "value");
            }
            match get(inst) {
                Ok(v) => {
                    *value = v;
                    Status::Ok
                }
                Err(why) => inst.error(&format!("{function}: {why}")),
            }
        })
    }
}

/// `fmi2GetStatus`: `fmi2DoStepStatus` gives the last step's status.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    unsafe {
        status_value(c, "fmi2GetStatus", s, value, |inst| match s {
            fmi2DoStepStatus => Ok(inst.last_step_status().into()),
            fmi2PendingStatus => Err("no asynchronous step is ever pending".into()),
            k => Err(format!("status kind {k} has no fmi2Status value")),
        })
    }
}

/// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        status_value(c, "fmi2GetRealStatus", s, value, |inst| match s {
            fmi2LastSuccessfulTime => Ok(inst.last_successful_time()),
            k => Err(format!("status kind {k} has no Real value")),
        })
    }
}

/// `fmi2GetBooleanStatus`: `fmi2Terminated`, true after a discarded step (the model cannot
/// go on from there without `fmi2SetFMUstate` or `fmi2Reset`).
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        status_value(c, "fmi2GetBooleanStatus", s, value, |inst| match s {
            fmi2Terminated if inst.phase() == Phase::StepFailed => Ok(fmi2True),
            fmi2Terminated => Ok(fmi2False),
            k => Err(format!("status kind {k} has no Boolean value")),
        })
    }
}

/// `fmi2GetIntegerStatus`: FMI 2.0 defines no Integer status.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    let _ = value;
    unsafe {
        let args = || format!("s={s}");
        with_instance(c, "fmi2GetIntegerStatus", mask::GET_STATUS, args, |inst| {
            inst.error(&format!(
                "fmi2GetIntegerStatus: status kind {s} has no Integer value"
            ))
        })
    }
}

/// `fmi2GetStringStatus`: only `fmi2PendingStatus` exists, and no step is ever pending.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    let _ = value;
    unsafe {
        let args = || format!("s={s}");
        with_instance(c, "fmi2GetStringStatus", mask::GET_STATUS, args, |inst| {
            inst.error(&format!(
                "fmi2GetStringStatus: status kind {s}: no asynchronous step is ever pending"
            ))
        })
    }
}
