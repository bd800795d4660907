//! The airway occlusion (`Torso::set_airway_occluded`, FMI `airway.occluded`,
//! `bt_set_airway_occluded`): while occluded no gas flows and the lungs' gas follows Boyle's
//! law from its volume and alveolar pressure at the moment of occlusion; the mouth pressure is
//! the alveolar pressure. Checked here against Boyle's law computed from the outputs alone,
//! on the relaxed default subject (the drive off), at level of detail 0 for speed.

use breathing_torso::anatomy::MuscleGroup;
use breathing_torso::capi::*;
use breathing_torso::fmi::variables::Input;
use breathing_torso::fmi::{FMI2, Instance, Status, table};
use breathing_torso::model::{Config, Drive, Quantity, Torso};
use breathing_torso::solver::Method;

/// 1 cmH2O [Pa].
const CMH2O: f64 = 98.0665;

/// Barometric pressure less the saturated water vapour's at 37 degC [Pa]: 101 325 Pa (one
/// standard atmosphere, 1033 cmH2O) less 47 mmHg (6266 Pa), written out here rather than
/// taken from the library, so that the law is checked independently.
const DRY: f64 = 101_325.0 - 47.0 * 133.322;

fn relaxed(method: Method) -> Torso {
    let mut config = Config::default();
    config.scene.level_of_detail = 0;
    config.drive.enabled = false;
    config.solver.method = method;
    Torso::new(config).unwrap()
}

/// The lungs inflated by 10 cmH2O at the airway opening for 0.3 s (still filling: the
/// flow is not zero), then the airway occluded and the opening's pressure removed, the muscles
/// relaxed throughout: the wall moves on until the trapped gas's pressure balances the relaxed
/// system's recoil (still positive, the lungs above their relaxed volume). Returns the torso, the lung volume and alveolar
/// pressure at the moment of occlusion.
fn occluded_after_inflation(method: Method) -> (Torso, f64, f64) {
    let mut torso = relaxed(method);
    torso.set_airway_opening(10.0 * CMH2O).unwrap();
    torso.advance_to(0.3).unwrap();
    let flow = torso.read(Quantity::AirwayFlow).unwrap();
    assert!(flow > 0.1, "still filling at the occlusion: {flow} L/s");
    let v0 = torso.read(Quantity::LungVolume).unwrap();
    let p0 = torso.read(Quantity::AlveolarPressure).unwrap();
    torso.set_airway_occluded(true).unwrap();
    torso.set_airway_opening(0.0).unwrap();
    // the occlusion itself changes neither the volume nor the alveolar pressure
    assert_eq!(torso.read(Quantity::LungVolume).unwrap(), v0);
    assert!((torso.read(Quantity::AlveolarPressure).unwrap() - p0).abs() < 1e-9 * DRY);
    assert_eq!(torso.read(Quantity::AirwayFlow).unwrap(), 0.0);
    (torso, v0, p0)
}

fn boyle_holds(method: Method) -> f64 {
    let (mut torso, v0, p0) = occluded_after_inflation(method);
    let mut volumes = Vec::new();
    for k in 1..=60 {
        torso.advance_to(0.3 + 0.05 * f64::from(k)).unwrap();
        let v = torso.read(Quantity::LungVolume).unwrap();
        let p = torso.read(Quantity::AlveolarPressure).unwrap();
        let mouth = torso.read(Quantity::MouthPressure).unwrap();
        assert_eq!(mouth, p, "behind the occlusion the mouth reads the alveoli");
        assert_eq!(torso.read(Quantity::AirwayFlow).unwrap(), 0.0);
        // Boyle's law on the dry gas, from the outputs
        let ratio = (DRY + p) * v / ((DRY + p0) * v0);
        assert!(
            (ratio - 1.0).abs() < 1e-9,
            "t {}: PV ratio {ratio}",
            torso.time()
        );
        // the volume stays at its occlusion value within the gas's compression: a pressure
        // change of |p - p0| changes the volume by at most v0 |p - p0| / (DRY + p)
        let compression = v0 * (p - p0).abs() / (DRY + p.min(p0));
        assert!(
            (v - v0).abs() <= compression * (1.0 + 1e-9),
            "t {}: volume moved {} L, compression {compression} L",
            torso.time(),
            v - v0
        );
        volumes.push(v);
    }
    // the trapped gas holds the lungs above their relaxed volume: its pressure is positive
    let p = torso.read(Quantity::AlveolarPressure).unwrap();
    println!(
        "{method:?}: occluded at {v0:.4} L, {:.2} cmH2O; 3 s later {:.4} L, {:.2} cmH2O",
        p0 / CMH2O,
        volumes.last().unwrap(),
        p / CMH2O
    );
    assert!(
        p > 0.0,
        "the relaxed system recoils against the trapped gas: {p} Pa"
    );
    // stable: the last second moves the volume by less than a millilitre
    let last = &volumes[volumes.len() - 20..];
    let spread = last.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - last.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(spread < 1e-3, "the occluded lungs still move by {spread} L");
    *volumes.last().unwrap()
}

