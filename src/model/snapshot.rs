//! Snapshots of a [`super::Torso`]'s data: plain, serialisable, versioned, self-contained;
//! and checkpoints, the same data held natively in reusable buffers for rolling back a
//! failed step.

use crate::anatomy::MuscleGroup;
use crate::solver::Integrator;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Magic bytes opening a serialised snapshot.
const MAGIC: &[u8; 8] = b"BTSNAP\0\x01";
/// Format version of serialised snapshots.
pub const SNAPSHOT_VERSION: u32 = 1;

/// Everything mutable about a [`super::Torso`], plus the fingerprint of the compiled model it
/// belongs to. Restoring into an instance of another model is an error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// Format version.
    pub version: u32,
    /// Fingerprint of the compiled model (subject, scene, constants).
    pub fingerprint: u64,
    /// Simulated time [s].
    pub time: f64,
    /// State vector.
    pub state: Vec<f64>,
    /// Activation inputs, one per group in [`crate::anatomy::MuscleGroup::ALL`] order.
    pub inputs: [f64; MuscleGroup::COUNT],
    /// Pressure at the airway opening [Pa]; snapshots written before it existed read 0.
    #[serde(default)]
    pub airway_opening: f64,
    /// The airway occluded: the lungs' dry gas content (P_B + P_alv - P_H2O) V_gas [Pa m^3]
    /// fixed when it closed ([`crate::dynamics::airway`]); `None` open, as snapshots written
    /// before it existed read.
    #[serde(default)]
    pub occlusion: Option<f64>,
    /// The drive.
    pub drive: super::Drive,
    /// Solver memory and statistics, serialised by the solver.
    pub solver: serde_json::Value,
    /// The quasi-static mode's memory (lung volume, last equilibrium, where its
    /// factorisation was taken); `None` in the other modes and in snapshots written before
    /// the mode existed.
    #[serde(default)]
    pub quasi: Option<super::torso::QuasiMemory>,
}

impl Snapshot {
    /// Serialises to bytes: magic, version, then the JSON body (floats round-trip exactly).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&SNAPSHOT_VERSION.to_le_bytes());
        // Serialising plain data to JSON cannot fail.
        out.extend_from_slice(&serde_json::to_vec(self).unwrap_or_default());
        out
    }

    /// Parses bytes written by [`Snapshot::to_bytes`]; garbage is an error, never a panic.
    pub fn from_bytes(bytes: &[u8]) -> Result<Snapshot> {
        let bad = |m: &str| Error::State(format!("not a breathing-torso snapshot: {m}"));
        if bytes.len() < 12 || &bytes[..8] != MAGIC {
            return Err(bad("missing header"));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version != SNAPSHOT_VERSION {
            return Err(bad(&format!(
                "version {version}, this library reads {SNAPSHOT_VERSION}"
            )));
        }
        serde_json::from_slice(&bytes[12..]).map_err(|e| bad(&e.to_string()))
    }
}

/// What a [`Snapshot`] keeps (time, state vector, inputs, airway pressure, drive, solver memory), held natively
/// for rolling back a step within one instance ([`super::Torso::checkpoint`],
/// [`super::Torso::rollback`]). Taking a checkpoint again reuses its buffers: one before every
/// communication step costs copies of three state-length vectors, with no allocation and no
/// serialisation. Rolling back continues bit for bit as restoring the equivalent snapshot.
#[derive(Clone, Debug, Default)]
pub struct Checkpoint {
    pub(super) fingerprint: u64,
    pub(super) time: f64,
    pub(super) state: Vec<f64>,
    pub(super) inputs: [f64; MuscleGroup::COUNT],
    pub(super) airway_opening: f64,
    pub(super) occlusion: Option<f64>,
    pub(super) drive: Option<super::Drive>,
    pub(super) solver: Option<Integrator>,
    pub(super) quasi: Option<super::torso::QuasiMemory>,
}

impl Checkpoint {
    /// Simulated time of the checkpoint [s] (0 while empty).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Whether a checkpoint was taken into it.
    pub fn is_empty(&self) -> bool {
        self.solver.is_none()
    }
}
