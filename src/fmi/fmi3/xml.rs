//! The FMI 3.0 `modelDescription.xml` and `terminalsAndIcons/terminalsAndIcons.xml`, both
//! generated from the one variable table through its FMI 3.0 view ([`super::view`]): the
//! same names, value references, causalities, variabilities, units, ranges and start values
//! as the FMI 2.0 description, with `Float64`/`Int32` types, the three Enumerations, the
//! marker array and `<ModelStructure>` dependencies given by value reference.

use super::view::{
    MARKER_ARRAY, MARKER_DIMENSIONS, Type3, Variable3, enumerations, type_of, variables,
};
use crate::fmi::variables::{Causality, Initial, MODEL_IDENTIFIER, Role, Start, Variable, table};
use crate::fmi::xml::{
    DESCRIPTION, bound, causality, generation_tool, initial, num, variability,
    write_default_experiment, write_log_categories, write_units, xml_document,
};
use crate::model::Quantity;
use quick_xml::Writer;
use std::io;

/// Capability attributes of `<CoSimulation>`, each honoured by the code (or, for the false
/// ones, by the functions that refuse): variable communication steps, FMU state get/set and
/// serialisation; no event mode, no intermediate update, no early return, no derivatives.
pub const CO_SIMULATION_ATTRIBUTES: [(&str, &str); 8] = [
    ("canHandleVariableCommunicationStepSize", "true"),
    ("canGetAndSetFMUState", "true"),
    ("canSerializeFMUState", "true"),
    ("hasEventMode", "false"),
    ("providesIntermediateUpdate", "false"),
    ("mightReturnEarlyFromDoStep", "false"),
    ("providesDirectionalDerivatives", "false"),
    ("maxOutputDerivativeOrder", "0"),
];

/// Path of the terminals file inside the FMU.
pub const TERMINALS_PATH: &str = "terminalsAndIcons/terminalsAndIcons.xml";

