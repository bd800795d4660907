//! A reduced basis for the quasi-static mechanics, measured (`bench::reduced`): modes from
//! equilibria of a forced-breathing run, tested on quiet breathing against the full static
//! solver in the same run. Prints one row per number of modes: the modes' energy share, the
//! largest anchor-position error against the full equilibrium and the best the modes can do
//! (projection), the pleural-pressure and airflow errors, the full residual left, Newton
//! iterations, residual evaluations and wall time per solve.
//!
//! `cargo run --release --example reduced_basis -- [LOD] [TEST_FRAMES] [MODES...]`
//! (defaults: 1, 448 frames = 8 s, modes 5 10 20 40). `TRAINING=quiet` trains on the tested
//! drive itself (an upper bound of what the modes can do, not a test).

use breathing_torso::bench::reduced::measure;
use breathing_torso::model::Drive;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let lod = args.first().map_or(Ok(1), |s| s.parse())?;
    let frames = args.get(1).map_or(Ok(448), |s| s.parse())?;
    let modes: Vec<usize> = if args.len() > 2 {
        args[2..]
            .iter()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?
    } else {
        vec![5, 10, 20, 40]
    };
    // training: 8 s of forced breathing, a snapshot every 4th frame (112)
    // TRAINING=quiet trains on the tested drive itself: the best case, not a test
    let (training, name) = match std::env::var("TRAINING").as_deref() {
        Ok("quiet") => (Drive::quiet(), "quiet"),
        _ => (Drive::forced(), "forced"),
    };
    let r = measure(lod, training, &modes, 448, 4, frames, 1e-8)?;
    println!(
        "level {}: {} unknowns; {} snapshots of {name} breathing; {} test frames of quiet breathing",
        r.lod, r.unknowns, r.snapshots, r.frames
    );
    println!(
        "full solver: {:.1} us and {:.2} Newton iterations per solve; one full residual {:.1} us",
        r.full_us_per_solve, r.full_iterations_per_solve, r.us_per_residual
    );
    println!(
        "| modes | energy | position error [mm] | projection [mm] | pleural [Pa] | flow [L/s] | full residual [N] | failed | iterations | residuals | us/solve |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for row in &r.rows {
        println!(
            "| {} | {:.8} | {:.4} | {:.4} | {:.3e} | {:.2e} | {:.2e} | {} | {:.2} | {:.2} | {:.1} |",
            row.modes,
            row.energy,
            row.max_position_error_mm,
            row.max_projection_error_mm,
            row.max_pleural_error_pa,
            row.max_flow_error_l_s,
            row.max_full_residual,
            row.failures,
            row.iterations_per_solve,
            row.residuals_per_solve,
            row.us_per_solve
        );
    }
    Ok(())
}
