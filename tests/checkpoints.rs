//! In-memory checkpoints (`Torso::checkpoint`, `Torso::rollback`), the FMU's way back from a
//! discarded step: rolling back continues bit for bit as restoring the equivalent snapshot
//! (with the explicit pair and with the Rosenbrock method), and as the run it was taken
//! from (explicit pair); inputs, drive and time come back; an empty checkpoint or one of
//! another model is refused and changes nothing.

use breathing_torso::anatomy::MuscleGroup;
use breathing_torso::model::{Checkpoint, Config, Drive, Torso};
use breathing_torso::solver::Method;

fn torso(lod: u32, method: Method) -> Torso {
    let mut c = Config::default();
    c.scene.level_of_detail = lod;
    c.solver.method = method;
    c.solver.rtol = 1e-6;
    c.solver.atol = 1e-8;
    c.drive = Drive::quiet();
    Torso::new(c).unwrap()
}

/// State and solver statistics after advancing to `t`.
fn run_to(torso: &mut Torso, t: f64) -> (Vec<f64>, u64) {
    torso.advance_to(t).unwrap();
    (torso.state().to_vec(), torso.solver_stats().rhs_evaluations)
}

fn rollback_matches_restore(method: Method, t0: f64, t1: f64) {
    let mut a = torso(0, method);
    a.advance_to(t0).unwrap();
    let mut cp = Checkpoint::default();
    assert!(cp.is_empty());
    a.checkpoint(&mut cp);
    assert!(!cp.is_empty() && cp.time() == t0);
    let snap = a.snapshot();
    let first = run_to(&mut a, t1);

    a.rollback(&cp).unwrap();
    assert_eq!(a.time(), t0);
    let rolled = run_to(&mut a, t1);

    let mut b = torso(0, method);
    b.restore(&snap).unwrap();
    let restored = run_to(&mut b, t1);
    assert_eq!(rolled, restored, "{method:?}: rollback and restore differ");
    if method != Method::Rosenbrock {
        // The explicit pair keeps nothing outside its memory: the rerun is the first run.
        assert_eq!(rolled, first);
    }
}

#[test]
fn rollback_continues_as_a_restored_snapshot_with_dormand_prince() {
    rollback_matches_restore(Method::Dopri5, 0.7, 1.3);
}

#[test]
fn rollback_continues_as_a_restored_snapshot_with_rosenbrock() {
    rollback_matches_restore(Method::Rosenbrock, 0.2, 0.3);
}

#[test]
fn a_reused_checkpoint_holds_the_latest_state() {
    let mut a = torso(0, Method::Dopri5);
    let mut cp = Checkpoint::default();
    a.advance_to(0.2).unwrap();
    a.checkpoint(&mut cp);
    a.advance_to(0.5).unwrap();
    a.checkpoint(&mut cp);
    let at_half = a.state().to_vec();
    a.set_activation(MuscleGroup::RectusAbdominis, 0.7).unwrap();
    a.set_drive(Drive::forced()).unwrap();
    a.advance_to(0.9).unwrap();
    a.rollback(&cp).unwrap();
    assert_eq!(a.time(), 0.5);
    assert_eq!(a.state(), at_half.as_slice());
    assert_eq!(a.activation_input(MuscleGroup::RectusAbdominis), 0.0);
    assert_eq!(a.config().drive, Drive::quiet());
}

#[test]
fn bad_rollbacks_are_refused_and_change_nothing() {
    let mut a = torso(0, Method::Dopri5);
    a.advance_to(0.3).unwrap();
    let before = a.state().to_vec();
    let err = a.rollback(&Checkpoint::default()).unwrap_err();
    assert!(err.to_string().contains("empty checkpoint"), "{err}");
    let other = torso(1, Method::Dopri5);
    let mut cp = Checkpoint::default();
    other.checkpoint(&mut cp);
    let err = a.rollback(&cp).unwrap_err();
    assert!(err.to_string().contains("different model"), "{err}");
    assert_eq!(a.time(), 0.3);
    assert_eq!(a.state(), before.as_slice());
}
