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

#![allow(non_camel_case_types)]

use crate::anatomy::{MuscleGroup, Posture, Sex};
use crate::fmi::variables::{Role, table};
use crate::model::{AdvanceOptions, Config, Drive, Scene, Snapshot, SolverConfig, Torso, Wave};
use crate::solver::Method;
use crate::{Error, Result};
use std::cell::RefCell;
use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

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
/// abdominis, external obliques, internal obliques).
pub const BT_MUSCLE_GROUPS: c_int = 8;

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
    pub group_gain_right: [f64; 8],
    /// Activation gain of each muscle group on the left side, 0-2, times `gain_left`.
    pub group_gain_left: [f64; 8],
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

thread_local! {
    static CREATION_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn c_message(s: &str) -> CString {
    CString::new(s.replace('\0', "")).unwrap_or_default()
}

fn code_of(e: &Error) -> c_int {
    match e {
        Error::InvalidParameter { .. } => BT_ERR_INVALID,
        Error::Numerical { .. } | Error::Unphysiological { .. } => BT_ERR_NUMERICAL,
        Error::Parse { .. } => BT_ERR_PARSE,
        Error::Io { .. } => BT_ERR_IO,
        Error::State(_) => BT_ERR_STATE,
    }
}

/// A failure of a C ABI call: its code and message.
struct Failure(c_int, String);

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        Failure(code_of(&e), e.to_string())
    }
}

type Outcome = std::result::Result<(), Failure>;

