//! `<ModelStructure>` tells the truth: the dependencies the model description declares are
//! generated from the variable table, and the feedthrough they claim is measured on the
//! instance. Setting every input to 1 at a communication point, without a step, must leave
//! every output whose declared input dependencies are empty bit for bit unchanged (in
//! initialization mode and after breathing steps), while the next step does respond to the
//! inputs (so that the measurement can see a change). The alveolar and pleural pressures
//! declare the airway-opening pressure, and do change with it at once.

use breathing_torso::fmi::instance::Instance;
use breathing_torso::fmi::table;
use breathing_torso::fmi::variables::{
    Causality, Role, ScalarType, VR_AIRWAY_OCCLUDED, VR_AIRWAY_OPENING, Variable,
};
use breathing_torso::fmi::xml::model_description;
use breathing_torso::fmi::{FMI2, Status};

fn outputs() -> Vec<&'static Variable> {
    table()
        .variables()
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .collect()
}

/// The Real inputs (the activations and the airway opening; `airway.occluded` is the one
/// Boolean input).
fn inputs() -> Vec<u32> {
    table()
        .variables()
        .iter()
        .filter(|v| v.causality == Causality::Input && v.ty == ScalarType::Real)
        .map(|v| v.vr)
        .collect()
}

/// Every input's value reference.
fn all_inputs() -> Vec<u32> {
    table()
        .variables()
        .iter()
        .filter(|v| v.causality == Causality::Input)
        .map(|v| v.vr)
        .collect()
}

/// Every output, as its bits (Real) or value (Integer), in table order.
fn read_outputs(inst: &mut Instance) -> Vec<u64> {
    outputs()
        .iter()
        .map(|v| match v.ty {
            ScalarType::Real => {
                let mut x = [f64::NAN];
                assert_eq!(
                    inst.get_real("fmi2GetReal", &[v.vr], &mut x),
                    Status::Ok,
                    "{}",
                    v.name
                );
                x[0].to_bits()
            }
            ScalarType::Integer => {
                let mut x = [0];
                assert_eq!(
                    inst.get_integer("fmi2GetInteger", &[v.vr], &mut x),
                    Status::Ok,
                    "{}",
                    v.name
                );
                x[0] as u64
            }
            _ => unreachable!("{} has no readable output type", v.name),
        })
        .collect()
}

/// The outputs whose values differ between `a` and `b` and that declare no dependency on the
/// inputs: each is a false claim of the model description.
fn false_claims(a: &[u64], b: &[u64]) -> Vec<String> {
    outputs()
        .iter()
        .zip(a.iter().zip(b))
        .filter(|(v, (x, y))| x != y && v.input_dependencies.as_deref() == Some(&[]))
        .map(|(v, _)| v.name.clone())
        .collect()
}

/// The outputs the airway-opening pressure reaches without a step.
const FED_THROUGH: [&str; 3] = ["pressure.pleural", "pressure.alveolar", "pressure.mouth"];

/// The inputs an output declares it depends on at once: the airway opening and the occlusion
/// for the pressures, the occlusion alone for the airflow (0 behind it), none for the rest.
fn declared(name: &str) -> &'static [u32] {
    if FED_THROUGH.contains(&name) {
        &[VR_AIRWAY_OPENING, VR_AIRWAY_OCCLUDED]
    } else if name == "flow.airway" {
        &[VR_AIRWAY_OCCLUDED]
    } else {
        &[]
    }
}

