//! Thoracic collapse through the FMU. Scene 35 of the random-scene soak (`torso bench soak
//! --scenes 250 --seconds 60 --seed 2011 --lod 0`: a small woman with the rib drive at 0.99)
//! used to squeeze the thorax from 3.49 to 1.56 L in 36 ms, below half its rest volume, and
//! the FMU discarded the step. The pleural pressure-volume law now stiffens towards the
//! subject's residual volume ([`breathing_torso::dynamics::pleural`]), so the scene and a held
//! maximal abdominal contraction (a forced expiration) run through with every step `fmi2OK`
//! and the lung volume above the residual volume less a small margin. The discard of a state
//! that leaves the physiological bounds stays tested with a state set through
//! `fmi2SetFMUstate` whose ribs are turned far into expiration: the step ends with
//! `fmi2Discard`, the log names the variable and its bound, and the model stays at its last
//! good time.

use breathing_torso::anatomy::{Posture, Sex, Subject};
use breathing_torso::dynamics::pleural::capacity_ratios;
use breathing_torso::fmi::instance::{FmuState, Instance, LogSink, Phase, mask};
use breathing_torso::fmi::table;
use breathing_torso::fmi::variables::ScalarType;
use breathing_torso::fmi::{FMI2, Status};
use breathing_torso::model::Snapshot;
use breathing_torso::model::bounds::{CAVITY_BOUNDS, cavity_bounds};
use std::cell::RefCell;
use std::rc::Rc;

type Log = Rc<RefCell<Vec<(Status, String, String)>>>;

/// How far below the residual volume the lung may be squeezed [fraction of RV]: the law
/// follows its (steep) tangent within its margin of the asymptote, so strong drives press a
/// little past it.
const RV_MARGIN: f64 = 0.05;

/// An instance with logging off (discards are reported even then), and its log.
fn instance() -> (Instance, Log) {
    let log: Log = Rc::new(RefCell::new(Vec::new()));
    let sink_log = log.clone();
    let sink: LogSink = Box::new(move |s, c, m| {
        sink_log
            .borrow_mut()
            .push((s, c.to_string(), m.to_string()))
    });
    (
        Instance::new(&FMI2, "collapse", None, Some(sink), false),
        log,
    )
}

fn set(inst: &mut Instance, name: &str, value: f64) {
    let var = table().by_name(name).unwrap_or_else(|| panic!("no {name}"));
    let status = match var.ty {
        ScalarType::Integer => inst.set_integer("fmi2SetInteger", &[var.vr], &[value as i32]),
        _ => inst.set_real("fmi2SetReal", &[var.vr], &[value]),
    };
    assert_eq!(status, Status::Ok, "{name} = {value}");
}

fn get(inst: &mut Instance, name: &str) -> f64 {
    let vr = table().by_name(name).expect("variable").vr;
    let mut v = [f64::NAN];
    assert_eq!(inst.get_real("fmi2GetReal", &[vr], &mut v), Status::Ok);
    v[0]
}

fn initialise(inst: &mut Instance) {
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
}

/// The subject of scene 35.
fn subject_35() -> Subject {
    Subject {
        sex: Sex::Female,
        age: 46.79979085894516,
        stature: 1.4782456174406253,
        mass: 45.34328870522832,
        breast_size: 0.8641515740383998,
        posture: Posture::Standing,
    }
}

/// Sets the subject's parameters of `inst` (a standing subject).
fn set_subject(inst: &mut Instance, s: &Subject) {
    assert_eq!(s.posture, Posture::Standing);
    let sex = match s.sex {
        Sex::Male => 0.0,
        Sex::Female => 1.0,
    };
    for (name, value) in [
        ("subject.sex", sex),
        ("subject.age", s.age),
        ("subject.stature", s.stature),
        ("subject.mass", s.mass),
        ("subject.breast_size", s.breast_size),
        ("posture", 0.0),
    ] {
        set(inst, name, value);
    }
}

/// Scene 35 of the soak, as `torso bench soak --scenes 250 --seconds 60 --seed 2011 --lod 0`
/// prints it.
fn scene_35(inst: &mut Instance) {
    set_subject(inst, &subject_35());
    for (name, value) in [
        ("scene.level_of_detail", 0.0),
        ("drive.frequency", 1.1087322289538222),
        ("drive.ribs.amplitude", 0.9888127133082364),
        ("drive.ribs.phase", -1.5816767960755342),
        ("drive.diaphragm.amplitude", 0.07729889918172239),
        ("drive.diaphragm.phase", -1.8306063318322954),
        ("drive.abdominals.amplitude", 0.5457829972439472),
        ("drive.abdominals.phase", 4.573349062818499),
        ("gain.left", 1.4821413192867987),
        ("gain.right", 1.1255222846607567),
    ] {
        set(inst, name, value);
    }
}