/// Runs `body` on the handle, records a failure's message on it, catches panics.
///
/// # Safety
/// `h` must be NULL or a live handle from `bt_create`.
unsafe fn with_handle(h: *mut BtTorso, body: impl FnOnce(&mut BtTorso) -> Outcome) -> c_int {
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
fn without_handle(body: impl FnOnce() -> Outcome) -> c_int {
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
unsafe fn put<T>(out: *mut T, v: T, name: &str) -> Outcome {
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
unsafe fn text<'a>(p: *const c_char, name: &str) -> std::result::Result<&'a str, Failure> {
    if p.is_null() {
        return Err(Failure(BT_ERR_NULL, format!("argument `{name}` is NULL")));
    }
    // SAFETY: NUL-terminated by the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| Failure(BT_ERR_INVALID, format!("argument `{name}` is not UTF-8")))
}

fn drive_to_c(d: &Drive) -> BtDrive {
    let w = |w: Wave| BtWave {
        amplitude: w.amplitude,
        phase: w.phase,
    };
    BtDrive {
        frequency: d.frequency,
        ribs: w(d.ribs),
        diaphragm: w(d.diaphragm),
        abdominals: w(d.abdominals),
        enabled: c_int::from(d.enabled),
        inspiratory_fraction: d.inspiratory_fraction,
    }
}

fn drive_from_c(d: &BtDrive) -> Drive {
    let w = |w: BtWave| Wave {
        amplitude: w.amplitude,
        phase: w.phase,
    };
    Drive {
        enabled: d.enabled != 0,
        frequency: d.frequency,
        inspiratory_fraction: d.inspiratory_fraction,
        ribs: w(d.ribs),
        diaphragm: w(d.diaphragm),
        abdominals: w(d.abdominals),
    }
}

fn int(name: &str, v: c_int, range: &str) -> Result<usize> {
    usize::try_from(v).map_err(|_| Error::invalid(name, v, range))
}

/// A path from a NULL or NUL-terminated C string (`None` for NULL or empty).
///
/// # Safety
/// `p` must be NULL or a NUL-terminated string.
unsafe fn c_path(p: *const c_char) -> Option<PathBuf> {
    if p.is_null() {
        return None;
    }
    // SAFETY: by the caller's contract.
    let p = unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    (!p.is_empty()).then(|| PathBuf::from(p))
}

/// Converts a C configuration (the path pointers must be NULL or NUL-terminated).
///
/// # Safety
/// `c.slp_reference` and `c.subject_mesh_dir` must be NULL or NUL-terminated strings.
unsafe fn config_from_c(c: &BtConfig) -> Result<Config> {
    let s = &c.subject;
    // SAFETY: by the caller's contract.
    let (slp_reference, subject_mesh_dir) =
        unsafe { (c_path(c.slp_reference), c_path(c.subject_mesh_dir)) };
    let config = Config {
        subject: crate::anatomy::Subject {
            sex: Sex::from_code(s.sex.into())?,
            age: s.age,
            stature: s.stature,
            mass: s.mass,
            breast_size: s.breast_size,
            posture: Posture::from_code(s.posture.into())?,
        },
        scene: Scene {
            level_of_detail: int("scene.level_of_detail", c.level_of_detail, "0, 1 or 2")? as u32,
            grid_rows: int("grid.rows", c.grid_rows, "1..16")?,
            grid_cols: int("grid.cols", c.grid_cols, "1..16")?,
            slp_reference,
        },
        solver: SolverConfig {
            method: Method::from_code(c.solver_method.into()).ok_or_else(|| {
                Error::invalid(
                    "solver.method",
                    c.solver_method,
                    format!("0..{}", Method::ALL.len() - 1),
                )
            })?,
            rtol: c.solver_rtol,
            atol: c.solver_atol,
            max_step: c.solver_max_step,
            ..SolverConfig::default()
        },
        drive: drive_from_c(&c.drive),
        lung_ratio: c.lung_ratio,
        gain_left: c.gain_left,
        gain_right: c.gain_right,
        group_gains: crate::model::GroupGains {
            right: c.group_gain_right,
            left: c.group_gain_left,
        },
        subject_mesh_dir,
        // the C ABI builds the default constants; overrides are a library-level study tool
        params: None,
    };
    Ok(config)
}

fn config_to_c(
    c: &Config,
    slp_reference: *const c_char,
    subject_mesh_dir: *const c_char,
) -> BtConfig {
    let s = &c.subject;
    BtConfig {
        subject: BtSubject {
            sex: s.sex.code(),
            age: s.age,
            stature: s.stature,
            mass: s.mass,
            breast_size: s.breast_size,
            posture: s.posture.code(),
        },
        level_of_detail: c.scene.level_of_detail as c_int,
        grid_rows: c.scene.grid_rows as c_int,
        grid_cols: c.scene.grid_cols as c_int,
        slp_reference,
        solver_method: c.solver.method.code(),
        solver_rtol: c.solver.rtol,
        solver_atol: c.solver.atol,
        solver_max_step: c.solver.max_step,
        drive: drive_to_c(&c.drive),
        lung_ratio: c.lung_ratio,
        gain_left: c.gain_left,
        gain_right: c.gain_right,
        subject_mesh_dir,
        group_gain_right: c.group_gains.right,
        group_gain_left: c.group_gains.left,
    }
}

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

/// Puts the model at the static equilibrium of the activations applied now (the activation
/// inputs plus the drive's value at the current time) and the airway-opening pressure, every
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

fn read_variable(b: &mut BtTorso, var: &crate::fmi::variables::Variable) -> Result<f64> {
    match var.role {
        Role::Time => Ok(b.torso.time()),
        Role::Input(input) => Ok(input.value(&b.torso)),
        Role::Parameter(p) => match p.get(b.torso.config()) {
            crate::fmi::variables::Value::Real(x) => Ok(x),
            crate::fmi::variables::Value::Integer(i) => Ok(f64::from(i)),
            crate::fmi::variables::Value::Boolean(b) => Ok(f64::from(u8::from(b))),
            crate::fmi::variables::Value::String(_) => {
                Err(Error::invalid(&var.name, "(string)", "a numeric variable"))
            }
        },
        Role::Output(q) => b.torso.read_output(&var.name, q),
    }
}

/// A grid marker beyond the generic FMU's [`MARKER_SLOTS`](crate::fmi::variables::MARKER_SLOTS)
/// outputs, which the C library reads as well (its grid may have up to 16 x 16 markers):
/// `BT_VR_MARKER(i, axis)` or `marker[i].<axis>` for i up to 256, as (0-based index, axis).
fn extra_grid_marker(vr: Option<u32>, name: Option<&str>) -> Option<(u16, u8)> {
    use crate::fmi::variables::{MARKER_SLOTS, MAX_MARKER_OUTPUTS, VR_MARKER};
    let (index, axis) = match (vr, name) {
        (Some(vr), _) => {
            let k = vr.checked_sub(VR_MARKER)?;
            (u16::try_from(k / 3).ok()?, (k % 3) as u8)
        }
        (None, Some(name)) => {
            let rest = name.strip_prefix("marker[")?;
            let (i, a) = rest.split_once("].")?;
            let i: u16 = i.parse().ok().filter(|&i| i >= 1)?;
            let axis = ["x", "y", "z"].iter().position(|x| *x == a)? as u8;
            (i - 1, axis)
        }
        (None, None) => return None,
    };
    (MARKER_SLOTS..MAX_MARKER_OUTPUTS)
        .contains(&index)
        .then_some((index, axis))
}

/// Reads a grid marker that is not one of the table's outputs ([`extra_grid_marker`]).
fn read_extra_marker(b: &mut BtTorso, (index, axis): (u16, u8)) -> Result<f64> {
    let name = format!(
        "marker[{}].{}",
        index + 1,
        ["x", "y", "z"][usize::from(axis)]
    );
    b.torso
        .read_output(&name, crate::model::Quantity::Marker { index, axis })
}

/// Reads any numeric FMI variable by value reference (`BT_VR_*` constants): outputs, inputs,
/// parameters, time. `BT_VR_MARKER(i, axis)` takes any i up to 256 (the largest grid, 16 x
/// 16), beyond the FMU's `BT_MARKER_SLOTS`; markers beyond the grid read 0.
///
/// # Safety
/// `h` must be NULL or a live handle; `value` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read(h: *mut BtTorso, vr: u32, value: *mut f64) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let v = match table().by_vr(vr) {
                Some(var) => read_variable(b, var)?,
                None => {
                    let marker = extra_grid_marker(Some(vr), None).ok_or_else(|| {
                        Failure(BT_ERR_INVALID, format!("unknown value reference {vr}"))
                    })?;
                    read_extra_marker(b, marker)?
                }
            };
            put(value, v, "value")
        })
    }
}

