//! The 34 functions of FMI 2.0 (common and co-simulation), exported unmangled from the cdylib.
//!
//! Each body runs inside `catch_unwind` (a panic becomes `fmi2Error`, is logged, and moves the
//! instance to its error state; nothing unwinds into the master), checks its pointers for
//! null, checks the instance's state against the function's mask ([`super::instance::mask`])
//! and forwards to the safe [`Instance`]. Strings received are copied; the logger is always
//! called with the format `"%s"`.

#![allow(non_snake_case)]

use super::instance::{FmuState, Instance, LogSink, mask};
use super::types::*;
use super::uri::file_uri_to_path;
use super::variables::table;
use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

use fmi2Status::{fmi2Error, fmi2OK};

/// Runs `body` on the instance behind `c` if `function` is allowed in its state; panics are
/// caught and reported. Every call is first logged under `logCalls` (when that category is
/// on) as `function(args)`, the arguments formatted by `args` only then, also when the call
/// is then refused.
///
/// # Safety
/// `c` must be null or a pointer returned by [`fmi2Instantiate`] (or by
/// `fmi3InstantiateCoSimulation`, which creates the same [`Instance`]) and not yet freed.
pub(super) unsafe fn with_instance(
    c: fmi2Component,
    function: &str,
    mask: u8,
    args: impl FnOnce() -> String,
    body: impl FnOnce(&mut Instance) -> fmi2Status,
) -> fmi2Status {
    if c.is_null() {
        return fmi2Error;
    }
    // SAFETY: the caller passes an instance created by fmi2Instantiate.
    let inst = unsafe { &mut *(c as *mut Instance) };
    let result = catch_unwind(AssertUnwindSafe(|| {
        inst.trace(|| format!("{function}({})", args()));
        if inst.allowed(function, mask) {
            body(inst)
        } else {
            fmi2Error
        }
    }));
    match result {
        Ok(status) => status,
        Err(payload) => {
            let message = format!(
                "{function}: internal error: {}",
                crate::error::panic_message(payload.as_ref())
            );
            let _ = catch_unwind(AssertUnwindSafe(|| inst.fail(&message)));
            fmi2Error
        }
    }
}

/// A slice from a C array; `None` when the pointer is null and `n > 0`.
///
/// # Safety
/// A non-null `p` must point to `n` valid elements.
pub(super) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: non-null, n elements, as the FMI standard requires of the caller.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// A mutable slice from a C array; `None` when the pointer is null and `n > 0`.
///
/// # Safety
/// A non-null `p` must point to `n` valid, writable elements.
pub(super) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: as for `slice`, and writable.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// A Rust string copied from a C string; `None` for null or non-UTF-8.
///
/// # Safety
/// A non-null `p` must point to a NUL-terminated string.
pub(super) unsafe fn string(p: *const c_char) -> Option<String> {
    if p.is_null() {
        return None;
    }
    // SAFETY: NUL-terminated by the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .ok()
        .map(str::to_string)
}

/// `[a, b, ...]` of a C array for `logCalls`, or `NULL`.
///
/// # Safety
/// As for [`slice`].
pub(super) unsafe fn show<T: std::fmt::Debug>(p: *const T, n: usize) -> String {
    match unsafe { slice(p, n) } {
        Some(values) => format!("{values:?}"),
        None => "NULL".into(),
    }
}

/// A C string array for `logCalls`: each string quoted, or `NULL`.
///
/// # Safety
/// As for [`slice`] and [`string`].
pub(super) unsafe fn show_strings(p: *const fmi2String, n: usize) -> String {
    match unsafe { slice(p, n) } {
        Some(ptrs) => {
            let shown: Vec<String> = ptrs
                .iter()
                .map(|&s| match unsafe { string(s) } {
                    Some(s) => format!("{s:?}"),
                    None => "NULL".into(),
                })
                .collect();
            format!("[{}]", shown.join(", "))
        }
        None => "NULL".into(),
    }
}

