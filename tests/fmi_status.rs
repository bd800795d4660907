//! Honest status and logging through the exported functions, with a C logger:
//!
//! - a call that returns `fmi2Warning`, `fmi2Discard` or `fmi2Error` logs at least one
//!   message with that status, also with `loggingOn = fmi2False`;
//! - every message a call logs has status `fmi2OK` or the status the call returns (a message
//!   logged as a warning belongs to a call that returns `fmi2Warning`);
//! - `logCalls` logs every call of every function that has an instance, with its name,
//!   before it is checked (illegal calls included);
//! - a tiny legal step after an accepted near-time mismatch succeeds and leaves the instance
//!   stepping.
//!
//! The logger is a Rust function with the fixed arguments the FMU passes (format `"%s"` and one
//! string), called through the variadic C type, as ctypes-based masters such as fmpy do; that
//! calling convention is the same for both on x86-64.
#![cfg(target_arch = "x86_64")]

use breathing_torso::fmi::ffi::*;
use breathing_torso::fmi::table;
use breathing_torso::fmi::types::fmi2Status::{self, *};
use breathing_torso::fmi::types::*;
use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int, c_void};
use std::ptr::{null, null_mut};
use std::sync::Mutex;

/// (status, category, message) as received.
type Messages = Mutex<Vec<(c_int, String, String)>>;

unsafe extern "C" fn record(
    env: *mut c_void,
    _name: *const c_char,
    status: c_int,
    category: *const c_char,
    _format: *const c_char,
    message: *const c_char,
) {
    let text = |p: *const c_char| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    let log = unsafe { &*(env as *const Messages) };
    if let Ok(mut log) = log.lock() {
        log.push((status, text(category), text(message)));
    }
}

/// One call: the function, its status and the messages it logged.
struct Call {
    function: &'static str,
    status: c_int,
    messages: Vec<(c_int, String, String)>,
}

/// An instance made through `fmi2Instantiate`, with every call and its messages recorded.
struct Fmu {
    c: fmi2Component,
    log: Box<Messages>,
    calls: Vec<Call>,
}

impl Fmu {
    fn new(logging_on: bool, resources: &CString) -> Fmu {
        let log: Box<Messages> = Box::default();
        // SAFETY: the same arguments in the same registers; see the module doc.
        let logger: fmi2CallbackLogger = Some(unsafe {
            std::mem::transmute::<
                unsafe extern "C" fn(
                    *mut c_void,
                    *const c_char,
                    c_int,
                    *const c_char,
                    *const c_char,
                    *const c_char,
                ),
                unsafe extern "C" fn(
                    fmi2ComponentEnvironment,
                    fmi2String,
                    fmi2Status,
                    fmi2String,
                    fmi2String,
                    ...
                ),
            >(record)
        });
        let callbacks = fmi2CallbackFunctions {
            logger,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: &*log as *const Messages as *mut c_void,
        };
        let guid = CString::new(table().guid()).unwrap();
        let c = unsafe {
            fmi2Instantiate(
                c"status".as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                resources.as_ptr(),
                &callbacks,
                0,
                logging_on as fmi2Boolean,
            )
        };
        assert!(!c.is_null());
        let messages = std::mem::take(&mut *log.lock().unwrap());
        let calls = vec![Call {
            function: "fmi2Instantiate",
            status: fmi2OK as c_int,
            messages,
        }];
        Fmu { c, log, calls }
    }

    /// Makes one call and records it; returns its status.
    fn call(
        &mut self,
        function: &'static str,
        f: impl FnOnce(fmi2Component) -> fmi2Status,
    ) -> fmi2Status {
        let status = f(self.c);
        let messages = std::mem::take(&mut *self.log.lock().unwrap());
        self.calls.push(Call {
            function,
            status: status as c_int,
            messages,
        });
        status
    }

    fn free(mut self) -> Vec<Call> {
        let c = self.c;
        unsafe { fmi2FreeInstance(c) };
        let messages = std::mem::take(&mut *self.log.lock().unwrap());
        self.calls.push(Call {
            function: "fmi2FreeInstance",
            status: fmi2OK as c_int,
            messages,
        });
        self.calls
    }
}

