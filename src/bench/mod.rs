//! Measurement kernels behind `torso bench`: timed frame loops of the model facade
//! (volumes only, volumes plus markers, or volumes plus the whole skin), the cost of one right-hand-side evaluation,
//! trajectories for work-precision studies (lung volume and marker positions at the output
//! rate, with a wall-time cap, by the model's own adaptive solver or by a fixed-step
//! semi-implicit Euler of the kind game engines use), and random scenes drawn from the
//! declared parameter ranges for the stress suite. Nothing here prints; the CLI (`src/cli/bench.rs`) formats the
//! results and the stress tests (`tests/stress_*.rs`) assert on them.

pub mod fmu;
pub mod physiology;
pub mod reduced;
pub mod relaxation;
pub mod stress;

use crate::anatomy::{MuscleGroup, Posture, SUBJECT_RANGES, Sex, Subject};
use crate::dynamics::statics::StaticsStats;
use crate::dynamics::{Layout, RIBS};
use crate::model::{AdvanceOptions, Config, Drive, Quantity, Torso, Wave};
use crate::numeric::rng::Pcg64;
use crate::solver::{Ode, SecondOrder, SemiImplicitEuler};
use crate::{Error, Result};
use serde::Serialize;
use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Instant;

/// Output rate of the SLP cameras [Hz]; every frame loop here reads at this rate.
pub const FRAME_RATE: f64 = 56.0;

/// Median of `v` (upper median for an even count); NaN for an empty slice.
pub fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// What a timed frame loop reads after every frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Reads {
    /// Lung, thorax, abdomen and trunk volumes.
    Volumes,
    /// The volumes plus every marker of the grid (x, y, z).
    VolumesAndMarkers,
    /// The volumes plus every vertex of the deformed skin (what an export of the whole skin
    /// at every frame needs).
    VolumesAndSkin,
}

/// One timed frame loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameRun {
    /// Wall time of the loop [s] (model build and marker-model build excluded).
    pub wall: f64,
    /// Wall time of [`Torso::new`] before the loop [s] (the model's compilation and the
    /// static equilibrium of the drive's start).
    pub build: f64,
    /// Right-hand-side evaluations during the loop.
    pub rhs_evaluations: u64,
    /// Accepted steps during the loop.
    pub steps: u64,
    /// Rejected steps during the loop.
    pub rejected: u64,
    /// Sum of everything read (kept so that nothing is optimised away).
    pub checksum: f64,
}

