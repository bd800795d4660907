//! Size of the cosinor equality tests by seeded simulation (`stats::montecarlo`): 400 pairs
//! of N = 500 samples (8.9 s at 56 Hz, 2.2 breaths of 0.25 Hz) that share one breathing
//! curve and differ only by independent errors, iid or AR(1) with phi = 0.5 and 0.9.
//!
//! A test of level 0.05 must reject between 3 % and 8 % of these true nulls: with 400
//! replications the binomial standard error at 5 % is 1.1 %, so the window is -1.8 to +2.7
//! standard errors around the level. The classical F tests assume independent errors: they
//! hold their level under iid errors only, and the test asserts that they do; under AR(1)
//! errors they must reject far more often (the variance of a harmonic coefficient grows by
//! about the error spectrum's ratio f(w) / f_flat = (1 + phi) / (1 - phi) = 3 at phi = 0.5
//! for the slow breathing frequencies, so F is inflated about threefold and
//! P(chi2_9 > 9 x 1.88 / 3) = 0.78), which the test checks too, so that the documented
//! warning stays true. The robust test must hold its level in all three cases.
//!
//! BARS equality costs about 60 ms per pair at N = 500 with its default chains (200 burn-in,
//! 2000 retained iterations), so it gets 200 replications (binomial standard error 1.5 %)
//! and iid errors only: it assumes independent errors like the classical F tests. Its
//! Hotelling T^2 screening p-value is a level-5 % test and must fall in the same window;
//! `P(H0 | data)` is a posterior probability, not a p-value, so only its upper side is
//! checked: read as a rejection below 0.05, it must not signal a difference more often than
//! a 5 % test would (8 %).
//! Power figures are measured by `cargo run --release --example equality_size` and
//! reported in docs/validation.md.

use breathing_torso::stats::bars::BarsConfig;
use breathing_torso::stats::montecarlo::{
    RejectionRates, Scenario, bars_rejection_rates, rejection_rates,
};

fn rates(phi: f64, seed: u64) -> RejectionRates {
    let sc = Scenario {
        phi,
        seed,
        ..Scenario::default()
    };
    assert_eq!((sc.n, sc.replications), (500, 400));
    rejection_rates(&sc, 0.05).expect("simulation runs")
}

fn in_window(name: &str, phi: f64, rate: f64) {
    assert!(
        (0.03..=0.08).contains(&rate),
        "{name} rejects {:.1} % of true nulls at phi = {phi} (level 5 %)",
        100.0 * rate
    );
}

#[test]
fn all_tests_hold_their_size_under_iid_errors() {
    let r = rates(0.0, 11);
    println!("{r:?}");
    in_window("F with intercept", 0.0, r.f_with_intercept);
    in_window("F without intercept", 0.0, r.f_without_intercept);
    in_window("paired F", 0.0, r.paired_f);
    in_window("robust test with intercept", 0.0, r.robust_with_intercept);
    in_window(
        "robust test without intercept",
        0.0,
        r.robust_without_intercept,
    );
}

#[test]
fn robust_test_holds_its_size_under_ar1_errors() {
    for (phi, seed) in [(0.5, 12), (0.9, 13)] {
        let r = rates(phi, seed);
        println!("phi {phi}: {r:?}");
        in_window("robust test with intercept", phi, r.robust_with_intercept);
        in_window(
            "robust test without intercept",
            phi,
            r.robust_without_intercept,
        );
        // The iid F tests cannot hold their level here (module doc): they must not be
        // mistaken for robust ones.
        for (name, v) in [
            ("F with intercept", r.f_with_intercept),
            ("F without intercept", r.f_without_intercept),
            ("paired F", r.paired_f),
        ] {
            assert!(
                v > 0.5,
                "{name} rejects only {:.1} % at phi = {phi}",
                100.0 * v
            );
        }
    }
}

#[test]
fn bars_equality_under_iid_errors() {
    let sc = Scenario {
        replications: 200,
        seed: 14,
        ..Scenario::default()
    };
    let (ph0, t2) = bars_rejection_rates(&sc, &BarsConfig::default(), 0.05).expect("BARS runs");
    println!("P(H0) < 0.05: {ph0}, T2 p < 0.05: {t2}");
    in_window("BARS T2 screening", 0.0, t2);
    assert!(
        ph0 <= 0.08,
        "BARS P(H0) < 0.05 in {:.1} % of true nulls",
        100.0 * ph0
    );
}
