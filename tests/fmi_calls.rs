//! The FMI layer from Rust: the exported functions with NULL and bogus arguments (never a
//! crash, always `fmi2Error`), instantiation refusals, the state machine through the safe
//! `Instance` with its log messages, and FMU-state bytes (round trip, every truncation and
//! corruption refused without a panic).

use breathing_torso::fmi::ffi::*;
use breathing_torso::fmi::instance::{FmuState, Instance, LogSink, Phase};
use breathing_torso::fmi::table;
use breathing_torso::fmi::types::fmi2Status::*;
use breathing_torso::fmi::types::*;
use breathing_torso::fmi::{FMI2, Status};
use std::cell::RefCell;
use std::ffi::CString;
use std::ptr::{null, null_mut};
use std::rc::Rc;

fn guid() -> CString {
    CString::new(table().guid()).unwrap()
}

fn callbacks() -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: null_mut(),
    }
}

fn instantiate(kind: fmi2Type, guid: &CString) -> fmi2Component {
    let cb = callbacks();
    unsafe {
        fmi2Instantiate(
            c"t".as_ptr(),
            kind,
            guid.as_ptr(),
            c"file:///tmp/a%20b".as_ptr(),
            &cb,
            0,
            0,
        )
    }
}

#[test]
fn instantiation_refusals() {
    let bad = CString::new("{00000000-0000-0000-0000-000000000000}").unwrap();
    assert!(instantiate(fmi2CoSimulation, &bad).is_null());
    assert!(instantiate(fmi2ModelExchange, &guid()).is_null());
    let cb = callbacks();
    unsafe {
        assert!(
            fmi2Instantiate(null(), fmi2CoSimulation, guid().as_ptr(), null(), &cb, 0, 0).is_null()
        );
        assert!(
            fmi2Instantiate(c"t".as_ptr(), fmi2CoSimulation, null(), null(), &cb, 0, 0).is_null()
        );
        assert!(
            fmi2Instantiate(
                c"t".as_ptr(),
                fmi2CoSimulation,
                guid().as_ptr(),
                null(),
                null(),
                0,
                0
            )
            .is_null()
        );
        // No resource location is allowed: the model reads nothing from resources by default.
        let c = fmi2Instantiate(
            c"t".as_ptr(),
            fmi2CoSimulation,
            guid().as_ptr(),
            null(),
            &cb,
            0,
            0,
        );
        assert!(!c.is_null());
        fmi2FreeInstance(c);
    }
}