fn vr(name: &str) -> fmi2ValueReference {
    table().by_name(name).unwrap().vr
}

fn set_real(fmu: &mut Fmu, name: &str, value: f64) -> fmi2Status {
    let r = [vr(name)];
    fmu.call("fmi2SetReal", |c| unsafe {
        fmi2SetReal(c, r.as_ptr(), 1, &value)
    })
}

/// Breathing with an extra activation: the explicit solver's stiffness test fires within the
/// first 0.2 s (logged as an event: the steps succeed).
fn breathe(fmu: &mut Fmu, steps: usize) -> f64 {
    let h = 1.0 / 56.0;
    let mut t = 0.0;
    for _ in 0..steps {
        assert_eq!(
            fmu.call("fmi2DoStep", |c| unsafe { fmi2DoStep(c, t, h, 1) }),
            fmi2OK
        );
        t += h;
    }
    t
}

fn check_statuses(calls: &[Call]) {
    for call in calls {
        for (status, category, message) in &call.messages {
            assert!(
                *status == fmi2OK as c_int || *status == call.status,
                "{} returned {} but logged status {status} [{category}] {message}",
                call.function,
                call.status
            );
        }
        if call.status != fmi2OK as c_int {
            assert!(
                call.messages.iter().any(|m| m.0 == call.status),
                "{} returned {} without a message of that status: {:?}",
                call.function,
                call.status,
                call.messages
            );
        }
    }
}

#[test]
fn statuses_and_messages_agree_with_and_without_logging() {
    for logging_on in [false, true] {
        // An unusable resource location: noted at instantiation, not a warning.
        let mut fmu = Fmu::new(logging_on, &CString::new("http://example.org/r").unwrap());
        let status = fmu.call("fmi2SetupExperiment", |c| unsafe {
            fmi2SetupExperiment(c, 1, 0.5, 0.0, 0, 0.0)
        });
        assert_eq!(
            status, fmi2Warning,
            "a tolerance outside solver.rtol's range"
        );
        assert_eq!(
            fmu.call("fmi2EnterInitializationMode", |c| unsafe {
                fmi2EnterInitializationMode(c)
            }),
            fmi2OK
        );
        // forced breathing (`Drive::forced`) at a loose tolerance: the step then grows to the
        // stability limit, where Dormand-Prince's stiffness detection (Hairer & Wanner) fires
        // (`torso simulate --scenario forced --rtol 1e-2 --duration 8` reports it; quiet
        // breathing, whose fast modes the dynamics no longer have, does not raise it)
        set_real(&mut fmu, "drive.frequency", 0.2);
        set_real(&mut fmu, "drive.ribs.amplitude", 0.28);
        set_real(&mut fmu, "drive.diaphragm.amplitude", 0.48);
        set_real(&mut fmu, "drive.diaphragm.phase", -0.1);
        set_real(&mut fmu, "drive.abdominals.amplitude", 0.4);
        set_real(&mut fmu, "activation.diaphragm", 0.1);
        set_real(&mut fmu, "solver.rtol", 1e-2);
        let s = CString::new("recording.csv").unwrap();
        let p = [s.as_ptr()];
        let r = [vr("slp.reference")];
        let status = fmu.call("fmi2SetString", |c| unsafe {
            fmi2SetString(c, r.as_ptr(), 1, p.as_ptr())
        });
        assert_eq!(status, fmi2Error);
        let last = fmu.calls.last().unwrap();
        let why = &last
            .messages
            .iter()
            .find(|m| m.1 == "logStatusError")
            .unwrap()
            .2;
        assert!(why.contains("no usable resource location"), "{why}");
        assert_eq!(
            fmu.call("fmi2ExitInitializationMode", |c| unsafe {
                fmi2ExitInitializationMode(c)
            }),
            fmi2OK
        );
        // 8 s, as the command above
        let t = breathe(&mut fmu, 448);
        assert_eq!(set_real(&mut fmu, "activation.scalenes", 2.0), fmi2Error);
        assert_eq!(
            fmu.call("fmi2DoStep", |c| unsafe { fmi2DoStep(c, t + 1.0, 0.1, 1) }),
            fmi2Error,
            "not the instance's time"
        );
        assert_eq!(
            fmu.call("fmi2Terminate", |c| unsafe { fmi2Terminate(c) }),
            fmi2OK
        );
        let calls = fmu.free();
        check_statuses(&calls);
        let all: Vec<&(c_int, String, String)> =
            calls.iter().flat_map(|c| c.messages.iter()).collect();
        let stiffness = all.iter().find(|m| m.2.contains("detected stiffness"));
        if logging_on {
            let m = stiffness.expect("the stiffness hint is logged with logging on");
            assert_eq!((m.0, m.1.as_str()), (fmi2OK as c_int, "logEvents"));
            assert!(all.iter().any(|m| m.2.contains("resources unavailable")));
        } else {
            assert!(stiffness.is_none(), "events are off with loggingOn = false");
            // Warnings and errors are reported all the same.
            assert!(all.iter().any(|m| m.0 == fmi2Warning as c_int));
        }
    }
}

