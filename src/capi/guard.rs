//! How every C ABI function runs: a failure (`Failure`: a `BT_ERR_*` code and its message)
//! is recorded on the handle (read by `bt_last_error`) or, for a call without one, on the
//! thread (`bt_creation_error`); a panic is caught and returned as `BT_ERR_PANIC`. Also the
//! checked readers of C arguments: output pointers and strings.

use super::{
    BT_ERR_INVALID, BT_ERR_IO, BT_ERR_NULL, BT_ERR_NUMERICAL, BT_ERR_PANIC, BT_ERR_PARSE,
    BT_ERR_STATE, BT_OK, BtTorso,
};
use crate::Error;
use std::cell::RefCell;
use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

thread_local! {
    pub(super) static CREATION_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

pub(super) fn c_message(s: &str) -> CString {
    CString::new(s.replace('\0', "")).unwrap_or_default()
}

pub(super) fn code_of(e: &Error) -> c_int {
    match e {
        Error::InvalidParameter { .. } => BT_ERR_INVALID,
        Error::Numerical { .. } | Error::Unphysiological { .. } => BT_ERR_NUMERICAL,
        Error::Parse { .. } => BT_ERR_PARSE,
        Error::Io { .. } => BT_ERR_IO,
        Error::State(_) => BT_ERR_STATE,
    }
}

/// A failure of a C ABI call: its code and message.
pub(super) struct Failure(pub(super) c_int, pub(super) String);

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        Failure(code_of(&e), e.to_string())
    }
}

pub(super) type Outcome = std::result::Result<(), Failure>;

/// Runs `body` on the handle, records a failure's message on it, catches panics.
///
/// # Safety
/// `h` must be NULL or a live handle from `bt_create`.
pub(super) unsafe fn with_handle(
    h: *mut BtTorso,
    body: impl FnOnce(&mut BtTorso) -> Outcome,
) -> c_int {
    if h.is_null() {
        return BT_ERR_NULL;
    }
    // SAFETY: a live handle by the caller's contract.
    let handle = unsafe { &mut *h };
    match catch_unwind(AssertUnwindSafe(|| body(handle))) {
        Ok(Ok(())) => {
            handle.last_error = CString::default();
            BT_OK
        }
        Ok(Err(Failure(code, message))) => {
            handle.last_error = c_message(&message);
            code
        }
        Err(p) => {
            handle.last_error = c_message(&format!(
                "internal error: {}",
                crate::error::panic_message(p.as_ref())
            ));
            BT_ERR_PANIC
        }
    }
}

/// Runs `body` outside any handle; a failure's message goes to the thread's creation error.
pub(super) fn without_handle(body: impl FnOnce() -> Outcome) -> c_int {
    let (code, message) = match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => (BT_OK, String::new()),
        Ok(Err(Failure(code, message))) => (code, message),
        Err(p) => (
            BT_ERR_PANIC,
            format!(
                "internal error: {}",
                crate::error::panic_message(p.as_ref())
            ),
        ),
    };
    CREATION_ERROR.with(|e| *e.borrow_mut() = c_message(&message));
    code
}

/// Writes `v` through `out`, or fails with `BT_ERR_NULL`.
///
/// # Safety
/// `out` must be NULL or writable.
pub(super) unsafe fn put<T>(out: *mut T, v: T, name: &str) -> Outcome {
    if out.is_null() {
        return Err(Failure(BT_ERR_NULL, format!("argument `{name}` is NULL")));
    }
    // SAFETY: non-null and writable by the caller's contract.
    unsafe { *out = v };
    Ok(())
}

/// A `&str` from a C string argument.
///
/// # Safety
/// `p` must be NULL or NUL-terminated.
pub(super) unsafe fn text<'a>(
    p: *const c_char,
    name: &str,
) -> std::result::Result<&'a str, Failure> {
    if p.is_null() {
        return Err(Failure(BT_ERR_NULL, format!("argument `{name}` is NULL")));
    }
    // SAFETY: NUL-terminated by the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| Failure(BT_ERR_INVALID, format!("argument `{name}` is not UTF-8")))
}
