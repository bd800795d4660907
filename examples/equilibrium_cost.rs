//! The cost of building a torso, which solves its start state (the static equilibrium under
//! the drive's start, `dynamics::equilibrium`), per level of detail, posture and scenario:
//! wall time of `Torso::new`, Newton iterations, Jacobians, relaxation time, right-hand-side
//! evaluations and the relative imbalance reached.
//!
//! `cargo run --release --example equilibrium_cost -- [LOD...]` (default: 0 1 2)

use breathing_torso::anatomy::Posture;
use breathing_torso::model::{Drive, Scene};
use breathing_torso::{Config, Torso};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let lods: Vec<u32> = std::env::args()
        .skip(1)
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let lods = if lods.is_empty() { vec![0, 1, 2] } else { lods };
    println!(
        "lod,posture,scenario,new_s,newton_iterations,jacobians,relaxation_s,rhs_evaluations,relative_imbalance,converged"
    );
    for lod in lods {
        for posture in [Posture::Standing, Posture::Supine] {
            for scenario in ["quiet", "forced"] {
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
                let wall = built.elapsed().as_secs_f64();
                // cached: the solve Torso::new made
                let eq = torso.start_at_equilibrium();
                println!(
                    "{lod},{posture:?},{scenario},{wall:.3},{},{},{:.2},{},{:.2e},{}",
                    eq.newton_iterations,
                    eq.jacobian_evaluations,
                    eq.relaxation_time,
                    eq.rhs_evaluations,
                    eq.relative_residual(),
                    eq.converged
                );
            }
        }
    }
    Ok(())
}
