//! A small, deterministic workload for instruction-count profiling (e.g. under
//! `valgrind --tool=callgrind`): the frame loop of `torso bench core` (quiet breathing,
//! default subject, Dormand-Prince 5(4)) at one level of detail, reading the four volumes every
//! frame, then `calls` isolated right-hand-side calls at the state reached. Prints the solver
//! counts and a checksum of the readings and of the last state, so that a change of the
//! results is seen at a glance.
//!
//! `cargo run --release --example frame_profile -- [lod] [frames] [calls]` (defaults 0, 100, 0).

use breathing_torso::bench::{Reads, frame_loop};
use breathing_torso::model::{Config, Drive};
use breathing_torso::{Quantity, Torso};

fn main() -> breathing_torso::Result<()> {
    let arg = |i: usize, default: usize| -> usize {
        std::env::args()
            .nth(i)
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let (lod, frames, calls) = (arg(1, 0), arg(2, 100), arg(3, 0));
    let mut config = Config {
        drive: Drive::quiet(),
        ..Config::default()
    };
    config.scene.level_of_detail = lod as u32;
    let run = frame_loop(&config, frames, Reads::Volumes)?;
    println!(
        "lod {lod}, {frames} frames: RHS {} steps {} (+{} rejected) checksum {:.17e}",
        run.rhs_evaluations, run.steps, run.rejected, run.checksum
    );
    if calls > 0 {
        let mut torso = Torso::new(config)?;
        let t = frames as f64 / 56.0;
        torso.advance_to(t)?;
        let y = torso.state().to_vec();
        let mut dy = vec![0.0; y.len()];
        let mut sum = 0.0;
        for _ in 0..calls {
            torso.rhs(t, std::hint::black_box(&y), &mut dy)?;
            sum += dy.iter().map(|v| v.abs()).sum::<f64>();
        }
        println!(
            "{calls} RHS calls: sum |f| {:.17e}, lung volume {:.17e}",
            sum / calls as f64,
            torso.read(Quantity::LungVolume)?
        );
    }
    Ok(())
}