/// Builds a torso for `config`, then times `frames` frames at [`FRAME_RATE`], reading `reads`
/// after each. The marker model (built once per compiled model) is built before the clock
/// starts when markers are read.
pub fn frame_loop(config: &Config, frames: usize, reads: Reads) -> Result<FrameRun> {
    let built = Instant::now();
    let mut torso = Torso::new(config.clone())?;
    let build = built.elapsed().as_secs_f64();
    if reads != Reads::Volumes {
        torso.marker_model()?;
    }
    let mut skin = Vec::new();
    let before = torso.solver_stats();
    let start = Instant::now();
    let mut checksum = 0.0;
    for i in 1..=frames {
        torso.advance_to(i as f64 / FRAME_RATE)?;
        for q in [
            Quantity::LungVolume,
            Quantity::ThoraxVolume,
            Quantity::AbdomenVolume,
            Quantity::TrunkVolume,
        ] {
            checksum += torso.read(q)?;
        }
        match reads {
            Reads::Volumes => {}
            Reads::VolumesAndMarkers => {
                for p in torso.markers()? {
                    checksum += p.x + p.y + p.z;
                }
            }
            Reads::VolumesAndSkin => {
                torso.skin_vertices(&mut skin)?;
                checksum += skin.iter().map(|p| p.x + p.y + p.z).sum::<f64>();
            }
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let after = torso.solver_stats();
    Ok(FrameRun {
        wall,
        build,
        rhs_evaluations: after.rhs_evaluations - before.rhs_evaluations,
        steps: after.steps - before.steps,
        rejected: after.rejected - before.rejected,
        checksum: black_box(checksum),
    })
}

/// Cost of one right-hand-side evaluation at one level of detail.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RhsCost {
    /// Level of detail.
    pub level_of_detail: u32,
    /// Length of the state vector.
    pub state_dim: usize,
    /// Median nanoseconds per call at the rest state (drive at t = 0).
    pub ns_rest: f64,
    /// Median nanoseconds per call at a breathing state (quiet drive, mid-inspiration).
    pub ns_breathing: f64,
}

/// Times `calls` calls of [`Torso::rhs`] (in `repeats` batches, median per call) at the rest
/// state and at the state reached after 1.5 s of quiet breathing, for `config`'s level of
/// detail.
pub fn rhs_cost(config: &Config, calls: usize, repeats: usize) -> Result<RhsCost> {
    let mut config = config.clone();
    config.drive = Drive::quiet();
    let mut torso = Torso::new(config.clone())?;
    let n = torso.state_dim();
    let rest = torso.state().to_vec();
    let t_breath = 1.5;
    torso.advance_to(t_breath)?;
    let breathing = torso.state().to_vec();
    let mut dy = vec![0.0; n];
    let mut time = |torso: &mut Torso, t: f64, y: &[f64]| -> Result<f64> {
        let mut per_call = Vec::with_capacity(repeats);
        for _ in 0..repeats.max(1) {
            let start = Instant::now();
            for _ in 0..calls.max(1) {
                torso.rhs(t, black_box(y), &mut dy)?;
                black_box(&dy);
            }
            per_call.push(start.elapsed().as_secs_f64() * 1e9 / calls.max(1) as f64);
        }
        Ok(median(&per_call))
    };
    let ns_rest = time(&mut torso, 0.0, &rest)?;
    let ns_breathing = time(&mut torso, t_breath, &breathing)?;
    Ok(RhsCost {
        level_of_detail: config.scene.level_of_detail,
        state_dim: n,
        ns_rest,
        ns_breathing,
    })
}

/// Lung volume and marker positions at every output frame of one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Lung volume per frame [L] (frame 0 at t = 0).
    pub lung: Vec<f64>,
    /// Marker positions per frame [m], `markers[frame][marker]`.
    pub markers: Vec<Vec<[f64; 3]>>,
    /// Wall time of the frame loop [s] (build and marker-model build excluded).
    pub wall: f64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
    /// Accepted steps.
    pub steps: u64,
    /// Whether the explicit solver's stiffness test had fired at the end of the run.
    pub stiffness_detected: bool,
    /// Accepted steps at which the stiffness test fired.
    pub stiff_steps: u64,
    /// Work counts of the static solves (quasi-static mode; `None` in the others).
    pub statics: Option<StaticsStats>,
}

/// Runs `config` for `duration` seconds, recording lung volume and markers at
/// [`FRAME_RATE`]. Returns `Ok(None)` when the wall time exceeds `cap` seconds (the run is
/// abandoned at the next frame).
pub fn trajectory(config: &Config, duration: f64, cap: f64) -> Result<Option<Trajectory>> {
    let mut torso = Torso::new(config.clone())?;
    torso.marker_model()?;
    let frames = (duration * FRAME_RATE).round() as usize;
    let mut out = Trajectory {
        lung: Vec::with_capacity(frames + 1),
        markers: Vec::with_capacity(frames + 1),
        ..Trajectory::default()
    };
    let statics_before = torso.statics_stats();
    let start = Instant::now();
    for i in 0..=frames {
        if i > 0 {
            torso.advance_to(i as f64 / FRAME_RATE)?;
        }
        out.lung.push(torso.read(Quantity::LungVolume)?);
        out.markers
            .push(torso.markers()?.iter().map(|p| [p.x, p.y, p.z]).collect());
        if start.elapsed().as_secs_f64() > cap {
            return Ok(None);
        }
    }
    out.wall = start.elapsed().as_secs_f64();
    let stats = torso.solver_stats();
    out.rhs_evaluations = stats.rhs_evaluations;
    out.steps = stats.steps;
    out.stiff_steps = stats.stiff_steps;
    out.stiffness_detected = torso.stiffness_detected();
    out.statics = torso
        .statics_stats()
        .zip(statics_before)
        .map(|(a, b)| StaticsStats {
            solves: a.solves - b.solves,
            iterations: a.iterations - b.iterations,
            jacobians: a.jacobians - b.jacobians,
            factorisations: a.factorisations - b.factorisations,
            residuals: a.residuals - b.residuals,
            continuations: a.continuations - b.continuations,
        });
    Ok(Some(out))
}

