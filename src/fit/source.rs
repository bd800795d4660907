//! What the fit and the synthetic recordings need from a model: its marker grid at rest and
//! the marker trajectories (and lung volume) produced by a drive, run from the rest state.
//! [`TorsoMarkers`] provides them from one [`Torso`] instance: it keeps a snapshot of the
//! freshly built state and restores it before every run, so the compiled model, the
//! solver's memory and the scratch space are reused across the hundreds of runs of a fit.
//! Frames are read off the solver's continuous extension ([`Torso::advance_sampled`]), so
//! they do not shorten its steps; and a run of one constant periodic drive simulates the
//! transient breath and one periodic breath only, when the breath has become periodic
//! ([`TorsoMarkers::run_periodic`]).

use crate::anatomy::skin::RigidTransform;
use crate::model::{Config, Drive, Quantity, Sample, Snapshot, Torso};
use crate::{Error, Result};
use nalgebra::Point3;

/// A piecewise-constant drive: `(start time [s], drive)` segments in increasing time order;
/// the first segment starts at 0. Breath-to-breath variability is a schedule with one
/// segment per breath.
pub type DriveSchedule = [(f64, Drive)];

/// Output of one model run at the requested times.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Per requested time, the marker positions (model frame) [m].
    pub markers: Vec<Vec<Point3<f64>>>,
    /// Per requested time, the lung volume [L] (empty unless asked for).
    pub lung_volume: Vec<f64>,
}

/// A model whose markers can be compared with a recording.
pub trait MarkerSource {
    /// The marker grid (rows, columns); a marker set other than the grid is (markers, 1).
    fn grid(&self) -> (usize, usize);

    /// Marker positions of the rest state (model frame), used for registration.
    fn rest_markers(&mut self) -> Result<Vec<Point3<f64>>>;

    /// The skin-fitting errors of the model's registration to a recording's first frame
    /// (mean before, mean after) [m], when the model registered and fitted its skin itself.
    fn skin_fit(&mut self) -> Result<Option<(f64, f64)>> {
        Ok(None)
    }

    /// The transform from the frame of the markers [`MarkerSource::run`] gives to the
    /// model's anatomical frame (x anterior, y superior, z right): the identity, unless the
    /// model registered its grid to a recording (`scene.slp_reference`) and gives its
    /// markers in the recording's frame, when it is that registration's recording -> model
    /// transform.
    fn to_anatomy(&mut self) -> Result<RigidTransform> {
        Ok(RigidTransform::identity())
    }

    /// Runs `schedule` from the rest state and records the markers (and the lung volume
    /// when `volumes`) at each of `times` (model time, increasing) into `out`, reusing its
    /// allocations.
    fn run(
        &mut self,
        schedule: &DriveSchedule,
        times: &[f64],
        volumes: bool,
        out: &mut Trajectory,
    ) -> Result<()>;

    /// A second, independent instance of this source giving bit for bit the same runs, for
    /// a search that evaluates two points at once on two threads; `None` when the source
    /// cannot make one (the default).
    fn spare(&self) -> Result<Option<Box<dyn MarkerSource + Send>>> {
        Ok(None)
    }
}

/// A [`MarkerSource`] backed by one [`Torso`].
pub struct TorsoMarkers {
    torso: Torso,
    rest: Snapshot,
    grid: (usize, usize),
    periodic: bool,
    last_run: RunReport,
}

/// How the last [`MarkerSource::run`] of a [`TorsoMarkers`] went.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunReport {
    /// Simulated time [s] (of the last attempt, when a warm start gave up).
    pub simulated_s: f64,
    /// Whether the frames were read off a periodic breath.
    pub periodic: bool,
    /// Largest marker distance between the start and the end of the checked breath [m]
    /// (NaN when no breath was checked).
    pub period_mismatch_m: f64,
    /// Largest lung-volume difference between the start and the end of the checked breath
    /// [L] (NaN when no breath was checked or volumes were not read).
    pub period_mismatch_l: f64,
}

/// Largest marker distance [m] between the two ends of a breath for the breath to count as
/// periodic: 0.1 um, a fraction of the fit's stopping tolerance on the cost (0.05 % of a
/// sub-millimetre cost) and four orders of magnitude below SLP noise (0.5 mm).
pub const PERIODIC_MARKER_TOLERANCE_M: f64 = 1e-7;
/// Largest lung-volume difference [L] between the two ends of a breath for the breath to
/// count as periodic when volumes are read: 10 nL, the order of the solver's own error on
/// the lung volume at its default tolerances (a few nL over a minute of quiet breathing).
pub const PERIODIC_VOLUME_TOLERANCE_L: f64 = 1e-5;

impl TorsoMarkers {
    /// Builds the torso for `config` and keeps its rest state.
    pub fn new(config: Config) -> Result<TorsoMarkers> {
        TorsoMarkers::from_torso(Torso::new_at_rest(config)?)
    }

