//! Running a torso over time at a fixed output rate, and summarising the breathing it shows
//! (tidal volume, end-expiratory volume, compartment shares, dome excursion).

use super::{AdvanceOptions, Quantity, Torso};
use crate::Result;
use crate::anatomy::MuscleGroup;
use serde::Serialize;

/// One output frame (SI units except volumes in litres).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Frame {
    /// Time [s].
    pub time: f64,
    /// Applied activation per group, in [`MuscleGroup::ALL`] order.
    pub activation: [f64; MuscleGroup::COUNT],
    /// Lung volume [L].
    pub lung: f64,
    /// Thoracic volume [L].
    pub thorax: f64,
    /// Abdominal volume [L].
    pub abdomen: f64,
    /// Trunk volume [L].
    pub trunk: f64,
    /// Volume displaced by the rib cage since the start [L].
    pub rib_cage_displaced: f64,
    /// Volume displaced by the abdominal wall since the start [L].
    pub abdomen_displaced: f64,
    /// Abdominal pressure [Pa].
    pub pressure: f64,
    /// Diaphragm dome displacement, cranial positive [m].
    pub diaphragm: f64,
    /// Sternum displacement [m].
    pub sternum: [f64; 3],
}

/// Reads the current frame of `torso`.
pub fn frame(torso: &mut Torso) -> Result<Frame> {
    let mut activation = [0.0; MuscleGroup::COUNT];
    for g in MuscleGroup::ALL {
        activation[g.index()] = torso.applied_activation(g);
    }
    Ok(Frame {
        time: torso.time(),
        activation,
        lung: torso.read(Quantity::LungVolume)?,
        thorax: torso.read(Quantity::ThoraxVolume)?,
        abdomen: torso.read(Quantity::AbdomenVolume)?,
        trunk: torso.read(Quantity::TrunkVolume)?,
        rib_cage_displaced: torso.read(Quantity::RibCageDisplaced)?,
        abdomen_displaced: torso.read(Quantity::AbdomenDisplaced)?,
        pressure: torso.read(Quantity::AbdominalPressure)?,
        diaphragm: torso.read(Quantity::DiaphragmDisplacement)?,
        sternum: [
            torso.read(Quantity::SternumDisplacement(0))?,
            torso.read(Quantity::SternumDisplacement(1))?,
            torso.read(Quantity::SternumDisplacement(2))?,
        ],
    })
}

/// Advances `torso` by `duration` seconds, recording a frame every 1/`rate` seconds (the
/// first at the current time). Steps are checked against the physiological bounds as the
/// FMU's are ([`super::AdvanceOptions::check_physiology`]): a run that leaves them fails with
/// [`crate::Error::Unphysiological`].
pub fn run(torso: &mut Torso, duration: f64, rate: f64) -> Result<Vec<Frame>> {
    let t0 = torso.time();
    let n = (duration * rate).round() as usize;
    let options = AdvanceOptions {
        check_physiology: true,
    };
    let mut frames = Vec::with_capacity(n + 1);
    frames.push(frame(torso)?);
    for i in 1..=n {
        torso.advance_to_with(t0 + i as f64 / rate, options)?;
        frames.push(frame(torso)?);
    }
    Ok(frames)
}

/// Breathing figures over whole cycles of the drive, after a settling cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BreathSummary {
    /// Tidal lung volume: peak-to-trough over the analysed cycles [L].
    pub tidal_volume: f64,
    /// End-expiratory (smallest) lung volume [L].
    pub end_expiratory_volume: f64,
    /// Peak-to-trough volume displaced by the rib-cage wall [L].
    pub rib_cage_swing: f64,
    /// Peak-to-trough volume displaced by the abdominal wall [L].
    pub abdomen_swing: f64,
    /// Rib-cage share of the displaced volume, rib / (rib + abdomen swings).
    pub rib_cage_share: f64,
    /// Peak-to-trough excursion of the diaphragm dome [m].
    pub dome_excursion: f64,
    /// Peak-to-trough abdominal volume change relative to its mean.
    pub abdomen_relative_swing: f64,
    /// Peak-to-trough abdominal pressure [Pa].
    pub pressure_swing: f64,
    /// Sternum's largest ventral displacement [m].
    pub sternum_ventral: f64,
}

/// Summarises `frames` using the frames at or after `from` seconds.
pub fn summarise(frames: &[Frame], from: f64) -> BreathSummary {
    let sel: Vec<&Frame> = frames.iter().filter(|f| f.time >= from - 1e-9).collect();
    let range = |f: &dyn Fn(&Frame) -> f64| {
        let (lo, hi) = sel
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), fr| {
                (lo.min(f(fr)), hi.max(f(fr)))
            });
        (lo, hi)
    };
    let (lo, hi) = range(&|f| f.lung);
    let (rlo, rhi) = range(&|f| f.rib_cage_displaced);
    let (alo, ahi) = range(&|f| f.abdomen_displaced);
    let (dlo, dhi) = range(&|f| f.diaphragm);
    let (vlo, vhi) = range(&|f| f.abdomen);
    let (plo, phi) = range(&|f| f.pressure);
    let (_, sx) = range(&|f| f.sternum[0]);
    let (rc, ab) = (rhi - rlo, ahi - alo);
    BreathSummary {
        tidal_volume: hi - lo,
        end_expiratory_volume: lo,
        rib_cage_swing: rc,
        abdomen_swing: ab,
        rib_cage_share: if rc + ab > 0.0 { rc / (rc + ab) } else { 0.0 },
        dome_excursion: dhi - dlo,
        abdomen_relative_swing: (vhi - vlo) / (0.5 * (vhi + vlo)),
        pressure_swing: phi - plo,
        sternum_ventral: sx,
    }
}