fn write_type_definitions(w: &mut Writer<Vec<u8>>) -> io::Result<()> {
    w.create_element("TypeDefinitions")
        .write_inner_content(|w| {
            for e in enumerations() {
                w.create_element("EnumerationType")
                    .with_attribute(("name", e.name))
                    .write_inner_content(|w| {
                        for (name, value) in &e.items {
                            let value = value.to_string();
                            w.create_element("Item")
                                .with_attribute(("name", name.as_str()))
                                .with_attribute(("value", value.as_str()))
                                .write_empty()?;
                        }
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

fn write_variable(w: &mut Writer<Vec<u8>>, v3: Variable3) -> io::Result<()> {
    let v = v3.variable();
    let ty = type_of(v);
    let vr = v3.vr().to_string();
    let (name, description) = match v3 {
        Variable3::Scalar(v) => (v.name.clone(), v.description.clone()),
        Variable3::MarkerArray(_) => (
            MARKER_ARRAY.to_string(),
            "Marker positions (markers x 3: x anterior, y cranial, z right), markers row-major \
             from the top row, column 1 on the subject's right; rows beyond grid.rows x \
             grid.cols read 0"
                .to_string(),
        ),
    };
    let mut e = w
        .create_element(ty.name())
        .with_attribute(("name", name.as_str()))
        .with_attribute(("valueReference", vr.as_str()))
        .with_attribute(("description", description.as_str()))
        .with_attribute(("causality", causality(v.causality)))
        .with_attribute(("variability", variability(v.variability)));
    if let Some(i) = v.initial {
        e = e.with_attribute(("initial", initial(i)));
    }
    let declared = match ty {
        Type3::Enumeration(i) => Some(enumerations()[i].name),
        _ => None,
    };
    if let Some(d) = declared {
        e = e.with_attribute(("declaredType", d));
    }
    if let Some(u) = v.unit {
        e = e.with_attribute(("unit", u));
    }
    if let Some(u) = v.display_unit {
        e = e.with_attribute(("displayUnit", u));
    }
    let lo = v.min.map(|x| bound(v.ty, x));
    let hi = v.max.map(|x| bound(v.ty, x));
    if let Some(lo) = &lo {
        e = e.with_attribute(("min", lo.as_str()));
    }
    if let Some(hi) = &hi {
        e = e.with_attribute(("max", hi.as_str()));
    }
    let start = match &v.start {
        Start::Real(x) => Some(num(*x)),
        Start::Integer(x) => Some(x.to_string()),
        Start::Boolean(x) => Some(x.to_string()),
        Start::None | Start::String(_) => None,
    };
    if let Some(s) = &start {
        e = e.with_attribute(("start", s.as_str()));
    }
    match (v3, &v.start) {
        (Variable3::MarkerArray(_), _) => {
            e.write_inner_content(|w| {
                for d in MARKER_DIMENSIONS {
                    let d = d.to_string();
                    w.create_element("Dimension")
                        .with_attribute(("start", d.as_str()))
                        .write_empty()?;
                }
                Ok(())
            })?;
        }
        (_, Start::String(s)) => {
            e.write_inner_content(|w| {
                w.create_element("Start")
                    .with_attribute(("value", s.as_str()))
                    .write_empty()?;
                Ok(())
            })?;
        }
        _ => {
            e.write_empty()?;
        }
    }
    Ok(())
}

/// One `<ModelStructure>` entry: the value reference of an unknown and those of the knowns
/// it depends on (empty: none).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unknown3 {
    /// Value reference of the unknown.
    pub vr: u32,
    /// Value references of its dependencies, ascending.
    pub dependencies: Vec<u32>,
}

/// The `<ModelStructure>` of the FMI 3.0 description: `(outputs, initial unknowns)`, the same
/// dependencies as the FMI 2.0 one (see [`crate::fmi::xml`]) given by value reference: every
/// output depends at a communication point on its table input dependencies; during
/// initialization the calculated outputs depend on every exact parameter and those inputs.
/// The marker array stands for all scalar markers (which have the same dependencies).
pub fn structure() -> (Vec<Unknown3>, Vec<Unknown3>) {
    let parameters: Vec<u32> = table()
        .variables()
        .iter()
        .filter(|v| v.causality == Causality::Parameter && v.initial == Some(Initial::Exact))
        .map(|v| v.vr)
        .collect();
    let mut outputs = Vec::new();
    let mut initial_unknowns = Vec::new();
    for v3 in variables() {
        let v = v3.variable();
        if v.causality != Causality::Output {
            continue;
        }
        let mut inputs: Vec<u32> = v.input_dependencies.iter().flatten().copied().collect();
        inputs.sort_unstable();
        if v.initial == Some(Initial::Calculated) {
            let mut all: Vec<u32> = parameters.iter().copied().chain(inputs.clone()).collect();
            all.sort_unstable();
            all.dedup();
            initial_unknowns.push(Unknown3 {
                vr: v3.vr(),
                dependencies: all,
            });
        }
        outputs.push(Unknown3 {
            vr: v3.vr(),
            dependencies: inputs,
        });
    }
    (outputs, initial_unknowns)
}

fn write_structure(w: &mut Writer<Vec<u8>>) -> io::Result<()> {
    let (outputs, initial_unknowns) = structure();
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            for (tag, list) in [("Output", &outputs), ("InitialUnknown", &initial_unknowns)] {
                for u in list.iter() {
                    let vr = u.vr.to_string();
                    let deps: Vec<String> = u.dependencies.iter().map(u32::to_string).collect();
                    let deps = deps.join(" ");
                    w.create_element(tag)
                        .with_attribute(("valueReference", vr.as_str()))
                        .with_attribute(("dependencies", deps.as_str()))
                        .write_empty()?;
                }
            }
            Ok(())
        })?;
    Ok(())
}

/// The complete FMI 3.0 `modelDescription.xml` text. The instantiation token is the GUID of
/// the FMI 2.0 description: both are the hash of the one table's interface, and FMU states
/// carry it, so that a state serialised through either interface restores through the other.
pub fn model_description() -> String {
    let t = table();
    let version = env!("CARGO_PKG_VERSION");
    let tool = generation_tool();
    xml_document(|w| {
        w.create_element("fmiModelDescription")
            .with_attribute(("fmiVersion", "3.0"))
            .with_attribute(("modelName", MODEL_IDENTIFIER))
            .with_attribute(("instantiationToken", t.guid()))
            .with_attribute(("description", DESCRIPTION))
            .with_attribute(("version", version))
            .with_attribute(("generationTool", tool.as_str()))
            .with_attribute(("variableNamingConvention", "structured"))
            .write_inner_content(|w| {
                let mut cs = w
                    .create_element("CoSimulation")
                    .with_attribute(("modelIdentifier", MODEL_IDENTIFIER))
                    .with_attribute(("needsExecutionTool", "false"));
                for (k, v) in CO_SIMULATION_ATTRIBUTES {
                    cs = cs.with_attribute((k, v));
                }
                cs.write_empty()?;
                write_units(w)?;
                write_type_definitions(w)?;
                write_log_categories(w)?;
                write_default_experiment(w)?;
                w.create_element("ModelVariables")
                    .write_inner_content(|w| {
                        for v in variables() {
                            write_variable(w, v)?;
                        }
                        Ok(())
                    })?;
                write_structure(w)?;
                Ok(())
            })?;
        Ok(())
    })
}

/// The members of the two buses: the activation inputs (`activation.<group>`, member
/// `<group>`) and the volume outputs (`volume.<name>`, member `<name>`).
pub fn bus_members() -> (Vec<&'static Variable>, Vec<&'static Variable>) {
    let vars = table().variables();
    let activations = vars
        .iter()
        .filter(|v| v.causality == Causality::Input && v.name.starts_with("activation."))
        .collect();
    let volumes = vars
        .iter()
        .filter(|v| {
            v.causality == Causality::Output
                && v.name.starts_with("volume.")
                && !matches!(v.role, Role::Output(Quantity::Marker { .. }))
        })
        .collect();
    (activations, volumes)
}

/// `terminalsAndIcons/terminalsAndIcons.xml`: an `activation` bus of the muscle-group
/// activation inputs and a `volumes` bus of the volume outputs (matching rule `bus`: members
/// connect by member name).
pub fn terminals_and_icons() -> String {
    let (activations, volumes) = bus_members();
    xml_document(|w| {
        w.create_element("fmiTerminalsAndIcons")
            .with_attribute(("fmiVersion", "3.0"))
            .write_inner_content(|w| {
                w.create_element("Terminals").write_inner_content(|w| {
                    for (name, prefix, members, description) in [
                        (
                            "activation",
                            "activation.",
                            &activations,
                            "Muscle-group activations in [0, 1] (inputs)",
                        ),
                        (
                            "volumes",
                            "volume.",
                            &volumes,
                            "Lung, cavity and displaced volumes (outputs)",
                        ),
                    ] {
                        w.create_element("Terminal")
                            .with_attribute(("name", name))
                            .with_attribute(("matchingRule", "bus"))
                            .with_attribute(("description", description))
                            .write_inner_content(|w| {
                                for v in members.iter() {
                                    let member = v.name.trim_start_matches(prefix);
                                    w.create_element("TerminalMemberVariable")
                                        .with_attribute(("variableName", v.name.as_str()))
                                        .with_attribute(("memberName", member))
                                        .with_attribute(("variableKind", "signal"))
                                        .write_empty()?;
                                }
                                Ok(())
                            })?;
                    }
                    Ok(())
                })?;
                Ok(())
            })?;
        Ok(())
    })
}
