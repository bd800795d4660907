//! What the fit and the synthetic recordings need from a model: its marker grid at rest and
//! the marker trajectories (and lung volume) produced by a drive, run from the rest state.
//! [`TorsoMarkers`] provides them from one [`Torso`] instance: it keeps a snapshot of the
//! freshly built state and restores it before every run, so the compiled model, the
//! solver's memory and the scratch space are reused across the hundreds of runs of a fit.

use crate::model::{Config, Drive, Quantity, Snapshot, Torso};
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
    /// The marker grid (rows, columns).
    fn grid(&self) -> (usize, usize);

    /// Marker positions of the rest state (model frame), used for registration.
    fn rest_markers(&mut self) -> Result<Vec<Point3<f64>>>;

    /// The skin-fitting errors of the model's registration to a recording's first frame
    /// (mean before, mean after) [m], when the model registered and fitted its skin itself.
    fn skin_fit(&mut self) -> Result<Option<(f64, f64)>> {
        Ok(None)
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
}

/// A [`MarkerSource`] backed by one [`Torso`].
pub struct TorsoMarkers {
    torso: Torso,
    rest: Snapshot,
    grid: (usize, usize),
}

impl TorsoMarkers {
    /// Builds the torso for `config` and keeps its rest state.
    pub fn new(config: Config) -> Result<TorsoMarkers> {
        TorsoMarkers::from_torso(Torso::new(config)?)
    }

    /// Wraps an already built torso; its current state becomes the rest state.
    pub fn from_torso(torso: Torso) -> Result<TorsoMarkers> {
        let grid = (
            torso.config().scene.grid_rows,
            torso.config().scene.grid_cols,
        );
        let rest = torso.snapshot();
        Ok(TorsoMarkers { torso, rest, grid })
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

    fn rest_markers(&mut self) -> Result<Vec<Point3<f64>>> {
        self.torso.restore(&self.rest)?;
        let mut out = Vec::new();
        read_markers(&mut self.torso, &mut out)?;
        Ok(out)
    }

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
        self.torso.restore(&self.rest)?;
        self.torso.set_drive(first.1)?;
        out.markers.resize_with(times.len(), Vec::new);
        out.lung_volume.clear();
        let mut next = 1;
        for (k, &t) in times.iter().enumerate() {
            while next < schedule.len() && schedule[next].0 <= t {
                self.torso.advance_to(schedule[next].0)?;
                self.torso.set_drive(schedule[next].1)?;
                next += 1;
            }
            self.torso.advance_to(t)?;
            read_markers(&mut self.torso, &mut out.markers[k])?;
            if volumes {
                out.lung_volume.push(self.torso.read(Quantity::LungVolume)?);
            }
        }
        Ok(())
    }
}