#[test]
fn occluded_relaxed_lungs_follow_boyles_law() {
    boyle_holds(Method::Dopri5);
}

/// The stiff method (its Jacobian carries the gas law's slope) gives the same occluded
/// volume as the explicit one, within their tolerances.
#[test]
fn the_stiff_method_honours_the_occlusion() {
    let explicit = boyle_holds(Method::Dopri5);
    let stiff = boyle_holds(Method::Rosenbrock);
    assert!(
        (explicit - stiff).abs() < 1e-4,
        "{explicit} L against {stiff} L"
    );
}

/// Released, the airway carries the flow again: the compressed gas leaves (expiratory flow)
/// and the relaxed lungs return to the volume of a run never occluded.
#[test]
fn released_occlusion_returns_to_normal_flow() {
    let (mut torso, _, _) = occluded_after_inflation(Method::Dopri5);
    torso.advance_to(1.0).unwrap();
    let p = torso.read(Quantity::AlveolarPressure).unwrap();
    torso.set_airway_occluded(false).unwrap();
    assert!(!torso.airway_occluded());
    torso.advance_to(1.02).unwrap();
    let flow = torso.read(Quantity::AirwayFlow).unwrap();
    assert!(
        flow < -0.1,
        "released at {:.2} cmH2O, the flow is {flow} L/s",
        p / CMH2O
    );
    assert_eq!(
        torso.read(Quantity::MouthPressure).unwrap(),
        torso.airway_opening()
    );
    torso.advance_to(8.0).unwrap();
    let mut never = relaxed(Method::Dopri5);
    never.advance_to(8.0).unwrap();
    let (a, b) = (
        torso.read(Quantity::LungVolume).unwrap(),
        never.read(Quantity::LungVolume).unwrap(),
    );
    assert!(
        (a - b).abs() < 1e-3,
        "{a} L after release, {b} L never occluded"
    );
    assert!(torso.read(Quantity::AirwayFlow).unwrap().abs() < 0.01);
}

/// Energy: occluded while moving (a forced breath's inspiration, then every muscle
/// relaxed), the model's mechanical energy plus the trapped gas's isothermal potential,
/// U(V) = P_dry V - n ln V (whose -dU/dV is the alveolar pressure n / V - P_dry the gas puts
/// on the wall), never rises between samples: the wall's dampers dissipate, the gas stores
/// and returns. The motion settles at the occluded equilibrium.
#[test]
fn occluded_motion_dissipates_energy() {
    let mut config = Config::default();
    config.scene.level_of_detail = 0;
    config.drive = Drive::forced();
    let mut torso = Torso::new(config).unwrap();
    torso.advance_to(1.2).unwrap();
    torso.set_drive(Drive::default()).unwrap();
    torso.set_airway_occluded(true).unwrap();
    let n = torso.occluded_gas_content().unwrap();
    let energy = |torso: &mut Torso| {
        let v = torso.read(Quantity::LungVolume).unwrap() * 1e-3;
        torso.mechanical_energy() + DRY * v - n * v.ln()
    };
    let start = energy(&mut torso);
    let mut last = start;
    let mut worst_rise: f64 = 0.0;
    let mut volumes = Vec::new();
    for i in 1..=200 {
        torso.advance_to(1.2 + 0.02 * f64::from(i)).unwrap();
        let e = energy(&mut torso);
        worst_rise = worst_rise.max(e - last);
        last = e;
        volumes.push(torso.read(Quantity::LungVolume).unwrap());
    }
    let spent = start - last;
    println!("energy spent {spent:.4e} J, largest rise between samples {worst_rise:.2e} J");
    assert!(spent > 0.0);
    assert!(worst_rise <= 1e-6 * spent, "energy rose by {worst_rise} J");
    let tail = &volumes[volumes.len() - 50..];
    let spread = tail.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - tail.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        spread < 1e-3,
        "still moving by {spread} L over the last second"
    );
}

