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
        3 * 60,
        "the generic FMU's marker outputs are the default 10 x 6 grid's 60 markers (issue 22)"
    );
    let defaults = breathing_torso::Config::default().scene;
    assert_eq!(
        usize::from(breathing_torso::fmi::variables::MARKER_SLOTS),
        defaults.grid_rows * defaults.grid_cols
    );
    assert!(t.by_name("marker[61].x").is_none());
    for name in [
        "activation.diaphragm",
        "volume.lung",
        "marker[60].z",
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

/// The generic FMU has the default grid's 60 markers as outputs, but the C library built on
/// the same table keeps grids of up to 16 x 16: `bt_read` and `bt_read_by_name` take the
/// markers beyond the 60th, equal to `bt_read_markers`, and refuse those beyond 256.
#[test]
fn the_c_library_reads_grid_markers_beyond_the_fmus_outputs() {
    use breathing_torso::capi::*;
    use breathing_torso::fmi::variables::{MARKER_SLOTS, marker_vr};
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        config.level_of_detail = 0;
        assert_eq!(
            bt_config_set(&mut config, c"grid.rows".as_ptr(), 16.0),
            BT_OK
        );
        assert_eq!(
            bt_config_set(&mut config, c"grid.cols".as_ptr(), 16.0),
            BT_OK
        );
        let h = bt_create(&config);
        assert!(!h.is_null());
        let mut xyz = vec![0.0; 3 * 256];
        let mut count = 0usize;
        assert_eq!(
            bt_read_markers(h, xyz.as_mut_ptr(), xyz.len(), &mut count),
            BT_OK
        );
        assert_eq!(count, 256);
        for index in [MARKER_SLOTS, 100, 255] {
            for axis in 0..3u8 {
                let mut v = f64::NAN;
                assert_eq!(bt_read(h, marker_vr(index, axis), &mut v), BT_OK);
                assert_eq!(v, xyz[3 * usize::from(index) + usize::from(axis)]);
                assert!(v != 0.0);
                let name = std::ffi::CString::new(format!(
                    "marker[{}].{}",
                    index + 1,
                    ["x", "y", "z"][usize::from(axis)]
                ))
                .unwrap();
                let mut w = f64::NAN;
                assert_eq!(bt_read_by_name(h, name.as_ptr(), &mut w), BT_OK);
                assert_eq!(w, v);
            }
        }
        let mut v = 0.0;
        assert_ne!(bt_read(h, marker_vr(256, 0), &mut v), BT_OK);
        assert_ne!(bt_read_by_name(h, c"marker[257].x".as_ptr(), &mut v), BT_OK);
        assert_ne!(bt_read_by_name(h, c"marker[0].x".as_ptr(), &mut v), BT_OK);
        bt_destroy(h);
    }
}

/// The generic FMU refuses a grid with more markers than its 60 outputs (rather than reading
/// the first 60 of a larger grid), naming the grid and the personalised FMU; a smaller grid
/// runs, its markers beyond rows x cols reading 0.
#[test]
fn the_generic_fmu_refuses_a_grid_beyond_its_marker_outputs() {
    use breathing_torso::fmi::instance::Instance;
    use breathing_torso::fmi::{FMI2, Status};
    use std::sync::{Arc, Mutex};
    let log = Arc::new(Mutex::new(Vec::<String>::new()));
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let run = |rows: i32, cols: i32| {
        let sink_log = log.clone();
        let sink: breathing_torso::fmi::instance::LogSink =
            Box::new(move |_s, _c: &str, m: &str| sink_log.lock().unwrap().push(m.to_string()));
        let mut inst = Instance::new(&FMI2, "grid", None, Some(sink), false);
        assert_eq!(
            inst.set_integer("fmi2SetInteger", &[vr("scene.level_of_detail")], &[0]),
            Status::Ok
        );
        assert_eq!(
            inst.set_integer(
                "fmi2SetInteger",
                &[vr("grid.rows"), vr("grid.cols")],
                &[rows, cols]
            ),
            Status::Ok
        );
        assert_eq!(
            inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
            Status::Ok
        );
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        (
            inst.exit_initialization_mode("fmi2ExitInitializationMode"),
            inst,
        )
    };
    let (status, _) = run(16, 4);
    assert_ne!(status, Status::Ok);
    let msg = log.lock().unwrap().join("\n");
    assert!(
        msg.contains("grid.rows x grid.cols")
            && msg.contains("16 x 4 = 64")
            && msg.contains("at most 60")
            && msg.contains("--subject"),
        "{msg}"
    );
    let (status, mut inst) = run(5, 6);
    assert_eq!(status, Status::Ok);
    let mut v = [0.0; 2];
    assert_eq!(
        inst.get_real(
            "fmi2GetReal",
            &[vr("marker[30].z"), vr("marker[31].x")],
            &mut v
        ),
        Status::Ok
    );
    assert!(v[0] != 0.0 && v[1] == 0.0, "{v:?}");
}
