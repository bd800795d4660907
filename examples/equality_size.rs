//! Size and power of the cosinor equality tests by simulation (`stats::montecarlo`): the
//! share of record pairs each test rejects at alpha = 0.05, under iid and AR(1) errors,
//! for true nulls and for a 5 % amplitude difference. The numbers in docs/validation.md come
//! from this program:
//!
//! `cargo run --release --example equality_size -- [REPLICATIONS] [N...]`
//!
//! (default 2000 replications, N = 500 and 1008; seed 1),
//! `cargo run --release --example equality_size -- bars [REPLICATIONS] [N]` for BARS
//! (default 100 replications, N = 500). Marginal noise SD 0.02 L for the
//! nulls, 0.02 and 0.05 L for the 5 % amplitude difference.

use breathing_torso::stats::bars::BarsConfig;
use breathing_torso::stats::montecarlo::{Scenario, bars_rejection_rates, rejection_rates};

/// `bars REPLICATIONS N`: the BARS equality's share of `P(H0) < 0.05` and of T^2 p < 0.05
/// (default BARS settings: 200 burn-in, 2000 retained iterations).
fn bars(args: &[String]) {
    let reps: usize = args
        .first()
        .map_or(100, |a| a.parse().expect("REPLICATIONS"));
    let n: usize = args.get(1).map_or(500, |a| a.parse().expect("N"));
    println!("| N | phi | noise SD [L] | amplitude ratio | P(H0) < 0.05 | T² p < 0.05 |");
    println!("|---|---|---|---|---|---|");
    for (ratio, phi) in [(1.0, 0.0), (1.0, 0.5), (1.0, 0.9), (1.05, 0.0)] {
        let sc = Scenario {
            n,
            phi,
            amplitude_ratio: ratio,
            replications: reps,
            ..Scenario::default()
        };
        let (ph0, t2) = bars_rejection_rates(&sc, &BarsConfig::default(), 0.05).expect("BARS runs");
        println!(
            "| {n} | {phi} | {} | {ratio} | {ph0:.3} | {t2:.3} |",
            sc.noise_sd
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "bars") {
        bars(&args[1..]);
        return;
    }
    let reps: usize = args.first().map_or(2000, |a| {
        a.parse().expect("REPLICATIONS is a positive integer")
    });
    let ns: Vec<usize> = if args.len() > 1 {
        args[1..]
            .iter()
            .map(|a| a.parse().expect("N is a positive integer"))
            .collect()
    } else {
        vec![500, 1008]
    };
    println!(
        "| N | phi | noise SD [L] | amplitude ratio | F with intercept | F without | paired F | robust with (bootstrap) | robust without (bootstrap) | robust with (nominal F) | robust without (nominal F) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for &n in &ns {
        for (ratio, noise) in [(1.0, 0.02), (1.05, 0.02), (1.05, 0.05)] {
            for phi in [0.0, 0.5, 0.9] {
                let sc = Scenario {
                    n,
                    phi,
                    noise_sd: noise,
                    amplitude_ratio: ratio,
                    replications: reps,
                    ..Scenario::default()
                };
                let r = rejection_rates(&sc, 0.05).expect("simulation runs");
                println!(
                    "| {n} | {phi} | {noise} | {ratio} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
                    r.f_with_intercept,
                    r.f_without_intercept,
                    r.paired_f,
                    r.robust_with_intercept,
                    r.robust_without_intercept,
                    r.robust_nominal_with_intercept,
                    r.robust_nominal_without_intercept
                );
            }
        }
    }
}
