//! `modelDescription.xml` and `documentation/index.html`, both generated from the variable
//! table ([`super::variables`]). The committed top-level `modelDescription.xml` must equal
//! [`model_description`]'s output (checked by `tests/fmi_generated.rs`).

use super::variables::{
    Causality, Initial, LOG_CATEGORIES, MODEL_IDENTIFIER, ScalarType, Start, Table, UNITS,
    Variability, Variable, table,
};
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, Event};
use std::io;

/// Capability flags declared in `<CoSimulation>` (all `true`); each is honoured by the code:
/// variable step sizes, FMU state get/set and (de)serialisation, and no use of the master's
/// memory functions.
pub const CAPABILITY_FLAGS: [&str; 4] = [
    "canHandleVariableCommunicationStepSize",
    "canGetAndSetFMUstate",
    "canSerializeFMUstate",
    "canNotUseMemoryManagementFunctions",
];

/// Formats a number for XML: shortest round-trip form, in exponent notation when that is shorter.
pub fn num(v: f64) -> String {
    let plain = format!("{v}");
    let sci = format!("{v:e}");
    if sci.len() < plain.len() { sci } else { plain }
}

pub(super) fn causality(c: Causality) -> &'static str {
    match c {
        Causality::Independent => "independent",
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
    }
}

pub(super) fn variability(v: Variability) -> &'static str {
    match v {
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

pub(super) fn initial(i: Initial) -> &'static str {
    match i {
        Initial::Exact => "exact",
        Initial::Calculated => "calculated",
    }
}

fn type_name(t: ScalarType) -> &'static str {
    match t {
        ScalarType::Real => "Real",
        ScalarType::Integer => "Integer",
        ScalarType::Boolean => "Boolean",
        ScalarType::String => "String",
    }
}

pub(super) fn bound(t: ScalarType, v: f64) -> String {
    match t {
        ScalarType::Integer => format!("{}", v as i64),
        _ => num(v),
    }
}

fn write_variable(w: &mut Writer<Vec<u8>>, v: &Variable) -> io::Result<()> {
    let vr = v.vr.to_string();
    let mut e = w
        .create_element("ScalarVariable")
        .with_attribute(("name", v.name.as_str()))
        .with_attribute(("valueReference", vr.as_str()))
        .with_attribute(("description", v.description.as_str()))
        .with_attribute(("causality", causality(v.causality)))
        .with_attribute(("variability", variability(v.variability)));
    if let Some(i) = v.initial {
        e = e.with_attribute(("initial", initial(i)));
    }
    e.write_inner_content(|w| {
        let mut t = w.create_element(type_name(v.ty));
        if let Some(u) = v.unit {
            t = t.with_attribute(("unit", u));
        }
        if let Some(u) = v.display_unit {
            t = t.with_attribute(("displayUnit", u));
        }
        let (lo, hi) = (v.min.map(|x| bound(v.ty, x)), v.max.map(|x| bound(v.ty, x)));
        if let Some(lo) = &lo {
            t = t.with_attribute(("min", lo.as_str()));
        }
        if let Some(hi) = &hi {
            t = t.with_attribute(("max", hi.as_str()));
        }
        let start = match &v.start {
            Start::None => None,
            Start::Real(x) => Some(num(*x)),
            Start::Integer(x) => Some(x.to_string()),
            Start::Boolean(x) => Some(x.to_string()),
            Start::String(x) => Some(x.clone()),
        };
        if let Some(s) = &start {
            t = t.with_attribute(("start", s.as_str()));
        }
        t.write_empty()?;
        Ok(())
    })?;
    Ok(())
}