/// Wall time [s] of [`trajectory`]'s frame loop reading the lung volume alone (no markers),
/// and its right-hand-side evaluations: in quasi-static mode no position is solved then,
/// so this is the integration's own cost, as an external integrator's is measured.
pub fn lung_loop(config: &Config, duration: f64) -> Result<(f64, u64)> {
    let mut torso = Torso::new(config.clone())?;
    let frames = (duration * FRAME_RATE).round() as usize;
    let before = torso.solver_stats().rhs_evaluations;
    let start = Instant::now();
    let mut checksum = torso.read(Quantity::LungVolume)?;
    for i in 1..=frames {
        torso.advance_to(i as f64 / FRAME_RATE)?;
        checksum += torso.read(Quantity::LungVolume)?;
    }
    let wall = start.elapsed().as_secs_f64();
    black_box(checksum);
    Ok((wall, torso.solver_stats().rhs_evaluations - before))
}

/// The torso seen as a second-order system for [`SemiImplicitEuler`]: the configuration is
/// rib angles, sternum position and quaternion, free vertex positions (the first
/// `Layout::theta_dot` entries of the state), the rest are velocities; the right-hand side is
/// [`Torso::rhs`] (current inputs plus the drive and tone at t).
pub struct TorsoSecondOrder<'a> {
    /// The torso whose right-hand side is integrated (its own state is not touched).
    pub torso: &'a mut Torso,
    layout: Layout,
}

impl<'a> TorsoSecondOrder<'a> {
    /// Wraps `torso`.
    pub fn new(torso: &'a mut Torso) -> Self {
        let layout = torso.compiled().model.layout;
        TorsoSecondOrder { torso, layout }
    }
}

impl Ode for TorsoSecondOrder<'_> {
    fn dim(&self) -> usize {
        self.layout.len
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) {
        // the only error is a length mismatch, which the solver rules out; poison the
        // result rather than panic if it ever happened
        if self.torso.rhs(t, y, dydt).is_err() {
            dydt.fill(f64::NAN);
        }
    }
}

impl SecondOrder for TorsoSecondOrder<'_> {
    fn configuration_len(&self) -> usize {
        self.layout.theta_dot
    }

    /// Rib angles, sternum and vertex positions move with their velocities; the sternum
    /// quaternion with q' = (0, w) q / 2, w the world-frame angular velocity (as in
    /// `dynamics::accelerations`).
    fn configuration_rates(&self, y: &[f64], dq: &mut [f64]) {
        let l = &self.layout;
        dq[l.theta..l.theta + RIBS].copy_from_slice(&y[l.theta_dot..l.theta_dot + RIBS]);
        dq[l.sternum_x..l.sternum_x + 3].copy_from_slice(&y[l.sternum_v..l.sternum_v + 3]);
        let n3 = 3 * l.vertices;
        dq[l.vertex_x..l.vertex_x + n3].copy_from_slice(&y[l.vertex_v..l.vertex_v + n3]);
        let [w0, x0, y0, z0] = [0, 1, 2, 3].map(|i| y[l.sternum_q + i]);
        let [wx, wy, wz] = [0, 1, 2].map(|i| y[l.sternum_w + i]);
        // (0, w) * q, Hamilton product, halved
        dq[l.sternum_q] = 0.5 * (-wx * x0 - wy * y0 - wz * z0);
        dq[l.sternum_q + 1] = 0.5 * (wx * w0 + wy * z0 - wz * y0);
        dq[l.sternum_q + 2] = 0.5 * (wy * w0 + wz * x0 - wx * z0);
        dq[l.sternum_q + 3] = 0.5 * (wz * w0 + wx * y0 - wy * x0);
    }

    /// Renormalises the sternum quaternion.
    fn project(&self, y: &mut [f64]) {
        let q = &mut y[self.layout.sternum_q..self.layout.sternum_q + 4];
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm > 0.0 && norm.is_finite() {
            q.iter_mut().for_each(|v| *v /= norm);
        }
    }
}