    /// Wraps an already built torso, put at its rest pose ([`Torso::start_at_rest`]): the
    /// state every run starts from (a run's first breath is the transient the periodic
    /// runs discard).
    pub fn from_torso(mut torso: Torso) -> Result<TorsoMarkers> {
        torso.start_at_rest();
        // A marker set other than the grid is one column of its markers.
        let grid = match torso.marker_set() {
            Some(set) => (set.len(), 1),
            None => (
                torso.config().scene.grid_rows,
                torso.config().scene.grid_cols,
            ),
        };
        let rest = torso.snapshot();
        Ok(TorsoMarkers {
            torso,
            rest,
            grid,
            periodic: true,
            last_run: RunReport::default(),
        })
    }

    /// Whether a run of one constant drive may read the frames after its second breath off
    /// the second breath once that breath is periodic (on by default; see
    /// [`TorsoMarkers::run_periodic`]). Off, every frame is simulated.
    pub fn set_periodic(&mut self, on: bool) {
        self.periodic = on;
    }

    /// How the last run went.
    pub fn last_run(&self) -> RunReport {
        self.last_run
    }

    /// The underlying torso.
    pub fn torso(&mut self) -> &mut Torso {
        &mut self.torso
    }
}

/// Reads the markers of `torso` into `out` (one point per grid point) through the facade.
pub fn read_markers(torso: &mut Torso, out: &mut Vec<Point3<f64>>) -> Result<()> {
    out.clear();
    out.extend_from_slice(torso.markers()?);
    Ok(())
}

/// Stores a sample's markers (and lung volume) into slot `k` of `out`.
fn store(sample: &mut Sample<'_>, volumes: bool, k: usize, out: &mut Trajectory) -> Result<()> {
    let m = &mut out.markers[k];
    m.clear();
    m.extend_from_slice(sample.markers()?);
    if volumes {
        out.lung_volume[k] = sample.read(Quantity::LungVolume)?;
    }
    Ok(())
}

impl TorsoMarkers {
    /// Runs `drive` for the frames at `times` (all after the first breath) and reads them
    /// off the periodic response, simulating only the breaths needed to reach it: the
    /// drive is periodic with the breath, so once one breath of the response is periodic,
    /// so is every later one, and each frame is read at its phase (time minus one breath,
    /// modulo the period) in that breath. The first breath from rest is the transient; then
    /// each breath is simulated with the states at every frame's phase and checked: it
    /// counts as periodic when its end matches its start (markers within
    /// [`PERIODIC_MARKER_TOLERANCE_M`], lung volume within [`PERIODIC_VOLUME_TOLERANCE_L`],
    /// about the solver's own error). The frames are also read as they come, so that if no
    /// breath ending before the last frame is periodic, the run simply goes on over every
    /// frame (the frames are then those of a plain run from rest, transient included).
    /// Returns false, having done nothing, when the drive has no period or the frames end
    /// within two breaths.
    pub fn run_periodic(
        &mut self,
        drive: Drive,
        times: &[f64],
        volumes: bool,
        out: &mut Trajectory,
    ) -> Result<bool> {
        let f = drive.frequency;
        let (Some(&first), Some(&last)) = (times.first(), times.last()) else {
            return Ok(false);
        };
        if !(f > 0.0 && f.is_finite()) || first < 0.0 || last <= 2.0 / f {
            return Ok(false);
        }
        /// What a sample is for.
        #[derive(Clone, Copy)]
        enum Slot {
            Frame(usize),
            Phase(usize),
            Start,
            End,
        }
        let period = 1.0 / drive.frequency;
        let settle = period;
        self.torso.restore(&self.rest)?;
        self.torso.set_drive(drive)?;
        let mut report = RunReport {
            period_mismatch_m: f64::NAN,
            period_mismatch_l: f64::NAN,
            ..RunReport::default()
        };
        // frames below `next` are stored
        let mut next = 0;
        // the breath being checked: [begin, begin + period]
        let mut begin = settle;
        let mut start: Option<(Vec<Point3<f64>>, f64)> = None;
        let mut plan: Vec<(f64, Slot)> = Vec::with_capacity(times.len() + 2);
        let mut got = Trajectory::default();
        loop {
            let end = begin + period;
            if last <= end {
                break;
            }
            let direct = times.partition_point(|t| *t <= end);
            plan.clear();
            plan.extend((next..direct).map(|k| (times[k], Slot::Frame(k))));
            plan.extend((0..times.len()).map(|k| {
                let phase = (times[k] - settle).rem_euclid(period);
                ((begin + phase).min(end), Slot::Phase(k))
            }));
            if start.is_none() {
                plan.push((begin, Slot::Start));
            }
            plan.push((end, Slot::End));
            plan.sort_by(|a, b| a.0.total_cmp(&b.0));
            let sample_times: Vec<f64> = plan.iter().map(|p| p.0).collect();
            got.markers.resize_with(plan.len(), Vec::new);
            got.lung_volume.clear();
            if volumes {
                got.lung_volume.resize(plan.len(), 0.0);
            }
            self.torso
                .advance_sampled(end, &sample_times, &mut |k, s| {
                    store(s, volumes, k, &mut got)
                })?;
            let lung = |j: usize| if volumes { got.lung_volume[j] } else { 0.0 };
            let mut end_sample = None;
            for (j, (_, slot)) in plan.iter().enumerate() {
                match *slot {
                    Slot::Frame(k) => {
                        out.markers[k].clone_from(&got.markers[j]);
                        if volumes {
                            out.lung_volume[k] = got.lung_volume[j];
                        }
                    }
                    Slot::Start => start = Some((got.markers[j].clone(), lung(j))),
                    Slot::End => end_sample = Some(j),
                    Slot::Phase(_) => {}
                }
            }
            next = direct;
            let (Some((start_markers, start_lung)), Some(e)) = (&start, end_sample) else {
                return Err(Error::State("periodic run lost its check points".into()));
            };
            report.period_mismatch_m = start_markers
                .iter()
                .zip(&got.markers[e])
                .map(|(p, q)| (p - q).norm())
                .fold(0.0, f64::max);
            if volumes {
                report.period_mismatch_l = (start_lung - got.lung_volume[e]).abs();
            }
            report.periodic = report.period_mismatch_m <= PERIODIC_MARKER_TOLERANCE_M
                && (!volumes || report.period_mismatch_l <= PERIODIC_VOLUME_TOLERANCE_L);
            if report.periodic {
                for (j, (_, slot)) in plan.iter().enumerate() {
                    if let Slot::Phase(k) = *slot {
                        out.markers[k].clone_from(&got.markers[j]);
                        if volumes {
                            out.lung_volume[k] = got.lung_volume[j];
                        }
                    }
                }
                next = times.len();
                break;
            }
            start = Some((got.markers[e].clone(), lung(e)));
            begin = end;
        }
        if next < times.len() {
            self.torso
                .advance_sampled(last, &times[next..], &mut |k, s| {
                    store(s, volumes, next + k, out)
                })?;
        }
        report.simulated_s = self.torso.time();
        self.last_run = report;
        Ok(true)
    }
}

