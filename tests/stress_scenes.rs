//! Stress subset (fast, run with the test suite): 20 random scenes drawn from every declared
//! parameter range (subject, posture, drive, gains; seeded; level of detail 0 for speed),
//! each simulated for 10 s. Every scene must run to the end with a finite state and finite
//! volumes within broad physical bounds; a numerical failure is printed and counted, and any
//! failure fails the test. The full soak is `torso bench soak`.

use breathing_torso::bench::{SceneOutcome, random_scene, stress_scene};
use breathing_torso::numeric::rng::Pcg64;

#[test]
fn twenty_random_scenes_run_ten_seconds_without_blow_up() {
    let mut rng = Pcg64::new(20_11, 6);
    let (mut numerical, mut bounds) = (Vec::new(), Vec::new());
    for i in 0..20 {
        let config = random_scene(&mut rng, 0).expect("random scenes are valid by construction");
        let outcome = stress_scene(&config, 10.0, 14.0).expect("scene runs");
        println!("scene {i:2}: {outcome:?}");
        match outcome {
            SceneOutcome::Ok { min_lung, max_lung } => {
                assert!(min_lung <= max_lung);
            }
            SceneOutcome::Numerical(reason) => numerical.push((i, reason, config)),
            SceneOutcome::OutOfBounds { time, what } => bounds.push((i, time, what, config)),
        }
    }
    println!(
        "{} numerical failures, {} out of bounds of 20 scenes",
        numerical.len(),
        bounds.len()
    );
    assert!(numerical.is_empty(), "numerical failures: {numerical:#?}");
    assert!(bounds.is_empty(), "out of bounds: {bounds:#?}");
}

#[test]
fn random_scenes_cover_their_ranges_and_are_reproducible() {
    let draw = |seed| {
        let mut rng = Pcg64::new(seed, 6);
        (0..200)
            .map(|_| random_scene(&mut rng, 0).expect("valid"))
            .collect::<Vec<_>>()
    };
    let a = draw(1);
    assert_eq!(a, draw(1), "same seed, same scenes");
    assert_ne!(a, draw(2));
    let span = |f: &dyn Fn(&breathing_torso::Config) -> f64| {
        let v: Vec<f64> = a.iter().map(f).collect();
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    };
    let (lo, hi) = span(&|c| c.subject.stature);
    assert!(lo < 1.5 && hi > 2.0, "stature {lo}..{hi}");
    let (lo, hi) = span(&|c| c.drive.frequency);
    assert!(lo < 0.2 && hi > 1.8, "frequency {lo}..{hi}");
    let (lo, hi) = span(&|c| c.gain_left);
    assert!(lo < 0.2 && hi > 1.8, "gain {lo}..{hi}");
    let (lo, hi) = span(&|c| c.drive.diaphragm.amplitude);
    assert!(lo < 0.1 && hi > 0.9, "amplitude {lo}..{hi}");
    for c in &a {
        let bmi = c.subject.mass / (c.subject.stature * c.subject.stature);
        assert!((13.0..=60.0).contains(&bmi), "BMI {bmi}");
    }
}
