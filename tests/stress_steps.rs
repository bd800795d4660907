//! Stress subset (fast, run with the test suite): all muscle groups stepped from 0 to full
//! activation at once and held, and communication steps from 1e-4 s to 1 s against one long
//! run (level of detail 0 for speed).

use breathing_torso::bench::{SceneOutcome, set_all_activations, stress_torso};
use breathing_torso::model::Drive;
use breathing_torso::{Config, Quantity, Torso};

fn lod0(drive: Drive) -> Config {
    let mut c = Config {
        drive,
        ..Config::default()
    };
    c.scene.level_of_detail = 0;
    c
}

#[test]
fn full_activation_step_in_all_groups_held_five_seconds_does_not_blow_up() {
    let mut torso = Torso::new(lod0(Drive::default())).expect("default model");
    torso.advance_to(0.5).expect("rest");
    let rest = torso.read(Quantity::LungVolume).expect("volume");
    set_all_activations(&mut torso, 1.0).expect("valid activations");
    let outcome = stress_torso(&mut torso, 5.0, 56.0).expect("runs");
    println!(
        "rest lung {rest} L, after the step: {outcome:?}, solver {:?}",
        torso.solver_stats()
    );
    assert!(
        matches!(outcome, SceneOutcome::Ok { .. }),
        "step response failed: {outcome:?}"
    );
    let held = torso.read(Quantity::LungVolume).expect("volume");
    assert!(
        (held - rest).abs() > 1e-3,
        "full activation must move the lung volume ({rest} -> {held} L)"
    );
    // and back: release everything, the torso settles without blowing up either
    set_all_activations(&mut torso, 0.0).expect("valid activations");
    let outcome = stress_torso(&mut torso, 2.0, 56.0).expect("runs");
    assert!(matches!(outcome, SceneOutcome::Ok { .. }), "{outcome:?}");
}

#[test]
fn communication_steps_from_1e_4_to_1_s_agree_with_one_long_run() {
    let end = 2.0;
    let config = lod0(Drive::quiet());
    let mut long = Torso::new(config.clone()).expect("model");
    long.advance_to(end).expect("long run");
    let reference = long.read(Quantity::LungVolume).expect("volume");
    for step in [1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.0] {
        let mut torso = Torso::new(config.clone()).expect("model");
        let n = (end / step).round() as usize;
        for i in 1..=n {
            torso.advance_to(i as f64 * step).expect("stepped run");
        }
        assert!((torso.time() - end).abs() < 1e-9);
        let v = torso.read(Quantity::LungVolume).expect("volume");
        let rel = (v - reference).abs() / reference;
        println!(
            "step {step:e} s: lung {v} L vs {reference} L, relative {rel:.2e}, {} steps",
            torso.solver_stats().steps
        );
        assert!(rel < 1e-4, "step {step} s: relative difference {rel:e}");
    }
}