/// Reads any numeric FMI variable by name (`"volume.lung"`, `"marker[3].y"`, ...; grid
/// markers up to `marker[256]`, as [`bt_read`]).
///
/// # Safety
/// `h` must be NULL or a live handle; `name` NULL or NUL-terminated; `value` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read_by_name(
    h: *mut BtTorso,
    name: *const c_char,
    value: *mut f64,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let name = text(name, "name")?;
            let v = match table().by_name(name) {
                Some(var) => read_variable(b, var)?,
                None => {
                    let marker = extra_grid_marker(None, Some(name)).ok_or_else(|| {
                        Failure(BT_ERR_INVALID, format!("unknown variable `{name}`"))
                    })?;
                    read_extra_marker(b, marker)?
                }
            };
            put(value, v, "value")
        })
    }
}

/// Number of markers of the scene (`grid_rows * grid_cols`).
///
/// # Safety
/// `h` must be NULL or a live handle; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_marker_count(h: *mut BtTorso, count: *mut usize) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let s = &b.torso.config().scene;
            put(count, s.grid_rows * s.grid_cols, "count")
        })
    }
}

/// Writes the marker positions [m] as x, y, z triples, row-major from the top row, column 1 on
/// the subject's right, into `xyz` (capacity `capacity` doubles: at least 3 x the marker
/// count, else `BT_ERR_BUFFER`). `count` (may be NULL) receives the number of markers.
///
/// # Safety
/// `h` must be NULL or a live handle; `xyz` NULL or `capacity` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read_markers(
    h: *mut BtTorso,
    xyz: *mut f64,
    capacity: usize,
    count: *mut usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let s = &b.torso.config().scene;
            let n = s.grid_rows * s.grid_cols;
            if !count.is_null() {
                *count = n;
            }
            if capacity < 3 * n {
                return Err(Failure(
                    BT_ERR_BUFFER,
                    format!("marker buffer holds {capacity} doubles, {} needed", 3 * n),
                ));
            }
            if xyz.is_null() {
                return Err(Failure(BT_ERR_NULL, "argument `xyz` is NULL".into()));
            }
            let out = std::slice::from_raw_parts_mut(xyz, 3 * n);
            // the markers of the state once (not 3 n reads by name); those past the marker
            // count read 0, as in `bt_read`
            let count = b.torso.marker_count().min(n);
            let time = b.torso.time();
            let markers = b
                .torso
                .markers()
                .map_err(|e| crate::Error::State(format!("cannot read the markers: {e}")))?;
            out.fill(0.0);
            for (i, (o, p)) in out.chunks_exact_mut(3).zip(&markers[..count]).enumerate() {
                for (axis, (o, x)) in o.iter_mut().zip(p.coords.iter()).enumerate() {
                    if !x.is_finite() {
                        let name = format!("marker[{}].{}", i + 1, ["x", "y", "z"][axis]);
                        return Err(crate::Error::Numerical {
                            time,
                            reason: format!("`{name}` is not finite ({x})"),
                        }
                        .into());
                    }
                    *o = *x;
                }
            }
            Ok(())
        })
    }
}