/// As [`trajectory`], integrated by the fixed-step semi-implicit Euler method with nominal
/// step `h` [s] (each 1/56 s frame in equal steps no larger than h) instead of the model's
/// adaptive solver; lung volume and markers are read off the state at every frame through
/// [`Torso::set_state`]. A step that leaves the finite numbers (h beyond the stability
/// limit) is returned as [`Error::Numerical`].
pub fn trajectory_semi_implicit(
    config: &Config,
    duration: f64,
    h: f64,
    cap: f64,
) -> Result<Option<Trajectory>> {
    let mut torso = Torso::new(config.clone())?;
    torso.marker_model()?;
    let frames = (duration * FRAME_RATE).round() as usize;
    let mut solver = SemiImplicitEuler::new(h, torso.state_dim())?;
    let mut y = torso.state().to_vec();
    let mut t = torso.time();
    let mut out = Trajectory {
        lung: Vec::with_capacity(frames + 1),
        markers: Vec::with_capacity(frames + 1),
        ..Trajectory::default()
    };
    let start = Instant::now();
    for i in 0..=frames {
        if i > 0 {
            let mut ode = TorsoSecondOrder::new(&mut torso);
            solver.integrate(&mut ode, &mut t, &mut y, i as f64 / FRAME_RATE)?;
            torso.set_state(t, &y)?;
        }
        out.lung.push(torso.read(Quantity::LungVolume)?);
        out.markers
            .push(torso.markers()?.iter().map(|p| [p.x, p.y, p.z]).collect());
        if start.elapsed().as_secs_f64() > cap {
            return Ok(None);
        }
    }
    out.wall = start.elapsed().as_secs_f64();
    let stats = solver.stats();
    out.rhs_evaluations = stats.rhs_evaluations;
    out.steps = stats.steps;
    Ok(Some(out))
}

/// Errors of a trajectory against a reference of the same length.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TrajectoryError {
    /// Max over frames of |lung volume - reference| [L].
    pub lung: f64,
    /// Max over frames and markers of the Euclidean marker position error [m].
    pub markers: f64,
}

/// Compares `run` with `reference` frame by frame.
pub fn trajectory_error(run: &Trajectory, reference: &Trajectory) -> Result<TrajectoryError> {
    if run.lung.len() != reference.lung.len() || run.markers.len() != reference.markers.len() {
        return Err(Error::State(format!(
            "trajectory of {} frames compared with a reference of {}",
            run.lung.len(),
            reference.lung.len()
        )));
    }
    let lung = run
        .lung
        .iter()
        .zip(&reference.lung)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let mut markers = 0.0f64;
    for (fa, fb) in run.markers.iter().zip(&reference.markers) {
        for (a, b) in fa.iter().zip(fb) {
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            markers = markers.max(d);
        }
    }
    Ok(TrajectoryError { lung, markers })
}

/// Declared range of the drive amplitudes (fraction of the maximal activation).
pub const AMPLITUDE_RANGE: (f64, f64) = (0.0, 1.0);
/// Declared range of the left/right activation gains.
pub const GAIN_RANGE: (f64, f64) = (0.0, 2.0);
/// Body-mass-index range a subject must satisfy [kg/m^2] (see [`Subject::validate`]).
pub const BMI_RANGE: (f64, f64) = (13.0, 60.0);

fn draw(rng: &mut Pcg64, (lo, hi): (f64, f64)) -> f64 {
    lo + (hi - lo) * rng.uniform()
}

/// A random, valid configuration drawn uniformly from every declared range: subject (sex,
/// age, stature, mass drawn within both its range and the BMI range, breast size, posture),
/// drive (frequency, the three amplitudes and phases), left/right gains; level of detail
/// `lod`, other settings at their defaults.
pub fn random_scene(rng: &mut Pcg64, lod: u32) -> Result<Config> {
    let range = |name: &str| {
        SUBJECT_RANGES
            .iter()
            .find(|r| r.0 == name)
            .map(|r| (r.1, r.2))
            .ok_or_else(|| Error::State(format!("no declared range for {name}")))
    };
    let stature = draw(rng, range("subject.stature")?);
    let (m_lo, m_hi) = range("subject.mass")?;
    let h2 = stature * stature;
    let mass = draw(
        rng,
        (m_lo.max(BMI_RANGE.0 * h2), m_hi.min(BMI_RANGE.1 * h2)),
    );
    let subject = Subject {
        sex: if rng.below(2) == 0 {
            Sex::Male
        } else {
            Sex::Female
        },
        age: draw(rng, range("subject.age")?),
        stature,
        mass,
        breast_size: draw(rng, range("subject.breast_size")?),
        posture: [Posture::Standing, Posture::Sitting, Posture::Supine][rng.below(3)],
    };
    let phase = (-2.0 * PI, 2.0 * PI);
    let wave = |rng: &mut Pcg64| Wave {
        amplitude: draw(rng, AMPLITUDE_RANGE),
        phase: draw(rng, phase),
    };
    let drive = Drive {
        enabled: true,
        frequency: draw(rng, (0.05, 2.0)),
        inspiratory_fraction: crate::model::drive::SINE_FRACTION,
        ribs: wave(rng),
        diaphragm: wave(rng),
        abdominals: wave(rng),
    };
    let mut config = Config {
        subject,
        drive,
        gain_left: draw(rng, GAIN_RANGE),
        gain_right: draw(rng, GAIN_RANGE),
        ..Config::default()
    };
    config.scene.level_of_detail = lod;
    config.validate()?;
    Ok(config)
}

