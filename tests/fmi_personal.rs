//! Personalised FMUs (`torso fmu build --subject`) built from a real short fit of the bundled
//! recording with the skin fitted (so the subject carries a skin reference): the model
//! description's start values are the fit's, the GUID is not the generic FMU's, only the
//! fit's grid markers are outputs, the `.ssv` beside it names the FMU's parameters with their
//! types, the relative `slp.reference` is found in the FMU's resources/, and the personalised
//! FMU without any parameter set runs exactly as the generic FMU with the `.ssv` applied.
//! Files that are not fit results are refused naming the file and the missing key.

use breathing_torso::fmi::instance::Instance;
use breathing_torso::fmi::personal::{PARAMETERS, table_in};
use breathing_torso::fmi::ssv;
use breathing_torso::fmi::types::fmi2Status::{fmi2Error, fmi2OK};
use breathing_torso::fmi::variables::{Value, table};
use breathing_torso::fmi::{FMI2, Status};
use quick_xml::Reader;
use quick_xml::events::Event;
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

fn torso(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(args)
        .output()
        .expect("run torso");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout),
    )
}

fn dir() -> PathBuf {
    std::env::temp_dir().join(format!("fmi_personal_{}", std::process::id()))
}

struct Built {
    fit: PathBuf,
    ssv: PathBuf,
    unpacked: PathBuf,
}

/// One short skin fit of the bundled recording at level of detail 0, made into a
/// personalised FMU (once for the whole file).
fn built() -> &'static Built {
    static BUILT: OnceLock<Built> = OnceLock::new();
    BUILT.get_or_init(|| {
        let dir = dir();
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::create_dir_all(dir.join("fit")).unwrap();
        let fit = dir.join("fit").join("result.json");
        let recording = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/data/recordings/demo_quiet.csv"
        );
        let (ok, msg) = torso(&[
            "fit",
            "--slp",
            recording,
            "--lod",
            "0",
            "--max-evals",
            "50",
            "--skin-fit",
            "--threads",
            "1",
            "--out",
            fit.to_str().unwrap(),
        ]);
        assert!(ok, "{msg}");
        let fmu = dir.join("subject.fmu");
        let (ok, msg) = torso(&[
            "fmu",
            "build",
            "--subject",
            fit.to_str().unwrap(),
            "--out",
            fmu.to_str().unwrap(),
        ]);
        assert!(ok, "{msg}");
        let unpacked = dir.join("unpacked");
        let mut zip = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
        zip.extract(&unpacked).unwrap();
        Built {
            fit,
            ssv: fmu.with_extension("ssv"),
            unpacked,
        }
    })
}

fn fit_json() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(&built().fit).unwrap()).unwrap()
}

/// Every `<ScalarVariable>` of a model description: name -> (type element, its attributes
/// and the variable's).
type Vars = HashMap<String, (String, HashMap<String, String>)>;

