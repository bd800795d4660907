//! What the FMI layer adds to a communication step, measured in one process: the FMU's
//! instance ([`Instance`], the object every `fmi2*` and `fmi3*` call of the shared library
//! acts on) stepped by `do_step` and read by one `get_real` of the four volumes and every
//! marker coordinate, against the model facade stepped by `advance_to_with` (with the
//! physiological check, as the C ABI's `bt_advance_to` and the FMU step) and read by
//! [`Torso::read`] and [`Torso::markers`]. Each step reads everything twice, so the second
//! read is the layer's own cost. The C entry points' argument checks are not in it;
//! `scripts/bench-fmu-overhead.sh` measures through the shared library and the official
//! headers.

use super::{FRAME_RATE, median};
use crate::fmi::{FMI2, Instance, Status, table, variables::VR_MARKER};
use crate::model::{AdvanceOptions, Quantity};
use crate::solver::Method;
use crate::{Error, Result, Torso};
use serde::Serialize;
use std::hint::black_box;
use std::time::Instant;

/// The volumes read at every step, by FMI name and as the facade's quantities.
const VOLUMES: [(&str, Quantity); 4] = [
    ("volume.lung", Quantity::LungVolume),
    ("volume.thorax", Quantity::ThoraxVolume),
    ("volume.abdomen", Quantity::AbdomenVolume),
    ("volume.trunk", Quantity::TrunkVolume),
];

/// Medians over the repeats of the per-step costs of both loops.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FmuOverhead {
    /// Solver method of both loops.
    pub method: String,
    /// Level of detail.
    pub level_of_detail: u32,
    /// Communication steps per loop (1/56 s each).
    pub frames: usize,
    /// Loops of each kind, alternating.
    pub repeats: usize,
    /// Values read per step (4 volumes and 3 coordinates per marker).
    pub values: usize,
    /// FMI loop: `do_step` [us per step].
    pub fmi_step_us: f64,
    /// FMI loop: the step's first `get_real` (observation and markers) [us per step].
    pub fmi_first_read_us: f64,
    /// FMI loop: the same `get_real` again [us per step].
    pub fmi_read_again_us: f64,
    /// Native loop: `advance_to_with` [us per step].
    pub native_step_us: f64,
    /// Native loop: the step's first read of the volumes and markers [us per step].
    pub native_first_read_us: f64,
    /// Native loop: the same reads again [us per step].
    pub native_read_again_us: f64,
    /// Whole FMI loop, steps and both reads [s].
    pub fmi_loop_s: f64,
    /// Whole native loop [s].
    pub native_loop_s: f64,
    /// Whether the last step's values are identical, bit for bit, both ways.
    pub identical: bool,
}

/// Per-step times of one loop [s]: step, first read, read again; and the last values.
struct LoopTimes {
    step: f64,
    first: f64,
    again: f64,
    last: Vec<f64>,
}

fn check(status: Status, what: &str) -> Result<()> {
    if status == Status::Ok {
        Ok(())
    } else {
        Err(Error::State(format!(
            "FMU instance: {what} returned {status:?}"
        )))
    }
}

/// An FMU instance in initialization mode at its start values with `method` and level of
/// detail `lod` set, for a run of `frames` steps.
fn configured(method: Method, lod: u32, frames: usize) -> Result<Instance> {
    let mut inst = Instance::new(&FMI2, "bench", None, None, false);
    let vr = |name: &str| {
        table()
            .by_name(name)
            .map(|v| v.vr)
            .ok_or_else(|| Error::State(format!("no FMI variable {name}")))
    };
    let stop = frames as f64 / FRAME_RATE;
    check(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, Some(stop)),
        "fmi2SetupExperiment",
    )?;
    check(
        inst.enter_initialization_mode(),
        "fmi2EnterInitializationMode",
    )?;
    check(
        inst.set_integer(
            "fmi2SetInteger",
            &[vr("solver.method")?, vr("scene.level_of_detail")?],
            &[method.code(), lod as i32],
        ),
        "fmi2SetInteger",
    )?;
    Ok(inst)
}

