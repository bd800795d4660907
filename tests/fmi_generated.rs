//! The variable table and what is generated from it: the committed `modelDescription.xml` is
//! current (`UPDATE_GENERATED=1 cargo test --test fmi_generated` rewrites it), the table's
//! ranges agree with `Config::validate` at every bound, names and value references are unique,
//! every unit is declared, and the GUID follows the interface.

use breathing_torso::Config;
use breathing_torso::fmi::variables::{
    Causality, Initial, Role, ScalarType, Start, UNITS, Value, table,
};
use breathing_torso::fmi::xml::{documentation_html, model_description};
use std::collections::HashSet;
use std::path::PathBuf;

#[test]
fn committed_model_description_is_current() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("modelDescription.xml");
    let generated = model_description();
    if std::env::var_os("UPDATE_GENERATED").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "modelDescription.xml is stale: run `UPDATE_GENERATED=1 cargo test --test fmi_generated` (or `torso fmu model-description`) and commit it"
    );
}

#[test]
fn table_is_consistent() {
    let t = table();
    let mut names = HashSet::new();
    let mut vrs = HashSet::new();
    let units: HashSet<&str> = UNITS
        .iter()
        .flat_map(|u| std::iter::once(u.name).chain(u.display.iter().map(|d| d.0)))
        .collect();
    for v in t.variables() {
        assert!(names.insert(v.name.as_str()), "duplicate name {}", v.name);
        assert!(vrs.insert(v.vr), "duplicate value reference {}", v.vr);
        for u in v.unit.iter().chain(v.display_unit.iter()) {
            assert!(units.contains(u), "{}: unit {u} not declared", v.name);
        }
        match v.causality {
            Causality::Output => assert!(
                v.initial == Some(Initial::Calculated) && v.start == Start::None,
                "{}",
                v.name
            ),
            Causality::Input => {
                assert!(v.initial.is_none() && v.start != Start::None, "{}", v.name)
            }
            Causality::Parameter => assert!(
                v.initial == Some(Initial::Exact) && v.start != Start::None,
                "{}",
                v.name
            ),
            Causality::Independent => assert!(v.start == Start::None, "{}", v.name),
        }
    }
    assert_eq!(
        t.variables()
            .iter()
            .filter(|v| v.name.starts_with("marker["))
            .count(),
        768
    );
    for name in [
        "activation.diaphragm",
        "volume.lung",
        "marker[256].z",
        "solver.rhs_evaluations",
        "slp.reference",
        "posture",
    ] {
        assert!(t.by_name(name).is_some(), "{name} missing");
    }
    assert_eq!(t.by_name("solver.steps").unwrap().ty, ScalarType::Integer);
    assert_eq!(t.by_name("marker[1].x").unwrap().vr, 2000);
    let g = t.guid();
    assert_eq!(g.len(), 38);
    assert!(model_description().contains(g) && documentation_html().contains(g));
}

/// The table's bounds are the facade's: the defaults with a parameter at its min or max
/// validate, and just outside they fail naming the same variable.
#[test]
fn ranges_agree_with_config_validate() {
    for v in table().variables() {
        let Role::Parameter(p) = v.role else { continue };
        let (Some(lo), Some(hi)) = (v.min, v.max) else {
            continue;
        };
        let value = |x: f64| match v.ty {
            ScalarType::Integer => Value::Integer(x as i32),
            _ => Value::Real(x),
        };
        for bound in [lo, hi] {
            let mut c = Config::default();
            if v.name == "subject.mass" {
                c.subject.stature = if bound == lo { 1.6 } else { 1.9 };
            }
            p.set(&mut c, value(bound)).unwrap();
            c.validate().unwrap_or_else(|e| {
                panic!(
                    "{} = {bound} is in the table's range but fails: {e}",
                    v.name
                )
            });
        }
        let step = if v.ty == ScalarType::Integer {
            1.0
        } else {
            (hi - lo).abs().max(1e-12) * 1e-3
        };
        for outside in [lo - step, hi + step] {
            let mut c = Config::default();
            let e = match p.set(&mut c, value(outside)) {
                Err(e) => e.to_string(),
                Ok(()) => c
                    .validate()
                    .expect_err(&format!(
                        "{} = {outside} is outside the table's range but passes",
                        v.name
                    ))
                    .to_string(),
            };
            assert!(
                e.contains(&v.name) || e.contains("negative"),
                "{}: {e}",
                v.name
            );
        }
    }
}