/// Broad physical bounds on the lung volume of an adult [L]: the largest predicted total lung
/// capacity within the subject ranges is under 10 L (ECSC, Quanjer 1993), the smallest
/// residual volume over 0.5 L; anything outside means the simulation has left physiology.
pub const LUNG_BOUNDS: (f64, f64) = (0.2, 15.0);

/// Bounds on every cavity volume (thorax, abdomen, trunk) relative to its value at the start
/// of a stress run (the rest state): a wall that halves or doubles a cavity has blown up. The
/// thorax's widen to the subject's residual volume and total lung capacity where those lie
/// beyond ([`crate::model::bounds::cavity_bounds`]).
pub const RELATIVE_VOLUME_BOUNDS: (f64, f64) = crate::model::bounds::CAVITY_BOUNDS;

/// Outcome of one stress scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum SceneOutcome {
    /// Ran to the end with a finite lung volume within [`LUNG_BOUNDS`] and cavity volumes
    /// within [`RELATIVE_VOLUME_BOUNDS`] of their start values; smallest and largest
    /// lung volume seen [L].
    Ok {
        /// Smallest lung volume [L].
        min_lung: f64,
        /// Largest lung volume [L].
        max_lung: f64,
    },
    /// The solver gave up with [`Error::Numerical`] (its message).
    Numerical(String),
    /// A volume was NaN, infinite or out of bounds at `time`.
    OutOfBounds {
        /// Simulated time [s].
        time: f64,
        /// The offending quantity and value.
        what: String,
    },
}

/// Simulates `config` for `seconds`, stepping with the facade's physiological check (the
/// FMU's: a step it rolls back ends the run out of bounds) and checking every output frame
/// (at `rate` Hz) that the state is finite, the lung volume within [`LUNG_BOUNDS`] and the thorax, abdomen and trunk
/// volumes within the subject's bounds ([`RELATIVE_VOLUME_BOUNDS`], the thorax's widened to its
/// residual volume and total lung capacity) of their values at the start.
/// Errors other than [`Error::Numerical`] are returned as errors.
pub fn stress_scene(config: &Config, seconds: f64, rate: f64) -> Result<SceneOutcome> {
    let mut torso = Torso::new(config.clone())?;
    stress_torso(&mut torso, seconds, rate)
}

/// As [`stress_scene`] on an existing torso (its inputs already set), from its current time.
pub fn stress_torso(torso: &mut Torso, seconds: f64, rate: f64) -> Result<SceneOutcome> {
    let t0 = torso.time();
    let frames = (seconds * rate).round().max(1.0) as usize;
    let (mut min_lung, mut max_lung) = (f64::INFINITY, f64::NEG_INFINITY);
    let cavities = [
        Quantity::ThoraxVolume,
        Quantity::AbdomenVolume,
        Quantity::TrunkVolume,
    ];
    let mut start = [0.0; 3];
    for (s, q) in start.iter_mut().zip(cavities) {
        *s = torso.read(q)?;
    }
    let bounds = crate::model::bounds::cavity_bounds(&torso.config().subject);
    for i in 0..=frames {
        if i > 0 {
            let options = AdvanceOptions {
                check_physiology: true,
            };
            match torso.advance_to_with(t0 + i as f64 / rate, options) {
                Ok(_) => {}
                Err(Error::Unphysiological { at, reason, .. }) => {
                    return Ok(SceneOutcome::OutOfBounds {
                        time: at,
                        what: reason,
                    });
                }
                Err(Error::Numerical { time, reason }) => {
                    return Ok(SceneOutcome::Numerical(format!("t = {time} s: {reason}")));
                }
                Err(e) => return Err(e),
            }
        }
        let lung = torso.read(Quantity::LungVolume)?;
        if !(lung.is_finite() && lung >= LUNG_BOUNDS.0 && lung <= LUNG_BOUNDS.1) {
            return Ok(SceneOutcome::OutOfBounds {
                time: torso.time(),
                what: format!("LungVolume = {lung} L"),
            });
        }
        min_lung = min_lung.min(lung);
        max_lung = max_lung.max(lung);
        for ((s, q), (lo, hi)) in start.iter().zip(cavities).zip(bounds) {
            let v = torso.read(q)?;
            let r = v / s;
            if !(r.is_finite() && r >= lo && r <= hi) {
                return Ok(SceneOutcome::OutOfBounds {
                    time: torso.time(),
                    what: format!(
                        "{q:?} = {v} L ({r} x its start value {s} L, outside [{lo:.3}, {hi:.3}])"
                    ),
                });
            }
        }
        if torso.state().iter().any(|v| !v.is_finite()) {
            return Ok(SceneOutcome::OutOfBounds {
                time: torso.time(),
                what: "non-finite state".into(),
            });
        }
    }
    Ok(SceneOutcome::Ok { min_lung, max_lung })
}

