//! What rolling back a communication step costs: per level of detail, the median time of
//! `Torso::snapshot` + `Torso::restore` (serialised solver memory) against
//! `Torso::checkpoint` + `Torso::rollback` (native, buffers reused), next to the time of one
//! 1/56 s and one 1 ms `advance_to` of quiet breathing.
//!
//! `cargo run --release --example checkpoint_cost [REPEATS]`

use breathing_torso::model::{Checkpoint, Config, Drive, Torso};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median wall time [us] of `f` over `repeats` calls.
fn time(repeats: usize, mut f: impl FnMut()) -> f64 {
    median(
        (0..repeats)
            .map(|_| {
                let t0 = Instant::now();
                f();
                t0.elapsed().as_secs_f64() * 1e6
            })
            .collect(),
    )
}

fn main() -> breathing_torso::Result<()> {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    println!(
        "lod, snapshot us, restore us, checkpoint us, rollback us, advance 1/56 s us, advance 1 ms us"
    );
    for lod in [0u32, 1, 2] {
        let mut config = Config {
            drive: Drive::quiet(),
            ..Config::default()
        };
        config.scene.level_of_detail = lod;
        let mut torso = Torso::new(config)?;
        torso.advance_to(1.0)?;
        let snap = torso.snapshot();
        let snapshot = time(repeats, || {
            std::hint::black_box(torso.snapshot());
        });
        let restore = time(repeats, || torso.restore(&snap).unwrap());
        let mut cp = Checkpoint::default();
        let checkpoint = time(repeats, || torso.checkpoint(&mut cp));
        let rollback = time(repeats, || torso.rollback(&cp).unwrap());
        let mut t = torso.time();
        let frame = time(56, || {
            t += 1.0 / 56.0;
            torso.advance_to(t).unwrap();
        });
        let milli = time(repeats, || {
            t += 1e-3;
            torso.advance_to(t).unwrap();
        });
        println!(
            "{lod}, {snapshot:.1}, {restore:.1}, {checkpoint:.1}, {rollback:.1}, {frame:.1}, {milli:.1}"
        );
    }
    Ok(())
}