#[test]
fn every_output_declares_its_input_dependencies() {
    let md = model_description();
    let outputs = outputs();
    assert_eq!(
        outputs.len(),
        8 + 4 + 8 + 3 + 3 * 60 + 3,
        "volumes and pressures, pressures and flow, sides, sternum, markers, solver"
    );
    for v in &outputs {
        let expected = declared(&v.name);
        let deps = expected
            .iter()
            .map(|&vr| table().index_of(vr).unwrap().to_string())
            .collect::<Vec<_>>()
            .join(" ");
        assert_eq!(
            v.input_dependencies.as_deref(),
            Some(expected),
            "{}'s dependencies",
            v.name
        );
        assert!(matches!(v.role, Role::Output(_)));
        let index = table().index_of(v.vr).unwrap();
        let line = format!("<Unknown index=\"{index}\" dependencies=\"{deps}\"/>");
        assert!(md.contains(&line), "{} ({line}) not in <Outputs>", v.name);
    }
    // The initial unknowns depend on the parameters, never on time, and on an input only
    // where the output declares it (the pressures on the airway opening and the occlusion,
    // the airflow on the occlusion).
    let start = md.find("<InitialUnknowns>").unwrap();
    let inputs: Vec<String> = all_inputs()
        .iter()
        .map(|&vr| table().index_of(vr).unwrap().to_string())
        .collect();
    // the inputs each initial unknown (by index) declares
    let declared_at = |index: &str| -> Vec<String> {
        table()
            .variables()
            .iter()
            .find(|v| table().index_of(v.vr).unwrap().to_string() == index)
            .map(|v| {
                declared(&v.name)
                    .iter()
                    .map(|&vr| table().index_of(vr).unwrap().to_string())
                    .collect()
            })
            .unwrap_or_default()
    };
    let time = table().index_of(0).unwrap().to_string();
    for line in md[start..].lines().filter(|l| l.contains("<Unknown ")) {
        let index = line.split("index=\"").nth(1).unwrap();
        let index = &index[..index.find('"').unwrap()];
        let deps = line.split("dependencies=\"").nth(1).unwrap();
        let deps: Vec<&str> = deps[..deps.find('"').unwrap()].split(' ').collect();
        let own = declared_at(index);
        let on_inputs: Vec<String> = deps
            .iter()
            .filter(|d| inputs.iter().any(|i| i == *d))
            .map(|d| d.to_string())
            .collect();
        assert!(!deps.is_empty(), "{line}");
        assert_eq!(on_inputs, own, "{line}");
        assert!(!deps.contains(&time.as_str()), "{line}");
        let mut sorted: Vec<usize> = deps.iter().map(|d| d.parse().unwrap()).collect();
        sorted.sort_unstable();
        assert_eq!(
            sorted.iter().map(usize::to_string).collect::<Vec<_>>(),
            deps,
            "ascending"
        );
    }
}

#[test]
fn setting_every_input_without_a_step_changes_no_output() {
    no_undeclared_feedthrough(0, 1.0);
}

/// The same in the quasi-static mode (`solver.method` 4), whose positions balance the
/// activations at once: what is read at a communication point balances the activations the
/// last step ended with, whether it was read before the inputs were set or not, and an
/// input acts from the next step on (no direct feedthrough, as declared).
#[test]
fn quasi_static_mode_has_no_undeclared_feedthrough() {
    // every group at once at 0.2 (with every group at 1 the quasi-static step after is
    // discarded: every muscle pulls at its maximum against every other)
    no_undeclared_feedthrough(4, 0.2);
}

