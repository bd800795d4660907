//! The start of a run: the tidal volume of each of the first breaths from the initial state,
//! and the lung volume at the start against its value one and two periods later (a start that
//! is not on the periodic orbit shows as a first breath unlike the third).
//!
//! `cargo run --release --example start_transient -- [LOD] [POSTURE] [SCENARIO] [BREATHS]`
//! (defaults: 1, standing, quiet, 3)

use breathing_torso::anatomy::Posture;
use breathing_torso::model::{Drive, Scene};
use breathing_torso::{Config, Quantity, Torso};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let lod: u32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let posture = match args.get(2).map(String::as_str) {
        Some("supine") => Posture::Supine,
        Some("sitting") => Posture::Sitting,
        _ => Posture::Standing,
    };
    let scenario = args.get(3).map(String::as_str).unwrap_or("quiet");
    let breaths: usize = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(3);
    let mut config = Config {
        drive: Drive::scenario(scenario)?,
        scene: Scene {
            level_of_detail: lod,
            ..Scene::default()
        },
        ..Config::default()
    };
    config.subject.posture = posture;
    let built = Instant::now();
    let mut torso = Torso::new(config)?;
    let build_ms = built.elapsed().as_secs_f64() * 1e3;
    let eq = torso.start_at_equilibrium();
    println!(
        "lod {lod} {posture:?} {scenario}: start state after {} Newton iterations ({} Jacobians) and {:.2} s of relaxation ({} RHS evaluations), relative imbalance {:.2e} ({:.3e} of {:.3e} N), converged {}",
        eq.newton_iterations,
        eq.jacobian_evaluations,
        eq.relaxation_time,
        eq.rhs_evaluations,
        eq.relative_residual(),
        eq.residual,
        eq.force_scale,
        eq.converged
    );
    let period = 1.0 / torso.config().drive.frequency;
    let rate = 56.0;
    let per_breath = (period * rate).round() as usize;
    let v0 = torso.read(Quantity::LungVolume)?;
    let mut range = vec![(f64::INFINITY, f64::NEG_INFINITY); breaths];
    let mut at_period = Vec::new();
    for i in 1..=breaths * per_breath {
        torso.advance_to(i as f64 / rate)?;
        let v = torso.read(Quantity::LungVolume)?;
        let b = &mut range[(i - 1) / per_breath];
        *b = (b.0.min(v), b.1.max(v));
        if i % per_breath == 0 {
            at_period.push(v);
        }
    }
    let tidal: Vec<f64> = range.iter().map(|(lo, hi)| hi - lo).collect();
    println!(
        "lod {lod} {posture:?} {scenario}: build + start {build_ms:.0} ms; lung volume at t0 {v0:.4} L, after each period {}",
        at_period
            .iter()
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    println!(
        "  tidal volumes [L] {}; first / third - 1 = {:+.2} %",
        tidal
            .iter()
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(" "),
        100.0 * (tidal[0] / tidal[breaths.min(3) - 1] - 1.0)
    );
    Ok(())
}
