//! The model for external integrators: the dimension of the first-order state, reading and
//! setting the state, and the right-hand side dy/dt = f(t, y).

use super::guard::{Failure, Outcome, put, with_handle};
use super::{BT_ERR_INVALID, BT_ERR_NULL, BtTorso};
use std::os::raw::c_int;

/// For external integrators: the dimension n of the model's first-order state y (layout in
/// the crate's `dynamics::Layout`: rib angles and rates, sternum pose and velocity, abdominal
/// vertex positions and velocities). In quasi-static mode (`solver_method` 4) y holds the
/// positions of the last equilibrium solved and `bt_rhs` is not available: the integrated
/// state is the lung volume alone (`bt_quasi_rate`, `bt_quasi_set_volume`).
///
/// # Safety
/// `h` must be NULL or a live handle; `n` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_state_dim(h: *mut BtTorso, n: *mut usize) -> c_int {
    unsafe { with_handle(h, |b| put(n, b.torso.state_dim(), "n")) }
}

/// Checks a caller's state length against the model's.
fn check_dim(b: &BtTorso, n: usize) -> Outcome {
    let dim = b.torso.state_dim();
    if n == dim {
        Ok(())
    } else {
        Err(Failure(
            BT_ERR_INVALID,
            format!("state length {n}: this model's state has {dim} elements (bt_state_dim)"),
        ))
    }
}

/// For external integrators: copies the current state y (n = `bt_state_dim` doubles) into `y`.
///
/// # Safety
/// `h` must be NULL or a live handle; `y` NULL or `n` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_get_state(h: *mut BtTorso, y: *mut f64, n: usize) -> c_int {
    unsafe {
        with_handle(h, |b| {
            check_dim(b, n)?;
            if y.is_null() {
                return Err(Failure(BT_ERR_NULL, "argument `y` is NULL".into()));
            }
            std::slice::from_raw_parts_mut(y, n).copy_from_slice(b.torso.current_state());
            Ok(())
        })
    }
}

/// For external integrators: sets the model to time `t` and state y (n doubles, finite), so
/// that the quantities read afterwards (`bt_read`, `bt_read_markers`) are those of that state
/// and the next `bt_advance_to` continues from it. On error nothing changes.
///
/// # Safety
/// `h` must be NULL or a live handle; `y` NULL or `n` readable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_set_state(h: *mut BtTorso, t: f64, y: *const f64, n: usize) -> c_int {
    unsafe {
        with_handle(h, |b| {
            check_dim(b, n)?;
            if y.is_null() {
                return Err(Failure(BT_ERR_NULL, "argument `y` is NULL".into()));
            }
            Ok(b.torso.set_state(t, std::slice::from_raw_parts(y, n))?)
        })
    }
}

/// For external integrators: evaluates dy/dt = f(t, y) with the current activation inputs
/// plus the built-in drive evaluated at `t` (thesis eq. 2.4; clamped to 0-1, times the side
/// gains), writing n doubles into `dydt`. Does not change the model's own state or time, so
/// an integrator may call it at any t and y; `bt_set_state` then reads quantities off its
/// solution.
///
/// # Safety
/// `h` must be NULL or a live handle; `y` NULL or `n` readable doubles; `dydt` NULL or `n`
/// writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_rhs(
    h: *mut BtTorso,
    t: f64,
    y: *const f64,
    dydt: *mut f64,
    n: usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            check_dim(b, n)?;
            if y.is_null() || dydt.is_null() {
                return Err(Failure(
                    BT_ERR_NULL,
                    "arguments `y` and `dydt` must not be NULL".into(),
                ));
            }
            if !t.is_finite() {
                return Err(Failure(BT_ERR_INVALID, format!("t = {t} is not finite")));
            }
            let y = std::slice::from_raw_parts(y, n);
            let dydt = std::slice::from_raw_parts_mut(dydt, n);
            Ok(b.torso.rhs(t, y, dydt)?)
        })
    }
}
