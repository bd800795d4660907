//! The fit of a model to an SLP recording (thesis 3.4 and 4.3): rigid registration of the
//! first frame (end-expiration) to the model's rest markers, breathing frequency from the
//! recording's principal displacement, then a bounded search over the rib-cage and
//! diaphragm amplitudes and phases minimising the mean marker-to-grid distance (eq. 3.1).
//!
//! The search: a linearised start (two basis runs, see [`linearised_start`]), then the
//! chosen optimiser in a box: amplitudes in [0, 1], each phase within pi of its start. The
//! cost applies one rigid pose correction fitted over all frames before eq. 3.1 (see
//! [`aligned_cost`]).
//!
//! Time convention: the model starts from rest, is driven for one breathing period to reach
//! its periodic regime, and recording time tau = 0 (the first frame) is model time 1/f.
//! The drive's phase at model time 1/f equals its phase at 0, so the fitted phases are
//! phases at the recording's first frame; the synthetic recordings use the same convention.

use super::breathing::{RecordingBreaths, breaths_of_signal};
use super::principal::principal_displacement;
use super::source::{MarkerSource, Trajectory};
use crate::anatomy::skin::{RigidTransform, register_rigid};
use crate::model::{Drive, Wave};
use crate::numeric::optimize::{
    Bounds, Minimum, NelderMeadOptions, Spare, cmaes, multistart, nelder_mead_parallel,
};
use crate::recording::Recording;
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
    /// Start from the linearised estimate (two extra model runs, counted as evaluations);
    /// otherwise from `start_amplitudes` and the recording's breath phase.
    pub linearised_start: bool,
    /// Starting rib-cage and diaphragm amplitudes when not `linearised_start`.
    pub start_amplitudes: (f64, f64),
    /// Abdominal muscles' wave, held fixed (not fitted; amplitude 0 by default as in the
    /// thesis's three-parameter fits).
    pub abdominals: Wave,
    /// Inspiratory fraction Ti/Ttot of the fitted drive, held fixed by the search (0.5: the
    /// sine of thesis eq. 2.4); `None`: the median Ti/Ttot of the recording's breaths
    /// ([`super::breathing`]), clamped to the drive's range.
    pub inspiratory_fraction: Option<f64>,
    /// Starting points of the multi-start method.
    pub starts: usize,
    /// Seed of the randomised methods.
    pub seed: u64,
    /// Start the search here, (A_ribs, A_diaphragm, phi_ribs, phi_diaphragm) with phases at
    /// the recording's first frame, with a small simplex (a polish of an earlier fit);
    /// overrides `linearised_start` and `start_amplitudes`.
    pub start: Option<[f64; 4]>,
    /// Threads for the Nelder-Mead search: with 2, a second instance of the model (sharing
    /// the compiled model) evaluates ahead the point the search is likely to need next
    /// ([`crate::numeric::optimize::nelder_mead_parallel`]); the search and its result are those
    /// of one thread.
    pub threads: usize,
    /// Leave each marker's constant offset out of the cost: the model's and the recording's
    /// trajectories of each marker are compared about their own means over the recording
    /// ([`centred_cost`]), with no pose refinement. For marker sets bound to the skin by
    /// registration without correspondences, where each recorded marker stands off its
    /// skin point by its unknown placement error and its height above the skin (half a
    /// 10-14 mm motion-capture marker); off (the thesis's eq. 3.1) for the grid.
    pub marker_offsets: bool,
    /// Remove each marker coordinate's slow drift (a linear spline, knots at least three
    /// breaths apart, [`super::drift`]) from the cost in closed form at each evaluation
    /// (variable projection); implies comparing each marker about its own mean. The fit
    /// then reports each drive parameter's sensitivity before and after the projection.
    pub drift: bool,
    /// Remove the whole trunk's sway before the fit, for a recording of a named marker set
    /// ([`super::named::fit_any_markers`]): the rigid motion of quasi-rigid reference
    /// markers, its part slower than the breath ([`super::sway`]). The grid and sets
    /// without reference markers get none, and the fit's `sway` says why.
    pub sway: bool,
    /// Labels of the sway's reference markers (`--reference`); empty: the markers over the
    /// back, found from the registered pose.
    pub reference: Vec<String>,
    /// Find and repair label swaps and ghost markers before the fit ([`super::clean`]);
    /// gaps longer than a breath are left out of the breath detection either way.
    pub clean: bool,
    /// Marker radius [m] of a named marker set: each recorded marker's centre stands this
    /// far off its skin point along the skin's outward normal
    /// ([`super::named::bind_with_radius`]); 0 takes the recorded points as skin points.
    pub marker_radius: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            method: Method::NelderMead,
            max_evals: 120,
            linearised_start: true,
            start_amplitudes: (0.3, 0.3),
            abdominals: Wave::default(),
            inspiratory_fraction: Some(crate::model::drive::SINE_FRACTION),
            starts: 4,
            seed: 1,
            start: None,
            threads: 1,
            marker_offsets: false,
            drift: false,
            sway: false,
            reference: Vec::new(),
            clean: true,
            marker_radius: 0.0,
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
    /// Model runs spent choosing the parameters: the linearised start's runs plus the
    /// optimiser's cost evaluations (one more run produces the outputs).
    pub evaluations: usize,
    /// Whether the optimiser met its tolerances (false: stopped on the budget).
    pub converged: bool,
    /// Model runs made ahead on a second thread that the search did not use (not in
    /// `evaluations`; zero with one thread).
    pub unused_ahead: usize,
    /// Wall time of the whole fit (registration, frequency, search, final run) [s].
    pub wall_s: f64,
    /// Diaphragm (abdominal) minus rib-cage phase, wrapped to (-pi, pi] (thesis 4.3.2).
    pub delta_phase: f64,
    /// The frequency estimate.
    pub frequency: FrequencyEstimate,
    /// Recording frame -> model frame.
    pub to_model: RigidTransform,
    /// The frame of `recorded` and `fitted.markers` -> the model's anatomical frame (x
    /// anterior, y superior, z right): the identity, unless the model gave its markers in
    /// the recording's frame (its skin fitted to the recording, `scene.slp_reference`),
    /// when it is the model's registration (recording -> model). Views of the markers use it.
    pub to_anatomy: RigidTransform,
    /// Mean distance between the registered first frame and the rest markers [m].
    pub registration_mean_m: f64,
    /// Skin fitting by the model (mean error before, after) [m], when it fitted its skin to
    /// the first frame (`scene.slp_reference`).
    pub skin_fit: Option<(f64, f64)>,
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
    /// The recording's breaths, read off its principal displacement.
    pub breathing: RecordingBreaths,
    /// Knot times of the drift spline removed by the cost [s] (None: no drift removed).
    pub drift_knots: Option<Vec<f64>>,
    /// Each drive parameter's sensitivity at the optimum, before and after the drift is
    /// projected out (empty without drift).
    pub sensitivity: Vec<Sensitivity>,
    /// The sway removed before the fit, or why none was (None: not asked for).
    pub sway: Option<super::sway::Sway>,
    /// What was repaired or left out of the recording, one sentence each: label swaps,
    /// ghost markers ([`super::clean`]), gaps longer than a breath.
    pub repairs: Vec<String>,
    /// Gaps longer than a breath, left out of the breath detection and never
    /// interpolated: (marker, first missing frame, frame after the last), 0-based.
    pub long_gaps: Vec<(usize, usize, usize)>,
}

