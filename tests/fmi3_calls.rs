//! The exported FMI 3.0 functions called directly, as a C importer would, on the paths fmpy
//! does not take: refused instantiations (token, event mode, intermediate variables, model
//! exchange, scheduled execution), NULL instances and arguments, `nValues` that does not
//! match, types without variables, Boolean bytes other than 0 and 1, the out-arguments of
//! `fmi3DoStep`, and every function that is not provided. Each must return its status (or
//! NULL) with a log line, never crash.

#![allow(non_snake_case)]

use breathing_torso::fmi::fmi3::ffi::*;
use breathing_torso::fmi::fmi3::types::{fmi3Instance, fmi3InstanceEnvironment, fmi3Status};
use breathing_torso::fmi::table;
use std::ffi::{CStr, CString};
use std::os::raw::c_char;
use std::ptr::{null, null_mut};
use std::sync::Mutex;

use fmi3Status::{fmi3Error, fmi3OK};

type Log = Mutex<Vec<(String, String)>>;

/// Records (category, message) into the `Log` the environment pointer points to.
unsafe extern "C" fn logger(
    env: fmi3InstanceEnvironment,
    _status: fmi3Status,
    category: *const c_char,
    message: *const c_char,
) {
    let text = |p: *const c_char| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    let log = unsafe { &*(env as *const Log) };
    log.lock().unwrap().push((text(category), text(message)));
}

fn last_message(log: &Log) -> String {
    log.lock()
        .unwrap()
        .last()
        .map(|m| m.1.clone())
        .unwrap_or_default()
}

fn env(log: &Log) -> fmi3InstanceEnvironment {
    log as *const Log as fmi3InstanceEnvironment
}

fn instantiate(log: &Log, token: &str, event_mode: bool, n_intermediate: usize) -> fmi3Instance {
    let name = CString::new("calls").unwrap();
    let token = CString::new(token).unwrap();
    let vrs = [1000u32];
    unsafe {
        fmi3InstantiateCoSimulation(
            name.as_ptr(),
            token.as_ptr(),
            null(),
            false,
            false,
            event_mode,
            false,
            vrs.as_ptr(),
            n_intermediate,
            env(log),
            Some(logger),
            None,
        )
    }
}

#[test]
fn refused_instantiations_return_null_and_say_why() {
    let log = Log::default();
    let guid = table().guid().to_string();
    assert!(instantiate(&log, "{not-the-token}", false, 0).is_null());
    assert!(
        last_message(&log).contains("instantiationToken"),
        "{}",
        last_message(&log)
    );
    assert!(instantiate(&log, &guid, true, 0).is_null());
    assert!(
        last_message(&log).contains("eventModeUsed"),
        "{}",
        last_message(&log)
    );
    assert!(instantiate(&log, &guid, false, 1).is_null());
    assert!(
        last_message(&log).contains("intermediate"),
        "{}",
        last_message(&log)
    );
    let name = CString::new("me").unwrap();
    let token = CString::new(guid.clone()).unwrap();
    let me = unsafe {
        fmi3InstantiateModelExchange(
            name.as_ptr(),
            token.as_ptr(),
            null(),
            false,
            false,
            env(&log),
            Some(logger),
        )
    };
    assert!(me.is_null());
    assert!(last_message(&log).contains("co-simulation only"));
    let se = unsafe {
        fmi3InstantiateScheduledExecution(
            name.as_ptr(),
            token.as_ptr(),
            null(),
            false,
            false,
            env(&log),
            Some(logger),
            None,
            None,
            None,
        )
    };
    assert!(se.is_null());
    // No logger at all: still NULL, no crash.
    let none = unsafe {
        fmi3InstantiateCoSimulation(
            name.as_ptr(),
            null(),
            null(),
            false,
            false,
            false,
            false,
            null(),
            0,
            null_mut(),
            None,
            None,
        )
    };
    assert!(none.is_null());
}