#[test]
fn log_calls_logs_every_call_it_can() {
    let mut fmu = Fmu::new(true, &CString::new("file:///tmp").unwrap());
    let mut state: fmi2FMUstate = null_mut();
    let mut size = 0usize;
    let mut real = 0.0;
    let mut int = 0;
    let mut boolean = 0;
    let mut string: fmi2String = null();
    let mut status = fmi2OK;
    let r = [vr("volume.lung")];
    let n = [vr("grid.rows")];
    let s = [vr("slp.reference")];
    let empty = CString::new("").unwrap();
    let strings = [empty.as_ptr()];
    let category = [c"logCalls".as_ptr()];
    unsafe {
        fmu.call("fmi2SetDebugLogging", |c| {
            fmi2SetDebugLogging(c, 1, 1, category.as_ptr())
        });
        fmu.call("fmi2DoStep", |c| fmi2DoStep(c, 0.0, 0.1, 1)); // illegal here
        fmu.call("fmi2SetupExperiment", |c| {
            fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0)
        });
        fmu.call("fmi2SetInteger", |c| fmi2SetInteger(c, n.as_ptr(), 1, &6));
        fmu.call("fmi2SetString", |c| {
            fmi2SetString(c, s.as_ptr(), 1, strings.as_ptr())
        });
        fmu.call("fmi2SetBoolean", |c| fmi2SetBoolean(c, r.as_ptr(), 1, &0));
        fmu.call("fmi2EnterInitializationMode", |c| {
            fmi2EnterInitializationMode(c)
        });
        fmu.call("fmi2SetReal", |c| {
            fmi2SetReal(c, [vr("activation.scalenes")].as_ptr(), 1, &0.2)
        });
        fmu.call("fmi2ExitInitializationMode", |c| {
            fmi2ExitInitializationMode(c)
        });
        fmu.call("fmi2DoStep", |c| fmi2DoStep(c, 0.0, 0.05, 1));
        fmu.call("fmi2GetReal", |c| fmi2GetReal(c, r.as_ptr(), 1, &mut real));
        fmu.call("fmi2GetInteger", |c| {
            fmi2GetInteger(c, n.as_ptr(), 1, &mut int)
        });
        fmu.call("fmi2GetBoolean", |c| {
            fmi2GetBoolean(c, r.as_ptr(), 1, &mut boolean)
        });
        fmu.call("fmi2GetString", |c| {
            fmi2GetString(c, s.as_ptr(), 1, &mut string)
        });
        fmu.call("fmi2GetFMUstate", |c| fmi2GetFMUstate(c, &mut state));
        fmu.call("fmi2SerializedFMUstateSize", |c| {
            fmi2SerializedFMUstateSize(c, state, &mut size)
        });
        let mut bytes = vec![0 as fmi2Byte; size];
        fmu.call("fmi2SerializeFMUstate", |c| {
            fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr(), size)
        });
        fmu.call("fmi2DeSerializeFMUstate", |c| {
            fmi2DeSerializeFMUstate(c, bytes.as_ptr(), size, &mut state)
        });
        fmu.call("fmi2SetFMUstate", |c| fmi2SetFMUstate(c, state));
        fmu.call("fmi2FreeFMUstate", |c| fmi2FreeFMUstate(c, &mut state));
        fmu.call("fmi2GetDirectionalDerivative", |c| {
            fmi2GetDirectionalDerivative(c, null(), 0, null(), 0, null(), null_mut())
        });
        fmu.call("fmi2SetRealInputDerivatives", |c| {
            fmi2SetRealInputDerivatives(c, null(), 0, null(), null())
        });
        fmu.call("fmi2GetRealOutputDerivatives", |c| {
            fmi2GetRealOutputDerivatives(c, null(), 0, null(), null_mut())
        });
        fmu.call("fmi2CancelStep", |c| fmi2CancelStep(c));
        fmu.call("fmi2GetStatus", |c| {
            fmi2GetStatus(c, fmi2DoStepStatus, &mut status)
        });
        fmu.call("fmi2GetRealStatus", |c| {
            fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut real)
        });
        fmu.call("fmi2GetBooleanStatus", |c| {
            fmi2GetBooleanStatus(c, fmi2Terminated, &mut boolean)
        });
        fmu.call("fmi2GetIntegerStatus", |c| {
            fmi2GetIntegerStatus(c, fmi2DoStepStatus, &mut int)
        });
        fmu.call("fmi2GetStringStatus", |c| {
            fmi2GetStringStatus(c, fmi2PendingStatus, &mut string)
        });
        fmu.call("fmi2Terminate", |c| fmi2Terminate(c));
        fmu.call("fmi2Reset", |c| fmi2Reset(c));
    }
    let calls = fmu.free();
    assert_eq!(
        calls.len(),
        33,
        "the 32 functions with an instance, fmi2DoStep twice"
    );
    for call in &calls {
        let logged = call
            .messages
            .iter()
            .find(|m| m.1 == "logCalls" && m.2.starts_with(&format!("{}(", call.function)));
        assert!(
            logged.is_some(),
            "{} not logged: {:?}",
            call.function,
            call.messages
        );
    }
    let step = calls.iter().find(|c| c.function == "fmi2DoStep").unwrap();
    assert_eq!(step.status, fmi2Error as c_int, "logged though refused");
    assert!(step.messages[0].2.contains("communicationStepSize=0.1"));
    check_statuses(&calls);
}

