//! A thoracic collapse found by the random-scene soak (`torso bench soak --scenes 100
//! --seconds 60 --seed 2011 --lod 0`, scene 35: a small woman with the rib drive at 0.99 whose
//! thorax falls from 3.49 to 1.56 L in 36 ms) is caught by the FMU: the step that leaves the
//! physiological bounds ends with `fmi2Discard`, the log names the variable and its bound, and
//! the model stays at its last good time with a state within bounds.

use breathing_torso::fmi::instance::{CAVITY_BOUNDS, Instance, LogSink, Phase, mask};
use breathing_torso::fmi::table;
use breathing_torso::fmi::types::fmi2Status::{self, *};
use breathing_torso::fmi::types::{fmi2LastSuccessfulTime, fmi2Terminated};
use breathing_torso::fmi::variables::ScalarType;
use std::cell::RefCell;
use std::rc::Rc;

type Log = Rc<RefCell<Vec<(fmi2Status, String, String)>>>;

/// An instance with logging off (discards are reported even then), and its log.
fn instance() -> (Instance, Log) {
    let log: Log = Rc::new(RefCell::new(Vec::new()));
    let sink_log = log.clone();
    let sink: LogSink = Box::new(move |s, c, m| {
        sink_log
            .borrow_mut()
            .push((s, c.to_string(), m.to_string()))
    });
    (Instance::new("collapse", None, Some(sink), false), log)
}

fn set(inst: &mut Instance, name: &str, value: f64) {
    let var = table().by_name(name).unwrap_or_else(|| panic!("no {name}"));
    let status = match var.ty {
        ScalarType::Integer => inst.set_integer(&[var.vr], &[value as i32]),
        _ => inst.set_real(&[var.vr], &[value]),
    };
    assert_eq!(status, fmi2OK, "{name} = {value}");
}

fn get(inst: &mut Instance, name: &str) -> f64 {
    let vr = table().by_name(name).expect("variable").vr;
    let mut v = [f64::NAN];
    assert_eq!(inst.get_real(&[vr], &mut v), fmi2OK);
    v[0]
}

/// Scene 35 of the soak, as printed in docs/bench/soak_100x60.txt.
fn scene_35(inst: &mut Instance) {
    for (name, value) in [
        ("subject.sex", 1.0),
        ("subject.age", 46.79979085894516),
        ("subject.stature", 1.4782456174406253),
        ("subject.mass", 45.34328870522832),
        ("subject.breast_size", 0.8641515740383998),
        ("posture", 0.0),
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

#[test]
fn thoracic_collapse_of_soak_scene_35_is_discarded_with_the_bound_named() {
    let (mut inst, log) = instance();
    scene_35(&mut inst);
    assert_eq!(inst.setup_experiment(None, 0.0, None), fmi2OK);
    assert_eq!(inst.enter_initialization_mode(), fmi2OK);
    assert_eq!(inst.exit_initialization_mode(), fmi2OK);
    let rest = get(&mut inst, "volume.thorax");
    let h = 1.0 / 56.0;
    let mut t = 0.0;
    let mut status = fmi2OK;
    for _ in 0..56 {
        status = inst.do_step(t, h);
        if status != fmi2OK {
            break;
        }
        t += h;
    }
    assert_eq!(status, fmi2Discard, "the collapse must end the step");
    assert!(t < 0.1, "discarded at {t} s: the soak saw it by 36 ms");
    assert_eq!(inst.phase(), Phase::StepFailed);
    assert_eq!(inst.time(), t, "the model stays at the start of the step");
    assert_eq!(inst.get_real_status(fmi2LastSuccessfulTime), Ok(t));
    assert_eq!(inst.get_boolean_status(fmi2Terminated), Ok(true));
    let thorax = get(&mut inst, "volume.thorax");
    let ratio = thorax / rest;
    assert!(
        (CAVITY_BOUNDS.0..=CAVITY_BOUNDS.1).contains(&ratio),
        "the restored state is within bounds: {thorax} L of {rest} L at rest"
    );
    let (s, category, message) = log.borrow().last().cloned().expect("the discard is logged");
    println!("{message}");
    assert_eq!(s, fmi2Discard);
    assert_eq!(category, "logStatusDiscard");
    assert!(
        message.contains("volume.thorax")
            && message.contains("[0.5, 2] x rest")
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
    assert_eq!(inst.setup_experiment(None, 0.0, None), fmi2OK);
    assert_eq!(inst.enter_initialization_mode(), fmi2OK);
    assert_eq!(inst.exit_initialization_mode(), fmi2OK);
    let h = 0.1;
    for k in 0..40 {
        assert_eq!(inst.do_step(k as f64 * h, h), fmi2OK, "step {k}: {log:?}");
    }
    assert!(log.borrow().is_empty(), "{:?}", log.borrow());
}
