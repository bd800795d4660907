//! `torso bench stress`: the long stress items, each printing its measured figures and
//! writing them (JSON, CSV, PNG) to an output folder:
//!
//! - `square`: every muscle group switched 0 <-> 1 at once as a square wave (20 Hz) for 60 s;
//! - `hold`: every group at full activation, held for 60 s;
//! - `drift`: an hour of quiet breathing, the end-expiratory lung volume of every breath and
//!   its drift (target: under 0.1 % from the first breath to the last);
//! - `steps`: communication steps from 1e-5 s to 2 s, and random step sequences, against one
//!   long run (final state within the stated tolerance).
//!
//! The exit status is 1 when any item misses its criterion.

use crate::bench::SceneOutcome;
use crate::bench::stress::{
    ActivationRun, Drift, SteppedRun, communication_steps, held_maximal, quiet_drift, random_steps,
    square_waves,
};
use crate::model::{Config, Drive};
use crate::stats::plot::{BLUE, HLine, Mark, Panel, RED, Trace, write_figure};
use crate::{Error, Result};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Largest drift of the end-expiratory lung volume over the quiet run (issue 6: 0.1 %).
pub const DRIFT_TARGET: f64 = 1e-3;

/// Largest accepted difference between a stepped run's final state and one long run, in
/// units of the solver's local tolerance (atol + rtol |y|) per component.
pub const STEPPED_STATE_TOLERANCE: f64 = 100.0;

/// Options of `torso bench stress`.
#[derive(Args, Debug)]
pub struct StressArgs {
    /// Items to run, comma-separated: square, hold, drift, steps.
    #[arg(long, default_value = "square,hold,drift,steps")]
    pub items: String,
    /// Level of detail of the square-wave, hold and step items.
    #[arg(long, default_value_t = 1)]
    pub lod: u32,
    /// Simulated seconds of the square waves and of the hold.
    #[arg(long, default_value_t = 60.0)]
    pub seconds: f64,
    /// Square-wave frequency [Hz].
    #[arg(long, default_value_t = 20.0)]
    pub square_hz: f64,
    /// Simulated seconds of quiet breathing for the drift.
    #[arg(long, default_value_t = 3600.0)]
    pub drift_seconds: f64,
    /// Level of detail of the drift run.
    #[arg(long, default_value_t = 1)]
    pub drift_lod: u32,
    /// End time of the communication-step runs [s] (a multiple of every step).
    #[arg(long, default_value_t = 4.0)]
    pub steps_end: f64,
    /// Random communication-step sequences.
    #[arg(long, default_value_t = 5)]
    pub random_sequences: usize,
    /// Seed of the random step sequences.
    #[arg(long, default_value_t = 2011)]
    pub seed: u64,
    /// Output folder.
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
}

/// Fixed communication steps of the `steps` item [s].
pub const STEPS: [f64; 8] = [1e-5, 1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.0, 2.0];

fn config(lod: u32, drive: Drive) -> Result<Config> {
    let mut c = Config {
        drive,
        ..Config::default()
    };
    c.scene.level_of_detail = lod;
    c.validate()?;
    Ok(c)
}

fn write_json(dir: &Path, name: &str, value: &impl Serialize) -> Result<PathBuf> {
    let path = dir.join(format!("{name}.json"));
    let text =
        serde_json::to_string_pretty(value).map_err(|e| Error::State(format!("JSON: {e}")))?;
    std::fs::write(&path, text).map_err(|e| Error::Io {
        path: path.clone(),
        source: e,
    })?;
    Ok(path)
}

fn print_activation(title: &str, r: &ActivationRun) {
    println!(
        "{title}: {} s, {:?}\n  lung at rest {:.4} L, at the end {:.4} L, range {:.4}-{:.4} L; thorax {:.3}-{:.3} x, abdomen {:.3}-{:.3} x, trunk {:.3}-{:.3} x of the rest values ({} checks)\n  {:.1} s wall, {} steps (+{} rejected), {} RHS evaluations, stiffness flag on {} steps",
        r.seconds,
        r.outcome,
        r.rest_lung,
        r.end_lung,
        r.monitor.lung.0,
        r.monitor.lung.1,
        r.monitor.ratios[0].0,
        r.monitor.ratios[0].1,
        r.monitor.ratios[1].0,
        r.monitor.ratios[1].1,
        r.monitor.ratios[2].0,
        r.monitor.ratios[2].1,
        r.monitor.checks,
        r.work.wall,
        r.work.steps,
        r.work.rejected,
        r.work.rhs_evaluations,
        r.work.stiff_steps
    );
}