/// Steps `inst` from its current time for `seconds` in steps of `h`, asserting `fmi2OK` for
/// every step; returns the smallest and largest lung volume read at the communication
/// points [L].
fn run_ok(inst: &mut Instance, log: &Log, seconds: f64, h: f64) -> (f64, f64) {
    let t0 = inst.time();
    let n = (seconds / h).round() as usize;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..n {
        let t = t0 + k as f64 * h;
        assert_eq!(
            inst.do_step("fmi2DoStep", t, h),
            Status::Ok,
            "step at {t}: {:?}",
            log.borrow()
        );
        let lung = get(inst, "volume.lung");
        lo = lo.min(lung);
        hi = hi.max(lung);
    }
    (lo, hi)
}

/// The lung volume of `subject`'s rest pose (FRC) at level of detail 0 [L]: an instance
/// without drive or inputs starts there (the equilibrium of zero activation).
fn rest_lung_volume(subject: &Subject) -> f64 {
    let (mut inst, _log) = instance();
    set_subject(&mut inst, subject);
    for (name, value) in [
        ("scene.level_of_detail", 0.0),
        ("drive.ribs.amplitude", 0.0),
        ("drive.diaphragm.amplitude", 0.0),
        ("drive.abdominals.amplitude", 0.0),
    ] {
        set(&mut inst, name, value);
    }
    initialise(&mut inst);
    get(&mut inst, "volume.lung")
}

/// The residual volume of `subject` scaled to the model's own rest (FRC) lung volume `rest`,
/// where the pleural law's lower asymptote stands [L].
fn residual_volume(subject: &Subject, rest: f64) -> f64 {
    rest * capacity_ratios(subject).0
}

#[test]
fn soak_scene_35_no_longer_collapses_and_every_step_is_ok() {
    let (mut inst, log) = instance();
    scene_35(&mut inst);
    initialise(&mut inst);
    let rest = rest_lung_volume(&subject_35());
    let rv = residual_volume(&subject_35(), rest);
    let (lo, hi) = run_ok(&mut inst, &log, 60.0, 1.0 / 56.0);
    println!(
        "scene 35, 60 s: lung {lo:.3}-{hi:.3} L (rest {rest:.3} L, RV {rv:.3} L, ECSC RV {:.3} L)",
        subject_35().rv_ecsc()
    );
    assert!(lo >= (1.0 - RV_MARGIN) * rv, "lung {lo} L, RV {rv} L");
    // the rib drive still empties the lungs most of the way to RV
    assert!(lo < rv + 0.25 * (rest - rv), "lung {lo} L, RV {rv} L");
    assert!(log.borrow().is_empty(), "{:?}", log.borrow());
}

/// A level-0 default instance with the drive off, its rest lung volume [L], and the lung
/// volume range [L] over 10 s (0.02 s steps, every step OK) with `groups` held at activation 1.
#[allow(clippy::type_complexity)]
fn hold_at_full_activation(groups: &[&str]) -> (Instance, Log, f64, (f64, f64)) {
    let (mut inst, log) = instance();
    set(&mut inst, "scene.level_of_detail", 0.0);
    for family in ["ribs", "diaphragm", "abdominals"] {
        set(&mut inst, &format!("drive.{family}.amplitude"), 0.0);
    }
    initialise(&mut inst);
    let rest = get(&mut inst, "volume.lung");
    for g in groups {
        set(&mut inst, &format!("activation.{g}"), 1.0);
    }
    let range = run_ok(&mut inst, &log, 10.0, 0.02);
    (inst, log, rest, range)
}

#[test]
fn held_maximal_abdominal_contraction_stops_near_residual_volume() {
    let (mut inst, log, rest, (lo, hi)) = hold_at_full_activation(&[
        "transversus_abdominis",
        "rectus_abdominis",
        "external_obliques",
        "internal_obliques",
    ]);
    let rv = residual_volume(&Subject::default(), rest);
    let end = get(&mut inst, "volume.lung");
    println!(
        "all four abdominal groups at 1 for 10 s: lung {lo:.3}-{hi:.3} L, {end:.3} L at the end (rest {rest:.3} L, RV {rv:.3} L)"
    );
    assert!(lo >= (1.0 - RV_MARGIN) * rv, "lung {lo} L, RV {rv} L");
    assert!(end < rest, "the contraction expires: {end} L from {rest} L");
    assert!(log.borrow().is_empty(), "{:?}", log.borrow());
}