#[test]
fn bad_arguments_are_errors_and_the_instance_goes_on() {
    let log = Log::default();
    let guid = table().guid().to_string();
    let c = instantiate(&log, &guid, false, 0);
    assert!(!c.is_null());
    unsafe {
        // NULL instance.
        assert_eq!(fmi3ExitInitializationMode(null_mut()), fmi3Error);
        fmi3FreeInstance(null_mut());
        assert_eq!(
            fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0),
            fmi3OK
        );
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);

        let lung = [1000u32];
        let mut v = [0.0f64; 2];
        assert_eq!(
            fmi3GetFloat64(c, lung.as_ptr(), 1, null_mut(), 1),
            fmi3Error
        );
        assert!(
            last_message(&log).contains("values[]"),
            "{}",
            last_message(&log)
        );
        assert_eq!(
            fmi3GetFloat64(c, lung.as_ptr(), 1, v.as_mut_ptr(), 2),
            fmi3Error
        );
        assert!(
            last_message(&log).contains("nValues = 2"),
            "{}",
            last_message(&log)
        );
        assert_eq!(
            fmi3GetFloat64(c, lung.as_ptr(), 1, v.as_mut_ptr(), 1),
            fmi3OK
        );
        assert!(v[0] > 1.0 && v[0] < 10.0, "lung volume {} L", v[0]);
        // A scalar marker other than the array's first element is no FMI 3.0 variable.
        let marker_y = [2001u32];
        assert_eq!(
            fmi3GetFloat64(c, marker_y.as_ptr(), 1, v.as_mut_ptr(), 1),
            fmi3Error
        );
        assert!(last_message(&log).contains("unknown value reference 2001"));

        // A fixed parameter after initialization: the message names FMI 3.0 functions only.
        let age = [100u32];
        let forty = [40.0f64];
        assert_eq!(
            fmi3SetFloat64(c, age.as_ptr(), 1, forty.as_ptr(), 1),
            fmi3Error
        );
        let m = last_message(&log);
        assert!(
            m.starts_with("fmi3SetFloat64: `subject.age` is a fixed parameter")
                && m.contains("after fmi3ExitInitializationMode")
                && !m.contains("fmi2"),
            "{m}"
        );

        // Types without variables: nothing to read is fine, any reference is an error.
        let mut f32s = [0.0f32; 1];
        assert_eq!(
            fmi3GetFloat32(c, lung.as_ptr(), 0, f32s.as_mut_ptr(), 0),
            fmi3OK
        );
        assert_eq!(
            fmi3GetFloat32(c, lung.as_ptr(), 1, f32s.as_mut_ptr(), 1),
            fmi3Error
        );
        assert!(
            last_message(&log)
                .starts_with("fmi3GetFloat32: value reference 1000 is not a Float32 variable"),
            "{}",
            last_message(&log)
        );
        let mut i8s = [0i8; 1];
        assert_eq!(
            fmi3GetInt8(c, lung.as_ptr(), 1, i8s.as_mut_ptr(), 1),
            fmi3Error
        );
        assert!(
            last_message(&log).contains("not an Int8 variable"),
            "{}",
            last_message(&log)
        );
        // An Enumeration read as Int32 is refused, naming Int64.
        let posture = [201u32];
        let mut i32s = [0i32; 1];
        assert_eq!(
            fmi3GetInt32(c, posture.as_ptr(), 1, i32s.as_mut_ptr(), 1),
            fmi3Error
        );
        assert!(
            last_message(&log).contains("`posture`, an Enumeration, not an Int32"),
            "{}",
            last_message(&log)
        );
        let mut i64s = [9i64; 1];
        assert_eq!(
            fmi3GetInt64(c, posture.as_ptr(), 1, i64s.as_mut_ptr(), 1),
            fmi3OK
        );
        assert_eq!(i64s, [0]);

        // Boolean bytes: any non-zero byte is true (tunable drive.enabled, vr 400).
        let enabled = [400u32];
        let two = [2u8];
        assert_eq!(
            fmi3SetBoolean(c, enabled.as_ptr(), 1, two.as_ptr() as *const bool, 1),
            fmi3OK
        );
        let mut back = [0u8];
        assert_eq!(
            fmi3GetBoolean(c, enabled.as_ptr(), 1, back.as_mut_ptr() as *mut bool, 1),
            fmi3OK
        );
        assert_eq!(back, [1]);

        // fmi3DoStep: NULL out-arguments are refused; then a step reports its flags.
        let (mut event, mut terminate, mut early, mut last) = (true, true, true, -1.0);
        assert_eq!(
            fmi3DoStep(
                c,
                0.0,
                0.1,
                false,
                null_mut(),
                &mut terminate,
                &mut early,
                &mut last
            ),
            fmi3Error
        );
        assert!(last_message(&log).contains("eventHandlingNeeded"));
        assert_eq!(
            fmi3DoStep(
                c,
                0.0,
                0.1,
                false,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last
            ),
            fmi3OK
        );
        assert_eq!((event, terminate, early, last), (false, false, false, 0.1));
        // A step from the wrong time: an error naming fmi3DoStep, the time unchanged.
        assert_eq!(
            fmi3DoStep(
                c,
                5.0,
                0.1,
                false,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last
            ),
            fmi3Error
        );
        assert!(
            last_message(&log).starts_with("fmi3DoStep"),
            "{}",
            last_message(&log)
        );
        assert_eq!(last, 0.1);

        // Not provided: fmi3Error with a log line saying so.
        let not_provided: [(&str, fmi3Status); 8] = [
            ("fmi3EnterEventMode", fmi3EnterEventMode(c)),
            ("fmi3EnterConfigurationMode", fmi3EnterConfigurationMode(c)),
            ("fmi3ExitConfigurationMode", fmi3ExitConfigurationMode(c)),
            ("fmi3EnterStepMode", fmi3EnterStepMode(c)),
            ("fmi3EvaluateDiscreteStates", fmi3EvaluateDiscreteStates(c)),
            (
                "fmi3EnterContinuousTimeMode",
                fmi3EnterContinuousTimeMode(c),
            ),
            ("fmi3SetTime", fmi3SetTime(c, 1.0)),
            (
                "fmi3GetNumberOfContinuousStates",
                fmi3GetNumberOfContinuousStates(c, null_mut()),
            ),
        ];
        for (name, status) in not_provided {
            assert_eq!(status, fmi3Error, "{name}");
        }
        let messages = log.lock().unwrap().clone();
        for (name, _) in not_provided {
            assert!(
                messages
                    .iter()
                    .any(|m| m.1.starts_with(&format!("{name}: not provided"))),
                "{name} logged nothing"
            );
        }

        // Still usable.
        assert_eq!(
            fmi3DoStep(
                c,
                0.1,
                0.1,
                false,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last
            ),
            fmi3OK
        );
        assert_eq!(fmi3Terminate(c), fmi3OK);
        fmi3FreeInstance(c);
    }
}