fn drift_outputs(dir: &Path, d: &Drift) -> Result<()> {
    let mut csv = String::from("breath,time_s,end_expiratory_l,peak_l,relative_to_first\n");
    let e0 = d.breaths.first().map_or(f64::NAN, |b| b.end_expiratory);
    for (k, b) in d.breaths.iter().enumerate() {
        csv.push_str(&format!(
            "{k},{},{},{},{:e}\n",
            b.time,
            b.end_expiratory,
            b.peak,
            (b.end_expiratory - e0) / e0
        ));
    }
    let path = dir.join("stress_drift.csv");
    std::fs::write(&path, csv).map_err(|e| Error::Io {
        path: path.clone(),
        source: e,
    })?;
    let t: Vec<f64> = d.breaths.iter().map(|b| b.time / 60.0).collect();
    let rel: Vec<f64> = d
        .breaths
        .iter()
        .map(|b| 100.0 * (b.end_expiratory - e0) / e0)
        .collect();
    let limit = |y: f64, label: &str| HLine {
        label: label.into(),
        y,
        color: RED,
        dashed: true,
    };
    write_figure(
        dir,
        "stress_drift",
        &[Panel {
            title: format!(
                "End-expiratory lung volume over {:.0} min of quiet breathing",
                d.seconds / 60.0
            ),
            x_label: "time [min]".into(),
            y_label: "change from the first breath [%]".into(),
            traces: vec![Trace {
                label: format!("end-expiratory volume (first {e0:.4} L)"),
                x: &t,
                y: &rel,
                color: BLUE,
                mark: Mark::Line,
            }],
            hlines: vec![
                limit(100.0 * DRIFT_TARGET, "target +-0.1 %"),
                limit(-100.0 * DRIFT_TARGET, ""),
            ],
            bands: Vec::new(),
        }],
    )
}

fn print_stepped(runs: &[SteppedRun]) {
    println!(
        "  {:<20} {:>8} {:>10} {:>10} {:>12} {:>11} {:>12} {:>9} {:>8}",
        "steps", "calls", "min h", "max h", "lung [L]", "lung rel", "state [tol]", "RHS", "wall"
    );
    for r in runs {
        println!(
            "  {:<20} {:>8} {:>10.3e} {:>10.3e} {:>12.8} {:>11.2e} {:>12.3} {:>9} {:>7.2}s",
            r.label,
            r.calls,
            r.step_range.0,
            r.step_range.1,
            r.lung,
            r.lung_relative,
            r.state_error,
            r.work.rhs_evaluations,
            r.work.wall
        );
    }
}

