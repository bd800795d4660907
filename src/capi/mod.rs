//! The native C ABI: everything the FMU offers and more (whole skin mesh, the right-hand side
//! for external integrators, snapshots as bytes), for C and C++ software that links the
//! library directly. The header `include/breathing_torso.h` is generated from this file by
//! cbindgen (with the FMI value references appended from [`crate::fmi::variables`]); a test
//! fails when the committed header is not current.
//!
//! Conventions: a `BtTorso *` is an opaque handle from [`bt_create`], released by
//! [`bt_destroy`]. Every function returns `BT_OK` (0) or a negative `BT_ERR_*` code; the
//! message of the last failure on a handle is [`bt_last_error`], and that of a failed
//! [`bt_create`] (or [`bt_config_set`]) is [`bt_creation_error`], kept per thread. Outputs are
//! written through caller pointers; buffers are caller-owned with an explicit capacity. No
//! function panics across the boundary (a caught panic returns `BT_ERR_PANIC`). Handles are
//! independent: one thread per handle at a time, any number of handles at once.
//!
//! The ABI's constants and structs are here; its functions are grouped by concern: how each
//! call runs and reports a failure (`guard`), the C structs' conversions (`convert`), a
//! handle's life and configuration (`lifecycle`), its inputs (`inputs`), stepping (`step`),
//! reading outputs (`read`), snapshots and reset (`state`), the model for external
//! integrators (`external`) and its quasi-static mode (`quasi`), and the header's
//! value-reference block (`header`); every function is re-exported here, so its path is
//! `capi::bt_*`. The header lists the functions in the order of these modules' declarations
//! below, each file's in its order.

#![allow(non_camel_case_types)]

mod convert;
mod guard;

// cbindgen lists the functions in the order of these declarations (then of each file), which
// is the header's order: keep each on its own line, apart, so that formatting does not sort
// them.
mod lifecycle;

mod inputs;

mod step;

mod read;

mod state;

mod external;

mod quasi;

mod header;

pub use external::{bt_get_state, bt_rhs, bt_set_state, bt_state_dim};
pub use header::header_value_references;
pub use inputs::{
    bt_get_drive, bt_set_activation, bt_set_activation_by_name, bt_set_airway_occluded,
    bt_set_airway_opening, bt_set_drive, bt_start_at_equilibrium,
};
pub use lifecycle::{
    bt_config_default, bt_config_set, bt_create, bt_creation_error, bt_destroy, bt_last_error,
    bt_version,
};
pub use quasi::{bt_quasi_rate, bt_quasi_set_volume};
pub use read::{
    bt_marker_count, bt_read, bt_read_by_name, bt_read_markers, bt_read_skin, bt_skin_sizes,
};
pub use state::{bt_reset, bt_restore, bt_snapshot};
pub use step::{bt_advance_to, bt_time};

use crate::model::Torso;
use std::ffi::CString;
use std::os::raw::{c_char, c_int};

/// Success.
pub const BT_OK: c_int = 0;
/// A required pointer argument was NULL.
pub const BT_ERR_NULL: c_int = -1;
/// A value is out of range or not finite, or a name is unknown (the message names it).
pub const BT_ERR_INVALID: c_int = -2;
/// The integrator failed; the model stays at its last good time (see `bt_time`).
pub const BT_ERR_NUMERICAL: c_int = -3;
/// Reserved for a quantity or feature a build or scene does not offer; no function of this
/// release returns it.
pub const BT_ERR_UNAVAILABLE: c_int = -4;
/// A caller buffer is too small; the needed size was written where the function says.
pub const BT_ERR_BUFFER: c_int = -5;
/// The request does not fit the model's state (e.g. a snapshot of another model).
pub const BT_ERR_STATE: c_int = -6;
/// An internal error was caught (a bug: please report the message).
pub const BT_ERR_PANIC: c_int = -7;
/// A file could not be read or written.
pub const BT_ERR_IO: c_int = -8;
/// A file could not be parsed (the message names file, line and column).
pub const BT_ERR_PARSE: c_int = -9;

/// Number of muscle groups (indices of `bt_set_activation`, in FMI input order: diaphragm,
/// external intercostals, internal intercostals, scalenes, transversus abdominis, rectus
/// abdominis, external obliques, internal obliques, sternocleidomastoids).
pub const BT_MUSCLE_GROUPS: c_int = 9;
// The C arrays sized by the group count are written with the literal (the header generator
// reads literals); this keeps them equal to the model's count.
const _: () = assert!(BT_MUSCLE_GROUPS as usize == crate::anatomy::MuscleGroup::COUNT);

/// The subject the model is built for.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct BtSubject {
    /// 0 male, 1 female.
    pub sex: c_int,
    /// Age [years], 18-90.
    pub age: f64,
    /// Stature [m], 1.40-2.10.
    pub stature: f64,
    /// Body mass [kg], 40-160 (body mass index 13-60).
    pub mass: f64,
    /// Breast size, 0-1.
    pub breast_size: f64,
    /// 0 standing, 1 sitting, 2 supine.
    pub posture: c_int,
}

