//! The guards every exported FMI function runs behind, in both versions: the call wrapper
//! ([`with_instance`]: panics caught and logged, a null instance refused, the call logged
//! under `logCalls` and checked against the state machine's mask), the readers of C
//! arguments (arrays, strings, their `logCalls` forms) and the FMU-state bodies that FMI 2.0
//! and FMI 3.0 share word for word but for the argument's spelling (`FMUstate`,
//! `FMUState`). Everything answers with the neutral [`Status`], which the caller translates.

use super::instance::{FmuState, Instance};
use super::status::Status;
use std::ffi::CStr;
use std::os::raw::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Runs `body` on the instance behind `c` if `function` is allowed in its state; panics are
/// caught and reported. Every call is first logged under `logCalls` (when that category is
/// on) as `function(args)`, the arguments formatted by `args` only then, also when the call
/// is then refused. The status comes back in the caller's spelling `S`.
///
/// # Safety
/// `c` must be null or a pointer returned by `fmi2Instantiate` or
/// `fmi3InstantiateCoSimulation` (both create an [`Instance`]) and not yet freed.
pub unsafe fn with_instance<S: From<Status>>(
    c: *mut c_void,
    function: &str,
    mask: u8,
    args: impl FnOnce() -> String,
    body: impl FnOnce(&mut Instance) -> Status,
) -> S {
    if c.is_null() {
        return Status::Error.into();
    }
    // SAFETY: the caller passes an instance created by an instantiation function.
    let inst = unsafe { &mut *(c as *mut Instance) };
    let result = catch_unwind(AssertUnwindSafe(|| {
        inst.trace(|| format!("{function}({})", args()));
        if inst.allowed(function, mask) {
            body(inst)
        } else {
            Status::Error
        }
    }));
    match result {
        Ok(status) => status.into(),
        Err(payload) => {
            let message = format!(
                "{function}: internal error: {}",
                crate::error::panic_message(payload.as_ref())
            );
            let _ = catch_unwind(AssertUnwindSafe(|| inst.fail(&message)));
            Status::Error.into()
        }
    }
}