#[test]
fn null_arguments_are_errors_not_crashes() {
    let c = instantiate(fmi2CoSimulation, &guid());
    assert!(!c.is_null());
    unsafe {
        assert_eq!(
            fmi2SetupExperiment(null_mut(), 0, 0.0, 0.0, 0, 0.0),
            fmi2Error
        );
        assert_eq!(fmi2DoStep(null_mut(), 0.0, 0.1, 0), fmi2Error);
        assert_eq!(fmi2SetReal(c, null(), 1, null()), fmi2Error);
        assert_eq!(fmi2SetReal(c, null(), 0, null()), fmi2OK, "nothing to set");
        assert_eq!(fmi2SetDebugLogging(c, 1, 2, null()), fmi2Error);
        assert_eq!(fmi2GetFMUstate(c, null_mut()), fmi2Error);
        assert_eq!(fmi2FreeFMUstate(c, null_mut()), fmi2Error);
        assert_eq!(fmi2SetFMUstate(c, null_mut()), fmi2Error);
        let bogus = 0x1234usize as fmi2FMUstate;
        assert_eq!(
            fmi2SetFMUstate(c, bogus),
            fmi2Error,
            "a pointer this instance did not hand out"
        );
        let mut size = 0usize;
        assert_eq!(fmi2SerializedFMUstateSize(c, bogus, &mut size), fmi2Error);
        assert_eq!(
            fmi2DeSerializeFMUstate(c, null(), 10, &mut null_mut()),
            fmi2Error
        );
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2GetReal(c, null(), 1, null_mut()), fmi2Error);
        let vr = [0u32];
        assert_eq!(fmi2GetReal(c, vr.as_ptr(), 1, null_mut()), fmi2Error);
        let mut t = f64::NAN;
        assert_eq!(fmi2GetReal(c, vr.as_ptr(), 1, &mut t), fmi2OK);
        assert_eq!(t, 0.0);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        assert_eq!(
            fmi2GetRealStatus(c, fmi2LastSuccessfulTime, null_mut()),
            fmi2Error
        );
        assert_eq!(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut t), fmi2OK);
        let mut b = 7;
        assert_eq!(fmi2GetBooleanStatus(c, fmi2Terminated, &mut b), fmi2OK);
        assert_eq!(b, fmi2False);
        assert_eq!(fmi2GetBooleanStatus(c, 99, &mut b), fmi2Error);
        assert_eq!(fmi2CancelStep(c), fmi2Error);
        assert_eq!(
            fmi2GetDirectionalDerivative(c, null(), 0, null(), 0, null(), null_mut()),
            fmi2Error
        );
        // FMU state through the C functions.
        let mut s: fmi2FMUstate = null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut s), fmi2OK);
        assert!(!s.is_null());
        assert_eq!(fmi2SerializedFMUstateSize(c, s, &mut size), fmi2OK);
        let mut buf = vec![0 as fmi2Byte; size];
        assert_eq!(
            fmi2SerializeFMUstate(c, s, buf.as_mut_ptr(), size - 1),
            fmi2Error,
            "buffer too small"
        );
        assert_eq!(fmi2SerializeFMUstate(c, s, buf.as_mut_ptr(), size), fmi2OK);
        let mut s2: fmi2FMUstate = null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(c, buf.as_ptr(), size, &mut s2),
            fmi2OK
        );
        assert_eq!(fmi2SetFMUstate(c, s2), fmi2OK);
        assert_eq!(fmi2FreeFMUstate(c, &mut s), fmi2OK);
        assert!(s.is_null());
        assert_eq!(
            fmi2FreeFMUstate(c, &mut s),
            fmi2OK,
            "freeing NULL is a no-op"
        );
        // s2 is released by fmi2FreeInstance.
        fmi2FreeInstance(c);
        fmi2FreeInstance(null_mut());
    }
}

/// Messages received by a test logger: (status, category, message).
type Log = Rc<RefCell<Vec<(Status, String, String)>>>;

fn recording_instance() -> (Instance, Log) {
    let log = Rc::new(RefCell::new(Vec::new()));
    let sink_log = log.clone();
    let sink: LogSink = Box::new(move |s, c, m| {
        sink_log
            .borrow_mut()
            .push((s, c.to_string(), m.to_string()))
    });
    (Instance::new(&FMI2, "t", None, Some(sink), false), log)
}

#[test]
fn state_machine_and_messages() {
    let (mut inst, log) = recording_instance();
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    assert_eq!(inst.phase(), Phase::Instantiated);
    assert!(!inst.allowed("fmi2DoStep", breathing_torso::fmi::instance::mask::DO_STEP));
    assert!(
        log.borrow()
            .last()
            .unwrap()
            .2
            .contains("illegal call sequence")
    );
    assert_eq!(
        inst.set_real("fmi2SetReal", &[vr("subject.age")], &[55.0]),
        Status::Ok
    );
    assert_eq!(
        inst.set_real("fmi2SetReal", &[vr("activation.scalenes")], &[f64::NAN]),
        Status::Error
    );
    let msg = log.borrow().last().unwrap().clone();
    assert_eq!((msg.0, msg.1.as_str()), (Status::Error, "logStatusError"));
    assert!(
        msg.2.contains("activation.scalenes") && msg.2.contains("[0, 1]"),
        "{}",
        msg.2
    );
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", Some(1e-7), 0.5, Some(10.0)),
        Status::Ok
    );
    assert_eq!(
        inst.config().solver.rtol,
        1e-7,
        "the master's tolerance becomes solver.rtol"
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    assert_eq!(inst.phase(), Phase::StepComplete);
    assert_eq!(inst.time(), 0.5);
    assert_eq!(
        inst.set_real("fmi2SetReal", &[vr("subject.age")], &[40.0]),
        Status::Error
    );
    assert_eq!(inst.config().subject.age, 55.0);
    assert_eq!(
        inst.do_step("fmi2DoStep", 0.5, 20.0),
        Status::Error,
        "beyond stopTime"
    );
    assert_eq!(
        inst.do_step("fmi2DoStep", 0.4, 0.1),
        Status::Error,
        "wrong current time"
    );
    let state = inst.get_fmu_state();
    assert_eq!(inst.reset(), Status::Ok);
    assert_eq!(
        (inst.phase(), inst.time(), inst.config().subject.age),
        (Phase::Instantiated, 0.0, 30.0)
    );
    assert_eq!(inst.set_fmu_state("fmi2SetFMUstate", &state), Status::Ok);
    assert_eq!(
        (inst.phase(), inst.time(), inst.config().subject.age),
        (Phase::StepComplete, 0.5, 55.0)
    );
    // Debug logging: events are off with loggingOn = false, on after fmi2SetDebugLogging.
    let n = log.borrow().len();
    assert_eq!(
        inst.set_debug_logging("fmi2SetDebugLogging", true, &["logEvents"]),
        Status::Ok
    );
    inst.reset();
    assert!(
        log.borrow()[n..]
            .iter()
            .any(|m| m.1 == "logEvents" && m.2 == "reset")
    );
}