fn fmi_loop(method: Method, lod: u32, frames: usize, vrs: &[u32]) -> Result<LoopTimes> {
    let mut inst = configured(method, lod, frames)?;
    // builds the model
    check(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        "fmi2ExitInitializationMode",
    )?;
    let mut out = vec![0.0; vrs.len()];
    // the first read builds the marker model, once per compiled model: left out
    check(inst.get_real("fmi2GetReal", vrs, &mut out), "fmi2GetReal")?;
    let (mut step, mut first, mut again) = (0.0, 0.0, 0.0);
    let h = 1.0 / FRAME_RATE;
    for k in 0..frames {
        let a = Instant::now();
        check(
            inst.do_step("fmi2DoStep", k as f64 / FRAME_RATE, h),
            "fmi2DoStep",
        )?;
        let b = Instant::now();
        check(inst.get_real("fmi2GetReal", vrs, &mut out), "fmi2GetReal")?;
        let c = Instant::now();
        check(inst.get_real("fmi2GetReal", vrs, &mut out), "fmi2GetReal")?;
        let d = Instant::now();
        black_box(&out);
        step += (b - a).as_secs_f64();
        first += (c - b).as_secs_f64();
        again += (d - c).as_secs_f64();
    }
    Ok(LoopTimes {
        step,
        first,
        again,
        last: out,
    })
}

fn read_all(torso: &mut Torso, out: &mut Vec<f64>) -> Result<()> {
    out.clear();
    for (_, q) in VOLUMES {
        out.push(torso.read(q)?);
    }
    for p in torso.markers()? {
        out.extend([p.x, p.y, p.z]);
    }
    Ok(())
}

fn native_loop(config: &crate::Config, frames: usize) -> Result<LoopTimes> {
    let mut torso = Torso::new(config.clone())?;
    torso.marker_model()?;
    let mut out = Vec::new();
    let (mut step, mut first, mut again) = (0.0, 0.0, 0.0);
    let options = AdvanceOptions {
        check_physiology: true,
    };
    for k in 0..frames {
        let a = Instant::now();
        // the time the FMU's step ends at: t + h
        torso.advance_to_with(k as f64 / FRAME_RATE + 1.0 / FRAME_RATE, options)?;
        let b = Instant::now();
        read_all(&mut torso, &mut out)?;
        let c = Instant::now();
        read_all(&mut torso, &mut out)?;
        let d = Instant::now();
        black_box(&out);
        step += (b - a).as_secs_f64();
        first += (c - b).as_secs_f64();
        again += (d - c).as_secs_f64();
    }
    Ok(LoopTimes {
        step,
        first,
        again,
        last: out,
    })
}

/// Runs `frames` communication steps of 1/56 s through an FMU instance at its start values
/// (the default subject breathing the quiet drive) with `method` at level of detail `lod`,
/// and the same scene through the facade, alternating, `repeats` times each; model and
/// marker-model builds excluded.
pub fn fmu_overhead(
    method: Method,
    lod: u32,
    frames: usize,
    repeats: usize,
) -> Result<FmuOverhead> {
    if frames == 0 || repeats == 0 {
        return Err(Error::invalid("frames/repeats", 0, "at least 1"));
    }
    // the scene as the instance builds it, for the facade's loop
    let config = configured(method, lod, frames)?.config().clone();
    let markers = config.scene.grid_rows * config.scene.grid_cols;
    let mut vrs = Vec::with_capacity(VOLUMES.len() + 3 * markers);
    for (name, _) in VOLUMES {
        vrs.push(
            table()
                .by_name(name)
                .map(|v| v.vr)
                .ok_or_else(|| Error::State(format!("no FMI variable {name}")))?,
        );
    }
    vrs.extend((0..3 * markers as u32).map(|i| VR_MARKER + i));
    let (mut fmi, mut native) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        fmi.push(fmi_loop(method, lod, frames, &vrs)?);
        native.push(native_loop(&config, frames)?);
    }
    let per_step = |runs: &[LoopTimes], f: fn(&LoopTimes) -> f64| {
        median(
            &runs
                .iter()
                .map(|r| f(r) * 1e6 / frames as f64)
                .collect::<Vec<_>>(),
        )
    };
    let whole = |runs: &[LoopTimes]| {
        median(
            &runs
                .iter()
                .map(|r| r.step + r.first + r.again)
                .collect::<Vec<_>>(),
        )
    };
    let identical = match (fmi.last(), native.last()) {
        (Some(a), Some(b)) => {
            a.last.len() == b.last.len()
                && a.last
                    .iter()
                    .zip(&b.last)
                    .all(|(x, y)| x.to_bits() == y.to_bits())
        }
        _ => false,
    };
    Ok(FmuOverhead {
        method: method.name().to_string(),
        level_of_detail: lod,
        frames,
        repeats,
        values: vrs.len(),
        fmi_step_us: per_step(&fmi, |r| r.step),
        fmi_first_read_us: per_step(&fmi, |r| r.first),
        fmi_read_again_us: per_step(&fmi, |r| r.again),
        native_step_us: per_step(&native, |r| r.step),
        native_first_read_us: per_step(&native, |r| r.first),
        native_read_again_us: per_step(&native, |r| r.again),
        fmi_loop_s: whole(&fmi),
        native_loop_s: whole(&native),
        identical,
    })
}
