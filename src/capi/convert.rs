//! Conversions between the C structs and the facade's types: the configuration
//! ([`BtConfig`](super::BtConfig) <-> [`Config`]) and the drive
//! ([`BtDrive`](super::BtDrive) <-> [`Drive`]), with the checks a C value needs (a
//! non-negative count, a path from a C string).

use super::{BtConfig, BtDrive, BtSubject, BtWave};
use crate::anatomy::{Posture, Sex};
use crate::model::{Config, Drive, Scene, SolverConfig, Wave};
use crate::solver::Method;
use crate::{Error, Result};
use std::ffi::CStr;
use std::os::raw::{c_char, c_int};
use std::path::PathBuf;

pub(super) fn drive_to_c(d: &Drive) -> BtDrive {
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

pub(super) fn drive_from_c(d: &BtDrive) -> Drive {
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

pub(super) fn int(name: &str, v: c_int, range: &str) -> Result<usize> {
    usize::try_from(v).map_err(|_| Error::invalid(name, v, range))
}

/// A path from a NULL or NUL-terminated C string (`None` for NULL or empty).
///
/// # Safety
/// `p` must be NULL or a NUL-terminated string.
pub(super) unsafe fn c_path(p: *const c_char) -> Option<PathBuf> {
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
pub(super) unsafe fn config_from_c(c: &BtConfig) -> Result<Config> {
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
        muscle_law: crate::dynamics::muscle::MuscleLaw::from_code(c.muscle_law.into())?,
        gravity: c.gravity,
        gravity_loads: crate::dynamics::GravityLoads::from_code(c.gravity_loads.into())?,
        postural_tone: crate::model::postural_tone_from_code(c.postural_tone.into())?,
    };
    Ok(config)
}

pub(super) fn config_to_c(
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
        muscle_law: c.muscle_law.code(),
        gravity: c.gravity,
        gravity_loads: c.gravity_loads.code(),
        postural_tone: crate::model::postural_tone_code(c.postural_tone),
    }
}