fn variables(xml: &str) -> (String, Vars) {
    let mut reader = Reader::from_str(xml);
    let mut out = HashMap::new();
    let mut guid = String::new();
    let mut current: Option<HashMap<String, String>> = None;
    let attrs = |e: &quick_xml::events::BytesStart| -> HashMap<String, String> {
        e.attributes()
            .map(|a| {
                let a = a.unwrap();
                (
                    String::from_utf8_lossy(a.key.as_ref()).into_owned(),
                    a.unescape_value().unwrap().into_owned(),
                )
            })
            .collect()
    };
    loop {
        match reader.read_event().unwrap() {
            Event::Start(e) | Event::Empty(e) => {
                let tag = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                match tag.as_str() {
                    "fmiModelDescription" => guid = attrs(&e)["guid"].clone(),
                    "ScalarVariable" => current = Some(attrs(&e)),
                    "Real" | "Integer" | "Boolean" | "String" => {
                        if let Some(mut v) = current.take() {
                            let name = v.remove("name").unwrap();
                            v.extend(attrs(&e));
                            out.insert(name, (tag, v));
                        }
                    }
                    _ => {}
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    (guid, out)
}

fn model_description() -> String {
    std::fs::read_to_string(built().unpacked.join("modelDescription.xml")).unwrap()
}

#[test]
fn start_values_are_the_fits_and_the_guid_is_its_own() {
    let fit = fit_json();
    let (guid, vars) = variables(&model_description());
    assert_ne!(guid, table().guid());
    let (generic_guid, generic) = variables(&breathing_torso::fmi::xml::model_description());
    assert_eq!(generic_guid, table().guid());
    let start = |name: &str| vars[name].1["start"].clone();
    let mut compared = 0;
    for (key, v) in fit.as_object().unwrap() {
        if key.starts_with("drive.") {
            assert_eq!(
                start(key).parse::<f64>().unwrap(),
                v.as_f64().unwrap(),
                "{key}"
            );
            compared += 1;
        }
    }
    for (key, v) in fit["subject"].as_object().unwrap() {
        let s = start(key);
        match v {
            serde_json::Value::String(name) => {
                let code = match name.as_str() {
                    "Male" | "Standing" => "0",
                    "Female" | "Sitting" => "1",
                    "Supine" => "2",
                    other => panic!("{key} = {other}"),
                };
                assert_eq!(s, code, "{key}");
            }
            _ => assert_eq!(s.parse::<f64>().unwrap(), v.as_f64().unwrap(), "{key}"),
        }
        compared += 1;
    }
    let model = &fit["model"];
    assert_eq!(start("scene.level_of_detail"), "0");
    assert_eq!(start("grid.rows"), model["grid.rows"].to_string());
    assert_eq!(start("grid.cols"), model["grid.cols"].to_string());
    // The fit's skin reference is in resources/subject/, named relative to resources/.
    let reference = start("slp.reference");
    assert_eq!(reference, "subject/result_reference.csv");
    assert!(
        built()
            .unpacked
            .join("resources")
            .join(&reference)
            .is_file()
    );
    assert!(compared >= 14, "{compared}");
    // The fitted drive is not the generic start (the fit moved it).
    assert_ne!(
        start("drive.ribs.amplitude"),
        generic["drive.ribs.amplitude"].1["start"]
    );
    // The fit's report is in documentation/.
    for f in [
        "documentation/fit.json",
        "documentation/fit_report.png",
        "documentation/index.html",
    ] {
        assert!(built().unpacked.join(f).is_file(), "{f}");
    }
}

#[test]
fn only_the_fits_grid_markers_are_outputs() {
    let (_, vars) = variables(&model_description());
    let fit = fit_json();
    let n =
        fit["model"]["grid.rows"].as_u64().unwrap() * fit["model"]["grid.cols"].as_u64().unwrap();
    let markers = vars.keys().filter(|k| k.starts_with("marker[")).count() as u64;
    assert_eq!(markers, 3 * n);
    assert!(vars.contains_key(&format!("marker[{n}].z")));
    assert!(!vars.contains_key(&format!("marker[{}].x", n + 1)));
    // The grid is fixed at the fit's: min = max = start.
    let rows = &vars["grid.rows"].1;
    assert_eq!(rows["min"], rows["start"]);
    assert_eq!(rows["max"], rows["start"]);
    // The ModelStructure indices point at outputs of this description (1-based).
    let (generic_guid, generic) = variables(&breathing_torso::fmi::xml::model_description());
    assert_eq!(generic_guid, table().guid());
    assert_eq!(
        generic.keys().filter(|k| k.starts_with("marker[")).count(),
        3 * 60
    );
}

#[test]
fn the_ssv_names_the_fmus_parameters_with_their_types() {
    let b = built();
    let text = std::fs::read_to_string(&b.ssv).unwrap();
    assert!(text.contains(ssv::SSV_NAMESPACE));
    let set = ssv::parse(&text, &b.ssv.display().to_string()).unwrap();
    let (_, vars) = variables(&model_description());
    let (_, generic) = variables(&breathing_torso::fmi::xml::model_description());
    assert!(set.len() >= 17, "{}", set.len());
    for (name, value) in &set {
        let ty = match value {
            Value::Real(_) => "Real",
            Value::Integer(_) => "Integer",
            Value::Boolean(_) => "Boolean",
            Value::String(_) => "String",
        };
        for (which, v) in [("personalised", &vars), ("generic", &generic)] {
            let (tag, attrs) = v
                .get(name)
                .unwrap_or_else(|| panic!("{name} not in the {which} FMU"));
            assert_eq!(tag, ty, "{name} in the {which} FMU");
            assert_eq!(attrs["causality"], "parameter", "{name}");
        }
        // Same value as the personalised FMU's start (paths aside: absolute in the .ssv).
        let start = &vars[name].1["start"];
        match value {
            Value::Real(x) => assert_eq!(start.parse::<f64>().unwrap(), *x, "{name}"),
            Value::Integer(i) => assert_eq!(start, &i.to_string(), "{name}"),
            Value::Boolean(x) => assert_eq!(start, &x.to_string(), "{name}"),
            Value::String(s) if s.is_empty() => assert_eq!(start, s),
            Value::String(s) => {
                assert!(
                    Path::new(s).is_absolute() && Path::new(s).is_file(),
                    "{name} = {s}"
                );
                assert!(
                    s.ends_with(start.trim_start_matches("subject/")),
                    "{s} vs {start}"
                );
            }
        }
    }
    // The FMU's own copy of the set, which the library reads at instantiation.
    let inner = b.unpacked.join("resources").join(PARAMETERS);
    let inner = ssv::parse(&std::fs::read_to_string(&inner).unwrap(), "inner").unwrap();
    assert_eq!(inner.len(), set.len());
}

fn lung_and_marker(inst: &mut Instance, steps: usize) -> Vec<[f64; 2]> {
    let t = inst.table();
    let vrs = [
        t.by_name("volume.lung").unwrap().vr,
        t.by_name("marker[1].x").unwrap().vr,
    ];
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    let h = 0.05;
    let mut out = Vec::new();
    for k in 0..steps {
        assert_eq!(inst.do_step("fmi2DoStep", k as f64 * h, h), Status::Ok);
        let mut v = [0.0; 2];
        assert_eq!(inst.get_real("fmi2GetReal", &vrs, &mut v), Status::Ok);
        out.push(v);
    }
    out
}

fn generic_with(set: &[(String, Value)]) -> Instance {
    let mut inst = Instance::new(&FMI2, "generic", None, None, false);
    let t = table();
    for (name, value) in set {
        let vr = [t.by_name(name).unwrap().vr];
        let status = match value {
            Value::Real(x) => inst.set_real("fmi2SetReal", &vr, &[*x]),
            Value::Integer(i) => inst.set_integer("fmi2SetInteger", &vr, &[*i]),
            Value::Boolean(b) => inst.set_boolean("fmi2SetBoolean", &vr, &[i32::from(*b)]),
            Value::String(s) => inst.set_string("fmi2SetString", &vr, std::slice::from_ref(s)),
        };
        assert_eq!(status, Status::Ok, "{name}");
    }
    inst
}

#[test]
fn the_personalised_fmu_runs_as_the_generic_one_with_the_ssv_applied() {
    let b = built();
    let resources = b.unpacked.join("resources");
    let personal_table = table_in(Some(&resources)).unwrap();
    let (guid, _) = variables(&model_description());
    assert_eq!(
        personal_table.guid(),
        guid,
        "the library computes the description's GUID"
    );
    let mut personal = Instance::with_table(
        &FMI2,
        "personal",
        Some(resources.clone()),
        None,
        false,
        personal_table,
    )
    .unwrap();
    let set = ssv::parse(&std::fs::read_to_string(&b.ssv).unwrap(), "set").unwrap();
    let mut generic = generic_with(&set);
    let steps = 40; // 2 s, about half a breath of the fitted drive
    let a = lung_and_marker(&mut personal, steps);
    let g = lung_and_marker(&mut generic, steps);
    for (k, (a, g)) in a.iter().zip(&g).enumerate() {
        for i in 0..2 {
            assert!(
                (a[i] - g[i]).abs() <= 1e-12 * g[i].abs(),
                "step {k}, output {i}: {} vs {}",
                a[i],
                g[i]
            );
        }
    }
    // The lung breathes and the skin reference matters: without it the marker differs.
    let swing = g.iter().map(|v| v[0]).fold(f64::NEG_INFINITY, f64::max)
        - g.iter().map(|v| v[0]).fold(f64::INFINITY, f64::min);
    assert!(swing > 0.05, "tidal swing {swing} L");
    let without: Vec<(String, Value)> = set
        .iter()
        .map(|(n, v)| match n.as_str() {
            "slp.reference" => (n.clone(), Value::String(String::new())),
            _ => (n.clone(), v.clone()),
        })
        .collect();
    let plain = lung_and_marker(&mut generic_with(&without), 1);
    assert!(
        (plain[0][1] - g[0][1]).abs() > 1e-6,
        "{} vs {}",
        plain[0][1],
        g[0][1]
    );
    // A missing skin reference in resources/ is an error naming the parameter.
    let broken = b.unpacked.parent().unwrap().join("broken");
    let _ = std::fs::remove_dir_all(&broken);
    std::fs::create_dir_all(broken.join("subject")).unwrap();
    std::fs::copy(resources.join(PARAMETERS), broken.join(PARAMETERS)).unwrap();
    let e = Instance::with_table(
        &FMI2,
        "broken",
        Some(broken.clone()),
        None,
        false,
        personal_table,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("slp.reference") && e.contains("subject/result_reference.csv"),
        "{e}"
    );
}

/// The laws a fit ran under travel into its personalised FMU: a fit result recording the hill
/// law, gravity acting at 9 m/s^2 and no tone builds an FMU with those start values; the
/// bundled fit (default laws) records the defaults.
#[test]
fn the_fits_laws_are_the_fmus() {
    let built = built();
    let fit = fit_json();
    let model = &fit["model"];
    assert_eq!(model["muscle_law"], serde_json::json!(0));
    assert_eq!(model["gravity_loads"], serde_json::json!(0));
    assert_eq!(model["postural_tone"], serde_json::json!(1));
    let (_, vars) = variables(&model_description());
    assert_eq!(vars["muscle_law"].1["start"], "0");
    let mut v = fit.clone();
    v["model"]["muscle_law"] = serde_json::json!(1);
    v["model"]["gravity"] = serde_json::json!(9.0);
    v["model"]["gravity_loads"] = serde_json::json!(1);
    v["model"]["postural_tone"] = serde_json::json!(0);
    // beside the bundled fit, where its skin reference is found
    let laws = built.fit.with_file_name("laws.json");
    std::fs::write(&laws, v.to_string()).unwrap();
    let fmu = dir().join("laws.fmu");
    let (ok, msg) = torso(&[
        "fmu",
        "build",
        "--subject",
        laws.to_str().unwrap(),
        "--out",
        fmu.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let mut zip = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
    let mut xml = String::new();
    zip.by_name("modelDescription.xml")
        .unwrap()
        .read_to_string(&mut xml)
        .unwrap();
    let (_, vars) = variables(&xml);
    let start = |name: &str| vars[name].1["start"].clone();
    assert_eq!(start("muscle_law"), "1");
    assert_eq!(start("gravity").parse::<f64>().unwrap(), 9.0);
    assert_eq!(start("gravity_loads"), "1");
    assert_eq!(start("postural_tone"), "0");
}

#[test]
fn files_that_are_not_fit_results_are_refused_naming_the_key() {
    let built = built();
    let dir = dir().join("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let mut fit = String::new();
    std::fs::File::open(&built.fit)
        .unwrap()
        .read_to_string(&mut fit)
        .unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&fit).unwrap();
    v.as_object_mut().unwrap().remove("model");
    let no_model = dir.join("no_model.json");
    std::fs::write(&no_model, v.to_string()).unwrap();
    let mut w: serde_json::Value = serde_json::from_str(&fit).unwrap();
    w["subject"].as_object_mut().unwrap().remove("subject.mass");
    let no_mass = dir.join("no_mass.json");
    std::fs::write(&no_mass, w.to_string()).unwrap();
    let mut x: serde_json::Value = serde_json::from_str(&fit).unwrap();
    x["drive.frequency"] = serde_json::json!(9.0);
    let fast = dir.join("fast.json");
    std::fs::write(&fast, x.to_string()).unwrap();
    let not_json = dir.join("not.json");
    std::fs::write(&not_json, "{\"drive.frequency\": ").unwrap();
    for (file, expect) in [
        (&no_model, "missing key `model`"),
        (&no_mass, "missing key `subject.mass` in `subject`"),
        (&fast, "drive.frequency"),
        (&not_json, "not.json:1:"),
    ] {
        let out = dir.join("x.fmu");
        let (ok, msg) = torso(&[
            "fmu",
            "build",
            "--subject",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(!ok, "{msg}");
        assert!(msg.contains(expect), "{msg}");
        if file != &not_json {
            assert!(msg.contains(&file.display().to_string()), "{msg}");
        }
    }
}

#[test]
fn a_subject_on_another_grid_has_that_grids_markers() {
    use breathing_torso::fmi::variables::{Personalisation, Table};
    let p = |rows: i32, cols: i32| Personalisation {
        starts: vec![
            ("grid.rows".into(), Value::Integer(rows)),
            ("grid.cols".into(), Value::Integer(cols)),
            ("subject.age".into(), Value::Real(52.5)),
        ],
        markers: None,
    };
    let t = Table::personalised(&p(4, 3)).unwrap();
    let markers: Vec<&str> = t
        .variables()
        .iter()
        .map(|v| v.name.as_str())
        .filter(|n| n.starts_with("marker["))
        .collect();
    assert_eq!(markers.len(), 36);
    assert_eq!(markers.last(), Some(&"marker[12].z"));
    assert_ne!(t.guid(), table().guid());
    assert_ne!(t.guid(), Table::personalised(&p(3, 4)).unwrap().guid());
    let (guid, vars) = variables(&breathing_torso::fmi::xml::model_description_for(&t));
    assert_eq!(guid, t.guid());
    assert_eq!(vars["subject.age"].1["start"], "52.5");
    assert_eq!(vars["grid.cols"].1["max"], "3");
    // The grid cannot be set to another size in that FMU.
    let mut inst = Instance::with_table(
        &FMI2,
        "grid",
        None,
        None,
        false,
        breathing_torso::fmi::variables::personalised_table(&p(4, 3)).unwrap(),
    )
    .unwrap();
    assert_eq!(inst.config().scene.grid_rows, 4);
    let vr = [t.by_name("grid.rows").unwrap().vr];
    assert_ne!(inst.set_integer("fmi2SetInteger", &vr, &[10]), Status::Ok);
    // Values outside a parameter's range, of the wrong type or for a non-parameter are refused.
    for (name, v) in [
        ("subject.age", Value::Real(500.0)),
        ("subject.age", Value::Integer(50)),
        ("volume.lung", Value::Real(3.0)),
        ("no.such", Value::Real(3.0)),
    ] {
        let e = Table::personalised(&Personalisation {
            starts: vec![(name.into(), v)],
            markers: None,
        })
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains(name), "{e}");
    }
}

/// Copies the folder `from` to `to` (created), files and subfolders.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let p = entry.unwrap().path();
        let target = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &target);
        } else {
            std::fs::copy(&p, &target).unwrap();
        }
    }
}

/// A copy of the unpacked personalised FMU at `dir()/<name>` (replacing any earlier one).
fn unpacked_copy(name: &str) -> PathBuf {
    let to = dir().join(name);
    let _ = std::fs::remove_dir_all(&to);
    copy_dir(&built().unpacked, &to);
    to
}

/// Instances made through the exported functions, as an importer makes them, with a logger
/// that records (status, category, message). x86-64 only: the logger is a Rust function
/// called through the variadic C type (tests/fmi_status.rs explains why that is sound there).
#[cfg(target_arch = "x86_64")]
mod exported {
    use breathing_torso::fmi::ffi::*;
    use breathing_torso::fmi::types::fmi2Status::{self, *};
    use breathing_torso::fmi::types::*;
    use std::ffi::{CStr, CString};
    use std::os::raw::{c_char, c_int, c_void};
    use std::path::Path;
    use std::ptr::null_mut;
    use std::sync::Mutex;

    pub type Messages = Mutex<Vec<(c_int, String, String)>>;

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

    pub struct Fmu {
        pub c: fmi2Component,
        pub log: Box<Messages>,
    }

    /// The `file:` URI of a folder (the test folders need no escapes).
    pub fn uri(dir: &Path) -> String {
        format!("file://{}", dir.display())
    }

    /// `fmi2Instantiate` with `guid` and the resource location `resources`: the instance, or
    /// the messages logged when it returned NULL.
    pub fn instantiate(guid: &str, resources: &str) -> Result<Fmu, Vec<String>> {
        let log: Box<Messages> = Box::default();
        // SAFETY: the same arguments in the same registers on x86-64.
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
        let guid = CString::new(guid).unwrap();
        let resources = CString::new(resources).unwrap();
        let c = unsafe {
            fmi2Instantiate(
                c"personal".as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                resources.as_ptr(),
                &callbacks,
                0,
                0,
            )
        };
        if c.is_null() {
            return Err(log.lock().unwrap().iter().map(|m| m.2.clone()).collect());
        }
        Ok(Fmu { c, log })
    }

    impl Fmu {
        /// The last message logged, if any.
        pub fn last_message(&self) -> String {
            let log = self.log.lock().unwrap();
            log.last().map(|m| m.2.clone()).unwrap_or_default()
        }

        pub fn set_string(&mut self, vr: u32, value: &str) -> fmi2Status {
            let s = CString::new(value).unwrap();
            unsafe { fmi2SetString(self.c, [vr].as_ptr(), 1, [s.as_ptr()].as_ptr()) }
        }

        /// Setup at t = 0, initialization mode in and out.
        pub fn start(&mut self) {
            unsafe {
                assert_eq!(fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
                assert_eq!(fmi2EnterInitializationMode(self.c), fmi2OK);
                assert_eq!(
                    fmi2ExitInitializationMode(self.c),
                    fmi2OK,
                    "{}",
                    self.last_message()
                );
            }
        }

        /// Steps `k0..k1` of `h` seconds, reading `vrs` after each.
        pub fn steps(&mut self, k0: usize, k1: usize, h: f64, vrs: &[u32]) -> Vec<Vec<f64>> {
            (k0..k1)
                .map(|k| {
                    let mut out = vec![0.0; vrs.len()];
                    unsafe {
                        assert_eq!(fmi2DoStep(self.c, k as f64 * h, h, 1), fmi2OK);
                        assert_eq!(
                            fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()),
                            fmi2OK
                        );
                    }
                    out
                })
                .collect()
        }

        /// The instance's state, serialized.
        pub fn serialize(&mut self) -> Vec<u8> {
            unsafe {
                let mut state: fmi2FMUstate = null_mut();
                assert_eq!(fmi2GetFMUstate(self.c, &mut state), fmi2OK);
                let mut size = 0usize;
                assert_eq!(fmi2SerializedFMUstateSize(self.c, state, &mut size), fmi2OK);
                let mut bytes = vec![0u8; size];
                assert_eq!(
                    fmi2SerializeFMUstate(self.c, state, bytes.as_mut_ptr() as *mut fmi2Byte, size),
                    fmi2OK
                );
                assert_eq!(fmi2FreeFMUstate(self.c, &mut state), fmi2OK);
                bytes
            }
        }

        /// Deserializes `bytes` and sets the state: the status of fmi2SetFMUstate.
        pub fn restore(&mut self, bytes: &[u8]) -> fmi2Status {
            unsafe {
                let mut state: fmi2FMUstate = null_mut();
                let status = fmi2DeSerializeFMUstate(
                    self.c,
                    bytes.as_ptr() as *const fmi2Byte,
                    bytes.len(),
                    &mut state,
                );
                assert_eq!(status, fmi2OK, "{}", self.last_message());
                let status = fmi2SetFMUstate(self.c, state);
                assert_eq!(fmi2FreeFMUstate(self.c, &mut state), fmi2OK);
                status
            }
        }
    }

    impl Drop for Fmu {
        fn drop(&mut self) {
            unsafe { fmi2FreeInstance(self.c) };
        }
    }
}

/// FMI 2.0 lets a state serialized by one instance be restored in another, and importers
/// unpack an FMU to a fresh folder for every run: a state saved in a copy unpacked in `u1`
/// restores in a copy unpacked in `u2` (with `u1` gone), in an initialised instance and in a
/// freshly instantiated one, and both continue exactly as the saving instance did. A state
/// saved with another skin reference is still refused, naming the parameter as given.
#[cfg(target_arch = "x86_64")]
#[test]
fn a_saved_state_restores_in_a_copy_unpacked_elsewhere() {
    use exported::{instantiate, uri};
    let (guid, _) = variables(&model_description());
    let u1 = unpacked_copy("u1");
    let u2 = unpacked_copy("u2");
    let t = table_in(Some(&u2.join("resources"))).unwrap();
    let vrs = [
        t.by_name("volume.lung").unwrap().vr,
        t.by_name("marker[1].x").unwrap().vr,
        t.by_name("marker[2].z").unwrap().vr,
    ];
    let h = 0.05;
    let (bytes, expected) = {
        let mut a = instantiate(&guid, &uri(&u1.join("resources"))).unwrap();
        a.start();
        a.steps(0, 10, h, &vrs);
        let bytes = a.serialize();
        (bytes, a.steps(10, 30, h, &vrs))
    };
    std::fs::remove_dir_all(&u1).unwrap();
    // The state names the skin reference as the FMU does, relative to resources/.
    let text = String::from_utf8_lossy(&bytes);
    assert!(!text.contains(&*u1.to_string_lossy()), "{text}");
    let resources2 = uri(&u2.join("resources"));
    let mut initialised = instantiate(&guid, &resources2).unwrap();
    initialised.start();
    assert_eq!(
        initialised.restore(&bytes),
        fmi2OK,
        "{}",
        initialised.last_message()
    );
    assert_eq!(initialised.steps(10, 30, h, &vrs), expected);
    let mut fresh = instantiate(&guid, &resources2).unwrap();
    assert_eq!(fresh.restore(&bytes), fmi2OK, "{}", fresh.last_message());
    assert_eq!(fresh.steps(10, 30, h, &vrs), expected);

    // Another skin reference (same content, another name) is another fixed parameter.
    let subject = u2.join("resources").join("subject");
    std::fs::copy(
        subject.join("result_reference.csv"),
        subject.join("other_reference.csv"),
    )
    .unwrap();
    let reference = t.by_name("slp.reference").unwrap().vr;
    let other = {
        let mut c = instantiate(&guid, &resources2).unwrap();
        assert_eq!(
            c.set_string(reference, "subject/other_reference.csv"),
            fmi2OK
        );
        c.start();
        c.steps(0, 2, h, &vrs);
        c.serialize()
    };
    let mut b = instantiate(&guid, &resources2).unwrap();
    b.start();
    assert_eq!(b.restore(&other), fmi2Error);
    let why = b.last_message();
    assert!(
        why.contains(
            "`slp.reference` \"subject/result_reference.csv\" here, \
             \"subject/other_reference.csv\" in the state"
        ),
        "{why}"
    );
    // The refused state changed nothing.
    assert_eq!(
        b.steps(0, 1, h, &vrs),
        initialised_first_step(&guid, &resources2, h, &vrs)
    );
}

#[cfg(target_arch = "x86_64")]
fn initialised_first_step(guid: &str, resources: &str, h: f64, vrs: &[u32]) -> Vec<Vec<f64>> {
    let mut f = exported::instantiate(guid, resources).unwrap();
    f.start();
    f.steps(0, 1, h, vrs)
}

/// When the GUID does not match, `fmi2Instantiate` says whether a parameter set was looked
/// for, where, and what it gave; notes on the way (an unusable resource location) are logged
/// before it returns NULL; a bad value in the set is named with its line and column.
#[cfg(target_arch = "x86_64")]
#[test]
fn instantiation_errors_say_where_the_parameter_set_was_looked_for() {
    use exported::{instantiate, uri};
    let (guid, _) = variables(&model_description());
    // The set missing: the generic table, and the path looked at.
    let missing = unpacked_copy("missing_set");
    let set = missing.join("resources").join(PARAMETERS);
    std::fs::remove_file(&set).unwrap();
    let log = instantiate(&guid, &uri(&missing.join("resources")))
        .err()
        .unwrap();
    let last = log.last().unwrap();
    assert!(!last.contains("  "), "{last}");
    assert!(
        last.contains(&format!("GUID {guid} does not match"))
            && last.contains(&format!("no parameter set was found at {}", set.display()))
            && last.contains(&format!("the generic FMU, GUID {}", table().guid())),
        "{last}"
    );
    // The set edited: found, and the GUID it gives.
    let edited = unpacked_copy("edited_set");
    let set = edited.join("resources").join(PARAMETERS);
    let mut values = ssv::parse(&std::fs::read_to_string(&set).unwrap(), "set").unwrap();
    for (name, v) in values.iter_mut() {
        if name == "subject.age" {
            *v = Value::Real(77.0);
        }
    }
    std::fs::write(&set, ssv::write("subject", &values)).unwrap();
    let edited_guid = table_in(Some(&edited.join("resources")))
        .unwrap()
        .guid()
        .to_string();
    assert_ne!(edited_guid, guid);
    let log = instantiate(&guid, &uri(&edited.join("resources")))
        .err()
        .unwrap();
    let last = log.last().unwrap();
    assert!(!last.contains("  "), "{last}");
    assert!(
        last.contains(&format!(
            "the parameter set {} makes this a personalised FMU with GUID {edited_guid}",
            set.display()
        )),
        "{last}"
    );
    // An unusable resource location: the note, then the message saying no set was looked for.
    let log = instantiate(&guid, "http://example.invalid/resources")
        .err()
        .unwrap();
    assert_eq!(log.len(), 2, "{log:?}");
    assert!(
        log[0].contains("resources unavailable") && log[0].contains("fmuResourceLocation"),
        "{log:?}"
    );
    assert!(
        log[1].contains("no parameter set was looked for"),
        "{log:?}"
    );
    // A value that is not a number: the set's path, line and column.
    let text = std::fs::read_to_string(&set).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // The value of subject.age is on the line after its ssv:Parameter.
    let i = 1 + lines
        .iter()
        .position(|l| l.contains("name=\"subject.age\""))
        .unwrap();
    let col = lines[i].find("value=").unwrap();
    lines[i] = format!("{}value=\"old\"/>", &lines[i][..col]);
    std::fs::write(&set, lines.join("\n")).unwrap();
    let (line, col) = (i + 1, col + 1);
    let log = instantiate(&guid, &uri(&edited.join("resources")))
        .err()
        .unwrap();
    let last = log.last().unwrap();
    assert!(
        last.contains(&format!("{}:{line}:{col}: `subject.age`", set.display())),
        "{last}"
    );
}

/// `torso fmu build --subject FIT` without `--out` names the FMU after the fit result,
/// `fmu/<stem>.fmu` with `fmu/<stem>.ssv` beside it, and leaves the generic FMU's name alone.
#[test]
fn without_out_the_fmu_is_named_after_the_fit() {
    let fit = &built().fit;
    let cwd = dir().join("default_name");
    let _ = std::fs::remove_dir_all(&cwd);
    std::fs::create_dir_all(&cwd).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["fmu", "build", "--subject", fit.to_str().unwrap()])
        .current_dir(&cwd)
        .output()
        .unwrap();
    let msg =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{msg}");
    assert_eq!(fit.file_stem().unwrap(), "result");
    let fmu = cwd.join("fmu").join("result.fmu");
    assert!(msg.contains("wrote fmu/result.fmu"), "{msg}");
    let mut zip = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
    assert!(zip.by_name(&format!("resources/{PARAMETERS}")).is_ok());
    assert!(cwd.join("fmu").join("result.ssv").is_file());
    assert!(!cwd.join("fmu").join("BreathingTorso.fmu").exists());
}

/// One short fit of the bundled laboratory recording of the 30-marker chest set (named
/// markers, level of detail 0), made into a personalised FMU: (fit result, unpacked FMU).
fn named_built() -> &'static (PathBuf, PathBuf) {
    static BUILT: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    BUILT.get_or_init(|| {
        // Beside dir(), which built() empties.
        let dir = std::env::temp_dir().join(format!("fmi_personal_named_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let fit = dir.join("fit.json");
        let recording = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/data/recordings/chest30_lab.c3d"
        );
        let (ok, msg) = torso(&[
            "fit",
            "--slp",
            recording,
            "--lod",
            "0",
            "--max-evals",
            "12",
            "--threads",
            "1",
            "--out",
            fit.to_str().unwrap(),
        ]);
        assert!(ok, "{msg}");
        let fmu = dir.join("named.fmu");
        let (ok, msg) = torso(&[
            "fmu",
            "build",
            "--subject",
            fit.to_str().unwrap(),
            "--out",
            fmu.to_str().unwrap(),
        ]);
        assert!(ok, "{msg}");
        let unpacked = dir.join("unpacked");
        let mut zip = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
        zip.extract(&unpacked).unwrap();
        (fit, unpacked)
    })
}

/// A personalised FMU of a fit of named markers has exactly the set's bound markers as
/// outputs, named by their labels, in the set's order at the grid's value references; the
/// bindings travel in its resources, and its GUID follows them.
#[test]
fn a_named_marker_sets_fmu_has_its_labels_as_outputs() {
    use breathing_torso::fmi::personal::MARKERS;
    use breathing_torso::fmi::variables::{Personalisation, Table, marker_vr};
    let (fit, unpacked) = named_built();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fit).unwrap()).unwrap();
    let labels: Vec<String> = json["marker_set"]["labels_bound"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap().to_string())
        .collect();
    assert!(
        labels.len() >= 20,
        "most of chest30's 30 markers bind: {labels:?}"
    );
    let md = std::fs::read_to_string(unpacked.join("modelDescription.xml")).unwrap();
    let (guid, vars) = variables(&md);
    let mut markers: Vec<(u32, String)> = vars
        .iter()
        .filter(|(n, _)| n.starts_with("marker"))
        .map(|(n, (_, a))| (a["valueReference"].parse().unwrap(), n.clone()))
        .collect();
    markers.sort();
    let expected: Vec<(u32, String)> = labels
        .iter()
        .enumerate()
        .flat_map(|(i, l)| {
            ["x", "y", "z"]
                .iter()
                .enumerate()
                .map(move |(a, x)| (marker_vr(i as u16, a as u8), format!("marker.{l}.{x}")))
        })
        .collect();
    assert_eq!(markers, expected);
    // The set travels in resources/ and rebuilds the same table (and GUID).
    assert!(unpacked.join("resources").join(MARKERS).is_file());
    let t = table_in(Some(&unpacked.join("resources"))).unwrap();
    assert_eq!(t.guid(), guid);
    assert_eq!(t.marker_set().unwrap().labels, labels);
    // Another binding of one marker is another interface.
    let p = t.personalisation().unwrap();
    let mut moved = (**p.markers.as_ref().unwrap()).clone();
    moved.bindings[0].barycentric = [1.0, 0.0, 0.0];
    let other = Table::personalised(&Personalisation {
        starts: p.starts.clone(),
        markers: Some(moved.into()),
    })
    .unwrap();
    assert_ne!(other.guid(), t.guid());
    assert_ne!(t.guid(), table().guid());
}

