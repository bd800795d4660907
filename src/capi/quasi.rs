//! The quasi-static mode for external integrators (`solver_method` 4): the reduced
//! right-hand side, the airflow into the lungs at a lung volume ([`bt_quasi_rate`]), and
//! setting the model to a time and lung volume ([`bt_quasi_set_volume`]).

use super::guard::{Failure, put, with_handle};
use super::{BT_ERR_NULL, BtTorso};
use std::os::raw::c_int;

/// For external integrators in quasi-static mode (`solver_method` 4), the reduced
/// right-hand side: the airflow into the lungs dV_L/dt [L/s] at time `t` and lung volume
/// `lung_volume` [L] (the mode's only state; start from `bt_read(h, BT_VR_VOLUME_LUNG, ..)`),
/// with the current activation inputs plus the built-in drive at `t`: the function the
/// library's own integrator steps (docs/dynamics.md, "Quasi-static mechanics"). Each call
/// solves the static equilibrium of the chest wall holding that volume, warm-started from the
/// last one solved. The model's time, lung volume and inputs do not change. Returns
/// `BT_ERR_STATE` in the other modes (their state is `bt_state_dim` long: use `bt_rhs`),
/// `BT_ERR_INVALID` for a non-finite `t` or a volume not above 0, and `BT_ERR_NUMERICAL` when
/// the equilibrium cannot be solved (the message names the reason, subject, posture and
/// activations; `rate` is then not written).
///
/// # Safety
/// `h` must be NULL or a live handle; `rate` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_quasi_rate(
    h: *mut BtTorso,
    t: f64,
    lung_volume: f64,
    rate: *mut f64,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            if rate.is_null() {
                return Err(Failure(BT_ERR_NULL, "argument `rate` is NULL".into()));
            }
            let r = b.torso.quasi_rate(t, lung_volume)?;
            put(rate, r, "rate")
        })
    }
}

/// For external integrators in quasi-static mode (`solver_method` 4): sets the model to time
/// `t` and lung volume `lung_volume` [L], so that what is read afterwards (`bt_read`,
/// `bt_read_markers`) is that of the chest wall's equilibrium holding that volume under the
/// activations applied at `t` (solved when first read), and the next `bt_advance_to`
/// continues from it. Errors as `bt_quasi_rate`'s; on error nothing changes.
///
/// # Safety
/// `h` must be NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_quasi_set_volume(h: *mut BtTorso, t: f64, lung_volume: f64) -> c_int {
    unsafe { with_handle(h, |b| Ok(b.torso.set_lung_volume(t, lung_volume)?)) }
}