/// An occluded torso's snapshot restores the occlusion and its gas content: the run goes on
/// bit for bit.
#[test]
fn snapshots_keep_the_occlusion() {
    let (mut torso, _, _) = occluded_after_inflation(Method::Dopri5);
    torso.advance_to(0.5).unwrap();
    let snapshot = torso.snapshot();
    assert!(snapshot.occlusion.is_some());
    torso.advance_to(1.0).unwrap();
    let expected = torso.read(Quantity::LungVolume).unwrap();
    let mut other = relaxed(Method::Dopri5);
    other.restore(&snapshot).unwrap();
    assert!(other.airway_occluded());
    other.advance_to(1.0).unwrap();
    assert_eq!(other.read(Quantity::LungVolume).unwrap(), expected);
}

/// The quasi-static formulation refuses an occlusion, naming the variable, and keeps its
/// state; a value other than 0 or 1 is refused by the input too.
#[test]
fn refused_occlusions_name_the_variable_and_keep_the_state() {
    let mut quasi = relaxed(Method::QuasiStatic);
    let before = quasi.read(Quantity::LungVolume).unwrap();
    let e = quasi.set_airway_occluded(true).unwrap_err().to_string();
    assert!(
        e.contains("airway.occluded") && e.contains("quasi-static"),
        "{e}"
    );
    assert!(!quasi.airway_occluded());
    assert_eq!(quasi.read(Quantity::LungVolume).unwrap(), before);

    let mut torso = relaxed(Method::Dopri5);
    let e = Input::AirwayOccluded
        .apply(&mut torso, 0.5)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("airway.occluded") && e.contains("0 (open) or 1"),
        "{e}"
    );
    assert!(!torso.airway_occluded());
}

/// Through the FMU: the Boolean input occludes the relaxed airway during quiet breathing's
/// expiration (the drive on), keeping the volume and the alveolar pressure of that moment; the
/// airflow then reads 0 and the mouth the alveolar pressure, and an inspiratory effort against
/// the occlusion (the diaphragm's input at 0.5) makes that pressure negative, the gas
/// rarefied by Boyle's law.
#[test]
fn the_fmu_occludes_the_airway() {
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let mut inst = Instance::new(&FMI2, "occlusion", None, None, false);
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.set_integer("fmi2SetInteger", &[vr("scene.level_of_detail")], &[0]),
        Status::Ok
    );
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    // a Boolean input is not a Real
    assert_ne!(
        inst.set_real("fmi2SetReal", &[vr("airway.occluded")], &[1.0]),
        Status::Ok
    );
    let read = |inst: &mut Instance, names: &[&str]| {
        let vrs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
        let mut out = vec![0.0; names.len()];
        assert_eq!(inst.get_real("fmi2GetReal", &vrs, &mut out), Status::Ok);
        out
    };
    let names = [
        "volume.lung",
        "pressure.alveolar",
        "pressure.mouth",
        "flow.airway",
    ];
    // quiet breathing until the airflow is expiratory
    let mut time = 0.0;
    let mut before = read(&mut inst, &names);
    while before[3] > -0.05 {
        assert_eq!(inst.do_step("fmi2DoStep", time, 0.05), Status::Ok);
        time += 0.05;
        before = read(&mut inst, &names);
        assert!(time < 10.0, "no expiration in 10 s");
    }
    // the drive off from here: the breath held by the occlusion alone
    assert_eq!(
        inst.set_boolean("fmi2SetBoolean", &[vr("drive.enabled")], &[0]),
        Status::Ok
    );
    before = read(&mut inst, &names);
    assert_eq!(
        inst.set_boolean("fmi2SetBoolean", &[vr("airway.occluded")], &[1]),
        Status::Ok
    );
    let mut occluded = [0];
    assert_eq!(
        inst.get_boolean("fmi2GetBoolean", &[vr("airway.occluded")], &mut occluded),
        Status::Ok
    );
    assert_eq!(occluded, [1]);
    let at = read(&mut inst, &names);
    assert_eq!(at[0], before[0], "the volume does not jump");
    assert!(
        (at[1] - before[1]).abs() < 1e-9 * DRY,
        "nor the alveolar pressure"
    );
    assert_eq!(at[2], at[1], "the mouth reads the alveoli");
    assert_eq!(at[3], 0.0, "no gas flows");
    let diaphragm = vr(&format!("activation.{}", MuscleGroup::Diaphragm.name()));
    assert_eq!(
        inst.set_real("fmi2SetReal", &[diaphragm], &[0.5]),
        Status::Ok
    );
    for _ in 0..20 {
        assert_eq!(inst.do_step("fmi2DoStep", time, 0.05), Status::Ok);
        time += 0.05;
    }
    let later = read(&mut inst, &names);
    assert_eq!(later[2], later[1]);
    assert_eq!(later[3], 0.0);
    assert!(
        later[1] < 0.0 && later[0] > at[0],
        "the diaphragm pulls against the trapped gas: {at:?} then {later:?}"
    );
    println!("occluded: {at:?}; diaphragm at 0.5 for 1 s: {later:?}");
    let ratio = (DRY + later[1]) * later[0] / ((DRY + at[1]) * at[0]);
    assert!((ratio - 1.0).abs() < 1e-9, "PV ratio {ratio}");
}

