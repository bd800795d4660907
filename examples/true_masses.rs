//! The quasi-static mode against the inertial formulation with the true masses (no selective
//! mass scaling, `params.true_masses`), on quiet breathing at 56 Hz: tidal volume (after the
//! first 4 s) and the largest marker difference over the frames after the first 4 s, with
//! each run's wall time and steps.
//!
//! `cargo run --release --example true_masses -- [LOD] [FRAMES] [METHOD]`
//! (defaults: 0, 1000 frames = 17.86 s, `dopri5`; METHOD any `--solver` name of the CLI for
//! the inertial run, e.g. `rosenbrock` where the true masses make the explicit step tiny).

use breathing_torso::dynamics::Params;
use breathing_torso::model::{Config, Drive, Quantity, Torso};
use breathing_torso::solver::Method;
use std::time::Instant;

const FRAME: f64 = 1.0 / 56.0;

struct Run {
    lung: Vec<f64>,
    markers: Vec<[f64; 3]>,
    seconds: f64,
    steps: u64,
}

fn run(
    lod: u32,
    frames: usize,
    method: Method,
    true_masses: bool,
) -> Result<Run, Box<dyn std::error::Error>> {
    let mut config = Config::default();
    config.scene.level_of_detail = lod;
    config.solver.method = method;
    config.drive = Drive::quiet();
    let mut params = Params::for_posture(config.subject.posture);
    params.true_masses = true_masses;
    config.params = Some(params);
    let mut torso = Torso::new(config)?;
    torso.markers()?;
    let mut out = Run {
        lung: Vec::new(),
        markers: Vec::new(),
        seconds: 0.0,
        steps: 0,
    };
    let start = Instant::now();
    for k in 1..=frames {
        torso.advance_to(k as f64 * FRAME)?;
        out.lung.push(torso.read(Quantity::LungVolume)?);
        out.markers
            .extend(torso.markers()?.iter().map(|p| [p.x, p.y, p.z]));
    }
    out.seconds = start.elapsed().as_secs_f64();
    out.steps = torso.solver_stats().steps;
    Ok(out)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let lod = args.first().map_or(Ok(0), |s| s.parse())?;
    let frames: usize = args.get(1).map_or(Ok(1000), |s| s.parse())?;
    let method = match args.get(2) {
        Some(s) => Method::from_name(s).ok_or_else(|| format!("unknown method {s}"))?,
        None => Method::Dopri5,
    };
    let inertial = run(lod, frames, method, true)?;
    let quasi = run(lod, frames, Method::QuasiStatic, false)?;
    let skip = (4.0 / FRAME) as usize;
    let tidal = |l: &[f64]| {
        let late = &l[skip.min(l.len() - 1)..];
        late.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - late.iter().copied().fold(f64::INFINITY, f64::min)
    };
    let per_frame = inertial.markers.len() / frames;
    let worst = inertial.markers[skip * per_frame..]
        .iter()
        .zip(&quasi.markers[skip * per_frame..])
        .map(|(a, b)| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    let (vi, vq) = (tidal(&inertial.lung), tidal(&quasi.lung));
    println!("level of detail {lod}, {frames} frames of quiet breathing");
    println!(
        "inertial, true masses ({method:?}): tidal volume {vi:.4} L, {:.2} s, {} steps",
        inertial.seconds, inertial.steps
    );
    println!(
        "quasi-static: tidal volume {vq:.4} L ({:+.2} %), {:.2} s, {} steps",
        100.0 * (vq / vi - 1.0),
        quasi.seconds,
        quasi.steps
    );
    println!("largest marker difference after 4 s: {:.3} mm", worst * 1e3);
    Ok(())
}
