//! One 1000-frame run (17.86 s of quiet breathing at 56 Hz, default subject) with a chosen
//! method and tolerance, against a Dormand-Prince reference at rtol 1e-10: the solver's
//! counts (steps, rejections, RHS evaluations, Jacobians, factorisations), the wall time of
//! the frame loop, and the largest lung-volume error over the frames.
//!
//! `cargo run --release --example stiff_run -- LOD METHOD RTOL` (METHOD: dopri5, bs3,
//! high-order or rosenbrock; atol = rtol / 100 as in `torso bench work-precision`).

use breathing_torso::model::{Config, Drive, Quantity, Torso};
use breathing_torso::solver::Method;
use std::time::Instant;

fn run(
    lod: u32,
    method: Method,
    rtol: f64,
) -> Result<(Vec<f64>, Torso, f64), Box<dyn std::error::Error>> {
    let mut c = Config::default();
    c.scene.level_of_detail = lod;
    c.solver.method = method;
    c.solver.rtol = rtol;
    c.solver.atol = rtol * 1e-2;
    c.drive = Drive::quiet();
    let mut torso = Torso::new(c)?;
    let mut out = Vec::with_capacity(1000);
    let start = Instant::now();
    for i in 1..=1000 {
        torso.advance_to(i as f64 / 56.0)?;
        out.push(torso.read(Quantity::LungVolume)?);
    }
    Ok((out, torso, start.elapsed().as_secs_f64()))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        return Err("usage: stiff_run LOD METHOD RTOL".into());
    }
    let lod: u32 = args[1].parse()?;
    let method = Method::from_name(&args[2]).ok_or("unknown method")?;
    let rtol: f64 = args[3].parse()?;
    let (reference, _, _) = run(lod, Method::Dopri5, 1e-10)?;
    let (lung, torso, wall) = run(lod, method, rtol)?;
    let err = lung
        .iter()
        .zip(&reference)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let s = torso.solver_stats();
    println!(
        "lod {lod} {} rtol {rtol:e}: wall {wall:.3} s, {} steps (+{} rejected), {} RHS, {} Jacobians, {} factorisations, max lung error {err:.2e} L",
        method.name(),
        s.steps,
        s.rejected,
        s.rhs_evaluations,
        s.jacobian_evaluations,
        s.factorizations
    );
    Ok(())
}