/// The FMU under the quasi-static method refuses the occlusion with an error naming the
/// variable and goes on with the airway open.
#[test]
fn the_quasi_static_fmu_refuses_the_occlusion_and_goes_on() {
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let mut inst = Instance::new(&FMI2, "quasi", None, None, false);
    for (name, value) in [("scene.level_of_detail", 0), ("solver.method", 4)] {
        assert_eq!(
            inst.set_integer("fmi2SetInteger", &[vr(name)], &[value]),
            Status::Ok
        );
    }
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    assert_eq!(
        inst.set_boolean("fmi2SetBoolean", &[vr("airway.occluded")], &[1]),
        Status::Error
    );
    let mut occluded = [1];
    assert_eq!(
        inst.get_boolean("fmi2GetBoolean", &[vr("airway.occluded")], &mut occluded),
        Status::Ok
    );
    assert_eq!(occluded, [0]);
    assert_eq!(inst.do_step("fmi2DoStep", 0.0, 0.05), Status::Ok);
}

/// The C ABI's setter: 0 and 1 accepted, anything else refused with the variable's name and
/// nothing changed.
#[test]
fn the_c_abi_occludes_and_refuses_other_values() {
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        config.level_of_detail = 0;
        config.drive.enabled = 0;
        let h = bt_create(&config);
        assert!(!h.is_null());
        let value = |name: &std::ffi::CStr| {
            let mut v = f64::NAN;
            assert_eq!(bt_read_by_name(h, name.as_ptr(), &mut v), BT_OK);
            v
        };
        assert_eq!(bt_set_airway_occluded(h, 2), BT_ERR_INVALID);
        let message = std::ffi::CStr::from_ptr(bt_last_error(h)).to_string_lossy();
        assert!(message.contains("airway.occluded"), "{message}");
        assert_eq!(value(c"airway.occluded"), 0.0);
        assert_eq!(bt_set_airway_occluded(h, 1), BT_OK);
        assert_eq!(value(c"airway.occluded"), 1.0);
        assert_eq!(bt_advance_to(h, 0.2, std::ptr::null_mut()), BT_OK);
        assert_eq!(value(c"flow.airway"), 0.0);
        assert_eq!(value(c"pressure.mouth"), value(c"pressure.alveolar"));
        assert_eq!(bt_set_airway_occluded(h, 0), BT_OK);
        assert_eq!(value(c"airway.occluded"), 0.0);
        bt_destroy(h);
    }
}