pub(super) fn null_argument(inst: &mut Instance, function: &str, argument: &str) -> fmi2Status {
    inst.error(&format!("{function}: argument {argument} must not be NULL"))
}

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
    unsafe {
        let args = || {
            format!(
                "loggingOn={loggingOn}, nCategories={nCategories}, categories={}",
                show_strings(categories, nCategories)
            )
        };
        with_instance(
            c,
            "fmi2SetDebugLogging",
            mask::SET_DEBUG_LOGGING,
            args,
            |inst| {
                let Some(ptrs) = slice(categories, nCategories) else {
                    return null_argument(inst, "fmi2SetDebugLogging", "categories[]");
                };
                let mut names = Vec::with_capacity(ptrs.len());
                for &p in ptrs {
                    match string(p) {
                        Some(s) => names.push(s),
                        None => {
                            return inst
                                .error("fmi2SetDebugLogging: a category is NULL or not UTF-8");
                        }
                    }
                }
                let refs: Vec<&str> = names.iter().map(String::as_str).collect();
                inst.set_debug_logging(loggingOn != fmi2False, &refs)
            },
        )
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
        move |status: fmi2Status, category: &str, message: &str| {
            let category = CString::new(category).unwrap_or_default();
            let message = CString::new(message.replace('\0', "")).unwrap_or_default();
            // SAFETY: the master's logger, called with the "%s" format and one string argument.
            unsafe {
                logger(
                    env,
                    name.as_ptr(),
                    status,
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
            Instance::new(&name, resources, sink, logging)
        } else {
            match Instance::with_table(&name, resources, sink, logging, fmu_table) {
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
            inst.log(fmi2OK, super::instance::Category::Events, &w);
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

/// Frees every FMU state still held by `inst`.
pub(super) fn free_states(inst: &mut Instance) {
    for addr in inst.fmu_states.drain() {
        // SAFETY: every address in the set came from Box::into_raw of an FmuState.
        drop(unsafe { Box::from_raw(addr as *mut FmuState) });
    }
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
        free_states(&mut inst);
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
                inst.setup_experiment(tol, startTime, stop)
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
            Instance::exit_initialization_mode,
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
    get: impl FnOnce(&mut Instance, &[u32], &mut [T]) -> fmi2Status,
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
            get(inst, vrs, out)
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
    set: impl FnOnce(&mut Instance, &[u32], &[T]) -> fmi2Status,
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
            set(inst, vrs, values)
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
            inst.set_string(vrs, &values)
        })
    }
}

// ---------------------------------------------------------------------------------------------
// FMU state

/// Whether `p` is an FMU state handed out by this instance and not freed.
pub(super) fn known(inst: &Instance, p: fmi2FMUstate) -> bool {
    !p.is_null() && inst.fmu_states.contains(&(p as usize))
}

/// Stores `state` at `*slot`: in place if `*slot` is a live state of this instance, newly
/// allocated if it is NULL.
///
/// # Safety
/// `slot` must be non-null and writable.
pub(super) unsafe fn store_state(
    inst: &mut Instance,
    function: &str,
    slot: *mut fmi2FMUstate,
    state: FmuState,
) -> fmi2Status {
    // SAFETY: slot checked non-null by the caller.
    let current = unsafe { *slot };
    if current.is_null() {
        let p = Box::into_raw(Box::new(state));
        inst.fmu_states.insert(p as usize);
        // SAFETY: writable slot.
        unsafe { *slot = p as fmi2FMUstate };
        fmi2OK
    } else if known(inst, current) {
        // SAFETY: a live FmuState of this instance.
        unsafe { *(current as *mut FmuState) = state };
        fmi2OK
    } else {
        inst.error(&format!(
            "{function}: *FMUstate is neither NULL nor a state of this instance"
        ))
    }
}

/// `fmi2GetFMUstate`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}");
        with_instance(c, "fmi2GetFMUstate", mask::GET_FMU_STATE, args, |inst| {
            if FMUstate.is_null() {
                return null_argument(inst, "fmi2GetFMUstate", "FMUstate");
            }
            let state = inst.get_fmu_state();
            store_state(inst, "fmi2GetFMUstate", FMUstate, state)
        })
    }
}

