//! A handle's life and its configuration: the library version, the defaults and
//! setting a configuration field by its FMI parameter name, building a model ([`bt_create`],
//! whose failure is [`bt_creation_error`]), releasing it, and the last failure's message on
//! a handle ([`bt_last_error`]).

use super::convert::{config_from_c, config_to_c};
use super::guard::{CREATION_ERROR, Failure, put, text, without_handle};
use super::{BT_ERR_INVALID, BT_ERR_NULL, BtConfig, BtTorso};
use crate::fmi::variables::{Role, table};
use crate::model::Torso;
use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// The library version, e.g. `"0.1.0"` (static string).
#[unsafe(no_mangle)]
pub extern "C" fn bt_version() -> *const c_char {
    static VERSION: &CStr =
        match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
            Ok(v) => v,
            Err(_) => c"unknown",
        };
    VERSION.as_ptr()
}

/// The message of the last failed `bt_create` or `bt_config_*` call on this thread (`""` if
/// none). Valid until the next such call on the thread.
#[unsafe(no_mangle)]
pub extern "C" fn bt_creation_error() -> *const c_char {
    CREATION_ERROR.with(|e| e.borrow().as_ptr())
}

/// Fills `config` with the defaults (male, 30 y, 1.75 m, 75 kg, standing, level of detail 1,
/// 10 x 6 markers, Dormand-Prince 5(4) at rtol 1e-6, the quiet drive): the FMU's start
/// values. `config->drive.enabled = 0` turns the built-in drive off.
///
/// # Safety
/// `config` must be NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_config_default(config: *mut BtConfig) -> c_int {
    without_handle(|| unsafe {
        put(
            config,
            config_to_c(
                &crate::fmi::variables::start_config(),
                std::ptr::null(),
                std::ptr::null(),
            ),
            "config",
        )
    })
}

/// Sets one configuration field by its FMI parameter name (`"subject.age"`, `"grid.rows"`,
/// `"drive.ribs.amplitude"`, ...); Integer parameters take integral values, Boolean ones
/// (`drive.enabled`) 0 or 1. The value is
/// range-checked (message in `bt_creation_error`). The String parameters `slp.reference` and
/// `subject.mesh_dir` are set through the struct's pointers.
///
/// # Safety
/// `config` must be NULL or a valid, writable configuration; `name` NULL or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_config_set(
    config: *mut BtConfig,
    name: *const c_char,
    value: f64,
) -> c_int {
    without_handle(|| unsafe {
        if config.is_null() {
            return Err(Failure(BT_ERR_NULL, "argument `config` is NULL".into()));
        }
        let name = text(name, "name")?;
        let var = table()
            .by_name(name)
            .ok_or_else(|| Failure(BT_ERR_INVALID, format!("unknown parameter `{name}`")))?;
        let Role::Parameter(p) = var.role else {
            return Err(Failure(
                BT_ERR_INVALID,
                format!("`{name}` is not a parameter"),
            ));
        };
        var.check(value)?;
        let v = match var.ty {
            crate::fmi::variables::ScalarType::Real => crate::fmi::variables::Value::Real(value),
            crate::fmi::variables::ScalarType::Integer if value.fract() == 0.0 => {
                crate::fmi::variables::Value::Integer(value as i32)
            }
            crate::fmi::variables::ScalarType::Boolean if value == 0.0 || value == 1.0 => {
                crate::fmi::variables::Value::Boolean(value == 1.0)
            }
            crate::fmi::variables::ScalarType::Boolean => {
                return Err(Failure(
                    BT_ERR_INVALID,
                    format!("`{name}` is Boolean: it takes 0 (false) or 1 (true), not {value}"),
                ));
            }
            crate::fmi::variables::ScalarType::String => {
                return Err(Failure(
                    BT_ERR_INVALID,
                    format!(
                        "`{name}` is a String parameter: set it through the BtConfig field (slp_reference, subject_mesh_dir)"
                    ),
                ));
            }
            _ => {
                return Err(Failure(
                    BT_ERR_INVALID,
                    format!("`{name}` takes an integer or is not numeric"),
                ));
            }
        };
        let (slp, mesh_dir) = ((*config).slp_reference, (*config).subject_mesh_dir);
        let mut rust = config_from_c(&*config)?;
        p.set(&mut rust, v)?;
        *config = config_to_c(&rust, slp, mesh_dir);
        Ok(())
    })
}

/// Builds a model. Returns NULL on failure; `bt_creation_error()` then says why (naming the
/// variable and its allowed range).
///
/// # Safety
/// `config` must be NULL or a valid configuration.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_create(config: *const BtConfig) -> *mut BtTorso {
    let mut handle = std::ptr::null_mut();
    without_handle(|| unsafe {
        if config.is_null() {
            return Err(Failure(BT_ERR_NULL, "argument `config` is NULL".into()));
        }
        let torso = Torso::new(config_from_c(&*config)?)?;
        handle = Box::into_raw(Box::new(BtTorso {
            torso,
            last_error: CString::default(),
            skin: Vec::new(),
        }));
        Ok(())
    });
    handle
}

/// Releases a model (NULL is ignored).
///
/// # Safety
/// `h` must be NULL or a live handle, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_destroy(h: *mut BtTorso) {
    if !h.is_null() {
        // SAFETY: created by Box::into_raw in bt_create.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(h) })));
    }
}

/// The message of the last failed call on `h` (`""` after a success). Valid until the next
/// call on `h`.
///
/// # Safety
/// `h` must be NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_last_error(h: *const BtTorso) -> *const c_char {
    if h.is_null() {
        return c"null handle".as_ptr();
    }
    // SAFETY: a live handle.
    unsafe { (*h).last_error.as_ptr() }
}