#[test]
fn a_tiny_step_after_a_near_time_mismatch_keeps_stepping() {
    let mut fmu = Fmu::new(false, &CString::new("file:///tmp").unwrap());
    unsafe {
        fmu.call("fmi2SetupExperiment", |c| {
            fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0)
        });
        fmu.call("fmi2EnterInitializationMode", |c| {
            fmi2EnterInitializationMode(c)
        });
        fmu.call("fmi2ExitInitializationMode", |c| {
            fmi2ExitInitializationMode(c)
        });
    }
    let mut t = 0.0;
    for _ in 0..3 {
        assert_eq!(
            fmu.call("fmi2DoStep", |c| unsafe { fmi2DoStep(c, t, 0.1, 1) }),
            fmi2OK
        );
        t += 0.1;
    }
    // Accepted: within the relative tolerance 1e-9 before the instance's time; the step ends
    // before the model's time.
    let early = t * (1.0 - 5e-10);
    let tiny = t * 1e-10;
    assert_eq!(
        fmu.call("fmi2DoStep", |c| unsafe { fmi2DoStep(c, early, tiny, 1) }),
        fmi2OK
    );
    let mut now = f64::NAN;
    let time = [0];
    unsafe { fmi2GetReal(fmu.c, time.as_ptr(), 1, &mut now) };
    assert_eq!(now, early + tiny, "the instance's time is t + h");
    for _ in 0..2 {
        let at = now;
        assert_eq!(
            fmu.call("fmi2DoStep", |c| unsafe { fmi2DoStep(c, at, 0.1, 1) }),
            fmi2OK,
            "still stepping"
        );
        now += 0.1;
    }
    check_statuses(&fmu.free());
}