#[test]
fn held_maximal_inspiration_stays_below_total_lung_capacity() {
    let (_inst, log, rest, (lo, hi)) =
        hold_at_full_activation(&["diaphragm", "external_intercostals", "scalenes"]);
    let tlc = rest * capacity_ratios(&Subject::default()).1;
    println!(
        "inspiratory groups at 1 for 10 s: lung {lo:.3}-{hi:.3} L (rest {rest:.3} L, TLC {tlc:.3} L)"
    );
    assert!(hi > rest, "the contraction inspires: {hi} L from {rest} L");
    assert!(hi <= (1.0 + RV_MARGIN) * tlc, "lung {hi} L, TLC {tlc} L");
    assert!(log.borrow().is_empty(), "{:?}", log.borrow());
}

/// Replaces the model snapshot inside a serialised FMU state (the FMI 2.0 serialised-state
/// layout of this FMU: magic, version, length of the instance part, instance part, model
/// snapshot).
fn with_snapshot(state: &FmuState, snapshot: &Snapshot) -> FmuState {
    let bytes = state.to_bytes();
    let mut len = [0u8; 8];
    len.copy_from_slice(&bytes[12..20]);
    let end = 20 + u64::from_le_bytes(len) as usize;
    let mut out = bytes[..end].to_vec();
    out.extend_from_slice(&snapshot.to_bytes());
    FmuState::from_bytes(&out).expect("a valid state")
}

#[test]
fn a_state_leaving_the_bounds_is_discarded_with_the_bound_named() {
    let (mut inst, log) = instance();
    set(&mut inst, "scene.level_of_detail", 0.0);
    initialise(&mut inst);
    let h = 1.0 / 56.0;
    run_ok(&mut inst, &log, 2.0 * h, h);
    let t = inst.time();
    let rest = get(&mut inst, "volume.thorax");
    // turn every rib 0.6 rad caudally (far into expiration): the thorax is crushed to about a
    // quarter of its volume. The model recovers from that within milliseconds, so the
    // communication step is a microsecond: its end is still outside the bounds.
    let state = inst.get_fmu_state();
    let bytes = state.to_bytes();
    let mut len = [0u8; 8];
    len.copy_from_slice(&bytes[12..20]);
    let mut snapshot = Snapshot::from_bytes(&bytes[20 + u64::from_le_bytes(len) as usize..])
        .expect("the model snapshot");
    // y = [24 rib angles | sternum pose | free vertex positions | rates]
    for theta in &mut snapshot.state[..24] {
        *theta -= 0.6;
    }
    assert_eq!(
        inst.set_fmu_state("fmi2SetFMUstate", &with_snapshot(&state, &snapshot)),
        Status::Ok
    );
    let crushed = get(&mut inst, "volume.thorax");
    let (lo, hi) = cavity_bounds(&Subject::default())[0];
    assert!(crushed < lo * rest, "{crushed} L of {rest} L");
    let status = inst.do_step("fmi2DoStep", t, 1e-6);
    assert_eq!(status, Status::Discard, "the step must be discarded");
    assert_eq!(inst.phase(), Phase::StepFailed);
    assert_eq!(inst.time(), t, "the model stays at the start of the step");
    assert_eq!(inst.last_successful_time(), t);
    assert_eq!(inst.phase(), Phase::StepFailed, "fmi2Terminated is true");
    assert_eq!(
        get(&mut inst, "volume.thorax"),
        crushed,
        "the state is restored to the start of the step"
    );
    let (s, category, message) = log.borrow().last().cloned().expect("the discard is logged");
    println!("{message}");
    assert_eq!(s, Status::Discard);
    assert_eq!(category, "logStatusDiscard");
    assert!(
        message.contains("volume.thorax")
            && message.contains(&format!("[{lo:.3}, {hi:.3}] x rest"))
            && message.contains("discarded"),
        "{message}"
    );
    assert!(
        !inst.allowed("fmi2DoStep", mask::DO_STEP),
        "no step after a discard"
    );
}

#[test]
fn quiet_breathing_is_never_discarded() {
    let (mut inst, log) = instance();
    set(&mut inst, "scene.level_of_detail", 0.0);
    set(&mut inst, "drive.ribs.amplitude", 0.2);
    set(&mut inst, "drive.diaphragm.amplitude", 0.25);
    initialise(&mut inst);
    run_ok(&mut inst, &log, 4.0, 0.1);
    assert!(log.borrow().is_empty(), "{:?}", log.borrow());
}