/// Sets every input to `level` (the airway opening to `level` Pa) at communication points.
fn no_undeclared_feedthrough(method: i32, level: f64) {
    let table = table();
    let vr = |n: &str| table.by_name(n).unwrap().vr;
    let inputs = inputs();
    let ones = vec![level; inputs.len()];
    assert_eq!(inputs.len(), 10);
    let zeros = vec![0.0; inputs.len()];
    let set_method = |inst: &mut Instance| {
        assert_eq!(
            inst.set_integer("fmi2SetInteger", &[vr("solver.method")], &[method]),
            Status::Ok
        );
    };

    let mut inst = Instance::new(&FMI2, "feedthrough", None, None, false);
    set_method(&mut inst);
    // Breathing, so that velocities and activations are not zero when the inputs change.
    let drive = [
        (vr("drive.ribs.amplitude"), 0.12),
        (vr("drive.diaphragm.amplitude"), 0.3),
    ];
    for (r, x) in drive {
        assert_eq!(inst.set_real("fmi2SetReal", &[r], &[x]), Status::Ok);
    }
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);

    // In initialization mode.
    let before = read_outputs(&mut inst);
    assert_eq!(inst.set_real("fmi2SetReal", &inputs, &ones), Status::Ok);
    let after = read_outputs(&mut inst);
    assert_eq!(false_claims(&before, &after), Vec::<String>::new());
    assert_eq!(inst.set_real("fmi2SetReal", &inputs, &zeros), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );

    // After breathing steps, at several communication points.
    let h = 0.05;
    let mut t = 0.0;
    for _ in 0..3 {
        for _ in 0..4 {
            assert_eq!(inst.do_step("fmi2DoStep", t, h), Status::Ok);
            t += h;
        }
        let state = inst.get_fmu_state();
        let before = read_outputs(&mut inst);
        assert_eq!(inst.set_real("fmi2SetReal", &inputs, &ones), Status::Ok);
        let after = read_outputs(&mut inst);
        assert_eq!(
            false_claims(&before, &after),
            Vec::<String>::new(),
            "t = {t}"
        );
        // The declared feedthrough is real: 1 Pa at the airway opening moves both pressures
        // (in the inertial formulation, whose pleural pressure carries it at once).
        for name in FED_THROUGH.iter().filter(|_| method == 0) {
            let i = outputs().iter().position(|v| v.name == *name).unwrap();
            let moved = f64::from_bits(after[i]) - f64::from_bits(before[i]);
            assert!((moved - level).abs() < 1e-9, "{name} moved by {moved} Pa");
        }
        // The inputs do act, through the state: the next step differs from one without them.
        assert_eq!(inst.do_step("fmi2DoStep", t, h), Status::Ok);
        let driven = read_outputs(&mut inst);
        assert_eq!(inst.set_fmu_state("fmi2SetFMUstate", &state), Status::Ok);
        assert_eq!(inst.do_step("fmi2DoStep", t, h), Status::Ok);
        let held = read_outputs(&mut inst);
        let lung = outputs()
            .iter()
            .position(|v| v.name == "volume.lung")
            .unwrap();
        assert_ne!(driven[lung], held[lung], "the inputs reach the state");
        assert_eq!(inst.set_fmu_state("fmi2SetFMUstate", &state), Status::Ok);
    }

    // A fresh read after the inputs changed (no value computed before) agrees too.
    let mut fresh = Instance::new(&FMI2, "fresh", None, None, false);
    set_method(&mut fresh);
    assert_eq!(
        fresh.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(fresh.enter_initialization_mode(), Status::Ok);
    assert_eq!(fresh.set_real("fmi2SetReal", &inputs, &ones), Status::Ok);
    let with_inputs = read_outputs(&mut fresh);
    let mut plain = Instance::new(&FMI2, "plain", None, None, false);
    set_method(&mut plain);
    assert_eq!(
        plain.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(plain.enter_initialization_mode(), Status::Ok);
    let without = read_outputs(&mut plain);
    assert_eq!(false_claims(&with_inputs, &without), Vec::<String>::new());

    // After steps too: inputs set before the first read of a communication point give what
    // a read before setting them gives.
    let step = |inst: &mut Instance, t: &mut f64| {
        for _ in 0..4 {
            assert_eq!(inst.do_step("fmi2DoStep", *t, 0.05), Status::Ok);
            *t += 0.05;
        }
    };
    assert_eq!(fresh.set_real("fmi2SetReal", &inputs, &zeros), Status::Ok);
    assert_eq!(
        fresh.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    assert_eq!(
        plain.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    let (mut tf, mut tp) = (0.0, 0.0);
    step(&mut fresh, &mut tf);
    step(&mut plain, &mut tp);
    assert_eq!(fresh.set_real("fmi2SetReal", &inputs, &ones), Status::Ok);
    let unread = read_outputs(&mut fresh);
    let read = read_outputs(&mut plain);
    assert_eq!(false_claims(&unread, &read), Vec::<String>::new());
}