pub(super) fn write_units(w: &mut Writer<Vec<u8>>) -> io::Result<()> {
    w.create_element("UnitDefinitions")
        .write_inner_content(|w| {
            for u in UNITS {
                w.create_element("Unit")
                    .with_attribute(("name", u.name))
                    .write_inner_content(|w| {
                        let exps: Vec<(String, String)> = u
                            .base
                            .iter()
                            .map(|(k, e)| (k.to_string(), e.to_string()))
                            .collect();
                        let factor = num(u.factor);
                        let mut b = w.create_element("BaseUnit");
                        for (k, e) in &exps {
                            b = b.with_attribute((k.as_str(), e.as_str()));
                        }
                        if u.factor != 1.0 {
                            b = b.with_attribute(("factor", factor.as_str()));
                        }
                        b.write_empty()?;
                        for (name, f) in u.display {
                            let f = num(*f);
                            w.create_element("DisplayUnit")
                                .with_attribute(("name", *name))
                                .with_attribute(("factor", f.as_str()))
                                .write_empty()?;
                        }
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

/// One `<Unknown>` of `<ModelStructure>`: its 1-based index and the 1-based indices of the
/// knowns it depends on (written as `dependencies`, an empty list meaning "none").
struct Unknown {
    index: usize,
    dependencies: Vec<usize>,
}

/// The `<ModelStructure>` unknowns, from the table: `(outputs, initial unknowns)`.
///
/// An output depends at a communication point on the inputs listed in its
/// [`Variable::input_dependencies`] (none: every output is read off the state). During
/// initialization the outputs with `initial="calculated"` are computed from the parameters
/// (every parameter is listed, a superset: the standard's "depends on all knowns" would also
/// name the inputs, which they do not depend on) and from the same inputs.
fn structure(t: &Table) -> (Vec<Unknown>, Vec<Unknown>) {
    let index_of = |vr: u32| t.index_of(vr).unwrap_or_default();
    let parameters: Vec<usize> = t
        .variables()
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Parameter && v.initial == Some(Initial::Exact))
        .map(|(i, _)| i + 1)
        .collect();
    let mut outputs = Vec::new();
    let mut initial_unknowns = Vec::new();
    for (i, v) in t.variables().iter().enumerate() {
        if v.causality != Causality::Output {
            continue;
        }
        let mut inputs: Vec<usize> = v
            .input_dependencies
            .iter()
            .flatten()
            .map(|&vr| index_of(vr))
            .collect();
        inputs.sort_unstable();
        if v.initial == Some(Initial::Calculated) {
            let mut all: Vec<usize> = parameters.iter().copied().chain(inputs.clone()).collect();
            all.sort_unstable();
            all.dedup();
            initial_unknowns.push(Unknown {
                index: i + 1,
                dependencies: all,
            });
        }
        outputs.push(Unknown {
            index: i + 1,
            dependencies: inputs,
        });
    }
    (outputs, initial_unknowns)
}

fn write_structure(w: &mut Writer<Vec<u8>>, t: &Table) -> io::Result<()> {
    let (outputs, initial_unknowns) = structure(t);
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            for (tag, list) in [
                ("Outputs", &outputs),
                ("InitialUnknowns", &initial_unknowns),
            ] {
                w.create_element(tag).write_inner_content(|w| {
                    for u in list.iter() {
                        let index = u.index.to_string();
                        let dependencies: Vec<String> =
                            u.dependencies.iter().map(usize::to_string).collect();
                        let dependencies = dependencies.join(" ");
                        w.create_element("Unknown")
                            .with_attribute(("index", index.as_str()))
                            .with_attribute(("dependencies", dependencies.as_str()))
                            .write_empty()?;
                    }
                    Ok(())
                })?;
            }
            Ok(())
        })?;
    Ok(())
}

/// The complete `modelDescription.xml` text of the generic FMU.
pub fn model_description() -> String {
    model_description_for(table())
}

/// An XML document's text: the declaration (version 1.0, UTF-8), then what `body` writes,
/// indented by two spaces, ending in a newline. Writing into memory cannot fail.
pub(crate) fn xml_document(body: impl FnOnce(&mut Writer<Vec<u8>>) -> io::Result<()>) -> String {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    let result = w
        .write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .and_then(|()| body(&mut w));
    debug_assert!(result.is_ok());
    let mut text = String::from_utf8(w.into_inner()).unwrap_or_default();
    text.push('\n');
    text
}

/// The complete `modelDescription.xml` text of the FMU whose variables are `t` (the generic
/// table or a personalised one, [`super::variables::Table::personalised`]).
pub fn model_description_for(t: &Table) -> String {
    let version = env!("CARGO_PKG_VERSION");
    let tool = generation_tool();
    xml_document(|w| {
        w.create_element("fmiModelDescription")
            .with_attribute(("fmiVersion", "2.0"))
            .with_attribute(("modelName", MODEL_IDENTIFIER))
            .with_attribute(("guid", t.guid()))
            .with_attribute(("description", DESCRIPTION))
            .with_attribute(("version", version))
            .with_attribute(("generationTool", tool.as_str()))
            .with_attribute(("variableNamingConvention", "structured"))
            .with_attribute(("numberOfEventIndicators", "0"))
            .write_inner_content(|w| {
                let mut cs = w
                    .create_element("CoSimulation")
                    .with_attribute(("modelIdentifier", MODEL_IDENTIFIER))
                    .with_attribute(("needsExecutionTool", "false"));
                for flag in CAPABILITY_FLAGS {
                    cs = cs.with_attribute((flag, "true"));
                }
                cs.write_empty()?;
                write_units(w)?;
                write_log_categories(w)?;
                write_default_experiment(w)?;
                w.create_element("ModelVariables")
                    .write_inner_content(|w| {
                        for v in t.variables() {
                            write_variable(w, v)?;
                        }
                        Ok(())
                    })?;
                write_structure(w, t)?;
                Ok(())
            })?;
        Ok(())
    })
}

/// The model's `description` attribute, the same in both versions' model descriptions.
pub const DESCRIPTION: &str = "Physically based breathing human torso (Maldonado 2011): muscle activations in, volumes, pressures and marker positions out";

/// The `generationTool` attribute: this crate and its version.
pub(super) fn generation_tool() -> String {
    format!("breathing-torso {}", env!("CARGO_PKG_VERSION"))
}

/// `<LogCategories>`, the same in FMI 2.0 and FMI 3.0.
pub(super) fn write_log_categories(w: &mut Writer<Vec<u8>>) -> io::Result<()> {
    w.create_element("LogCategories").write_inner_content(|w| {
        for (name, description) in LOG_CATEGORIES {
            w.create_element("Category")
                .with_attribute(("name", *name))
                .with_attribute(("description", *description))
                .write_empty()?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `<DefaultExperiment>`, the same in FMI 2.0 and FMI 3.0: 10 s from 0 in 20 ms steps,
/// tolerance 1e-6.
pub(super) fn write_default_experiment(w: &mut Writer<Vec<u8>>) -> io::Result<()> {
    w.create_element("DefaultExperiment")
        .with_attribute(("startTime", "0"))
        .with_attribute(("stopTime", "10"))
        .with_attribute(("tolerance", "1e-6"))
        .with_attribute(("stepSize", "0.02"))
        .write_empty()?;
    Ok(())
}

fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `documentation/index.html` of the generic FMU: the variable table, for people.
pub fn documentation_html() -> String {
    documentation_html_for(table())
}

/// `documentation/index.html` of the FMU whose variables are `t`; a personalised FMU's page
/// says so and points at the fit result beside it.
pub fn documentation_html_for(t: &Table) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{MODEL_IDENTIFIER} FMU</title>\n\
         <style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}</style>\n</head>\n<body>\n\
         <h1>{MODEL_IDENTIFIER}</h1>\n<p>FMI 2.0 co-simulation FMU of a physically based breathing human torso \
         (breathing-torso {}). GUID <code>{}</code>.</p>\n\
         <p>Muscle activations are inputs; the built-in sinusoidal drive (thesis eq. 2.4) is set by the \
         <code>drive.*</code> parameters, which may change between steps. Each communication step is \
         integrated inside the FMU by an adaptive embedded Runge-Kutta method. Grid markers are numbered \
         row-major from the top row, column 1 on the subject's right; markers beyond \
         <code>grid.rows</code> x <code>grid.cols</code> read 0, and a grid with more markers than \
         the FMU's marker outputs is refused.</p>\n<table>\n\
         <tr><th>name</th><th>vr</th><th>type</th><th>causality</th><th>variability</th><th>unit</th>\
         <th>min</th><th>max</th><th>start</th><th>description</th></tr>\n",
        env!("CARGO_PKG_VERSION"),
        t.guid()
    );
    if t.personalisation().is_some() {
        s.push_str(
            "<p>This FMU is personalised: the start values of the subject's and the fitted drive's \
             parameters are those of the fit in <a href=\"fit.json\">fit.json</a>, and the files the \
             subject needs are in <code>resources/subject/</code>.</p>\n",
        );
        s.push_str(match t.marker_set() {
            None => "<p>Only the markers of the subject's grid are outputs.</p>\n",
            Some(_) => {
                "<p>The marker outputs are the subject's named marker set, <code>marker.&lt;label&gt;</code>, \
                 each read off the deformed skin at its binding (<code>resources/subject/markers.json</code>).</p>\n"
            }
        });
    }
    for v in t.variables() {
        let start = match &v.start {
            Start::None => String::new(),
            Start::Real(x) => num(*x),
            Start::Integer(x) => x.to_string(),
            Start::Boolean(x) => x.to_string(),
            Start::String(x) => format!("\"{x}\""),
        };
        let _ = writeln!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape_html(&v.name),
            v.vr,
            type_name(v.ty),
            causality(v.causality),
            variability(v.variability),
            v.unit.unwrap_or(""),
            v.min.map(|x| bound(v.ty, x)).unwrap_or_default(),
            v.max.map(|x| bound(v.ty, x)).unwrap_or_default(),
            escape_html(&start),
            escape_html(&v.description)
        );
    }
    s.push_str("</table>\n</body>\n</html>\n");
    s
}