/// A slice from a C array; `None` when the pointer is null and `n > 0`.
///
/// # Safety
/// A non-null `p` must point to `n` valid elements.
pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
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
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
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
pub unsafe fn string(p: *const c_char) -> Option<String> {
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
pub unsafe fn show<T: std::fmt::Debug>(p: *const T, n: usize) -> String {
    match unsafe { slice(p, n) } {
        Some(values) => format!("{values:?}"),
        None => "NULL".into(),
    }
}

/// A C string array for `logCalls`: each string quoted, or `NULL`.
///
/// # Safety
/// As for [`slice`] and [`string`].
pub unsafe fn show_strings(p: *const *const c_char, n: usize) -> String {
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

/// Logs that `argument` of `function` is NULL and returns [`Status::Error`].
pub fn null_argument(inst: &mut Instance, function: &str, argument: &str) -> Status {
    inst.error(&format!("{function}: argument {argument} must not be NULL"))
}

/// The body of `fmi2SetDebugLogging` and `fmi3SetDebugLogging`: the category names read
/// from C, then [`Instance::set_debug_logging`].
///
/// # Safety
/// A non-null `categories` must point to `n` pointers, each null or NUL-terminated.
pub unsafe fn set_debug_logging(
    inst: &mut Instance,
    function: &str,
    on: bool,
    categories: *const *const c_char,
    n: usize,
) -> Status {
    let Some(ptrs) = (unsafe { slice(categories, n) }) else {
        return null_argument(inst, function, "categories[]");
    };
    let mut names = Vec::with_capacity(ptrs.len());
    for &p in ptrs {
        match unsafe { string(p) } {
            Some(s) => names.push(s),
            None => return inst.error(&format!("{function}: a category is NULL or not UTF-8")),
        }
    }
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    inst.set_debug_logging(function, on, &refs)
}

// ---------------------------------------------------------------------------------------------
// FMU states: the handles given out are `Box<FmuState>` pointers, remembered by the instance
// until freed (with the instance at the latest).

/// Frees every FMU state still held by `inst`.
pub fn free_states(inst: &mut Instance) {
    for addr in inst.fmu_states.drain() {
        // SAFETY: every address in the set came from Box::into_raw of an FmuState.
        drop(unsafe { Box::from_raw(addr as *mut FmuState) });
    }
}

/// Whether `p` is an FMU state handed out by this instance and not freed.
pub fn known(inst: &Instance, p: *mut c_void) -> bool {
    !p.is_null() && inst.fmu_states.contains(&(p as usize))
}

/// Stores `state` at `*slot`: in place if `*slot` is a live state of this instance, newly
/// allocated if it is NULL.
///
/// # Safety
/// `slot` must be non-null and writable.
pub unsafe fn store_state(
    inst: &mut Instance,
    function: &str,
    slot: *mut *mut c_void,
    state: FmuState,
) -> Status {
    // SAFETY: slot checked non-null by the caller.
    let current = unsafe { *slot };
    if current.is_null() {
        let p = Box::into_raw(Box::new(state));
        inst.fmu_states.insert(p as usize);
        // SAFETY: writable slot.
        unsafe { *slot = p as *mut c_void };
        Status::Ok
    } else if known(inst, current) {
        // SAFETY: a live FmuState of this instance.
        unsafe { *(current as *mut FmuState) = state };
        Status::Ok
    } else {
        inst.error(&format!(
            "{function}: *FMUstate is neither NULL nor a state of this instance"
        ))
    }
}

/// `GetFMUstate`: saves the instance's state at `*slot` (the argument named `arg`).
///
/// # Safety
/// `slot` null or writable.
pub unsafe fn get_state(
    inst: &mut Instance,
    function: &str,
    arg: &str,
    slot: *mut *mut c_void,
) -> Status {
    if slot.is_null() {
        return null_argument(inst, function, arg);
    }
    let state = inst.get_fmu_state();
    unsafe { store_state(inst, function, slot, state) }
}

/// `SetFMUstate`: restores a live state of this instance.
///
/// # Safety
/// `state` is checked against the states this instance handed out before it is read.
pub unsafe fn set_state(
    inst: &mut Instance,
    function: &str,
    arg: &str,
    state: *mut c_void,
) -> Status {
    if !known(inst, state) {
        return inst.error(&format!(
            "{function}: {arg} is not a state of this instance"
        ));
    }
    // SAFETY: a live FmuState of this instance; cloned so the instance may change freely.
    let state = unsafe { (*(state as *const FmuState)).clone() };
    inst.set_fmu_state(function, &state)
}

/// `FreeFMUstate`: frees `*slot` and sets it to NULL (a NULL `*slot` is no error).
///
/// # Safety
/// `slot` null or readable and writable.
pub unsafe fn free_state(
    inst: &mut Instance,
    function: &str,
    arg: &str,
    slot: *mut *mut c_void,
) -> Status {
    if slot.is_null() {
        return null_argument(inst, function, arg);
    }
    // SAFETY: non-null slot.
    let p = unsafe { *slot };
    if p.is_null() {
        return Status::Ok;
    }
    if !inst.fmu_states.remove(&(p as usize)) {
        return inst.error(&format!(
            "{function}: *{arg} is not a state of this instance"
        ));
    }
    // SAFETY: a live FmuState of this instance, now forgotten by it.
    unsafe {
        drop(Box::from_raw(p as *mut FmuState));
        *slot = std::ptr::null_mut();
    }
    Status::Ok
}

/// `SerializedFMUstateSize`.
///
/// # Safety
/// `size` null or writable.
pub unsafe fn serialized_size(
    inst: &mut Instance,
    function: &str,
    arg: &str,
    state: *mut c_void,
    size: *mut usize,
) -> Status {
    if size.is_null() {
        return null_argument(inst, function, "size");
    }
    if !known(inst, state) {
        return inst.error(&format!(
            "{function}: {arg} is not a state of this instance"
        ));
    }
    // SAFETY: a live FmuState of this instance; a writable size.
    unsafe { *size = (*(state as *const FmuState)).to_bytes().len() };
    Status::Ok
}

/// `SerializeFMUstate`: writes the self-contained, versioned byte form into `out` (`size`
/// bytes).
///
/// # Safety
/// `out` null or `size` writable bytes.
pub unsafe fn serialize(
    inst: &mut Instance,
    function: &str,
    arg: &str,
    state: *mut c_void,
    out: *mut u8,
    size: usize,
) -> Status {
    if !known(inst, state) {
        return inst.error(&format!(
            "{function}: {arg} is not a state of this instance"
        ));
    }
    // SAFETY: a live FmuState of this instance.
    let bytes = unsafe { (*(state as *const FmuState)).to_bytes() };
    if size < bytes.len() {
        return inst.error(&format!(
            "{function}: buffer of {size} bytes, {} needed",
            bytes.len()
        ));
    }
    let Some(out) = (unsafe { slice_mut(out, bytes.len()) }) else {
        return null_argument(inst, function, "serializedState");
    };
    out.copy_from_slice(&bytes);
    Status::Ok
}

/// `DeSerializeFMUstate`: anything but a state written by this FMU is an error.
///
/// # Safety
/// `bytes` null or `size` readable bytes; `slot` null or writable.
pub unsafe fn deserialize(
    inst: &mut Instance,
    function: &str,
    arg: &str,
    bytes: *const u8,
    size: usize,
    slot: *mut *mut c_void,
) -> Status {
    if slot.is_null() {
        return null_argument(inst, function, arg);
    }
    let Some(bytes) = (unsafe { slice(bytes, size) }) else {
        return null_argument(inst, function, "serializedState");
    };
    match FmuState::from_bytes_for(bytes, inst.table()) {
        Ok(state) => unsafe { store_state(inst, function, slot, state) },
        Err(e) => inst.error(&format!("{function}: {e}")),
    }
}
