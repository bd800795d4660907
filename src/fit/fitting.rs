//! The fit of a model to an SLP recording (thesis 3.4 and 4.3): rigid registration of the
//! first frame (end-expiration) to the model's rest markers, breathing frequency from the
//! recording's principal displacement, then a bounded search over the rib-cage and
//! diaphragm amplitudes and phases minimising the mean marker-to-grid distance (eq. 3.1).
//!
//! Time convention: the model starts from rest, is driven for one breathing period to reach
//! its periodic regime, and recording time tau = 0 (the first frame) is model time 1/f.
//! The drive's phase at model time 1/f equals its phase at 0, so the fitted phases are
//! phases at the recording's first frame; the synthetic recordings use the same convention.

use super::Recording;
use super::optimize::{Bounds, Minimum, NelderMeadOptions, cmaes, multistart, nelder_mead};
use super::principal::principal_displacement;
use super::source::{MarkerModel, Trajectory};
use crate::anatomy::skin::{RigidTransform, register_rigid};
use crate::model::{Drive, Wave};
use crate::stats::frequency::{FrequencyEstimate, estimate_frequency};
use crate::{Error, Result};
use nalgebra::Point3;
use std::f64::consts::PI;
use std::time::Instant;

/// The search method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Bounded Nelder-Mead with adaptive coefficients (the thesis's method).
    NelderMead,
    /// Nelder-Mead from several starting points, then a polish of the best.
    Multistart,
    /// CMA-ES, for noisy or odd recordings.
    Cmaes,
}

impl Method {
    /// Parses `nelder-mead`, `multistart` or `cmaes`.
    pub fn from_name(name: &str) -> Result<Method> {
        match name {
            "nelder-mead" | "nm" => Ok(Method::NelderMead),
            "multistart" => Ok(Method::Multistart),
            "cmaes" | "cma-es" => Ok(Method::Cmaes),
            _ => Err(Error::invalid(
                "--method",
                name,
                "nelder-mead, multistart or cmaes",
            )),
        }
    }

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Method::NelderMead => "nelder-mead",
            Method::Multistart => "multistart",
            Method::Cmaes => "cmaes",
        }
    }
}

/// Allowed range of the fitted amplitudes (the drive's full range, fractions of the
/// maximal activation; thesis Table 4.3 found 0.02-0.62).
pub const AMPLITUDE_RANGE: (f64, f64) = (0.0, 1.0);

/// Settings of [`fit_recording`].
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Search method.
    pub method: Method,
    /// Largest number of cost evaluations.
    pub max_evals: usize,
    /// Starting rib-cage and diaphragm amplitudes.
    pub start_amplitudes: (f64, f64),
    /// Abdominal muscles' wave, held fixed (not fitted; amplitude 0 by default as in the
    /// thesis's three-parameter fits).
    pub abdominals: Wave,
    /// Starting points of the multi-start method.
    pub starts: usize,
    /// Seed of the randomised methods.
    pub seed: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            method: Method::NelderMead,
            max_evals: 120,
            start_amplitudes: (0.3, 0.3),
            abdominals: Wave::default(),
            starts: 4,
            seed: 1,
        }
    }
}

/// The outcome of a fit.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The fitted drive (phases at the recording's first frame, wrapped to (-pi, pi]).
    pub drive: Drive,
    /// Final cost, eq. 3.1 [m].
    pub cost_m: f64,
    /// Cost at the starting point [m].
    pub initial_cost_m: f64,
    /// Cost evaluations.
    pub evaluations: usize,
    /// Whether the optimiser met its tolerances (false: stopped on the budget).
    pub converged: bool,
    /// Wall time of the whole fit (registration, frequency, search, final run) [s].
    pub wall_s: f64,
    /// Diaphragm (abdominal) minus rib-cage phase, wrapped to (-pi, pi] (thesis 4.3.2).
    pub delta_phase: f64,
    /// The frequency estimate.
    pub frequency: FrequencyEstimate,
    /// Recording frame -> model frame.
    pub to_model: RigidTransform,
    /// Mean distance between the registered first frame and the rest markers [m].
    pub registration_mean_m: f64,
    /// RMS residual of the registration [m].
    pub registration_rms_m: f64,
    /// Recording times relative to the first frame [s].
    pub times: Vec<f64>,
    /// The recording's points in the model frame.
    pub recorded: Vec<Vec<Option<Point3<f64>>>>,
    /// The fitted model's markers and lung volume at the recording's times.
    pub fitted: Trajectory,
    /// Which method was used.
    pub method: Method,
    /// Grid (rows, columns).
    pub grid: (usize, usize),
}

/// Wraps an angle to (-pi, pi].
pub fn wrap_angle(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI { w + 2.0 * PI } else { w }
}

/// Mean Euclidean distance between model markers and tracked recorded points over all
/// frames and points (thesis eq. 3.1); untracked points are left out.
pub fn mean_distance(model: &[Vec<Point3<f64>>], recorded: &[Vec<Option<Point3<f64>>>]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (m, r) in model.iter().zip(recorded) {
        for (p, q) in m.iter().zip(r) {
            if let Some(q) = q {
                sum += (p - q).norm();
                n += 1;
            }
        }
    }
    if n == 0 {
        f64::INFINITY
    } else {
        sum / n as f64
    }
}

/// Checks that the recording's grid is the model's, naming both sizes when not.
pub fn check_grid(recording: (usize, usize), model: (usize, usize)) -> Result<()> {
    if recording != model {
        return Err(Error::invalid(
            "recording grid",
            format!(
                "{}x{} ({} points)",
                recording.0,
                recording.1,
                recording.0 * recording.1
            ),
            format!(
                "the model's marker grid {}x{} ({} points); build the model with grid.rows = {} and grid.cols = {}",
                model.0,
                model.1,
                model.0 * model.1,
                recording.0,
                recording.1
            ),
        ));
    }
    Ok(())
}

