//! Fast versions (seconds, level of detail 0) of the long stress items of `torso bench
//! stress`: 20 Hz square waves of activation in every group, maximal activation held, quiet
//! breathing with the end-expiratory volume of every breath, communication steps from 1e-5 s
//! to 2 s and random step sequences against one long run. The full versions (60 s, an hour,
//! level of detail 1) are run by `torso bench stress`; what they gave is in CHANGELOG.md.

use breathing_torso::Config;
use breathing_torso::bench::SceneOutcome;
use breathing_torso::bench::stress::{
    communication_steps, held_maximal, quiet_drift, random_steps, square_waves,
};
use breathing_torso::model::Drive;

fn lod0(drive: Drive) -> Config {
    let mut c = Config {
        drive,
        ..Config::default()
    };
    c.scene.level_of_detail = 0;
    c
}

#[test]
fn square_waves_at_20_hz_in_all_groups_for_3_s_do_not_blow_up() {
    let r = square_waves(&lod0(Drive::default()), 3.0, 20.0, 56.0).expect("runs");
    println!("{r:?}");
    assert!(
        matches!(r.outcome, SceneOutcome::Ok { .. }),
        "{:?}",
        r.outcome
    );
    // 120 switches, checked at each and in between
    assert!(r.monitor.checks >= 240, "{}", r.monitor.checks);
    // the torso does respond to the switching
    assert!(
        r.monitor.lung.1 - r.monitor.lung.0 > 0.05,
        "lung range {:?}",
        r.monitor.lung
    );
}

#[test]
fn maximal_activation_held_10_s_stays_within_bounds() {
    let r = held_maximal(&lod0(Drive::default()), 10.0, 56.0).expect("runs");
    println!("{r:?}");
    assert!(
        matches!(r.outcome, SceneOutcome::Ok { .. }),
        "{:?}",
        r.outcome
    );
    assert!(
        (r.end_lung - r.rest_lung).abs() > 1e-3,
        "activation moves the lung"
    );
    assert_eq!(r.monitor.checks, 560, "every 56 Hz frame of 10 s");
}

#[test]
fn two_minutes_of_quiet_breathing_keep_the_end_expiratory_volume() {
    let d = quiet_drift(&lod0(Drive::quiet()), 120.0, 56.0).expect("runs");
    println!(
        "{} breaths, first {:?}, last {:?}, drift {:e}, max deviation {:e}",
        d.breaths.len(),
        d.breaths.first(),
        d.breaths.last(),
        d.first_to_last,
        d.max_deviation
    );
    assert!(
        matches!(d.outcome, SceneOutcome::Ok { .. }),
        "{:?}",
        d.outcome
    );
    // 0.25 Hz over 120 s: 30 minima, the first and last within half a breath of the ends
    assert!((28..=30).contains(&d.breaths.len()), "{}", d.breaths.len());
    for w in d.breaths.windows(2) {
        let period = w[1].time - w[0].time;
        assert!((period - 4.0).abs() < 0.05, "breath period {period} s");
    }
    let tidal = d.breaths[5].peak - d.breaths[5].end_expiratory;
    assert!(tidal > 0.1, "tidal volume {tidal} L");
    assert!(d.first_to_last.abs() < 1e-3, "drift {:e}", d.first_to_last);
}

#[test]
fn communication_steps_1e_5_to_2_s_and_random_sequences_match_one_long_run() {
    let config = lod0(Drive::quiet());
    // 1e-5 s over 0.02 s (2,000 calls), the rest over 2 s
    let fine = communication_steps(&config, 0.02, &[1e-5, 1e-3]).expect("runs");
    let coarse = communication_steps(&config, 2.0, &[1e-2, 0.1, 0.5, 1.0, 2.0]).expect("runs");
    let random = random_steps(&config, 2.0, 3, (1e-5, 2.0), 2011).expect("runs");
    // Global error is not bounded by the local tolerance: over the first 20 ms from rest
    // the long run (large steps, each within tolerance) differs from the 1e-5 s and 1e-3 s
    // runs (the more accurate ones) by 130-150 local tolerances; over 4 s every step and
    // random sequence stayed within 55 (`torso bench stress --items steps --lod 0`).
    let bounded = fine
        .iter()
        .map(|r| (r, 1000.0))
        .chain(coarse.iter().chain(&random).map(|r| (r, 100.0)));
    for (r, bound) in bounded {
        println!(
            "{}: {} calls, steps {:.1e}..{:.1e} s, lung rel {:.2e}, state {:.3} tol, {} RHS",
            r.label,
            r.calls,
            r.step_range.0,
            r.step_range.1,
            r.lung_relative,
            r.state_error,
            r.work.rhs_evaluations
        );
        assert!(r.lung_relative < 1e-4, "{}: {:e}", r.label, r.lung_relative);
        assert!(r.state_error <= bound, "{}: {}", r.label, r.state_error);
    }
    assert_eq!(fine[0].calls, 2000);
    // one call of 2 s is the reference itself
    let whole = coarse.last().expect("2 s");
    assert_eq!(whole.calls, 1);
    assert_eq!(whole.state_error, 0.0);
}