impl MarkerSource for TorsoMarkers {
    fn grid(&self) -> (usize, usize) {
        self.grid
    }

    fn skin_fit(&mut self) -> Result<Option<(f64, f64)>> {
        let model = self.torso.marker_model()?;
        Ok(model
            .registration()
            .map(|r| (r.fit.mean_before, r.fit.mean_after)))
    }

    fn to_anatomy(&mut self) -> Result<RigidTransform> {
        let model = self.torso.marker_model()?;
        Ok(model
            .registration()
            .map_or_else(RigidTransform::identity, |r| r.to_model))
    }

    /// Another torso on the same compiled model (the skin and marker model are shared), at
    /// the same rest state, with the same settings.
    fn spare(&self) -> Result<Option<Box<dyn MarkerSource + Send>>> {
        let mut torso = Torso::with_compiled_at_rest(
            self.torso.config().clone(),
            self.torso.compiled().clone(),
        )?;
        torso.set_marker_set(self.torso.marker_set().cloned());
        torso.restore(&self.rest)?;
        Ok(Some(Box::new(TorsoMarkers {
            torso,
            rest: self.rest.clone(),
            grid: self.grid,
            periodic: self.periodic,
            last_run: RunReport::default(),
        })))
    }

    fn rest_markers(&mut self) -> Result<Vec<Point3<f64>>> {
        self.torso.restore(&self.rest)?;
        let mut out = Vec::new();
        read_markers(&mut self.torso, &mut out)?;
        Ok(out)
    }

    /// Frames are read off the solver's continuous extension; with one constant drive and
    /// [`TorsoMarkers::set_periodic`] on, [`TorsoMarkers::run_periodic`] is tried first.
    fn run(
        &mut self,
        schedule: &DriveSchedule,
        times: &[f64],
        volumes: bool,
        out: &mut Trajectory,
    ) -> Result<()> {
        let Some(first) = schedule.first() else {
            return Err(Error::invalid(
                "drive schedule",
                "empty",
                "at least one drive",
            ));
        };
        out.markers.resize_with(times.len(), Vec::new);
        out.lung_volume.clear();
        if volumes {
            out.lung_volume.resize(times.len(), 0.0);
        }
        if self.periodic
            && schedule.len() == 1
            && self.run_periodic(first.1, times, volumes, out)?
        {
            return Ok(());
        }
        self.torso.restore(&self.rest)?;
        self.torso.set_drive(first.1)?;
        let mut k = 0;
        for (s, segment) in schedule.iter().enumerate() {
            if s > 0 {
                if segment.0 > times.last().copied().unwrap_or(0.0) {
                    break;
                }
                self.torso.advance_to(segment.0.max(self.torso.time()))?;
                self.torso.set_drive(segment.1)?;
            }
            let next_start = schedule.get(s + 1).map_or(f64::INFINITY, |n| n.0);
            let j = k + times[k..].partition_point(|t| *t < next_start);
            if j > k {
                self.torso
                    .advance_sampled(times[j - 1], &times[k..j], &mut |i, smp| {
                        store(smp, volumes, k + i, out)
                    })?;
            }
            k = j;
        }
        self.last_run = RunReport {
            simulated_s: self.torso.time(),
            periodic: false,
            period_mismatch_m: f64::NAN,
            period_mismatch_l: f64::NAN,
        };
        Ok(())
    }
}
