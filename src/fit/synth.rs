//! Synthetic SLP recordings with known parameters: a model run under a drive, its markers
//! moved into a camera frame by a rigid transform, with Gaussian noise, breath-to-breath
//! variability and dropped points.
//!
//! Timing follows the fit's convention (see [`super::fitting`]): the model is driven from
//! rest, and the recording starts at end-expiration (the smallest lung volume in the period
//! after the first rib-cage activation minimum past one period), as the thesis's recordings
//! start (figure 3.4); the true phases are the drive's phases at that first frame.
//! Variability: from the second breath on, each breath's period and amplitudes are scaled
//! by 1 + v N(0, 1) (clamped to [0.5, 1.5]), a [`Breaths`] schedule; the drive changes at
//! the breath boundaries (rib-cage inspiration onsets) with phases chosen so the waves are
//! continuous ([`Breaths::schedule`]).

use super::fitting::wrap_angle;
use super::source::{MarkerSource, Trajectory};
use crate::anatomy::skin::RigidTransform;
use crate::model::{Breath, Breaths, Drive};
use crate::numeric::rng::Pcg64;
use crate::recording::Recording;
use crate::recording::Units;
use crate::{Error, Result};
use nalgebra::{Point3, Rotation3, Unit, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// How the camera frame is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Camera {
    /// The model frame itself.
    Identity,
    /// A camera about 1.2 m in front of the chest looking at it, tilted up to 15 degrees
    /// about a random axis and shifted up to 10 cm.
    Random,
    /// A motion-capture laboratory's frame: z up, the subject turned by a random angle
    /// (uniform over the full turn) about the vertical and standing at a random spot within
    /// 2 m of the origin, the floor at z = 0 (the model's origin is on the floor).
    Lab,
}

/// A random laboratory pose (see [`Camera::Lab`]): model (x anterior, y up, z right) ->
/// lab (z up).
fn lab_frame(rng: &mut Pcg64) -> RigidTransform {
    // Model y (up) -> lab z, model x (anterior) -> lab x, model z (right) -> lab -y.
    let upright = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
        1.0, 0.0, 0.0, //
        0.0, 0.0, -1.0, //
        0.0, 1.0, 0.0,
    ));
    let yaw = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 2.0 * PI * rng.uniform());
    let rotation = yaw * UnitQuaternion::from_rotation_matrix(&upright);
    let translation = Vector3::new(
        4.0 * (rng.uniform() - 0.5),
        4.0 * (rng.uniform() - 0.5),
        0.0,
    );
    RigidTransform {
        rotation,
        translation,
        scale: 1.0,
    }
}

/// Settings of a synthetic recording.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthOptions {
    /// Nominal drive (thesis eq. 2.4, with its inspiratory fraction).
    pub drive: Drive,
    /// Frame rate [Hz] (SLP: 56).
    pub rate: f64,
    /// Duration [s].
    pub duration: f64,
    /// Standard deviation of the Gaussian noise on each coordinate [m].
    pub noise: f64,
    /// Seed of every random draw.
    pub seed: u64,
    /// Camera frame.
    pub camera: Camera,
    /// Breath-to-breath variability v of period and amplitudes (0: none).
    pub variability: f64,
    /// Probability that a point is not tracked in a frame.
    pub dropout: f64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            drive: Drive::quiet(),
            rate: 56.0,
            duration: 18.0,
            noise: 0.5e-3,
            seed: 1,
            camera: Camera::Random,
            variability: 0.0,
            dropout: 0.0,
        }
    }
}

/// A synthetic recording and what produced it.
#[derive(Clone, Debug, PartialEq)]
pub struct Synthetic {
    /// The recording (camera frame).
    pub recording: Recording,
    /// The drive a fit should recover: nominal frequency and amplitudes, phases at the first
    /// frame.
    pub truth: Drive,
    /// Model frame -> camera frame (registration recovers its inverse).
    pub camera: RigidTransform,
    /// Mean length of the noise vectors added to the tracked points [m]: the cost a perfect
    /// fit would reach.
    pub noise_floor_m: f64,
    /// Model time of the first frame [s].
    pub start_time: f64,
    /// The drive schedule applied (model time, drive).
    pub schedule: Vec<(f64, Drive)>,
    /// The breaths of the schedule (model time; empty without variability).
    pub breaths: Breaths,
}

impl SynthOptions {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.drive.validate()?;
        let check = |name: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(Error::invalid(name, v, format!("[{lo}, {hi}]")))
            }
        };
        check("--rate", self.rate, 1.0, 1000.0)?;
        check("--duration", self.duration, 1.0, 3600.0)?;
        check("--noise-mm", self.noise * 1e3, 0.0, 50.0)?;
        check("--variability", self.variability, 0.0, 0.5)?;
        check("--dropout", self.dropout, 0.0, 0.5)?;
        if self.drive.ribs.amplitude <= 0.0 && self.drive.diaphragm.amplitude <= 0.0 {
            return Err(Error::invalid(
                "drive amplitudes",
                "0",
                "a rib-cage or diaphragm amplitude above 0 (a recording needs a breath)",
            ));
        }
        Ok(())
    }
}

