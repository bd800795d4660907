//! [`Torso`]: the model facade.

use super::{Config, Drive, Quantity, Snapshot};
use crate::anatomy::MuscleGroup;
use crate::solver::Stats;
use crate::{Error, Result};

/// Statistics of one [`Torso::advance_to`] call.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdvanceStats {
    /// Accepted steps in this call.
    pub steps: u64,
    /// Rejected steps in this call.
    pub rejected: u64,
    /// Right-hand-side evaluations in this call.
    pub rhs_evaluations: u64,
}

/// A breathing torso: a compiled model plus its mutable data.
pub struct Torso {
    config: Config,
    time: f64,
    inputs: [f64; 8],
}

impl Torso {
    /// Builds the model for `config` (validated first; the error names the bad field).
    pub fn new(config: Config) -> Result<Torso> {
        config.validate()?;
        Ok(Torso {
            config,
            time: 0.0,
            inputs: [0.0; 8],
        })
    }

    /// The configuration the model was built from (with the current drive).
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Current simulated time [s].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Sets the activation input of `group` (in [0, 1]); a rejected value leaves the state as it was.
    pub fn set_activation(&mut self, group: MuscleGroup, value: f64) -> Result<()> {
        super::check(&format!("activation.{}", group.name()), value, (0.0, 1.0))?;
        self.inputs[group.index()] = value;
        Ok(())
    }

    /// The activation input of `group`.
    pub fn activation_input(&self, group: MuscleGroup) -> f64 {
        self.inputs[group.index()]
    }

    /// Replaces the drive (validated first).
    pub fn set_drive(&mut self, drive: Drive) -> Result<()> {
        drive.validate()?;
        self.config.drive = drive;
        Ok(())
    }

    /// Integrates from the current time to `t`, inputs held constant.
    pub fn advance_to(&mut self, t: f64) -> Result<AdvanceStats> {
        Err(Error::Numerical {
            time: self.time,
            reason: format!("cannot advance to {t}: dynamics not built"),
        })
    }

    /// Reads a quantity.
    pub fn read(&mut self, quantity: Quantity) -> Result<f64> {
        match quantity {
            Quantity::Time => Ok(self.time),
            q => Err(Error::State(format!("{q:?} is not available"))),
        }
    }

    /// Cumulative solver statistics.
    pub fn solver_stats(&self) -> Stats {
        Stats::default()
    }

    /// A snapshot of the mutable data.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            version: super::snapshot::SNAPSHOT_VERSION,
            fingerprint: 0,
            time: self.time,
            state: Vec::new(),
            inputs: self.inputs,
            drive: self.config.drive,
            solver: serde_json::Value::Null,
        }
    }

    /// Restores a snapshot taken from a model with the same fingerprint.
    pub fn restore(&mut self, snapshot: &Snapshot) -> Result<()> {
        self.time = snapshot.time;
        self.inputs = snapshot.inputs;
        self.config.drive = snapshot.drive;
        Ok(())
    }

    /// Back to the freshly built state (time 0, rest state, zero inputs, solver memory cleared).
    pub fn reset(&mut self) {
        self.time = 0.0;
        self.inputs = [0.0; 8];
    }
}