impl Fit {
    /// Adds a sentence per gap longer than a breath to [`Fit::repairs`], naming each
    /// marker by `labels`.
    pub fn note_long_gaps(&mut self, labels: &[String]) {
        let breath = 1.0 / self.drive.frequency;
        for &(p, a, b) in &self.long_gaps {
            let label = labels.get(p).map_or("?", String::as_str);
            let end = (b.max(1) - 1).min(self.times.len().saturating_sub(1));
            self.repairs.push(format!(
                "marker {label}: untracked from frame {} to frame {b} ({:.2}-{:.2} s), longer than a breath ({breath:.2} s): \
                 left out there (not interpolated) and out of the breath detection",
                a + 1,
                self.times[a.min(end)],
                self.times[end],
            ));
        }
    }
}

/// How much a drive parameter moves the markers at the fit's optimum: the root mean square
/// over the tracked samples of the markers' displacement per unit of the parameter
/// (forward difference; 4 model runs after the search), about each marker's mean and after
/// the drift spline is projected out of it. A
/// parameter whose effect the projection removes is one the recording cannot tell from
/// drift.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensitivity {
    /// FMI name of the parameter.
    pub name: &'static str,
    /// RMS marker displacement per unit of the parameter, about each marker's mean [m per
    /// unit].
    pub raw_m: f64,
    /// The same after the drift is projected out [m per unit].
    pub projected_m: f64,
}

/// Forward-difference steps of the sensitivities: amplitude 0.01, phase 0.02 rad.
const SENSITIVITY_STEPS: [f64; 4] = [0.01, 0.01, 0.02, 0.02];
/// FMI names of the fitted parameters, in the search's order.
const PARAMETER_NAMES: [&str; 4] = [
    "drive.ribs.amplitude",
    "drive.diaphragm.amplitude",
    "drive.ribs.phase",
    "drive.diaphragm.phase",
];

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