/// Phase [rad] of the fundamental of `signal` at `f` Hz: the least-squares fit
/// c + a sin(2 pi f t) + b cos(2 pi f t) = c + R sin(2 pi f t + psi), psi = atan2(b, a).
fn fundamental_phase(times: &[f64], signal: &[f64], f: f64) -> f64 {
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut aty = nalgebra::Vector3::<f64>::zeros();
    for (t, y) in times.iter().zip(signal) {
        let w = 2.0 * PI * f * t;
        let row = nalgebra::Vector3::new(1.0, w.sin(), w.cos());
        ata += row * row.transpose();
        aty += row * *y;
    }
    let sol = ata
        .try_inverse()
        .map(|inv| inv * aty)
        .unwrap_or_else(nalgebra::Vector3::zeros);
    sol[2].atan2(sol[1])
}

/// Fits `model` to `recording` (see the module doc). `progress(evaluations, best cost)` is
/// called after each cost evaluation.
pub fn fit_recording(
    model: &mut dyn MarkerModel,
    recording: &Recording,
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Fit> {
    let start = Instant::now();
    recording.validate()?;
    check_grid(recording.grid, model.grid())?;
    if options.max_evals < 10 {
        return Err(Error::invalid(
            "--max-evals",
            options.max_evals,
            "at least 10",
        ));
    }
    // Registration of the first frame to the rest markers.
    let rest = model.rest_markers()?;
    let (to_model, rms) = register_rigid(&rest, &recording.frames[0], false)?;
    let recorded: Vec<Vec<Option<Point3<f64>>>> = recording
        .frames
        .iter()
        .map(|f| f.iter().map(|q| q.map(|q| to_model.apply(&q))).collect())
        .collect();
    let registration_mean_m = mean_distance(std::slice::from_ref(&rest), &recorded[..1]);

    // Frequency and a starting phase from the principal displacement, signed so that the
    // breath moves the grid ventrally (+x in the model frame) on inspiration.
    let registered = Recording {
        grid: recording.grid,
        times: recording.times.clone(),
        frames: recorded.clone(),
        units: recording.units,
    };
    let pd = principal_displacement(&registered)?;
    let frequency = estimate_frequency(&pd.signal, recording.rate())?;
    let f = frequency.frequency_hz;
    crate::model::check(
        "drive.frequency (estimated from the recording)",
        f,
        (0.05, 2.0),
    )?;
    let ventral: f64 = pd.loadings.iter().map(|l| l.x).sum();
    let sign = if ventral < 0.0 { -1.0 } else { 1.0 };
    let t0 = recording.times[0];
    let times: Vec<f64> = recording.times.iter().map(|t| t - t0).collect();
    let signal: Vec<f64> = pd.signal.iter().map(|v| sign * v).collect();
    let psi = fundamental_phase(&times, &signal, f);

    // The search over (A_ribs, A_diaphragm, phi_ribs, phi_diaphragm).
    let settle = 1.0 / f;
    let model_times: Vec<f64> = times.iter().map(|t| settle + t).collect();
    let (alo, ahi) = AMPLITUDE_RANGE;
    let bounds = Bounds::new(&[
        (alo, ahi),
        (alo, ahi),
        (psi - PI, psi + PI),
        (psi - PI, psi + PI),
    ])?;
    let drive_of = |x: &[f64]| Drive {
        frequency: f,
        ribs: Wave {
            amplitude: x[0],
            phase: x[2],
        },
        diaphragm: Wave {
            amplitude: x[1],
            phase: x[3],
        },
        abdominals: options.abdominals,
    };
    let mut traj = Trajectory::default();
    let mut cost = |x: &[f64]| -> Result<f64> {
        model.run(&[(0.0, drive_of(x))], &model_times, false, &mut traj)?;
        Ok(mean_distance(&traj.markers, &recorded))
    };
    let x0 = [
        options.start_amplitudes.0.clamp(alo, ahi),
        options.start_amplitudes.1.clamp(alo, ahi),
        psi,
        psi,
    ];
    let nm = NelderMeadOptions {
        max_evals: options.max_evals,
        ..NelderMeadOptions::default()
    };
    let m: Minimum = match options.method {
        Method::NelderMead => nelder_mead(&mut cost, &x0, &bounds, &nm, progress)?,
        Method::Multistart => multistart(
            &mut cost,
            &x0,
            &bounds,
            &nm,
            options.starts,
            options.seed,
            progress,
        )?,
        Method::Cmaes => cmaes(
            &mut cost,
            &x0,
            &bounds,
            options.max_evals,
            0.25,
            options.seed,
            progress,
        )?,
    };
    let mut drive = drive_of(&m.x);
    drive.ribs.phase = wrap_angle(drive.ribs.phase);
    drive.diaphragm.phase = wrap_angle(drive.diaphragm.phase);
    let mut fitted = Trajectory::default();
    model.run(&[(0.0, drive_of(&m.x))], &model_times, true, &mut fitted)?;
    Ok(Fit {
        drive,
        cost_m: m.f,
        initial_cost_m: m.f_start,
        evaluations: m.evaluations,
        converged: m.converged,
        wall_s: start.elapsed().as_secs_f64(),
        delta_phase: wrap_angle(m.x[3] - m.x[2]),
        frequency,
        to_model,
        registration_mean_m,
        registration_rms_m: rms,
        times,
        recorded,
        fitted,
        method: options.method,
        grid: recording.grid,
    })
}