/// `fmi2SetFMUstate`.
///
/// # Safety
/// FMI 2.0 calling conventions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}");
        with_instance(c, "fmi2SetFMUstate", mask::SET_FMU_STATE, args, |inst| {
            if !known(inst, FMUstate) {
                return inst.error("fmi2SetFMUstate: FMUstate is not a state of this instance");
            }
            // SAFETY: a live FmuState of this instance; cloned so the instance may change freely.
            let state = (*(FMUstate as *const FmuState)).clone();
            inst.set_fmu_state(&state)
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
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}");
        with_instance(
            c,
            "fmi2FreeFMUstate",
            mask::FMU_STATE_MEMORY,
            args,
            |inst| {
                if FMUstate.is_null() {
                    return null_argument(inst, "fmi2FreeFMUstate", "FMUstate");
                }
                let p = *FMUstate;
                if p.is_null() {
                    return fmi2OK;
                }
                if !inst.fmu_states.remove(&(p as usize)) {
                    return inst
                        .error("fmi2FreeFMUstate: *FMUstate is not a state of this instance");
                }
                drop(Box::from_raw(p as *mut FmuState));
                *FMUstate = std::ptr::null_mut();
                fmi2OK
            },
        )
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
    unsafe {
        with_instance(
            c,
            "fmi2SerializedFMUstateSize",
            mask::FMU_STATE_MEMORY,
            || format!("FMUstate={FMUstate:?}"),
            |inst| {
                if size.is_null() {
                    return null_argument(inst, "fmi2SerializedFMUstateSize", "size");
                }
                if !known(inst, FMUstate) {
                    return inst.error(
                        "fmi2SerializedFMUstateSize: FMUstate is not a state of this instance",
                    );
                }
                *size = (*(FMUstate as *const FmuState)).to_bytes().len();
                fmi2OK
            },
        )
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
    unsafe {
        let args = || format!("FMUstate={FMUstate:?}, size={size}");
        with_instance(
            c,
            "fmi2SerializeFMUstate",
            mask::FMU_STATE_MEMORY,
            args,
            |inst| {
                if !known(inst, FMUstate) {
                    return inst
                        .error("fmi2SerializeFMUstate: FMUstate is not a state of this instance");
                }
                let bytes = (*(FMUstate as *const FmuState)).to_bytes();
                if size < bytes.len() {
                    return inst.error(&format!(
                        "fmi2SerializeFMUstate: buffer of {size} bytes, {} needed",
                        bytes.len()
                    ));
                }
                let Some(out) = slice_mut(serializedState as *mut u8, bytes.len()) else {
                    return null_argument(inst, "fmi2SerializeFMUstate", "serializedState");
                };
                out.copy_from_slice(&bytes);
                fmi2OK
            },
        )
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
    unsafe {
        with_instance(
            c,
            "fmi2DeSerializeFMUstate",
            mask::FMU_STATE_MEMORY,
            || format!("size={size}"),
            |inst| {
                if FMUstate.is_null() {
                    return null_argument(inst, "fmi2DeSerializeFMUstate", "FMUstate");
                }
                let Some(bytes) = slice(serializedState as *const u8, size) else {
                    return null_argument(inst, "fmi2DeSerializeFMUstate", "serializedState");
                };
                match FmuState::from_bytes_for(bytes, inst.table()) {
                    Ok(state) => store_state(inst, "fmi2DeSerializeFMUstate", FMUstate, state),
                    Err(e) => inst.error(&format!("fmi2DeSerializeFMUstate: {e}")),
                }
            },
        )
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
            inst.do_step(currentCommunicationPoint, communicationStepSize)
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
            fmi2OK
        })
    }
}

/// Shared body of the status getters.
///
/// # Safety
/// FMI 2.0 calling conventions.
unsafe fn status_value<T>(
    c: fmi2Component,
    function: &str,
    kind: fmi2StatusKind,
    value: *mut T,
    get: impl FnOnce(&mut Instance) -> Result<T, fmi2Status>,
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
                    fmi2OK
                }
                Err(status) => status,
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
    unsafe { status_value(c, "fmi2GetStatus", s, value, |inst| inst.get_status(s)) }
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
        status_value(c, "fmi2GetRealStatus", s, value, |inst| {
            inst.get_real_status(s)
        })
    }
}

/// `fmi2GetBooleanStatus`: `fmi2Terminated` (true after a discarded step).
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
        status_value(c, "fmi2GetBooleanStatus", s, value, |inst| {
            inst.get_boolean_status(s)
                .map(|b| if b { fmi2True } else { fmi2False })
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