/// A random camera pose (see [`Camera::Random`]) aimed at `target` (model frame).
fn random_camera(rng: &mut Pcg64, target: &Point3<f64>) -> RigidTransform {
    // Camera axes: z_c looks along -x (posteriorly, into the chest), y_c points down, x_c
    // completes a right-handed frame. Rows of the rotation are the camera axes in the model.
    let look = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
        0.0, 0.0, -1.0, //
        0.0, -1.0, 0.0, //
        -1.0, 0.0, 0.0,
    ));
    let axis = Unit::new_normalize(Vector3::new(rng.normal(), rng.normal(), rng.normal()));
    let tilt = UnitQuaternion::from_axis_angle(&axis, (15.0f64).to_radians() * rng.uniform());
    let rotation = tilt * UnitQuaternion::from_rotation_matrix(&look);
    let shift = Vector3::new(
        rng.uniform() - 0.5,
        rng.uniform() - 0.5,
        rng.uniform() - 0.5,
    ) * 0.2;
    // The target lands 1.2 m in front of the camera, plus the shift.
    let translation = Vector3::new(0.0, 0.0, 1.2) + shift - rotation * target.coords;
    RigidTransform {
        rotation,
        translation,
        scale: 1.0,
    }
}

/// The first rib-cage activation minimum (phase -pi/2 mod 2 pi) at or after one period.
fn first_activation_minimum(d: &Drive) -> f64 {
    let f = d.frequency;
    let settle = 1.0 / f;
    let phase_at = 2.0 * PI * f * settle + d.ribs.phase;
    settle + (-PI / 2.0 - phase_at).rem_euclid(2.0 * PI) / (2.0 * PI * f)
}

/// The breaths of the recording (with variability; none without): from `first_boundary`
/// on, each breath starts at a rib-cage inspiration onset with its own period and depth,
/// both the nominal ones scaled by 1 + v N(0, 1) clamped to [0.5, 1.5] (the period drawn
/// first, through the frequency, which stays in the drive's [0.05, 2] Hz).
fn breaths(o: &SynthOptions, rng: &mut Pcg64, first_boundary: f64, end: f64) -> Breaths {
    let f = o.drive.frequency;
    let mut out = Vec::new();
    if o.variability > 0.0 {
        let mut t = first_boundary;
        while t < end {
            let scale = |rng: &mut Pcg64| (1.0 + o.variability * rng.normal()).clamp(0.5, 1.5);
            let fk = (f / scale(rng)).clamp(0.05, 2.0);
            let depth = scale(rng);
            out.push(Breath {
                start: t,
                period: 1.0 / fk,
                depth,
            });
            t += 1.0 / fk;
        }
    }
    Breaths(out)
}

/// End-expiration: the time of the smallest lung volume within one period from the first
/// rib-cage activation minimum, under the nominal drive (one model run).
fn end_expiration(model: &mut dyn MarkerSource, o: &SynthOptions) -> Result<f64> {
    let d = o.drive;
    let a = first_activation_minimum(&d);
    let n = (o.rate / d.frequency).ceil() as usize;
    let times: Vec<f64> = (0..=n).map(|k| a + k as f64 / o.rate).collect();
    let mut traj = Trajectory::default();
    model.run(&[(0.0, d)], &times, true, &mut traj)?;
    let k = traj
        .lung_volume
        .iter()
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |b, (i, &v)| if v < b.1 { (i, v) } else { b },
        )
        .0;
    Ok(times[k])
}

/// Generates a synthetic recording from `model` (see the module doc).
pub fn synthesize(model: &mut dyn MarkerSource, o: &SynthOptions) -> Result<Synthetic> {
    o.validate()?;
    let mut rng = Pcg64::new(o.seed, 3);
    let start = end_expiration(model, o)?;
    let f = o.drive.frequency;
    let breaths = breaths(
        o,
        &mut rng,
        first_activation_minimum(&o.drive) + 1.0 / f,
        start + o.duration + 1.0 / f,
    );
    let segments = breaths.schedule(&o.drive);
    let n = (o.duration * o.rate).round() as usize + 1;
    let times: Vec<f64> = (0..n).map(|i| i as f64 / o.rate).collect();
    let model_times: Vec<f64> = times.iter().map(|t| start + t).collect();
    let mut traj = Trajectory::default();
    model.run(&segments, &model_times, false, &mut traj)?;
    let centroid = {
        let first = &traj.markers[0];
        Point3::from(first.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / first.len() as f64)
    };
    let camera = match o.camera {
        Camera::Identity => RigidTransform::identity(),
        Camera::Random => random_camera(&mut rng, &centroid),
        Camera::Lab => lab_frame(&mut rng),
    };
    let (mut noise_sum, mut tracked) = (0.0, 0usize);
    let frames: Vec<Vec<Option<Point3<f64>>>> = traj
        .markers
        .iter()
        .map(|frame| {
            frame
                .iter()
                .map(|p| {
                    if o.dropout > 0.0 && rng.uniform() < o.dropout {
                        return None;
                    }
                    let e = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * o.noise;
                    noise_sum += e.norm();
                    tracked += 1;
                    Some(camera.apply(&(p + e)))
                })
                .collect()
        })
        .collect();
    let d = o.drive;
    // Phases of the nominal drive at the first frame.
    let at_start = |phase: f64| wrap_angle(2.0 * PI * d.frequency * start + phase);
    let mut truth = d;
    truth.ribs.phase = at_start(d.ribs.phase);
    truth.diaphragm.phase = at_start(d.diaphragm.phase);
    truth.abdominals.phase = at_start(d.abdominals.phase);
    Ok(Synthetic {
        recording: Recording {
            grid: model.grid(),
            times,
            frames,
            units: Units::Metres,
            provenance: Vec::new(),
        },
        truth,
        camera,
        noise_floor_m: if tracked > 0 {
            noise_sum / tracked as f64
        } else {
            0.0
        },
        start_time: start,
        schedule: segments,
        breaths,
    })
}