/// Through the exported functions: the FMU's marker outputs are the native model's positions
/// of the set's markers (the same subject, drive and bindings, built without the FMU layer),
/// and each is the point at its barycentric binding on the deformed skin.
#[cfg(target_arch = "x86_64")]
#[test]
fn a_named_marker_sets_fmu_reads_the_markers_off_the_skin() {
    use breathing_torso::anatomy::skin::MarkerSet;
    use breathing_torso::fmi::personal::from_fit_json;
    use breathing_torso::fmi::variables::{Role, start_config};
    use exported::{instantiate, uri};
    use std::sync::Arc;
    let (fit, unpacked) = named_built();
    let t = table_in(Some(&unpacked.join("resources"))).unwrap();
    let set = t.marker_set().unwrap().clone();
    let vrs: Vec<u32> = set
        .labels
        .iter()
        .flat_map(|l| ["x", "y", "z"].map(|a| t.by_name(&format!("marker.{l}.{a}")).unwrap().vr))
        .collect();
    let mut fmu = instantiate(t.guid(), &uri(&unpacked.join("resources"))).unwrap();
    fmu.start();
    let h = 0.25;
    let got = fmu.steps(0, 8, h, &vrs);

    // The native model: the fit's parameters on the generic start configuration, the set's
    // bindings read back from the fit result.
    let mut config = start_config();
    for (name, value) in from_fit_json(fit).unwrap().generic {
        let Role::Parameter(p) = table().by_name(&name).unwrap().role else {
            panic!("{name}")
        };
        p.set(&mut config, value).unwrap();
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fit).unwrap()).unwrap();
    let native_set =
        MarkerSet::from_bindings_json("recording", &json["marker_set"]["bindings"], "fit").unwrap();
    assert_eq!(native_set.labels, set.labels);
    let mut native = breathing_torso::Torso::new(config).unwrap();
    native.set_marker_set(Some(Arc::new(native_set.clone())));
    let mut skin = Vec::new();
    let mut moved = 0.0f64;
    let (mut worst_native, mut worst_skin) = (0.0f64, 0.0f64);
    for (k, row) in got.iter().enumerate() {
        native.advance_to((k + 1) as f64 * h).unwrap();
        let positions = native.markers().unwrap().to_vec();
        native.skin_vertices(&mut skin).unwrap();
        let triangles = native.marker_model().unwrap().skin().triangles.clone();
        let on_skin = native_set.positions(&skin, &triangles);
        for (i, p) in positions.iter().enumerate() {
            for a in 0..3 {
                let fmu_value = row[3 * i + a];
                worst_native = worst_native.max((fmu_value - p[a]).abs());
                worst_skin = worst_skin.max((fmu_value - on_skin[i][a]).abs());
                assert!(
                    (fmu_value - p[a]).abs() <= 1e-12 * p[a].abs().max(1e-3),
                    "{} axis {a} at step {k}: FMU {fmu_value}, native {}",
                    set.labels[i],
                    p[a]
                );
                // 1 um: the bound point blended alone against the whole skin's blend.
                assert!(
                    (fmu_value - on_skin[i][a]).abs() <= 1e-6,
                    "{} axis {a}: FMU {fmu_value}, on the skin {}",
                    set.labels[i],
                    on_skin[i][a]
                );
            }
            moved = moved.max((row[3 * i] - got[0][3 * i]).abs());
        }
    }
    eprintln!(
        "{} markers: largest difference FMU - native {worst_native:e} m, FMU - skin at the binding {worst_skin:e} m, largest x excursion {moved:e} m",
        set.len()
    );
    assert!(moved > 1e-4, "the markers move with breathing ({moved} m)");
}

