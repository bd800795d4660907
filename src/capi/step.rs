//! Stepping a handle in time: [`bt_advance_to`] (the step with the physiological check the
//! FMU runs) and the current time.

use super::guard::{put, with_handle};
use super::{BtAdvanceStats, BtTorso};
use crate::model::AdvanceOptions;
use std::os::raw::c_int;

/// Integrates to time `t` [s] with the inputs held, checking the state it ends in against the
/// physiological bounds as the FMU does (the thorax, abdomen and trunk volumes against their
/// rest values, `docs/fmi.md`). `BT_ERR_NUMERICAL` when the solver failed (the model stays at
/// its last good time, `bt_time`) or the step ended outside the bounds (the model is back
/// where the step started); `bt_last_error` says which. `stats` may be NULL.
///
/// # Safety
/// `h` must be NULL or a live handle; `stats` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_advance_to(
    h: *mut BtTorso,
    t: f64,
    stats: *mut BtAdvanceStats,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let options = AdvanceOptions {
                check_physiology: true,
            };
            let s = b.torso.advance_to_with(t, options)?;
            if !stats.is_null() {
                *stats = BtAdvanceStats {
                    steps: s.steps,
                    rejected: s.rejected,
                    rhs_evaluations: s.rhs_evaluations,
                };
            }
            Ok(())
        })
    }
}

/// Current simulated time [s].
///
/// # Safety
/// `h` must be NULL or a live handle; `t` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_time(h: *mut BtTorso, t: *mut f64) -> c_int {
    unsafe { with_handle(h, |b| put(t, b.torso.time(), "t")) }
}