/// Sets every muscle group's activation input of `torso` to `value`.
pub fn set_all_activations(torso: &mut Torso, value: f64) -> Result<()> {
    for g in MuscleGroup::ALL {
        torso.set_activation(g, value)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 3.0);
        assert!(median(&[]).is_nan());
    }

    fn quiet_lod0() -> Config {
        let mut c = Config {
            drive: Drive::quiet(),
            ..Config::default()
        };
        c.scene.level_of_detail = 0;
        c
    }

    #[test]
    fn configuration_rates_are_the_position_part_of_the_rhs() {
        let mut torso = Torso::new(quiet_lod0()).expect("model");
        torso.advance_to(0.7).expect("breathing state");
        let y = torso.state().to_vec();
        let mut ode = TorsoSecondOrder::new(&mut torso);
        let p = ode.configuration_len();
        let mut f = vec![0.0; ode.dim()];
        ode.rhs(0.7, &y, &mut f);
        let mut dq = vec![0.0; p];
        ode.configuration_rates(&y, &mut dq);
        let scale = f[..p].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "the torso moves");
        for (i, (a, b)) in dq.iter().zip(&f[..p]).enumerate() {
            assert!((a - b).abs() <= 1e-12 * scale, "entry {i}: {a} vs {b}");
        }
    }

    #[test]
    fn semi_implicit_euler_converges_at_first_order_on_the_torso_and_fails_when_unstable() {
        let mut c = quiet_lod0();
        c.solver.rtol = 1e-10;
        c.solver.atol = 1e-12;
        let duration = 0.1;
        let reference = trajectory(&c, duration, f64::INFINITY)
            .expect("reference")
            .expect("no cap");
        let lung_error = |h: f64| {
            let run = trajectory_semi_implicit(&c, duration, h, f64::INFINITY)
                .expect("stable")
                .expect("no cap");
            assert_eq!(run.rhs_evaluations, run.steps);
            trajectory_error(&run, &reference)
                .expect("same frames")
                .lung
        };
        let (e1, e2) = (lung_error(4e-4), lung_error(2e-4));
        assert!(e2 > 0.0 && (1.6..2.4).contains(&(e1 / e2)), "{e1} / {e2}");
        // one step per 56 Hz frame is far beyond the stability limit
        match trajectory_semi_implicit(&c, 0.5, 1.0 / FRAME_RATE, f64::INFINITY) {
            Err(Error::Numerical { .. }) => {}
            other => panic!("expected a numerical failure, got {:?}", other.map(|_| ())),
        }
    }

    #[test]
    fn trajectory_error_is_the_max_over_frames_and_markers() {
        let reference = Trajectory {
            lung: vec![1.0, 2.0, 3.0],
            markers: vec![vec![[0.0; 3], [1.0, 1.0, 1.0]]; 3],
            ..Trajectory::default()
        };
        let mut run = reference.clone();
        run.lung[1] += 0.25;
        run.lung[2] -= 0.5;
        run.markers[2][1] = [1.0, 4.0, 5.0];
        let e = trajectory_error(&run, &reference).expect("same length");
        assert_eq!(e.lung, 0.5);
        assert_eq!(e.markers, 5.0);
        run.lung.pop();
        assert!(trajectory_error(&run, &reference).is_err());
    }
}