/// Runs `torso bench stress`.
pub fn run(args: &StressArgs) -> Result<()> {
    let items: Vec<&str> = args.items.split(',').map(str::trim).collect();
    for item in &items {
        if !["square", "hold", "drift", "steps"].contains(item) {
            return Err(Error::invalid(
                "--items",
                item,
                "a comma-separated list of square, hold, drift, steps",
            ));
        }
    }
    if !(args.seconds > 0.0 && args.drift_seconds > 0.0 && args.steps_end > 0.0) {
        return Err(Error::invalid(
            "--seconds/--drift-seconds/--steps-end",
            args.seconds,
            "> 0",
        ));
    }
    std::fs::create_dir_all(&args.out).map_err(|e| Error::Io {
        path: args.out.clone(),
        source: e,
    })?;
    let mut failures = Vec::new();
    let rate = crate::bench::FRAME_RATE;
    if items.contains(&"square") {
        let c = config(args.lod, Drive::default())?;
        let r = square_waves(&c, args.seconds, args.square_hz, rate)?;
        print_activation(
            &format!(
                "square waves 0 <-> 1 at {} Hz in all groups, level of detail {}",
                args.square_hz, args.lod
            ),
            &r,
        );
        if !matches!(r.outcome, SceneOutcome::Ok { .. }) {
            failures.push("square");
        }
        let p = write_json(&args.out, "stress_square", &r)?;
        println!("  wrote {}", p.display());
    }
    if items.contains(&"hold") {
        let c = config(args.lod, Drive::default())?;
        let r = held_maximal(&c, args.seconds, rate)?;
        print_activation(
            &format!(
                "maximal activation of all groups held, level of detail {}",
                args.lod
            ),
            &r,
        );
        if !matches!(r.outcome, SceneOutcome::Ok { .. }) {
            failures.push("hold");
        }
        let p = write_json(&args.out, "stress_hold", &r)?;
        println!("  wrote {}", p.display());
    }
    if items.contains(&"drift") {
        let c = config(args.drift_lod, Drive::quiet())?;
        let d = quiet_drift(&c, args.drift_seconds, rate)?;
        let e = |k: usize| d.breaths.get(k).map_or(f64::NAN, |b| b.end_expiratory);
        let tidal = d
            .breaths
            .last()
            .map_or(f64::NAN, |b| b.peak - b.end_expiratory);
        println!(
            "quiet breathing {} s, level of detail {}: {:?}\n  {} breaths; end-expiratory lung volume first {:.6} L, second {:.6} L, last {:.6} L; tidal volume (last) {:.4} L\n  drift first -> last {:+.3e} ({:+.4} %), largest deviation from the first {:.3e}, slope {:+.3e} per hour (target under {} %)\n  {:.1} s wall, {} steps (+{} rejected), {} RHS evaluations",
            d.seconds,
            args.drift_lod,
            d.outcome,
            d.breaths.len(),
            e(0),
            e(1),
            e(d.breaths.len().saturating_sub(1)),
            tidal,
            d.first_to_last,
            100.0 * d.first_to_last,
            d.max_deviation,
            d.slope_per_hour,
            100.0 * DRIFT_TARGET,
            d.work.wall,
            d.work.steps,
            d.work.rejected,
            d.work.rhs_evaluations
        );
        if !(matches!(d.outcome, SceneOutcome::Ok { .. }) && d.first_to_last.abs() < DRIFT_TARGET) {
            failures.push("drift");
        }
        drift_outputs(&args.out, &d)?;
        let p = write_json(&args.out, "stress_drift", &d)?;
        println!(
            "  wrote {}, stress_drift.csv, stress_drift.png",
            p.display()
        );
    }
    if items.contains(&"steps") {
        let c = config(args.lod, Drive::quiet())?;
        println!(
            "communication steps over {} s of quiet breathing, level of detail {}, {} rtol {:e} atol {:e}, against one call to {} s (state error in units of atol + rtol |y|, criterion <= {}):",
            args.steps_end,
            args.lod,
            c.solver.method.name(),
            c.solver.rtol,
            c.solver.atol,
            args.steps_end,
            STEPPED_STATE_TOLERANCE
        );
        let steps: Vec<f64> = STEPS
            .iter()
            .copied()
            .filter(|h| *h <= args.steps_end)
            .collect();
        let mut runs = communication_steps(&c, args.steps_end, &steps)?;
        runs.extend(random_steps(
            &c,
            args.steps_end,
            args.random_sequences,
            (1e-5, 2.0),
            args.seed,
        )?);
        print_stepped(&runs);
        if runs
            .iter()
            .any(|r| r.state_error.is_nan() || r.state_error > STEPPED_STATE_TOLERANCE)
        {
            failures.push("steps");
        }
        let p = write_json(&args.out, "stress_steps", &runs)?;
        println!("  wrote {}", p.display());
    }
    if failures.is_empty() {
        println!("stress: every item passed");
        Ok(())
    } else {
        Err(Error::State(format!(
            "stress items failed: {}",
            failures.join(", ")
        )))
    }
}