/// One sinusoidal drive wave (thesis eq. 2.4).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct BtWave {
    /// Amplitude, 0-1 (fraction of the maximal activation).
    pub amplitude: f64,
    /// Phase [rad], -2 pi .. 2 pi.
    pub phase: f64,
}

/// The built-in drive.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct BtDrive {
    /// Breathing frequency [Hz], 0.05-2.
    pub frequency: f64,
    /// Rib-cage muscles.
    pub ribs: BtWave,
    /// Diaphragm.
    pub diaphragm: BtWave,
    /// Abdominal wall muscles.
    pub abdominals: BtWave,
    /// 1: the drive runs; 0: off, the muscles follow the activation inputs alone (FMI
    /// `drive.enabled`).
    pub enabled: c_int,
    /// Inspiratory fraction Ti/Ttot of every family's wave, 0.2-0.8; 0.5 is the sine of
    /// thesis eq. 2.4 (FMI `drive.inspiratory_fraction`).
    pub inspiratory_fraction: f64,
}

/// Everything needed to build a model. Fill it with `bt_config_default`, then change fields
/// directly or by FMI parameter name with `bt_config_set`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct BtConfig {
    /// The subject.
    pub subject: BtSubject,
    /// Level of detail 0, 1 or 2.
    pub level_of_detail: c_int,
    /// Marker grid rows, 1-16.
    pub grid_rows: c_int,
    /// Marker grid columns, 1-16.
    pub grid_cols: c_int,
    /// SLP recording registering the marker grid (NUL-terminated path), or NULL for the
    /// default grid. Copied by `bt_create`.
    pub slp_reference: *const c_char,
    /// Integration method code (0 Dormand-Prince 5(4), 1 Bogacki-Shampine 3(2), 2 high order,
    /// 3 Rosenbrock-W for stiff scenes, 4 quasi-static: the chest wall in equilibrium at every
    /// instant, the lung volume the only state).
    pub solver_method: c_int,
    /// Relative tolerance, 1e-12 .. 1e-2.
    pub solver_rtol: f64,
    /// Absolute tolerance, 1e-14 .. 1e-2.
    pub solver_atol: f64,
    /// Largest internal step [s], 1e-5 .. 1.
    pub solver_max_step: f64,
    /// The drive.
    pub drive: BtDrive,
    /// Lung volume as a fraction of the thoracic volume at rest, 0.3-1; the rest (heart,
    /// mediastinum) keeps its volume, so lung and thoracic volumes change one to one.
    pub lung_ratio: f64,
    /// Activation gain of the left side, 0-2.
    pub gain_left: f64,
    /// Activation gain of the right side, 0-2.
    pub gain_right: f64,
    /// Subject mesh directory written by `torso mesh prepare` (NUL-terminated path; FMI
    /// `subject.mesh_dir`): its skin and cavity replace the generated ones. NULL or `""`:
    /// generated geometry. Copied by `bt_create`.
    pub subject_mesh_dir: *const c_char,
    /// Activation gain of each muscle group (index as `bt_set_activation`) on the right side,
    /// 0-2, times `gain_right` (FMI `gain.<group>.right`; 1 healthy, 0 paralysed).
    pub group_gain_right: [f64; 9],
    /// Activation gain of each muscle group on the left side, 0-2, times `gain_left`.
    pub group_gain_left: [f64; 9],
    /// Muscle law (FMI `muscle_law`): 0 the seed thesis's shortening linear spring, 1 passive
    /// and active parts with the passive wall fitted to the adult chest wall's compliance.
    pub muscle_law: c_int,
    /// Gravitational acceleration [m/s^2], 0 to 3 x 9.81 (FMI `gravity`; 9.81 by default).
    pub gravity: f64,
    /// How gravity loads the model (FMI `gravity_loads`): 0 preloads cancel it at each
    /// posture's rest (default), 1 it acts (the abdominal contents' hydrostatic pressure, the
    /// tissues' tensions from the standing reference, the rest found under the loads).
    pub gravity_loads: c_int,
    /// The posture's tonic muscle activity (FMI `postural_tone`): 1 on (default; standing
    /// under muscle law 1 the abdominal wall's tone, 0.017 of the maximal force, Cholewicki et
    /// al. 1997), 0 off (a relaxed subject, as in a relaxation manoeuvre).
    pub postural_tone: c_int,
}

/// Statistics of one `bt_advance_to` call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct BtAdvanceStats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
}

/// An opaque model handle.
pub struct BtTorso {
    torso: Torso,
    last_error: CString,
    /// The deformed skin's vertices of the last `bt_read_skin`, kept to reuse its memory.
    skin: Vec<nalgebra::Point3<f64>>,
}
