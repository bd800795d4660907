//! Steps, right-hand-side evaluations and lung-volume error of 1000 frames (56 Hz) of quiet
//! breathing with Dormand-Prince at rtol 1e-6 and a range of absolute tolerances, against a
//! reference at rtol 1e-10: shows where the step size stops being set by accuracy and is set
//! by stability. `cargo run --release --example tolerance_sweep -- [LOD]`.

use breathing_torso::model::{Drive, Scene, SolverConfig};
use breathing_torso::{Config, Quantity, Torso};

/// Lung volume per frame, wall time, RHS evaluations and steps of one run.
fn run(lod: u32, rtol: f64, atol: f64) -> (Vec<f64>, f64, f64, f64) {
    let config = Config {
        drive: Drive::quiet(),
        scene: Scene {
            level_of_detail: lod,
            ..Scene::default()
        },
        solver: SolverConfig {
            rtol,
            atol,
            ..SolverConfig::default()
        },
        ..Config::default()
    };
    let mut torso = Torso::new(config).expect("default subject builds");
    let start = std::time::Instant::now();
    let mut lung = Vec::with_capacity(1000);
    for i in 1..=1000 {
        torso
            .advance_to(i as f64 / 56.0)
            .expect("quiet breathing integrates");
        lung.push(torso.read(Quantity::LungVolume).expect("lung volume"));
    }
    (
        lung,
        start.elapsed().as_secs_f64(),
        torso.read(Quantity::SolverRhsEvaluations).expect("stats"),
        torso.read(Quantity::SolverSteps).expect("stats"),
    )
}

fn main() {
    let lod: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let (reference, ..) = run(lod, 1e-10, 1e-12);
    for atol in [1e-8, 1e-7, 1e-6, 1e-5] {
        let (lung, wall, rhs, steps) = run(lod, 1e-6, atol);
        let error = lung
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "LOD {lod}, rtol 1e-6, atol {atol:e}: wall {wall:.2} s, {rhs} RHS evaluations, {steps} steps, max lung-volume error {error:.2e} L"
        );
    }
}