/// A named set's fit result without its bindings, or with a bad one, is refused naming the
/// file and the entry; a personalised FMU whose `markers.json` was damaged is refused at
/// `fmi2Instantiate` naming the file, and one whose binding was edited no longer matches its
/// GUID.
#[cfg(target_arch = "x86_64")]
#[test]
fn a_named_sets_bindings_are_checked_in_the_fit_and_in_the_fmu() {
    use breathing_torso::fmi::personal::MARKERS;
    use exported::{instantiate, uri};
    let (fit, unpacked) = named_built();
    let dir = std::env::temp_dir().join(format!("fmi_personal_named_bad_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fit).unwrap()).unwrap();
    let mut no_bindings = json.clone();
    no_bindings["marker_set"]
        .as_object_mut()
        .unwrap()
        .remove("bindings");
    let mut bad_bary = json.clone();
    bad_bary["marker_set"]["bindings"][2]["barycentric"] = serde_json::json!([0.5, 0.6, -0.1]);
    for (name, value, expect) in [
        (
            "no_bindings.json",
            &no_bindings,
            "missing key `bindings` in `marker_set`",
        ),
        (
            "bad_bary.json",
            &bad_bary,
            "barycentric coordinates >= 0 summing to 1",
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, value.to_string()).unwrap();
        let (ok, msg) = torso(&[
            "fmu",
            "build",
            "--subject",
            file.to_str().unwrap(),
            "--out",
            dir.join("x.fmu").to_str().unwrap(),
        ]);
        assert!(!ok, "{msg}");
        assert!(
            msg.contains(expect) && msg.contains(&file.display().to_string()),
            "{msg}"
        );
    }
    let good_guid = table_in(Some(&unpacked.join("resources")))
        .unwrap()
        .guid()
        .to_string();
    let copy = dir.join("copy");
    copy_dir(unpacked, &copy);
    let markers = copy.join("resources").join(MARKERS);
    let text = std::fs::read_to_string(&markers).unwrap();
    std::fs::write(&markers, &text[..text.len() / 2]).unwrap();
    let messages = instantiate(&good_guid, &uri(&copy.join("resources")))
        .err()
        .unwrap()
        .join("\n");
    assert!(
        messages.contains(&markers.display().to_string()),
        "{messages}"
    );
    let mut edited: serde_json::Value = serde_json::from_str(&text).unwrap();
    edited["bindings"][0]["triangle"] = serde_json::json!(0);
    std::fs::write(&markers, edited.to_string()).unwrap();
    let messages = instantiate(&good_guid, &uri(&copy.join("resources")))
        .err()
        .unwrap()
        .join("\n");
    assert!(messages.contains("GUID"), "{messages}");
}
