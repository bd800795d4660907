//! A handle's state as a whole: snapshots as bytes (written and restored) and the reset to
//! the freshly built state.

use super::guard::{Failure, put, with_handle};
use super::{BT_ERR_BUFFER, BT_ERR_NULL, BtTorso};
use crate::model::Snapshot;
use std::os::raw::c_int;

/// Writes a snapshot of the model's mutable data (self-contained, versioned bytes) into
/// `buffer` (`capacity` bytes). `size` receives the snapshot's size; with a NULL or too small
/// buffer the call returns `BT_ERR_BUFFER` after writing `size`, so it can size the buffer.
///
/// # Safety
/// `h` must be NULL or a live handle; `buffer` NULL or `capacity` writable bytes; `size`
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_snapshot(
    h: *mut BtTorso,
    buffer: *mut u8,
    capacity: usize,
    size: *mut usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let bytes = b.torso.snapshot().to_bytes();
            put(size, bytes.len(), "size")?;
            if buffer.is_null() || capacity < bytes.len() {
                return Err(Failure(
                    BT_ERR_BUFFER,
                    format!(
                        "snapshot needs {} bytes, buffer holds {capacity}",
                        bytes.len()
                    ),
                ));
            }
            std::slice::from_raw_parts_mut(buffer, bytes.len()).copy_from_slice(&bytes);
            Ok(())
        })
    }
}

/// Restores a snapshot written by `bt_snapshot` of a model with the same configuration.
/// Anything else is an error and changes nothing.
///
/// # Safety
/// `h` must be NULL or a live handle; `buffer` NULL or `size` readable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_restore(h: *mut BtTorso, buffer: *const u8, size: usize) -> c_int {
    unsafe {
        with_handle(h, |b| {
            if buffer.is_null() {
                return Err(Failure(BT_ERR_NULL, "argument `buffer` is NULL".into()));
            }
            let snapshot = Snapshot::from_bytes(std::slice::from_raw_parts(buffer, size))?;
            Ok(b.torso.restore(&snapshot)?)
        })
    }
}

/// Back to the freshly built state: time 0, zero inputs, solver memory cleared, at the static
/// equilibrium of the drive's start (the rest pose when the drive is off or starts at zero
/// activation; docs/dynamics.md, "The start state").
///
/// # Safety
/// `h` must be NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_reset(h: *mut BtTorso) -> c_int {
    unsafe {
        with_handle(h, |b| {
            b.torso.reset();
            Ok(())
        })
    }
}