#[test]
fn fmu_state_bytes_round_trip_and_refuse_garbage() {
    let (mut inst, _) = recording_instance();
    inst.set_real(
        "fmi2SetReal",
        &[table().by_name("drive.ribs.amplitude").unwrap().vr],
        &[0.3],
    );
    inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None);
    inst.enter_initialization_mode();
    inst.exit_initialization_mode("fmi2ExitInitializationMode");
    let state = inst.get_fmu_state();
    let bytes = state.to_bytes();
    assert_eq!(FmuState::from_bytes(&bytes).unwrap(), state);
    for len in 0..bytes.len() {
        assert!(
            FmuState::from_bytes(&bytes[..len]).is_err(),
            "prefix of {len} of {} bytes accepted: {:?}",
            bytes.len(),
            String::from_utf8_lossy(&bytes[len.saturating_sub(40)..len])
        );
    }
    // Flip every byte of the header and a spread of the body: refused or still a valid state.
    let mut seed = 0x9e3779b97f4a7c15u64;
    for i in (0..bytes.len()).step_by(7) {
        let mut b = bytes.clone();
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        b[i] ^= (seed as u8) | 1;
        let _ = FmuState::from_bytes(&b);
    }
    let noise: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    assert!(FmuState::from_bytes(&noise).is_err());
}

/// An initialised instance refuses a state saved with other fixed parameters (Status::Error, a
/// log line naming them, nothing changed), as the C ABI's `bt_restore` refuses a snapshot of
/// another model; after fmi2Reset, when fixed parameters may be set again, it takes it.
#[test]
fn fmu_state_of_other_fixed_parameters_is_refused_once_initialised() {
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let start = |stature: f64| {
        let (mut inst, log) = recording_instance();
        assert_eq!(
            inst.set_integer("fmi2SetInteger", &[vr("scene.level_of_detail")], &[0]),
            Status::Ok
        );
        assert_eq!(
            inst.set_real("fmi2SetReal", &[vr("subject.stature")], &[stature]),
            Status::Ok
        );
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(
            inst.exit_initialization_mode("fmi2ExitInitializationMode"),
            Status::Ok
        );
        (inst, log)
    };
    let (mut a, _) = start(1.75);
    assert_eq!(a.do_step("fmi2DoStep", 0.0, 0.1), Status::Ok);
    let state_a = a.get_fmu_state();
    let (mut b, log) = start(1.9);
    assert_eq!(b.do_step("fmi2DoStep", 0.0, 0.2), Status::Ok);
    let lung = |i: &mut Instance| {
        let mut v = [0.0];
        assert_eq!(
            i.get_real("fmi2GetReal", &[vr("volume.lung")], &mut v),
            Status::Ok
        );
        v[0]
    };
    let before = lung(&mut b);
    for state in [
        state_a.clone(),
        FmuState::from_bytes(&state_a.to_bytes()).unwrap(),
    ] {
        assert_eq!(b.set_fmu_state("fmi2SetFMUstate", &state), Status::Error);
        let msg = log.borrow().last().unwrap().clone();
        assert_eq!(msg.0, Status::Error);
        assert!(
            msg.2.contains("fmi2SetFMUstate")
                && msg
                    .2
                    .contains("`subject.stature` 1.9 here, 1.75 in the state")
                && !msg.2.contains("scene.level_of_detail"),
            "{}",
            msg.2
        );
        assert_eq!(
            (b.phase(), b.time(), b.config().subject.stature),
            (Phase::StepComplete, 0.2, 1.9)
        );
        assert_eq!(lung(&mut b), before);
    }
    // Its own states and those of an instance with the same fixed parameters but another
    // drive are taken.
    let own = b.get_fmu_state();
    assert_eq!(b.do_step("fmi2DoStep", 0.2, 0.1), Status::Ok);
    assert_eq!(b.set_fmu_state("fmi2SetFMUstate", &own), Status::Ok);
    assert_eq!((b.time(), lung(&mut b)), (0.2, before));
    let (mut c, _) = start(1.9);
    assert_eq!(
        c.set_real("fmi2SetReal", &[vr("drive.ribs.amplitude")], &[0.3]),
        Status::Ok
    );
    assert_eq!(c.set_fmu_state("fmi2SetFMUstate", &own), Status::Ok);
    assert_eq!((c.time(), lung(&mut c)), (0.2, before));
    // After fmi2Reset the fixed parameters are open again: the state's are taken.
    assert_eq!(b.reset(), Status::Ok);
    assert_eq!(b.set_fmu_state("fmi2SetFMUstate", &state_a), Status::Ok);
    assert_eq!(
        (b.phase(), b.time(), b.config().subject.stature),
        (Phase::StepComplete, 0.1, 1.75)
    );
}