/// Sizes of the whole skin mesh (the surface the markers sit on): its vertex and triangle
/// counts, fixed for the handle's life. The first skin or marker call builds the skin model (a
/// few tenths of a second, shared with the markers). Either output may be NULL.
///
/// # Safety
/// `h` must be NULL or a live handle; the outputs NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_skin_sizes(
    h: *mut BtTorso,
    vertices: *mut usize,
    triangles: *mut usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let model = b.torso.marker_model()?;
            let skin = model.skin();
            if !vertices.is_null() {
                *vertices = skin.vertices.len();
            }
            if !triangles.is_null() {
                *triangles = skin.triangles.len();
            }
            Ok(())
        })
    }
}

/// Writes the skin mesh of the current state: vertex positions [m] as x, y, z triples into
/// `vertices` (`vertex_capacity` doubles, at least 3 x the vertex count of `bt_skin_sizes`),
/// in the markers' frame (the recording's when the grid is registered, else the model's),
/// and the triangles as vertex-index triples, counter-clockwise seen from outside, into
/// `triangles` (`triangle_capacity` indices, at least 3 x the triangle count). Either buffer
/// may be NULL and is then skipped: the triangles never change, so read them once and the
/// vertices every frame. Both NULL is `BT_ERR_NULL`; a buffer too small is `BT_ERR_BUFFER`
/// and nothing is written.
///
/// # Safety
/// `h` must be NULL or a live handle; buffers NULL or writable for their capacities.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read_skin(
    h: *mut BtTorso,
    vertices: *mut f64,
    vertex_capacity: usize,
    triangles: *mut u32,
    triangle_capacity: usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            if vertices.is_null() && triangles.is_null() {
                return Err(Failure(
                    BT_ERR_NULL,
                    "arguments `vertices` and `triangles` are both NULL".into(),
                ));
            }
            let model = b.torso.marker_model()?;
            let skin = model.skin();
            let (nv, nt) = (3 * skin.vertices.len(), 3 * skin.triangles.len());
            if !vertices.is_null() && vertex_capacity < nv {
                return Err(Failure(
                    BT_ERR_BUFFER,
                    format!("skin vertex buffer holds {vertex_capacity} doubles, {nv} needed"),
                ));
            }
            if !triangles.is_null() && triangle_capacity < nt {
                return Err(Failure(
                    BT_ERR_BUFFER,
                    format!("skin triangle buffer holds {triangle_capacity} indices, {nt} needed"),
                ));
            }
            if !vertices.is_null() {
                b.torso.skin_vertices(&mut b.skin)?;
                let out = std::slice::from_raw_parts_mut(vertices, nv);
                for (o, p) in out.chunks_exact_mut(3).zip(&b.skin) {
                    o.copy_from_slice(&[p.x, p.y, p.z]);
                }
            }
            if !triangles.is_null() {
                let out = std::slice::from_raw_parts_mut(triangles, nt);
                for (o, t) in out.chunks_exact_mut(3).zip(&skin.triangles) {
                    o.copy_from_slice(t);
                }
            }
            Ok(())
        })
    }
}

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

/// The value-reference block appended to `include/breathing_torso.h`: one `BT_VR_*` constant
/// per FMI variable (name upper-cased, `.` as `_`), a macro for the markers, the GUID and the
/// marker slot count, all generated from [`crate::fmi::variables`]. `bt_read` takes these.
pub fn header_value_references() -> String {
    use crate::fmi::variables::{MARKER_SLOTS, Role, VR_MARKER};
    use std::fmt::Write;
    let t = table();
    let mut s = String::from(
        "/* FMI value references (generated from the variable table), for bt_read(). */\n",
    );
    let _ = writeln!(s, "#define BT_FMI_GUID \"{}\"", t.guid());
    let _ = writeln!(s, "#define BT_MARKER_SLOTS {MARKER_SLOTS}");
    for v in t.variables() {
        if matches!(v.role, Role::Output(crate::model::Quantity::Marker { .. })) {
            continue;
        }
        let name: String = v
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() {
                    c.to_ascii_uppercase()
                } else {
                    '_'
                }
            })
            .collect();
        let _ = writeln!(s, "#define BT_VR_{name} {}u", v.vr);
    }
    let _ = writeln!(
        s,
        "/* marker[i].x|y|z, axis 0 = x, 1 = y, 2 = z: i = 1..BT_MARKER_SLOTS are the FMU's outputs (the\n   \
         default 10 x 6 grid); bt_read takes i up to 256 (a grid of up to 16 x 16) */\n\
         #define BT_VR_MARKER(i, axis) ({VR_MARKER}u + 3u * ((unsigned)(i) - 1u) + (unsigned)(axis))"
    );
    s
}
