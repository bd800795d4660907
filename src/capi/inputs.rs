//! The model's inputs on a handle: the muscle groups' activations (by index or name), the
//! airway-opening pressure and occlusion, the built-in drive (replaced or read), and the start at the
//! equilibrium of the inputs applied now.

use super::convert::{drive_from_c, drive_to_c};
use super::guard::{Failure, put, text, with_handle};
use super::{BT_ERR_INVALID, BT_ERR_NULL, BT_MUSCLE_GROUPS, BtDrive, BtTorso};
use crate::anatomy::MuscleGroup;
use std::os::raw::{c_char, c_int};

/// Sets the activation input (0-1) of muscle group `group` (0..BT_MUSCLE_GROUPS-1). The
/// state stays where it is: the input acts from it as a step (`bt_start_at_equilibrium`
/// starts a run at the inputs' equilibrium instead).
///
/// # Safety
/// `h` must be NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_set_activation(h: *mut BtTorso, group: c_int, value: f64) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let g = usize::try_from(group)
                .ok()
                .and_then(|i| MuscleGroup::ALL.get(i))
                .ok_or_else(|| {
                    Failure(
                        BT_ERR_INVALID,
                        format!("muscle group {group}: allowed 0..{}", BT_MUSCLE_GROUPS - 1),
                    )
                })?;
            Ok(b.torso.set_activation(*g, value)?)
        })
    }
}

/// Sets the activation input (0-1) of a muscle group by name (`"diaphragm"`,
/// `"external_intercostals"`, ...: the FMI input names without `activation.`).
///
/// # Safety
/// `h` must be NULL or a live handle; `name` NULL or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_set_activation_by_name(
    h: *mut BtTorso,
    name: *const c_char,
    value: f64,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let name = text(name, "name")?;
            let g = MuscleGroup::from_name(name)
                .ok_or_else(|| Failure(BT_ERR_INVALID, format!("unknown muscle group `{name}`")))?;
            Ok(b.torso.set_activation(g, value)?)
        })
    }
}

/// Sets the pressure at the airway opening relative to the body surface [Pa] (FMI input
/// `pressure.airway_opening`; 0 breathing air, a ventilator's pressure, within +-50 cmH2O).
/// It reaches the alveolar and pleural pressures at once and the volumes through the
/// dynamics; a rejected value (`BT_ERR_INVALID`) changes nothing.
///
/// # Safety
/// `h` must be NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_set_airway_opening(h: *mut BtTorso, pascal: f64) -> c_int {
    unsafe { with_handle(h, |b| Ok(b.torso.set_airway_opening(pascal)?)) }
}

/// Occludes the airway at the mouth (`occluded` 1) or opens it (0) (FMI input
/// `airway.occluded`): while occluded no gas flows, the lungs' gas follows Boyle's law from
/// its volume and alveolar pressure at the moment of occlusion, and the mouth pressure
/// (`pressure.mouth`) equals the alveolar pressure. Any other value, or an occlusion under
/// the quasi-static method, is refused (`BT_ERR_INVALID`) and changes nothing.
///
/// # Safety
/// `h` must be NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_set_airway_occluded(h: *mut BtTorso, occluded: c_int) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let occluded = match occluded {
                0 => false,
                1 => true,
                v => {
                    return Err(Failure(
                        BT_ERR_INVALID,
                        format!("airway.occluded: {v}, allowed 0 (open) or 1 (occluded)"),
                    ));
                }
            };
            Ok(b.torso.set_airway_occluded(occluded)?)
        })
    }
}

/// Puts the model at the static equilibrium of the activations applied now (the activation
/// inputs plus the drive's value at the current time, plus the tone) and the airway-opening pressure, every
/// velocity zero (docs/dynamics.md, "The start state"): call it after setting the inputs a
/// run starts with. `bt_create` and `bt_reset` start at the equilibrium of the drive's start
/// with zero inputs, and `bt_set_drive` before the first step moves the start with it; the
/// activation and airway-pressure setters never move the state, so without this call they
/// act as steps. Solved once per model and activations (cached), by Newton iterations with a
/// damped relaxation of at most 40 s of model time as their fallback. `relative_imbalance`
/// (may be NULL) receives the largest unbalanced load over the largest anchor force at the
/// result: at most the solver's rtol when the solve settled (Newton typically reaches 1e-9);
/// larger when Newton stalled and the relaxation stopped at 40 s, the model then at the
/// state it reached.
///
/// # Safety
/// `h` must be NULL or a live handle; `relative_imbalance` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_start_at_equilibrium(
    h: *mut BtTorso,
    relative_imbalance: *mut f64,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let start = b.torso.start_at_equilibrium();
            if !relative_imbalance.is_null() {
                *relative_imbalance = start.relative_residual();
            }
            Ok(())
        })
    }
}

/// Replaces the drive (validated; on error nothing changes).
///
/// # Safety
/// `h` must be NULL or a live handle; `drive` NULL or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_set_drive(h: *mut BtTorso, drive: *const BtDrive) -> c_int {
    unsafe {
        with_handle(h, |b| {
            if drive.is_null() {
                return Err(Failure(BT_ERR_NULL, "argument `drive` is NULL".into()));
            }
            Ok(b.torso.set_drive(drive_from_c(&*drive))?)
        })
    }
}

/// Reads the current drive.
///
/// # Safety
/// `h` must be NULL or a live handle; `drive` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_get_drive(h: *mut BtTorso, drive: *mut BtDrive) -> c_int {
    unsafe {
        with_handle(h, |b| {
            put(drive, drive_to_c(&b.torso.config().drive), "drive")
        })
    }
}
