//! The quasi-static mode against the inertial formulation on 1000 frames of quiet breathing
//! (17.86 s at 56 Hz, default subject): tidal volume, largest marker difference, wall time
//! with the 60 grid markers read every frame and with the lung volume alone, and the static
//! solver's work.
//!
//! `cargo run --release --example quasi_static -- [LOD] [RTOL]`

use breathing_torso::model::{Config, Drive, Quantity, Torso};
use breathing_torso::solver::Method;
use std::time::Instant;

const FRAMES: usize = 1000;
const FRAME: f64 = 1.0 / 56.0;

struct Run {
    lung: Vec<f64>,
    markers: Vec<[f64; 3]>,
    seconds: f64,
}

fn run(
    lod: u32,
    rtol: f64,
    method: Method,
    markers: bool,
) -> Result<(Run, Torso), Box<dyn std::error::Error>> {
    let mut config = Config::default();
    config.scene.level_of_detail = lod;
    config.solver.method = method;
    config.solver.rtol = rtol;
    config.drive = Drive::quiet();
    let mut torso = Torso::new(config)?;
    if markers {
        torso.markers()?; // builds the skin and grid outside the timed loop
    }
    let mut out = Run {
        lung: Vec::with_capacity(FRAMES),
        markers: Vec::new(),
        seconds: 0.0,
    };
    let start = Instant::now();
    for k in 1..=FRAMES {
        torso.advance_to(k as f64 * FRAME)?;
        out.lung.push(torso.read(Quantity::LungVolume)?);
        if markers {
            out.markers
                .extend(torso.markers()?.iter().map(|p| [p.x, p.y, p.z]));
        }
    }
    out.seconds = start.elapsed().as_secs_f64();
    Ok((out, torso))
}

fn tidal(lung: &[f64]) -> f64 {
    let late = &lung[(4.0 / FRAME) as usize..];
    late.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - late.iter().copied().fold(f64::INFINITY, f64::min)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let lod: u32 = args.get(1).map_or(Ok(1), |s| s.parse())?;
    let rtol: f64 = args.get(2).map_or(Ok(1e-6), |s| s.parse())?;
    let (inertial, it) = run(lod, rtol, Method::Dopri5, true)?;
    let (qs, torso) = run(lod, rtol, Method::QuasiStatic, true)?;
    let (qs_volumes, tv) = run(lod, rtol, Method::QuasiStatic, false)?;
    let diff = inertial
        .markers
        .iter()
        .zip(&qs.markers)
        .map(|(a, b)| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0f64, f64::max);
    println!("level of detail {lod}, rtol {rtol:e}, {FRAMES} frames of quiet breathing");
    println!(
        "tidal volume: inertial {:.4} L, quasi-static {:.4} L ({:+.2} %)",
        tidal(&inertial.lung),
        tidal(&qs.lung),
        100.0 * (tidal(&qs.lung) / tidal(&inertial.lung) - 1.0)
    );
    println!(
        "largest marker difference, quasi-static against inertial: {:.3} mm",
        diff * 1e3
    );
    println!(
        "wall time, 60 markers every frame: inertial {:.3} s ({} RHS), quasi-static {:.3} s",
        inertial.seconds,
        it.solver_stats().rhs_evaluations,
        qs.seconds
    );
    println!(
        "wall time, lung volume only: quasi-static {:.3} s ({:.2}x cheaper than with markers)",
        qs_volumes.seconds,
        qs.seconds / qs_volumes.seconds
    );
    for (name, t) in [("with markers", &torso), ("volumes only", &tv)] {
        let s = t.solver_stats();
        if let Some(st) = t.statics_stats() {
            println!(
                "quasi-static {name}: {} steps, {} RHS; {} solves, {} Newton iterations, {} Jacobians ({} residuals), {} factorisations, {} continuations; {:.1} us per solve",
                s.steps,
                s.rhs_evaluations,
                st.solves,
                st.iterations,
                st.jacobians,
                st.residuals,
                st.factorisations,
                st.continuations,
                if name == "with markers" {
                    qs.seconds
                } else {
                    qs_volumes.seconds
                } * 1e6
                    / st.solves as f64
            );
        }
    }
    Ok(())
}