/// A short young woman: RV/FRC 0.42 (ECSC 1993), below the fixed 0.5 x rest the thorax was
/// once bounded by.
fn young_short_woman() -> Subject {
    Subject {
        sex: Sex::Female,
        age: 18.0,
        stature: 1.50,
        mass: 48.0,
        breast_size: 0.3,
        posture: Posture::Standing,
    }
}

#[test]
fn a_full_expiration_to_a_low_residual_volume_is_not_discarded() {
    let s = young_short_woman();
    let (rv_ratio, _) = capacity_ratios(&s);
    assert!(rv_ratio < 0.45, "RV/FRC {rv_ratio}");
    let bounds = cavity_bounds(&s);
    assert!(bounds[0].0 < rv_ratio && bounds[0].0 <= CAVITY_BOUNDS.0);
    let (mut inst, log) = instance();
    set_subject(&mut inst, &s);
    for (name, value) in [
        ("scene.level_of_detail", 0.0),
        ("drive.ribs.amplitude", 0.0),
        ("drive.diaphragm.amplitude", 0.0),
        ("drive.abdominals.amplitude", 0.0),
    ] {
        set(&mut inst, name, value);
    }
    initialise(&mut inst);
    let rest = get(&mut inst, "volume.lung");
    for g in [
        "internal_intercostals",
        "transversus_abdominis",
        "rectus_abdominis",
        "external_obliques",
        "internal_obliques",
    ] {
        set(&mut inst, &format!("activation.{g}"), 1.0);
    }
    // the effort empties the lungs within the first step and holds them near RV
    let (lo, _) = run_ok(&mut inst, &log, 0.3, 0.02);
    let rv = rest * rv_ratio;
    println!(
        "maximal expiratory effort for 0.3 s: lung down to {lo:.3} L = {:.3} x rest {rest:.3} L (RV {rv:.3} L, bound {:.3} x rest)",
        lo / rest,
        bounds[0].0
    );
    assert!(
        lo < CAVITY_BOUNDS.0 * rest,
        "the lungs pass below the fixed bound: {lo} L of {rest} L"
    );
    assert!(lo >= (1.0 - RV_MARGIN) * rv, "lung {lo} L, RV {rv} L");
    assert!(log.borrow().is_empty(), "{:?}", log.borrow());
}

/// Held maximal expiratory effort of the short young woman, 2 s at level of detail 0: the
/// transversus abdominis drags its first via vertex onto its origin 1 cm away. As a string
/// through points this stalled the solver (over 550,000 RHS evaluations for 0.1 s, steps of
/// about 1.4 us); the band's core (`dynamics::PATH_CORE`) keeps the pull smooth there. Counts,
/// not times: the bound is an RHS budget.
#[test]
fn held_maximal_expiration_does_not_stall_the_solver() {
    use breathing_torso::anatomy::MuscleGroup;
    use breathing_torso::model::{Drive, Scene};
    use breathing_torso::{Config, Quantity, Torso};
    let mut drive = Drive::quiet();
    drive.ribs.amplitude = 0.0;
    drive.diaphragm.amplitude = 0.0;
    let mut torso = Torso::new(Config {
        subject: young_short_woman(),
        drive,
        scene: Scene {
            level_of_detail: 0,
            ..Scene::default()
        },
        ..Config::default()
    })
    .expect("the subject builds");
    let rest = torso.read(Quantity::LungVolume).unwrap();
    for g in [
        MuscleGroup::InternalIntercostals,
        MuscleGroup::TransversusAbdominis,
        MuscleGroup::RectusAbdominis,
        MuscleGroup::ExternalObliques,
        MuscleGroup::InternalObliques,
    ] {
        torso.set_activation(g, 1.0).unwrap();
    }
    for k in 1..=100 {
        torso
            .advance_to(0.02 * k as f64)
            .expect("the effort integrates");
    }
    let lung = torso.read(Quantity::LungVolume).unwrap();
    let stats = torso.solver_stats();
    println!(
        "2 s of maximal expiratory effort: lung {:.3} x rest, {} RHS evaluations, {} steps (+{} rejected)",
        lung / rest,
        stats.rhs_evaluations,
        stats.steps,
        stats.rejected
    );
    assert!(lung < 0.5 * rest, "the effort holds the lungs near RV");
    assert!(
        stats.rhs_evaluations < 50_000,
        "{} RHS evaluations",
        stats.rhs_evaluations
    );
}
