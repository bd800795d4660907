//! SSP parameter sets (`.ssv`, SystemStructureParameterValues of SSP 1.0, Modelica
//! Association 2019, section 7): writing the parameters of a personalised FMU so that an SSP
//! tool can apply them to the generic FMU, and reading them back (a personalised FMU reads its
//! own set from `resources/subject/parameters.ssv` when it is instantiated).
//!
//! The file is an `ssv:ParameterSet` (attributes `version="1.0"` and `name`) holding
//! `ssv:Parameters`, whose every `ssv:Parameter name=".."` holds one typed value:
//! `ssv:Real`, `ssv:Integer`, `ssv:Boolean` or `ssv:String`, each with a `value` attribute.
//! Names are the FMU's variable names.

use super::variables::{Table, Value};
use crate::{Error, Result};
use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

/// XML namespace of SSP 1.0 parameter values.
pub const SSV_NAMESPACE: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";

/// The text of a `.ssv` parameter set called `name` holding `parameters` in the order given.
/// Reals are written in their shortest round-trip form, so reading the file gives the same
/// `f64`s.
pub fn write(name: &str, parameters: &[(String, Value)]) -> String {
    super::xml::xml_document(|w| {
        w.create_element("ssv:ParameterSet")
            .with_attribute(("xmlns:ssv", SSV_NAMESPACE))
            .with_attribute(("version", "1.0"))
            .with_attribute(("name", name))
            .write_inner_content(|w| {
                w.create_element("ssv:Parameters")
                    .write_inner_content(|w| {
                        for (pname, value) in parameters {
                            let (tag, text) = match value {
                                Value::Real(x) => ("ssv:Real", super::xml::num(*x)),
                                Value::Integer(i) => ("ssv:Integer", i.to_string()),
                                Value::Boolean(b) => ("ssv:Boolean", b.to_string()),
                                Value::String(s) => ("ssv:String", s.clone()),
                            };
                            w.create_element("ssv:Parameter")
                                .with_attribute(("name", pname.as_str()))
                                .write_inner_content(|w| {
                                    w.create_element(tag)
                                        .with_attribute(("value", text.as_str()))
                                        .write_empty()?;
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

/// The 1-based line and column (in characters) of byte `at` of `text`.
fn line_column(text: &str, at: usize) -> (usize, usize) {
    let mut at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text[..at];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// Byte offset of attribute `key` (its name) inside the markup `text[start..end]`, if there.
fn attribute_at(text: &str, start: usize, end: usize, key: &str) -> Option<usize> {
    let tag = text.get(start..end)?;
    let mut from = 0;
    while let Some(i) = tag[from..].find(key).map(|i| i + from) {
        let preceded = tag[..i].ends_with(|c: char| c.is_ascii_whitespace());
        let followed = tag[i + key.len()..].trim_start().starts_with('=');
        if preceded && followed {
            return Some(start + i);
        }
        from = i + key.len();
    }
    None
}

/// Reads the parameters of a `.ssv` text (`path` names it in errors, with the line and column
/// of the element, or of the attribute, that is wrong). Every parameter must hold exactly one
/// of `ssv:Real`, `ssv:Integer`, `ssv:Boolean`, `ssv:String`.
pub fn parse(text: &str, path: &str) -> Result<Vec<(String, Value)>> {
    let mut reader = Reader::from_str(text);
    reader.config_mut().trim_text(true);
    let err = |at: usize, message: String| {
        let (line, column) = line_column(text, at);
        Error::Parse {
            path: path.to_string(),
            line,
            column,
            message,
        }
    };
    let offset = |p: u64| usize::try_from(p).unwrap_or(usize::MAX).min(text.len());
    let mut out = Vec::new();
    let mut root_seen = false;
    let mut current: Option<(String, Option<Value>)> = None;
    loop {
        let before = offset(reader.buffer_position());
        let event = reader.read_event().map_err(|e| {
            err(
                offset(reader.error_position()),
                format!("not well-formed XML: {e}"),
            )
        })?;
        let end = offset(reader.buffer_position());
        // Text is trimmed, so the event's markup starts at the first non-blank byte after the
        // previous event (which is where `<` of an element is).
        let at = text[before..end]
            .find(|c: char| !c.is_ascii_whitespace())
            .map_or(before, |i| before + i);
        let empty = matches!(event, Event::Empty(_));
        match event {
            Event::Start(e) | Event::Empty(e) => {
                // Where attribute `key` is written (else the element).
                let key_at = |key: &str| attribute_at(text, at, end, key).unwrap_or(at);
                let attr = |e: &BytesStart, key: &str| -> Result<Option<String>> {
                    match e.try_get_attribute(key) {
                        Ok(Some(a)) => a
                            .unescape_value()
                            .map(|v| Some(v.into_owned()))
                            .map_err(|x| err(key_at(key), format!("attribute `{key}`: {x}"))),
                        Ok(None) => Ok(None),
                        Err(x) => Err(err(key_at(key), format!("attribute `{key}`: {x}"))),
                    }
                };
                let local = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                if !root_seen {
                    if local != "ParameterSet" {
                        return Err(err(
                            at,
                            format!("the root element is `{local}`, not ssv:ParameterSet"),
                        ));
                    }
                    let namespaced = e.attributes().flatten().any(|a| {
                        a.key.as_ref().starts_with(b"xmlns")
                            && a.value.as_ref() == SSV_NAMESPACE.as_bytes()
                    });
                    if !namespaced {
                        return Err(err(
                            at,
                            format!(
                                "ssv:ParameterSet does not declare the namespace {SSV_NAMESPACE}"
                            ),
                        ));
                    }
                    root_seen = true;
                    continue;
                }
                match local.as_str() {
                    "Parameter" => {
                        if let Some((name, _)) = &current {
                            return Err(err(at, format!("parameter `{name}` is not closed")));
                        }
                        let name = attr(&e, "name")?
                            .ok_or_else(|| err(at, "ssv:Parameter without a `name`".into()))?;
                        if empty {
                            return Err(err(
                                at,
                                format!(
                                    "parameter `{name}` holds no value (ssv:Real, ssv:Integer, ssv:Boolean or ssv:String)"
                                ),
                            ));
                        }
                        current = Some((name, None));
                    }
                    "Real" | "Integer" | "Boolean" | "String" => {
                        let Some((name, value)) = current.as_mut() else {
                            return Err(err(at, format!("ssv:{local} outside an ssv:Parameter")));
                        };
                        if value.is_some() {
                            return Err(err(
                                at,
                                format!("parameter `{name}` holds more than one value"),
                            ));
                        }
                        let raw = attr(&e, "value")?.ok_or_else(|| {
                            err(at, format!("ssv:{local} of `{name}` without a `value`"))
                        })?;
                        let bad = |what: &str| {
                            err(key_at("value"), format!("`{name}`: {raw:?} is not {what}"))
                        };
                        *value = Some(match local.as_str() {
                            "Real" => {
                                Value::Real(raw.trim().parse().map_err(|_| bad("a real number"))?)
                            }
                            "Integer" => {
                                Value::Integer(raw.trim().parse().map_err(|_| bad("an integer"))?)
                            }
                            "Boolean" => Value::Boolean(match raw.trim() {
                                "true" | "1" => true,
                                "false" | "0" => false,
                                _ => return Err(bad("a boolean (true, false, 1, 0)")),
                            }),
                            _ => Value::String(raw),
                        });
                    }
                    _ => {}
                }
            }
            Event::End(e) if e.local_name().as_ref() == b"Parameter" => match current.take() {
                Some((name, Some(v))) => out.push((name, v)),
                Some((name, None)) => {
                    return Err(err(
                        at,
                        format!(
                            "parameter `{name}` holds no value (ssv:Real, ssv:Integer, ssv:Boolean or ssv:String)"
                        ),
                    ));
                }
                None => {}
            },
            Event::Eof => break,
            _ => {}
        }
    }
    if !root_seen {
        return Err(err(0, "no ssv:ParameterSet element".into()));
    }
    Ok(out)
}

/// Checks that every parameter of a set is a parameter of the FMU described by `table`, with
/// the set's type, and within the variable's range; the error names the set (`path`), the
/// parameter and what it should be.
pub fn check(table: &Table, parameters: &[(String, Value)], path: &str) -> Result<()> {
    use super::variables::{Causality, ScalarType};
    for (name, value) in parameters {
        let var = table
            .by_name(name)
            .filter(|v| v.causality == Causality::Parameter)
            .ok_or_else(|| {
                Error::State(format!("{path}: `{name}` is not a parameter of the FMU"))
            })?;
        let (ty, x) = match value {
            Value::Real(x) => (ScalarType::Real, Some(*x)),
            Value::Integer(i) => (ScalarType::Integer, Some(f64::from(*i))),
            Value::Boolean(_) => (ScalarType::Boolean, None),
            Value::String(_) => (ScalarType::String, None),
        };
        if ty != var.ty {
            return Err(Error::State(format!(
                "{path}: `{name}` is given as {ty:?}, the FMU's variable is {:?}",
                var.ty
            )));
        }
        if let Some(x) = x {
            var.check(x)
                .map_err(|e| Error::State(format!("{path}: {e}")))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set() -> Vec<(String, Value)> {
        vec![
            ("subject.age".into(), Value::Real(41.25)),
            ("drive.ribs.phase".into(), Value::Real(-0.1 - 1e-17 * 3.0)),
            ("drive.frequency".into(), Value::Real(0.2345678901234567)),
            ("subject.sex".into(), Value::Integer(1)),
            ("drive.enabled".into(), Value::Boolean(true)),
            (
                "slp.reference".into(),
                Value::String("a <&> \"b\".csv".into()),
            ),
        ]
    }

    #[test]
    fn a_written_set_reads_back_exactly_and_matches_the_table() {
        let text = write("subject", &set());
        assert!(text.contains(SSV_NAMESPACE), "{text}");
        assert!(text.contains("<ssv:Real value=\"41.25\"/>"), "{text}");
        let back = parse(&text, "t.ssv").unwrap();
        assert_eq!(back, set());
        check(super::super::variables::table(), &back, "t.ssv").unwrap();
    }

    /// A set written by hand, blank lines and odd spacing included, with `value` put at a
    /// known line and column.
    fn by_hand(age: &str, mass: &str) -> String {
        format!(
            "<?xml version=\"1.0\"?>\n\
             <ssv:ParameterSet xmlns:ssv=\"{SSV_NAMESPACE}\" version=\"1.0\" name=\"s\">\n\
             <ssv:Parameters>\n\
             <ssv:Parameter name=\"subject.age\">\n\
             \n\
             \x20 <ssv:Real value=\"{age}\"/>\n\
             </ssv:Parameter>\n\
             <ssv:Parameter name=\"subject.mass\">\n\
             \x20  <ssv:Real   value=\"{mass}\"/></ssv:Parameter>\n\
             </ssv:Parameters>\n\
             </ssv:ParameterSet>\n"
        )
    }

    #[test]
    fn errors_name_the_line_and_column_of_the_bad_value() {
        let good = by_hand("41", "70");
        assert_eq!(good.lines().nth(5), Some("  <ssv:Real value=\"41\"/>"));
        assert_eq!(parse(&good, "h.ssv").unwrap().len(), 2);
        // The age's `value` is on line 6, column 13; the mass's on line 9, column 16.
        let e = parse(&by_hand("old", "70"), "h.ssv")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("h.ssv:6:13: `subject.age`"), "{e}");
        let e = parse(&by_hand("41", "heavy"), "h.ssv")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("h.ssv:9:16: `subject.mass`"), "{e}");
        // An element out of place is named where it starts: line 6, column 3.
        let stray = by_hand("41", "70").replace(
            "<ssv:Parameter name=\"subject.age\">\n\n",
            "<ssv:Parameter name=\"subject.age\"/>\n\n",
        );
        let e = parse(&stray, "h.ssv").unwrap_err().to_string();
        assert!(
            e.starts_with("h.ssv:4:1: parameter `subject.age` holds no"),
            "{e}"
        );
        // Malformed XML: the misspelt end tag at line 9, column 28.
        let broken = by_hand("41", "70").replace("/></ssv:Parameter>", "/></ssv:Parametre>");
        let e = parse(&broken, "h.ssv").unwrap_err().to_string();
        assert!(e.starts_with("h.ssv:9:28: not well-formed"), "{e}");
        // A multi-byte character counts as one column.
        assert_eq!(line_column("\u{e9}\u{e9}x", 4), (1, 3));
        assert_eq!(line_column("ab\ncd", 3), (2, 1));
    }

    #[test]
    fn bad_sets_are_refused_with_the_file_line_and_name() {
        let text = write("subject", &set());
        let e = parse(&text.replace("41.25", "forty"), "t.ssv")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.ssv:") && e.contains("subject.age") && e.contains("forty"),
            "{e}"
        );
        let e = parse(&text.replace(SSV_NAMESPACE, "urn:x"), "t.ssv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("namespace"), "{e}");
        let e = parse("<a/>", "t.ssv").unwrap_err().to_string();
        assert!(e.contains("root element"), "{e}");
        let t = super::super::variables::table();
        let e = check(t, &[("volume.lung".into(), Value::Real(1.0))], "t.ssv").unwrap_err();
        assert!(e.to_string().contains("volume.lung"), "{e}");
        let e = check(t, &[("subject.sex".into(), Value::Real(1.0))], "t.ssv").unwrap_err();
        assert!(e.to_string().contains("Integer"), "{e}");
        let e = check(t, &[("subject.age".into(), Value::Real(500.0))], "t.ssv").unwrap_err();
        assert!(e.to_string().contains("subject.age"), "{e}");
    }
}