/// The noise floor of a recording estimated from the recording alone [m]: the mean length of
/// its points' measurement noise vectors, the cost a perfect model would reach (what a
/// synthetic recording's truth states as `noise_floor_m`). Breathing moves a point smoothly
/// (a few millimetres at 0.1-1 Hz), so the second difference x[k+1] - 2 x[k] + x[k-1] of a
/// point's coordinate over three consecutive tracked frames is its noise, of variance 6
/// sigma^2 for white noise of standard deviation sigma, plus the motion's curvature, about
/// (2 pi f / fs)^2 of its amplitude: 14 um for 5 mm at 0.25 Hz and 30 Hz, far below the
/// noise of surface trackers. sigma comes from the median absolute second difference
/// (sigma = 1.4826 MAD / sqrt 6, robust against the odd tracking glitch), and the mean length
/// of an isotropic Gaussian vector is sigma sqrt(8 / pi). `frames` are the points of each
/// frame at the uniformly spaced `times`; triples across a gap or an uneven spacing are left
/// out. NaN with fewer than 30 triples.
pub fn estimated_noise_floor(times: &[f64], frames: &[Vec<Option<Point3<f64>>>]) -> f64 {
    let mut d2 = Vec::new();
    for k in 1..frames.len().saturating_sub(1) {
        let (h0, h1) = (times[k] - times[k - 1], times[k + 1] - times[k]);
        if !(h0 > 0.0 && (h1 - h0).abs() <= 0.01 * h0) {
            continue;
        }
        for (i, q) in frames[k].iter().enumerate() {
            let (Some(a), Some(b), Some(c)) = (
                frames[k - 1].get(i).copied().flatten(),
                *q,
                frames[k + 1].get(i).copied().flatten(),
            ) else {
                continue;
            };
            let d = a.coords - 2.0 * b.coords + c.coords;
            d2.extend(d.iter().map(|x| x.abs()));
        }
    }
    if d2.len() < 90 {
        return f64::NAN;
    }
    let mid = d2.len() / 2;
    let (_, median, _) = d2.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    let sigma = 1.4826 * *median / 6f64.sqrt();
    sigma * (8.0 / std::f64::consts::PI).sqrt()
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

/// Reusable buffers for [`aligned_cost`].
#[derive(Default)]
struct Pairs {
    model: Vec<Point3<f64>>,
    recorded: Vec<Option<Point3<f64>>>,
}

/// The cost with the camera pose refined over the whole recording: the rigid transform
/// (Umeyama, least squares over every frame's tracked points) taking the first-frame
/// registered points onto the model markers is applied before eq. 3.1. The pose is one
/// transform for the whole recording, so it absorbs where the recording's first frame sits
/// in the breath (a first-frame registration assumes the rest pose) but none of the breath.
/// Returns the cost and the correction.
fn aligned_cost(
    model: &[Vec<Point3<f64>>],
    recorded: &[Vec<Option<Point3<f64>>>],
    pairs: &mut Pairs,
) -> Result<(f64, RigidTransform)> {
    pairs.model.clear();
    pairs.recorded.clear();
    for (m, r) in model.iter().zip(recorded) {
        pairs.model.extend_from_slice(m);
        pairs.recorded.extend_from_slice(r);
    }
    let (t, _) = register_rigid(&pairs.model, &pairs.recorded, false)?;
    let (mut sum, mut n) = (0.0, 0usize);
    for (p, q) in pairs.model.iter().zip(&pairs.recorded) {
        if let Some(q) = q {
            sum += (t.apply(q) - p).norm();
            n += 1;
        }
    }
    Ok((
        if n == 0 {
            f64::INFINITY
        } else {
            sum / n as f64
        },
        t,
    ))
}

/// The cost with each marker's constant offset left out: the mean Euclidean distance
/// between the model's and the recording's marker trajectories, each taken about its own
/// mean over the frames where the marker is tracked, over all frames and tracked markers.
/// A constant offset of a marker (where it was placed, its height above the skin) does not
/// count; its motion does.
pub fn centred_cost(model: &[Vec<Point3<f64>>], recorded: &[Vec<Option<Point3<f64>>>]) -> f64 {
    let points = recorded.first().map_or(0, Vec::len);
    let mut mean_m = vec![nalgebra::Vector3::zeros(); points];
    let mut mean_q = vec![nalgebra::Vector3::zeros(); points];
    let mut count = vec![0usize; points];
    for (m, r) in model.iter().zip(recorded) {
        for (p, (a, q)) in m.iter().zip(r).enumerate() {
            if let Some(q) = q {
                mean_m[p] += a.coords;
                mean_q[p] += q.coords;
                count[p] += 1;
            }
        }
    }
    for p in 0..points {
        let n = count[p].max(1) as f64;
        mean_m[p] /= n;
        mean_q[p] /= n;
    }
    let (mut sum, mut n) = (0.0, 0usize);
    for (m, r) in model.iter().zip(recorded) {
        for (p, (a, q)) in m.iter().zip(r).enumerate() {
            if let Some(q) = q {
                sum += ((a.coords - mean_m[p]) - (q.coords - mean_q[p])).norm();
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

/// Reference amplitude of the two basis runs of [`linearised_start`].
const BASIS_AMPLITUDE: f64 = 0.3;
/// Phase shifts tried per family by [`linearised_start`].
const SHIFTS: usize = 24;

/// The two basis responses of the linearised model ([`linearised_start`]): the markers'
/// response to the rib-cage and to the diaphragm drive alone, at amplitude 0.3 and phase
/// `psi`, one breath of each (after two breaths of settling) sampled every `h` seconds.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearBasis {
    /// Per family (rib cage, diaphragm), per sample, per marker: the marker's position.
    runs: [Vec<Vec<Point3<f64>>>; 2],
    /// Sample interval [s].
    h: f64,
    /// Breathing period [s].
    period: f64,
    /// Phase of both families' waves in the basis runs [rad].
    psi: f64,
}

/// The two basis runs of the linearised model at frequency `f` (2 model runs, each three
/// breaths from rest); `rate` is the recording's frame rate.
pub fn linear_basis(
    model: &mut dyn MarkerSource,
    f: f64,
    psi: f64,
    abdominals: Wave,
    inspiratory_fraction: f64,
    rate: f64,
) -> Result<LinearBasis> {
    let period = 1.0 / f;
    let h = 1.0 / rate.max(1.0);
    // One breath of each basis response, after two breaths of settling: frame time t
    // (model time `period + t` in the fit) is read at its phase, model time
    // 2 period + (t mod period).
    let n = (period / h).ceil() as usize + 2;
    let grid: Vec<f64> = (0..n).map(|j| 2.0 * period + j as f64 * h).collect();
    let mut runs: [Vec<Vec<Point3<f64>>>; 2] = [Vec::new(), Vec::new()];
    for (family, out) in runs.iter_mut().enumerate() {
        let wave = |on: bool| Wave {
            amplitude: if on { BASIS_AMPLITUDE } else { 0.0 },
            phase: psi,
        };
        let drive = Drive {
            enabled: true,
            frequency: f,
            inspiratory_fraction,
            ribs: wave(family == 0),
            diaphragm: wave(family == 1),
            abdominals,
        };
        let mut traj = Trajectory::default();
        model.run(&[(0.0, drive)], &grid, false, &mut traj)?;
        *out = traj.markers;
    }
    Ok(LinearBasis {
        runs,
        h,
        period,
        psi,
    })
}

impl LinearBasis {
    /// The basis of the markers `columns` only (indices into the model's markers).
    pub fn columns(&self, columns: &[usize]) -> LinearBasis {
        let pick = |run: &Vec<Vec<Point3<f64>>>| -> Vec<Vec<Point3<f64>>> {
            run.iter()
                .map(|frame| columns.iter().map(|&c| frame[c]).collect())
                .collect()
        };
        LinearBasis {
            runs: [pick(&self.runs[0]), pick(&self.runs[1])],
            ..*self
        }
    }
}

/// The best linearised fit of a recording ([`linearised_fit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearFit {
    /// (A_ribs, A_diaphragm, phi_ribs, phi_diaphragm), phases at the first frame.
    pub x: [f64; 4],
    /// Sum of squared residual lengths over the samples used [m^2].
    pub residual: f64,
    /// Sum of squared lengths of the recorded motion about each marker's mean [m^2].
    pub total: f64,
    /// Tracked samples (frame, marker) used.
    pub samples: usize,
}

impl LinearFit {
    /// Root-mean-square length of the residual per sample [m].
    pub fn rms_m(&self) -> f64 {
        (self.residual / self.samples.max(1) as f64).sqrt()
    }

    /// Fraction of the recorded motion (about each marker's mean) left unexplained.
    pub fn unexplained(&self) -> f64 {
        if self.total > 0.0 {
            self.residual / self.total
        } else {
            1.0
        }
    }
}

/// The linearised fit of `recorded` (model frame, frames at `times` from the first frame,
/// markers in the basis's order): the displacement is taken as c_r D_r(t + s_r) +
/// c_d D_d(t + s_d), with D_r and D_d the basis responses, time-shifted by s in [0, 1/f)
/// (a phase change of 2 pi f s in the periodic regime); both sides are taken about each
/// marker's mean. For each pair of shifts the non-negative least-squares (c_r, c_d) are
/// solved; the best pair gives A = 0.3 c and phi = psi + 2 pi f s.
pub fn linearised_fit(
    basis: &LinearBasis,
    recorded: &[Vec<Option<Point3<f64>>>],
    times: &[f64],
) -> LinearFit {
    let LinearBasis { h, period, psi, .. } = *basis;
    let points = basis.runs[0].first().map_or(0, Vec::len);
    let n = basis.runs[0].len();
    // Frames used: about 300, evenly spread.
    let stride = (times.len() / 300).max(1);
    let frames: Vec<usize> = (0..times.len()).step_by(stride).collect();
    let disp = |b: &[Vec<Point3<f64>>], t: f64, p: usize| {
        let x = (t.rem_euclid(period) / h).clamp(0.0, (n - 1) as f64);
        let j = (x.floor() as usize).min(n - 2);
        let w = x - j as f64;
        b[j][p].coords * (1.0 - w) + b[j + 1][p].coords * w
    };
    // Pre-sample each basis at every shift.
    let sample = |b: &[Vec<Point3<f64>>], s: usize| -> Vec<Vec<nalgebra::Vector3<f64>>> {
        let sigma = s as f64 * period / SHIFTS as f64;
        frames
            .iter()
            .map(|&i| (0..points).map(|p| disp(b, times[i] + sigma, p)).collect())
            .collect()
    };
    // Per-point time means are removed from data and bases: the camera pose refinement of
    // the cost absorbs any constant offset (see `aligned_cost`).
    let centre = |mut v: Vec<Vec<nalgebra::Vector3<f64>>>| {
        for p in 0..points {
            let mean = v.iter().map(|f| f[p]).sum::<nalgebra::Vector3<f64>>() / v.len() as f64;
            for f in v.iter_mut() {
                f[p] -= mean;
            }
        }
        v
    };
    let dr: Vec<_> = (0..SHIFTS)
        .map(|s| centre(sample(&basis.runs[0], s)))
        .collect();
    let dd: Vec<_> = (0..SHIFTS)
        .map(|s| centre(sample(&basis.runs[1], s)))
        .collect();
    let mut rmean = vec![nalgebra::Vector3::zeros(); points];
    let mut rcount = vec![0usize; points];
    for &i in &frames {
        for (p, q) in recorded[i].iter().enumerate() {
            if let Some(q) = q {
                rmean[p] += q.coords;
                rcount[p] += 1;
            }
        }
    }
    for (m, c) in rmean.iter_mut().zip(&rcount) {
        *m /= (*c).max(1) as f64;
    }
    let mut best = LinearFit {
        x: [0.0, 0.0, psi, psi],
        residual: f64::INFINITY,
        total: 0.0,
        samples: rcount.iter().sum(),
    };
    // The sums that depend on one shift are computed once per shift; only the cross term
    // needs every pair.
    let mut rr = 0.0;
    for &i in &frames {
        for (p, q) in recorded[i].iter().enumerate() {
            if let Some(q) = q {
                rr += (q.coords - rmean[p]).norm_squared();
            }
        }
    }
    let single = |d: &[Vec<Vec<nalgebra::Vector3<f64>>>]| -> Vec<(f64, f64)> {
        d.iter()
            .map(|u| {
                let (mut uu, mut ur) = (0.0, 0.0);
                for (k, &i) in frames.iter().enumerate() {
                    for (p, q) in recorded[i].iter().enumerate() {
                        if let Some(q) = q {
                            uu += u[k][p].norm_squared();
                            ur += u[k][p].dot(&(q.coords - rmean[p]));
                        }
                    }
                }
                (uu, ur)
            })
            .collect()
    };
    let (sr_sums, sd_sums) = (single(&dr), single(&dd));
    for (sr, a) in dr.iter().enumerate() {
        for (sd, b) in dd.iter().enumerate() {
            let ((aa, ar), (bb, br)) = (sr_sums[sr], sd_sums[sd]);
            let mut ab = 0.0;
            for (k, &i) in frames.iter().enumerate() {
                for (p, q) in recorded[i].iter().enumerate() {
                    if q.is_some() {
                        ab += a[k][p].dot(&b[k][p]);
                    }
                }
            }
            best.total = rr;
            let residual = |cr: f64, cd: f64| {
                rr - 2.0 * (cr * ar + cd * br) + cr * cr * aa + 2.0 * cr * cd * ab + cd * cd * bb
            };
            let det = aa * bb - ab * ab;
            let mut candidates = vec![
                (if aa > 0.0 { (ar / aa).max(0.0) } else { 0.0 }, 0.0),
                (0.0, if bb > 0.0 { (br / bb).max(0.0) } else { 0.0 }),
            ];
            if det > 1e-12 * aa * bb {
                let cr = (ar * bb - br * ab) / det;
                let cd = (br * aa - ar * ab) / det;
                if cr >= 0.0 && cd >= 0.0 {
                    candidates.push((cr, cd));
                }
            }
            for (cr, cd) in candidates {
                let res = residual(cr, cd);
                if res < best.residual {
                    let phase = |s: usize| psi + wrap_angle(2.0 * PI * s as f64 / SHIFTS as f64);
                    best.residual = res.max(0.0);
                    best.x = [
                        (cr * BASIS_AMPLITUDE).clamp(AMPLITUDE_RANGE.0, AMPLITUDE_RANGE.1),
                        (cd * BASIS_AMPLITUDE).clamp(AMPLITUDE_RANGE.0, AMPLITUDE_RANGE.1),
                        phase(sr),
                        phase(sd),
                    ];
                }
            }
        }
    }
    best
}

/// A starting point from a linearised model (2 model runs, [`linear_basis`]), the best
/// [`linearised_fit`]. Returns (A_ribs, A_diaphragm, phi_ribs, phi_diaphragm).
#[allow(clippy::too_many_arguments)]
fn linearised_start(
    model: &mut dyn MarkerSource,
    recorded: &[Vec<Option<Point3<f64>>>],
    times: &[f64],
    f: f64,
    psi: f64,
    abdominals: Wave,
    inspiratory_fraction: f64,
    rate: f64,
) -> Result<[f64; 4]> {
    let basis = linear_basis(model, f, psi, abdominals, inspiratory_fraction, rate)?;
    Ok(linearised_fit(&basis, recorded, times).x)
}

/// Model runs spent by [`linearised_start`].
pub const START_RUNS: usize = 2;

/// Evaluations of the fit's cost (thesis eq. 3.1) on one marker source: each runs the
/// drive of a parameter vector over the recording's times and returns the mean distance of
/// the aligned markers. The trajectory and the matched pairs are kept from one evaluation
/// to the next.
struct CostRun<'a, S: MarkerSource + ?Sized, D> {
    source: &'a mut S,
    recorded: &'a [Vec<Option<Point3<f64>>>],
    times: &'a [f64],
    drive_of: &'a D,
    traj: Trajectory,
    pairs: Pairs,
    centred: bool,
    drift: Option<super::drift::DriftBasis>,
}

impl<'a, S: MarkerSource + ?Sized, D: Fn(&[f64]) -> Drive> CostRun<'a, S, D> {
    fn new(
        source: &'a mut S,
        recorded: &'a [Vec<Option<Point3<f64>>>],
        times: &'a [f64],
        drive_of: &'a D,
    ) -> Self {
        CostRun {
            source,
            recorded,
            times,
            drive_of,
            traj: Trajectory::default(),
            pairs: Pairs::default(),
            centred: false,
            drift: None,
        }
    }

    /// The cost [m] of the parameters `x` (amplitudes and phases).
    fn cost(&mut self, x: &[f64]) -> Result<f64> {
        let drive = (self.drive_of)(x);
        self.source
            .run(&[(0.0, drive)], self.times, false, &mut self.traj)?;
        if let Some(basis) = &self.drift {
            return Ok(basis.projected_cost(&self.traj.markers, self.recorded));
        }
        if self.centred {
            return Ok(centred_cost(&self.traj.markers, self.recorded));
        }
        Ok(aligned_cost(&self.traj.markers, self.recorded, &mut self.pairs)?.0)
    }
}

/// Fits `model` to `recording` (see the module doc). `progress(evaluations, best cost)` is
/// called after each cost evaluation.
pub fn fit_recording(
    model: &mut dyn MarkerSource,
    recording: &Recording,
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Fit> {
    recording.validate()?;
    check_grid(recording.grid, model.grid())?;
    if !options.clean {
        return fit_marker_frames(model, recording, options, progress);
    }
    let labels: Vec<String> = (0..recording.points())
        .map(crate::recording::grid_label)
        .collect();
    let cleaned = super::clean::clean(&recording.times, &labels, &recording.frames)?;
    let repaired = Recording {
        frames: cleaned.frames,
        ..recording.clone()
    };
    let mut fit = fit_marker_frames(model, &repaired, options, progress)?;
    fit.repairs.splice(0..0, cleaned.notes);
    fit.note_long_gaps(&labels);
    Ok(fit)
}

/// The fit of [`fit_recording`] for a recording of any marker set: its points are the
/// model's markers in the same order (`recording.grid` = `model.grid()`, (markers, 1) for a
/// set other than the grid, e.g. bound by [`crate::anatomy::skin::register_to_surface`]);
/// the grid's side limit does not apply. The first frame is registered to the rest markers
/// by correspondence (rigid), as for the grid.
pub fn fit_marker_frames(
    model: &mut dyn MarkerSource,
    recording: &Recording,
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Fit> {
    let start = Instant::now();
    recording.validate_frames()?;
    if recording.grid != model.grid() {
        return Err(Error::invalid(
            "recording markers",
            recording.points(),
            format!("the model's {} markers", model.grid().0 * model.grid().1),
        ));
    }
    if options.max_evals < 10 {
        return Err(Error::invalid(
            "--max-evals",
            options.max_evals,
            "at least 10",
        ));
    }
    // Registration of the first frame to the rest markers.
    let rest = model.rest_markers()?;
    let skin_fit = model.skin_fit()?;
    let to_anatomy = model.to_anatomy()?;
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
        provenance: recording.provenance.clone(),
    };
    let mut pd = principal_displacement(&registered)?;
    let mut frequency = estimate_frequency(&pd.signal, recording.rate())?;
    // Gaps longer than a breath are not interpolated: their markers are left out of the
    // breath detection (the cost compares tracked samples only).
    let mut long_gaps = Vec::new();
    let gaps = super::clean::long_gaps(
        &recording.times,
        &recording.frames,
        1.0 / frequency.frequency_hz,
    );
    if !gaps.is_empty() {
        let mut left_out: Vec<usize> = gaps.iter().map(|g| g.0).collect();
        left_out.dedup();
        pd = super::principal::principal_displacement_without(&registered, &left_out)?;
        frequency = estimate_frequency(&pd.signal, recording.rate())?;
        long_gaps = gaps;
    }
    let f = frequency.frequency_hz;
    crate::model::check(
        "drive.frequency (estimated from the recording)",
        f,
        (0.05, 2.0),
    )?;
    // Ventral is +x of the model's anatomical frame; the markers' frame is that of the
    // recording when the model fitted its skin to it (`to_anatomy` then turns it back).
    let ventral: f64 = pd
        .loadings
        .iter()
        .map(|l| (to_anatomy.rotation * l).x)
        .sum();
    let sign = if ventral < 0.0 { -1.0 } else { 1.0 };
    let t0 = recording.times[0];
    let times: Vec<f64> = recording.times.iter().map(|t| t - t0).collect();
    let signal: Vec<f64> = pd.signal.iter().map(|v| sign * v).collect();
    let psi = fundamental_phase(&times, &signal, f);
    let breathing = breaths_of_signal(&times, &signal, f);
    let inspiratory_fraction = match options.inspiratory_fraction {
        Some(v) => v,
        None if breathing.ti_ttot.is_finite() => {
            let (lo, hi) = crate::model::drive::INSPIRATORY_FRACTION_RANGE;
            breathing.ti_ttot.clamp(lo, hi)
        }
        None => {
            return Err(Error::invalid(
                "Ti/Ttot from the recording",
                "no whole breath",
                "a recording with at least one whole breath (minimum, maximum, minimum), or a given Ti/Ttot",
            ));
        }
    };

    // The search over (A_ribs, A_diaphragm, phi_ribs, phi_diaphragm).
    let settle = 1.0 / f;
    let model_times: Vec<f64> = times.iter().map(|t| settle + t).collect();
    let (alo, ahi) = AMPLITUDE_RANGE;
    let drive_of = |x: &[f64]| Drive {
        enabled: true,
        frequency: f,
        inspiratory_fraction,
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
    let linearised = options.linearised_start && options.start.is_none();
    let x0 = if let Some(x) = options.start {
        [x[0].clamp(alo, ahi), x[1].clamp(alo, ahi), x[2], x[3]]
    } else if linearised {
        linearised_start(
            model,
            &recorded,
            &times,
            f,
            psi,
            options.abdominals,
            inspiratory_fraction,
            recording.rate(),
        )?
    } else {
        [
            options.start_amplitudes.0.clamp(alo, ahi),
            options.start_amplitudes.1.clamp(alo, ahi),
            psi,
            psi,
        ]
    };
    let x0 = [x0[0], x0[1], wrap_angle(x0[2]), wrap_angle(x0[3])];
    // Each phase is searched within pi of its start (inside the drive's [-2 pi, 2 pi]).
    let bounds = Bounds::new(&[
        (alo, ahi),
        (alo, ahi),
        (x0[2] - PI, x0[2] + PI),
        (x0[3] - PI, x0[3] + PI),
    ])?;
    let start_runs = if linearised { START_RUNS } else { 0 };
    let budget = options.max_evals - start_runs;
    let nm = NelderMeadOptions {
        max_evals: budget,
        initial_step: if options.start.is_some() {
            0.01
        } else if linearised {
            0.03
        } else {
            0.15
        },
        // Stop when the simplex spans less than 0.4 % of each range (amplitude 0.004,
        // phase 0.025 rad) and its costs agree within 0.05 % (0.4 um at a 0.8 mm cost).
        x_tol: 4e-3,
        f_rel_tol: 5e-4,
        ..NelderMeadOptions::default()
    };
    let mut spare_model = if options.threads > 1 && options.method == Method::NelderMead {
        model.spare()?
    } else {
        None
    };
    let mut main_run = CostRun::new(&mut *model, &recorded, &model_times, &drive_of);
    let about_means = options.marker_offsets || options.drift;
    let drift_basis = options
        .drift
        .then(|| super::drift::DriftBasis::new(&times, f));
    main_run.centred = about_means;
    main_run.drift = drift_basis.clone();
    let mut cost = |x: &[f64]| main_run.cost(x);
    let mut spare_run = spare_model.as_deref_mut().map(|spare| {
        let mut run = CostRun::new(spare, &recorded, &model_times, &drive_of);
        run.centred = about_means;
        run.drift = drift_basis.clone();
        run
    });
    let mut spare_cost = spare_run.as_mut().map(|run| move |x: &[f64]| run.cost(x));
    let m: Minimum = match options.method {
        Method::NelderMead => nelder_mead_parallel(
            &mut cost,
            spare_cost.as_mut().map(|c| c as &mut Spare),
            &x0,
            &bounds,
            &nm,
            progress,
        )?,
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
            budget,
            if linearised || options.start.is_some() {
                0.1
            } else {
                0.25
            },
            options.seed,
            progress,
        )?,
    };
    let mut drive = drive_of(&m.x);
    drive.ribs.phase = wrap_angle(drive.ribs.phase);
    drive.diaphragm.phase = wrap_angle(drive.diaphragm.phase);
    let mut fitted = Trajectory::default();
    model.run(&[(0.0, drive_of(&m.x))], &model_times, true, &mut fitted)?;
    let mut sensitivity = Vec::new();
    if let Some(basis) = &drift_basis {
        let mut moved = Trajectory::default();
        for i in 0..4 {
            let mut x = m.x.clone();
            let step = if x[i] + SENSITIVITY_STEPS[i] > ahi && i < 2 {
                -SENSITIVITY_STEPS[i]
            } else {
                SENSITIVITY_STEPS[i]
            };
            x[i] += step;
            model.run(&[(0.0, drive_of(&x))], &model_times, false, &mut moved)?;
            let diff: Vec<Vec<Option<Point3<f64>>>> = moved
                .markers
                .iter()
                .zip(&fitted.markers)
                .zip(&recorded)
                .map(|((a, b), r)| {
                    a.iter()
                        .zip(b)
                        .zip(r)
                        .map(|((a, b), q)| q.map(|_| Point3::from((a - b) / step)))
                        .collect()
                })
                .collect();
            let zeros: Vec<Vec<Point3<f64>>> = diff
                .iter()
                .map(|f| vec![Point3::origin(); f.len()])
                .collect();
            let drift = basis.drift(&zeros, &diff);
            // Before: about each marker's mean (what the cost without drift sees).
            let points = diff.first().map_or(0, Vec::len);
            let mut mean = vec![nalgebra::Vector3::zeros(); points];
            let mut count = vec![0usize; points];
            for d in &diff {
                for (p, q) in d.iter().enumerate() {
                    if let Some(q) = q {
                        mean[p] += q.coords;
                        count[p] += 1;
                    }
                }
            }
            for (m, c) in mean.iter_mut().zip(&count) {
                *m /= (*c).max(1) as f64;
            }
            let (mut raw, mut projected, mut n) = (0.0, 0.0, 0usize);
            for (d, dr) in diff.iter().zip(&drift) {
                for (p, (q, e)) in d.iter().zip(dr).enumerate() {
                    if let Some(q) = q {
                        raw += (q.coords - mean[p]).norm_squared();
                        projected += (q.coords - e).norm_squared();
                        n += 1;
                    }
                }
            }
            let n = n.max(1) as f64;
            sensitivity.push(Sensitivity {
                name: PARAMETER_NAMES[i],
                raw_m: (raw / n).sqrt(),
                projected_m: (projected / n).sqrt(),
            });
        }
    }
    let correction = if about_means {
        RigidTransform::identity()
    } else {
        aligned_cost(&fitted.markers, &recorded, &mut Pairs::default())?.1
    };
    let to_model = RigidTransform {
        rotation: correction.rotation * to_model.rotation,
        translation: correction.rotation * to_model.translation + correction.translation,
        scale: 1.0,
    };
    let recorded: Vec<Vec<Option<Point3<f64>>>> = recording
        .frames
        .iter()
        .map(|f| f.iter().map(|q| q.map(|q| to_model.apply(&q))).collect())
        .collect();
    Ok(Fit {
        drive,
        cost_m: m.f,
        initial_cost_m: m.f_start,
        evaluations: m.evaluations + start_runs,
        converged: m.converged,
        unused_ahead: m.unused_ahead,
        wall_s: start.elapsed().as_secs_f64(),
        delta_phase: wrap_angle(m.x[3] - m.x[2]),
        frequency,
        to_model,
        to_anatomy,
        registration_mean_m,
        skin_fit,
        registration_rms_m: rms,
        times,
        recorded,
        fitted,
        method: options.method,
        grid: recording.grid,
        breathing,
        drift_knots: drift_basis.map(|b| b.knots),
        sensitivity,
        sway: options.sway.then(|| {
            super::sway::Sway::none(
                "the recording is the SLP grid, over the front only: forward sway and breathing are the same signal there",
                Vec::new(),
                "none",
            )
        }),
        repairs: Vec::new(),
        long_gaps,
    })
}

/// The rest-pose grid a fit implies, in the recording's frame: for each point, the mean
/// over the frames where it is tracked of the registered recorded point minus the fitted
/// model's displacement from rest at that frame. The skin is fitted to the rest
/// (activation-free) pose (thesis 3.2), and no frame of a recording is at rest, not even
/// end-expiration, where the expiratory muscles (internal intercostals, in antiphase with
/// the rib-cage wave) are active; averaging over every frame also divides the recording's
/// noise by the square root of the number of frames. `rest` is the model's rest markers in
/// the model frame of `fit` (the model the fit ran on).
pub fn rest_reference(fit: &Fit, rest: &[Point3<f64>]) -> Result<Vec<Option<Point3<f64>>>> {
    if rest.len() != fit.grid.0 * fit.grid.1 {
        return Err(Error::invalid(
            "rest markers",
            rest.len(),
            format!("{} points", fit.grid.0 * fit.grid.1),
        ));
    }
    let mut sum = vec![nalgebra::Vector3::zeros(); rest.len()];
    let mut count = vec![0usize; rest.len()];
    for (recorded, model) in fit.recorded.iter().zip(&fit.fitted.markers) {
        for (p, (q, m)) in recorded.iter().zip(model).enumerate() {
            if let Some(q) = q {
                sum[p] += q.coords - (m - rest[p]);
                count[p] += 1;
            }
        }
    }
    Ok(sum
        .iter()
        .zip(&count)
        .map(|(s, &n)| (n > 0).then(|| fit.to_model.apply_inverse(&Point3::from(s / n as f64))))
        .collect())
}

/// Evaluations kept for the polish of [`fit_with_skin`].
pub const SKIN_POLISH_EVALS: usize = 40;

/// A fit with the model's skin fitted to the recording (thesis 3.2) at the pose the
/// recording implies:
/// 1. a fit on `config` with rigid registration (`scene.slp_reference` unset);
/// 2. the rest-pose grid that fit implies ([`rest_reference`]) is written to `reference` (a
///    still recording in the recording's frame) and becomes `scene.slp_reference`: the
///    model registers its grid to it and fits its rest skin to it;
/// 3. a Nelder-Mead polish on that model from the first fit's optimum.
///
/// The evaluations of both searches count against `options.max_evals` (the first gets all
/// but [`SKIN_POLISH_EVALS`]); the result is the polish's, with the first fit's starting
/// cost, the total evaluations and the total wall time.
pub fn fit_with_skin(
    config: &crate::Config,
    recording: &Recording,
    reference: &std::path::Path,
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Fit> {
    let start = Instant::now();
    if options.max_evals < SKIN_POLISH_EVALS + 10 {
        return Err(Error::invalid(
            "--max-evals",
            options.max_evals,
            format!(
                "at least {} with skin fitting (a first fit and a polish)",
                SKIN_POLISH_EVALS + 10
            ),
        ));
    }
    let mut rigid = config.clone();
    rigid.scene.slp_reference = None;
    let mut source = super::TorsoMarkers::new(rigid)?;
    let first = fit_recording(
        &mut source,
        recording,
        &FitOptions {
            max_evals: options.max_evals - SKIN_POLISH_EVALS,
            ..options.clone()
        },
        progress,
    )?;
    let rest = source.rest_markers()?;
    let frame = rest_reference(&first, &rest)?;
    // Two identical frames: a still recording of the rest pose (the format needs two).
    let t0 = recording.times.first().copied().unwrap_or(0.0);
    Recording {
        grid: recording.grid,
        times: vec![t0, t0 + 1.0 / recording.rate().max(1.0)],
        frames: vec![frame.clone(), frame],
        units: crate::recording::Units::Metres,
        provenance: Vec::new(),
    }
    .write(reference)?;
    let mut fitted = config.clone();
    fitted.scene.slp_reference = Some(reference.to_path_buf());
    let mut source = super::TorsoMarkers::new(fitted)?;
    let d = &first.drive;
    let done = first.evaluations;
    let mut second = fit_recording(
        &mut source,
        recording,
        &FitOptions {
            method: Method::NelderMead,
            max_evals: options.max_evals - done,
            start: Some([
                d.ribs.amplitude,
                d.diaphragm.amplitude,
                d.ribs.phase,
                d.diaphragm.phase,
            ]),
            ..options.clone()
        },
        &mut |n, best| progress(done + n, best),
    )?;
    second.evaluations += done;
    second.initial_cost_m = first.initial_cost_m;
    second.method = options.method;
    second.wall_s = start.elapsed().as_secs_f64();
    Ok(second)
}