/// The state at fmi2ExitInitializationMode is the static equilibrium of the inputs set during
/// initialisation: with the drive's amplitudes 0 and the diaphragm input held at 0.3, the
/// lung volume is already the inspired one and stays there over 4 s (within 1 % of the
/// volume the activation inspired from rest); fmi2Reset and a new initialisation with the
/// same input start at the same state.
#[test]
fn initialisation_starts_at_the_inputs_equilibrium() {
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let start = |inst: &mut Instance, diaphragm: f64| {
        for family in ["ribs", "diaphragm", "abdominals"] {
            let name = format!("drive.{family}.amplitude");
            assert_eq!(
                inst.set_real("fmi2SetReal", &[vr(&name)], &[0.0]),
                Status::Ok
            );
        }
        assert_eq!(
            inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
            Status::Ok
        );
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(
            inst.set_real("fmi2SetReal", &[vr("activation.diaphragm")], &[diaphragm]),
            Status::Ok
        );
        assert_eq!(
            inst.exit_initialization_mode("fmi2ExitInitializationMode"),
            Status::Ok
        );
        let mut v = [0.0];
        assert_eq!(
            inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut v),
            Status::Ok
        );
        v[0]
    };
    let (mut inst, _log) = recording_instance();
    let rest = start(&mut inst, 0.0);
    assert_eq!(inst.reset(), Status::Ok);
    let held = start(&mut inst, 0.3);
    let inspired = held - rest;
    assert!(inspired > 0.1, "the diaphragm inspired {inspired} L");
    assert_eq!(inst.do_step("fmi2DoStep", 0.0, 4.0), Status::Ok);
    let mut v = [0.0];
    assert_eq!(
        inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut v),
        Status::Ok
    );
    assert!(
        (v[0] - held).abs() < 0.01 * inspired,
        "lung volume {held} L at the start, {} L 4 s later",
        v[0]
    );
    assert_eq!(inst.reset(), Status::Ok);
    assert_eq!(start(&mut inst, 0.3), held);
}

#[test]
fn a_drive_parameter_changed_after_initialisation_acts_as_a_step() {
    // After fmi2ExitInitializationMode the start is fixed: a tunable drive parameter set
    // before the first step changes the drive from there on and leaves the state where it
    // is, as an input would (docs/dynamics.md, "The start state").
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let (mut inst, _log) = recording_instance();
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    let mut before = [0.0];
    assert_eq!(
        inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut before),
        Status::Ok
    );
    assert_eq!(
        inst.set_real("fmi2SetReal", &[vr("drive.diaphragm.amplitude")], &[0.6]),
        Status::Ok
    );
    let mut after = [0.0];
    assert_eq!(
        inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut after),
        Status::Ok
    );
    assert_eq!(
        after[0], before[0],
        "the state moved when the drive changed"
    );
}
