//! The model on a prepared subject mesh: a subject's skin and cavity made from the generated
//! ones (scaled by 1.05 about the skin's centroid, 1 mm of noise, the cavity exported at a
//! finer resolution than the model's layout) run through the preparation pipeline of
//! `torso mesh prepare`, loaded through `subject.mesh_dir`; the model breathes within the
//! physiology ranges, left and right stay paired, and bad directories give clear errors
//! through the facade, the FMI layer and the C ABI.

mod mesh_support;

use breathing_torso::anatomy::skin::Skin;
use breathing_torso::anatomy::{Anatomy, Subject, SubjectMesh};
use breathing_torso::capi::*;
use breathing_torso::fmi::instance::{FmuState, Instance, LogSink};
use breathing_torso::fmi::table;
use breathing_torso::fmi::{FMI2, Status};
use breathing_torso::mesh::{PrepareOptions, TriMesh, io, pipeline};
use breathing_torso::model::run::{BreathSummary, run, summarise};
use breathing_torso::model::{Config, Drive};
use breathing_torso::{Error, Quantity, Torso};
use mesh_support::Rng;
use nalgebra::{Point3, Vector3};
use std::cell::RefCell;
use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::OnceLock;

/// Scale of the subject's surfaces relative to the generated ones.
const SCALE: f64 = 1.05;
/// Noise amplitude [m] along the vertex normals.
const NOISE: f64 = 0.001;
/// Level of detail of the model in these tests.
const LOD: u32 = 0;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("torso_mesh_model_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Scales `m` about `centre` and moves each vertex along its normal by uniform noise.
fn perturb(m: &mut TriMesh, centre: &Point3<f64>, rng: &mut Rng) {
    m.scale(centre, &Vector3::repeat(SCALE));
    let normals = m.vertex_normals();
    for (p, n) in m.vertices.iter_mut().zip(&normals) {
        *p += n * (NOISE * rng.signed());
    }
}

/// The generated skin and the generated cavity at level of detail 1 (642 vertices), written
/// as OBJ files, perturbed, and prepared exactly as `torso mesh prepare` does.
fn prepared_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = scratch("subject");
        let subject = Subject::default();
        let anatomy = Anatomy::build(&subject, 1).unwrap();
        let skin = Skin::for_anatomy(&anatomy, &Default::default()).unwrap();
        let mut skin = TriMesh::new(skin.vertices, skin.triangles).unwrap();
        let ab = &anatomy.abdomen;
        let mut cavity = TriMesh::new(
            ab.anchor.iter().map(|&a| anatomy.rest(a)).collect(),
            ab.triangles.clone(),
        )
        .unwrap();
        let centre = skin.centroid();
        let mut rng = Rng(20130401);
        perturb(&mut skin, &centre, &mut rng);
        perturb(&mut cavity, &centre, &mut rng);
        let (s, a) = (dir.join("in_skin.obj"), dir.join("in_abdomen.obj"));
        io::write(&skin, &s).unwrap();
        io::write(&cavity, &a).unwrap();
        let (prepared, report) = pipeline::prepare_all(
            io::read(&s).unwrap(),
            Some(io::read(&a).unwrap()),
            Vec::new(),
            &PrepareOptions::default(),
        )
        .unwrap();
        let out = dir.join("prepared");
        pipeline::write_prepared(&out, &prepared, &report).unwrap();
        out
    })
}

fn config(mesh_dir: Option<&Path>, drive: Drive) -> Config {
    let mut c = Config {
        drive,
        subject_mesh_dir: mesh_dir.map(Path::to_path_buf),
        ..Config::default()
    };
    c.scene.level_of_detail = LOD;
    c
}

/// One settling breath, then the summary of two.
fn breathe(mesh_dir: Option<&Path>) -> (BreathSummary, Torso) {
    let drive = Drive::quiet();
    let mut torso = Torso::new(config(mesh_dir, drive)).unwrap();
    let period = 1.0 / drive.frequency;
    let frames = run(&mut torso, 3.0 * period, 28.0).unwrap();
    (summarise(&frames, period), torso)
}

#[test]
fn the_cavity_and_skin_are_fitted_to_the_subject() {
    let dir = prepared_dir();
    let mesh = SubjectMesh::load(dir).unwrap();
    let subject = Subject::default();
    let generated = Anatomy::build(&subject, LOD).unwrap();
    let fitted = Anatomy::build_on(&subject, LOD, Some(dir)).unwrap();
    let fit = fitted.cavity_fit.clone().unwrap();
    println!("{fit:#?}");
    // The layout is the generated one's; the volume is the subject's.
    assert_eq!(fitted.abdomen.len(), generated.abdomen.len());
    assert_eq!(fitted.muscles.len(), generated.muscles.len());
    // The 162 vertices of level 0 sample the subject's 642-vertex cavity: the flat
    // triangles cut its curvature (chordal loss of a few per cent).
    let surface = mesh.abdomen.as_ref().unwrap().volume();
    assert!(
        (fit.fitted_volume / surface - 1.0).abs() < 0.1,
        "fitted {} vs surface {surface}",
        fit.fitted_volume
    );
    assert!(fit.surface_insertion_vertices > 0);
    assert!(fit.rim_distance_max < breathing_torso::anatomy::prepared::INSERTION_REACH);
    // Every fitted vertex lies on the subject's surface.
    let bvh = breathing_torso::mesh::Bvh::new(mesh.abdomen.as_ref().unwrap());
    for &a in &fitted.abdomen.anchor {
        let d = bvh.closest(&fitted.rest(a)).unwrap().distance;
        assert!(d < 1e-9, "vertex {d} m off the surface");
    }
    // The skin lies on the subject's skin and keeps the generated layout.
    let skin = Skin::for_anatomy(&fitted, &Default::default()).unwrap();
    let gen_skin = Skin::for_anatomy(&generated, &Default::default()).unwrap();
    assert_eq!(skin.vertices.len(), gen_skin.vertices.len());
    let bvh = breathing_torso::mesh::Bvh::new(&mesh.skin);
    let worst = skin
        .vertices
        .iter()
        .map(|p| bvh.closest(p).unwrap().distance)
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "skin vertex {worst} m off the subject's skin");
    let ratio = skin.volume() / gen_skin.volume();
    println!("skin volume ratio {ratio:.4}");
    assert!((ratio / SCALE.powi(3) - 1.0).abs() < 0.05, "{ratio}");
}

#[test]
fn fitting_to_the_generated_surfaces_changes_nothing() {
    // The generated skin and cavity of the same level of detail, written as they are: every
    // template vertex already lies on them, so the fit must give back the generated model.
    let dir = scratch("identity");
    let subject = Subject::default();
    let generated = Anatomy::build(&subject, LOD).unwrap();
    let skin = Skin::for_anatomy(&generated, &Default::default()).unwrap();
    io::write(
        &TriMesh::new(skin.vertices.clone(), skin.triangles.clone()).unwrap(),
        dir.join("skin.obj"),
    )
    .unwrap();
    let ab = &generated.abdomen;
    let cavity = TriMesh::new(
        ab.anchor.iter().map(|&a| generated.rest(a)).collect(),
        ab.triangles.clone(),
    )
    .unwrap();
    io::write(&cavity, dir.join("abdomen.obj")).unwrap();
    let fitted = Anatomy::build_on(&subject, LOD, Some(&dir)).unwrap();
    assert_eq!(fitted.anchors.len(), generated.anchors.len());
    for (i, (p, q)) in fitted.anchors.iter().zip(&generated.anchors).enumerate() {
        assert_eq!(p.body, q.body, "anchor {i}");
        assert!(
            (p.rest - q.rest).norm() < 1e-9,
            "anchor {i}: {:?} vs {:?}",
            p.rest,
            q.rest
        );
    }
    // Same elements; the diaphragm's forces are shares of the insertions' arc length, so they
    // carry the positions' rounding (within 1e-9 m) into the ninth digit.
    assert_eq!(fitted.muscles.len(), generated.muscles.len());
    for (m, g) in fitted.muscles.iter().zip(&generated.muscles) {
        assert_eq!(
            (m.group, &m.path, m.gain, m.side),
            (g.group, &g.path, g.gain, g.side)
        );
        assert!(
            (m.max_force - g.max_force).abs() < 1e-6 * g.max_force,
            "{m:?} vs {g:?}"
        );
        // the tissue a diaphragm fibre stands for (the smooth dome's arcs over its route),
        // carried to the fitted chords
        match (m.tissue_length, g.tissue_length) {
            (Some(a), Some(b)) => assert!((a - b).abs() < 1e-6 * b, "{m:?} vs {g:?}"),
            (a, b) => assert_eq!(a, b, "{m:?} vs {g:?}"),
        }
    }
    let fit = fitted.cavity_fit.clone().unwrap();
    assert_eq!(fit.carriers_changed, 0);
    assert!(fit.moved_max < 1e-9, "{}", fit.moved_max);
    let refit = Skin::for_anatomy(&fitted, &Default::default()).unwrap();
    for (p, q) in refit.vertices.iter().zip(&skin.vertices) {
        assert!((p - q).norm() < 1e-9);
    }
}

#[test]
fn the_model_on_a_prepared_mesh_breathes_within_physiology() {
    let dir = prepared_dir();
    let (generated, _) = breathe(None);
    let (s, mut torso) = breathe(Some(dir));
    for (name, s) in [("generated", generated), ("prepared", s)] {
        println!(
            "{name}: VT {:.3} L, EELV {:.3} L, rib share {:.1} %, abdomen swing {:.3} %, excursion {:.2} cm",
            s.tidal_volume,
            s.end_expiratory_volume,
            100.0 * s.rib_cage_share,
            100.0 * s.abdomen_relative_swing,
            100.0 * s.dome_excursion
        );
    }
    assert!(
        (0.35..=0.8).contains(&s.tidal_volume),
        "quiet tidal volume {}",
        s.tidal_volume
    );
    assert!(
        s.abdomen_relative_swing < 0.01,
        "abdominal volume swing {}",
        s.abdomen_relative_swing
    );
    assert!(
        (0.40..=0.75).contains(&s.rib_cage_share),
        "rib-cage share {}",
        s.rib_cage_share
    );
    // Left and right: the subject's noise breaks exact symmetry; the ribs of a pair turn
    // alike within a tolerance (see `symmetry_tolerance`).
    let y = torso.state();
    let scale = y[..24].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = (0..12)
        .map(|r| (y[r] - y[12 + r]).abs())
        .fold(0.0, f64::max);
    println!(
        "largest left-right rib angle difference {:.3e} rad of {:.3e} ({:.2} %)",
        worst,
        scale,
        100.0 * worst / scale
    );
    assert!(
        worst <= symmetry_tolerance() * scale,
        "ribs turn asymmetrically: {worst} of {scale}"
    );
    let z = torso.read(Quantity::SternumDisplacement(2)).unwrap().abs();
    let x = torso.read(Quantity::SternumDisplacement(0)).unwrap().abs();
    println!("sternum sideways {:.3e} m, ventral {:.3e} m", z, x);
    assert!(
        z <= symmetry_tolerance() * x.max(1e-4),
        "sternum sideways {z}"
    );
}

/// Allowed left-right difference, as a fraction of the largest rib rotation (or of the
/// sternum's ventral motion): the 1 mm noise on a cavity of about 12 cm radius changes the
/// local wall geometry (rest lengths, areas, directions) by up to about 1/120, and a rib's
/// rotation averages many elements, so its asymmetry stays under that; 1 % still catches a
/// side losing muscles or insertions, which gives differences of order 100 %.
fn symmetry_tolerance() -> f64 {
    0.01
}

#[test]
fn rest_on_a_prepared_mesh_is_an_equilibrium_near_frc() {
    let mut torso = Torso::new(config(Some(prepared_dir()), Drive::default())).unwrap();
    let frc = torso.config().subject.frc_ecsc();
    let lung = torso.read(Quantity::LungVolume).unwrap();
    println!("rest lung volume {lung:.3} L, ECSC FRC {frc:.3} L");
    assert!((lung - frc).abs() <= 0.3 * frc, "{lung} vs {frc}");
    let y0 = torso.state().to_vec();
    torso.advance_to(20.0).unwrap();
    // positions, angles and the quaternion come before the rates: they stay put to well
    // under a micrometre; the rates jitter within their error scale, 2 pi f_inertia x rtol x
    // 1 m = 1.6e-4 m/s (`dynamics::error_weights`), as the solver steps at its stability
    // limit on a right-hand side that is zero to rounding
    let split = breathing_torso::dynamics::Layout::new(&torso.compiled().model).theta_dot;
    let y = torso.state();
    let drift = y[..split]
        .iter()
        .zip(&y0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let rates = y[split..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!("largest drift over 20 s at rest: positions {drift:e}, rates {rates:e}");
    assert!(drift < 1e-6, "rest drifts by {drift}");
    assert!(rates < 1.6e-4, "rest moves at {rates}");
}

#[test]
fn markers_are_read_on_the_subject_skin() {
    let dir = prepared_dir();
    let mesh = SubjectMesh::load(dir).unwrap();
    let bvh = breathing_torso::mesh::Bvh::new(&mesh.skin);
    let farthest = |mesh_dir: Option<&Path>| {
        // at the rest pose, not the equilibrium of the drive's start
        let mut torso = Torso::new_at_rest(config(mesh_dir, Drive::quiet())).unwrap();
        torso
            .markers()
            .unwrap()
            .iter()
            .map(|p| bvh.closest(p).unwrap().distance)
            .fold(0.0, f64::max)
    };
    let (on_subject, on_generated) = (farthest(Some(dir)), farthest(None));
    println!(
        "rest markers from the subject's skin: {:.2} mm (generated skin: {:.2} mm)",
        on_subject * 1e3,
        on_generated * 1e3
    );
    // At rest the markers lie on the fitted skin, whose flat triangles are within a fraction
    // of a millimetre of the subject's; the generated skin is 5 % smaller.
    assert!(on_subject < 5e-4, "{on_subject}");
    assert!(on_generated > 3e-3, "{on_generated}");
}

#[test]
fn skin_only_directory_keeps_the_generated_cavity() {
    let dir = scratch("skin_only");
    std::fs::copy(prepared_dir().join("skin.obj"), dir.join("skin.obj")).unwrap();
    let subject = Subject::default();
    let a = Anatomy::build_on(&subject, LOD, Some(&dir)).unwrap();
    let g = Anatomy::build(&subject, LOD).unwrap();
    assert!(a.cavity_fit.is_none() && a.subject_mesh.is_some());
    for (p, q) in a.anchors.iter().zip(&g.anchors) {
        assert_eq!(p.rest, q.rest);
    }
}

fn message(e: Error) -> String {
    e.to_string()
}

#[test]
fn bad_directories_are_refused_with_the_file_and_the_reason() {
    let subject = Subject::default();
    let build = |d: &Path| message(Anatomy::build_on(&subject, LOD, Some(d)).unwrap_err());
    // Missing directory, missing skin.
    let missing = std::env::temp_dir().join("torso_mesh_model_no_such_dir");
    let m = build(&missing);
    assert!(
        m.contains("subject.mesh_dir") && m.contains("no_such_dir"),
        "{m}"
    );
    let empty = scratch("empty");
    let m = build(&empty);
    assert!(m.contains("skin.obj") && m.contains("missing"), "{m}");
    // An open skin.
    let open = scratch("open");
    let mut skin = io::read(prepared_dir().join("skin.obj")).unwrap();
    skin.triangles.truncate(skin.triangles.len() - 3);
    io::write(&skin, open.join("skin.obj")).unwrap();
    let m = build(&open);
    assert!(m.contains("skin.obj") && m.contains("open surface"), "{m}");
    // A skin in millimetres.
    let mm = scratch("millimetres");
    let mut skin = io::read(prepared_dir().join("skin.obj")).unwrap();
    skin.scale(&Point3::origin(), &Vector3::repeat(1000.0));
    io::write(&skin, mm.join("skin.obj")).unwrap();
    let m = build(&mm);
    assert!(m.contains("skin.obj") && m.contains("millimetres"), "{m}");
    // A cavity outside the skin.
    let outside = scratch("outside");
    std::fs::copy(prepared_dir().join("skin.obj"), outside.join("skin.obj")).unwrap();
    let mut cav = io::read(prepared_dir().join("abdomen.obj")).unwrap();
    cav.translate(&Vector3::new(0.0, 0.0, 0.3));
    io::write(&cav, outside.join("abdomen.obj")).unwrap();
    let m = build(&outside);
    assert!(
        m.contains("abdomen.obj") && m.contains("outside skin.obj"),
        "{m}"
    );
    // A cavity that does not reach the costal margin: shrunk to 60 % about its centroid.
    let low = scratch("low");
    std::fs::copy(prepared_dir().join("skin.obj"), low.join("skin.obj")).unwrap();
    let mut cav = io::read(prepared_dir().join("abdomen.obj")).unwrap();
    let c = cav.centroid();
    cav.scale(&c, &Vector3::repeat(0.6));
    io::write(&cav, low.join("abdomen.obj")).unwrap();
    let m = build(&low);
    assert!(
        m.contains("abdomen.obj") && m.contains("costal margin"),
        "{m}"
    );
    // A garbled file: the parse error names file and line.
    let garbled = scratch("garbled");
    std::fs::write(garbled.join("skin.obj"), "v 0 0 0\nf 1 2 x\n").unwrap();
    let m = build(&garbled);
    assert!(m.contains("skin.obj:2:"), "{m}");
    // Through the facade, before anything is built.
    let e = Torso::new(config(Some(&missing), Drive::default()))
        .err()
        .unwrap();
    assert!(message(e).contains("subject.mesh_dir"));
}

type Log = Rc<RefCell<Vec<(Status, String)>>>;

fn instance() -> (Instance, Log) {
    let log = Rc::new(RefCell::new(Vec::new()));
    let sink_log = log.clone();
    let sink: LogSink = Box::new(move |s, _c, m| sink_log.borrow_mut().push((s, m.to_string())));
    (Instance::new(&FMI2, "t", None, Some(sink), false), log)
}

#[test]
fn fmu_sets_the_mesh_directory_and_refuses_a_bad_one_without_losing_the_instance() {
    let t = table();
    let var = t
        .by_name("subject.mesh_dir")
        .expect("subject.mesh_dir variable");
    let lod = t.by_name("scene.level_of_detail").unwrap().vr;
    let lung = t.by_name("volume.lung").unwrap().vr;
    let (mut inst, log) = instance();
    assert_eq!(
        inst.set_integer("fmi2SetInteger", &[lod], &[LOD as i32]),
        Status::Ok
    );
    // A bad directory: error naming the variable and the path; the instance carries on.
    let bad = std::env::temp_dir().join("torso_mesh_model_missing_fmu");
    let bad = bad.display().to_string();
    assert_eq!(
        inst.set_string("fmi2SetString", &[var.vr], std::slice::from_ref(&bad)),
        Status::Error
    );
    let last = log.borrow().last().unwrap().1.clone();
    assert!(
        last.contains("subject.mesh_dir") && last.contains(&bad),
        "{last}"
    );
    assert_eq!(inst.config().subject_mesh_dir, None);
    // A good one.
    let good = prepared_dir().display().to_string();
    assert_eq!(
        inst.set_string("fmi2SetString", &[var.vr], std::slice::from_ref(&good)),
        Status::Ok
    );
    let mut got = [std::ptr::null(); 1];
    let status = inst.get_string("fmi2GetString", &[var.vr], &mut got);
    assert_eq!(status, Status::Ok);
    assert_eq!(unsafe { CStr::from_ptr(got[0]) }.to_str().unwrap(), good);
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    assert_eq!(inst.do_step("fmi2DoStep", 0.0, 0.5), Status::Ok);
    let mut v = [0.0];
    assert_eq!(inst.get_real("fmi2GetReal", &[lung], &mut v), Status::Ok);
    let frc = Subject::default().frc_ecsc();
    assert!((v[0] - frc).abs() <= 0.3 * frc, "lung {} L", v[0]);
    // After initialisation the directory is fixed.
    assert_eq!(
        inst.set_string("fmi2SetString", &[var.vr], &[String::new()]),
        Status::Error
    );
    assert_eq!(inst.do_step("fmi2DoStep", 0.5, 0.5), Status::Ok);
}

/// The prepared subject mesh copied into `resources/subject_mesh` of a new scratch folder
/// standing for an unpacked FMU; returns its resources folder.
fn resources_with_mesh(name: &str) -> PathBuf {
    let resources = scratch(name).join("resources");
    let to = resources.join("subject_mesh");
    std::fs::create_dir_all(&to).unwrap();
    for entry in std::fs::read_dir(prepared_dir()).unwrap() {
        let p = entry.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
    resources
}

/// A relative `subject.mesh_dir` is found in the generic FMU's resources/, kept as given, and
/// a state saved with it restores in an instance whose resources are another copy (the first
/// one deleted), continuing exactly as the saving instance did.
#[test]
fn a_relative_mesh_directory_moves_with_the_fmus_resources() {
    let t = table();
    let var = t.by_name("subject.mesh_dir").unwrap().vr;
    let lod = t.by_name("scene.level_of_detail").unwrap().vr;
    let lung = t.by_name("volume.lung").unwrap().vr;
    let (a_res, b_res) = (
        resources_with_mesh("moved_a"),
        resources_with_mesh("moved_b"),
    );
    let steps = |inst: &mut Instance, k0: usize, k1: usize| -> Vec<f64> {
        (k0..k1)
            .map(|k| {
                assert_eq!(inst.do_step("fmi2DoStep", k as f64 * 0.1, 0.1), Status::Ok);
                let mut v = [0.0];
                assert_eq!(inst.get_real("fmi2GetReal", &[lung], &mut v), Status::Ok);
                v[0]
            })
            .collect()
    };
    let mut a = Instance::new(&FMI2, "a", Some(a_res.clone()), None, false);
    assert_eq!(
        a.set_integer("fmi2SetInteger", &[lod], &[LOD as i32]),
        Status::Ok
    );
    let given = "subject_mesh".to_string();
    assert_eq!(
        a.set_string("fmi2SetString", &[var], std::slice::from_ref(&given)),
        Status::Ok
    );
    let mut got = [std::ptr::null(); 1];
    assert_eq!(a.get_string("fmi2GetString", &[var], &mut got), Status::Ok);
    assert_eq!(unsafe { CStr::from_ptr(got[0]) }.to_str().unwrap(), given);
    assert_eq!(
        a.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(a.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        a.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    steps(&mut a, 0, 3);
    let bytes = a.get_fmu_state().to_bytes();
    let expected = steps(&mut a, 3, 8);
    drop(a);
    std::fs::remove_dir_all(a_res.parent().unwrap()).unwrap();
    let state = FmuState::from_bytes(&bytes).unwrap();
    let mut b = Instance::new(&FMI2, "b", Some(b_res), None, false);
    assert_eq!(b.set_fmu_state("fmi2SetFMUstate", &state), Status::Ok);
    assert_eq!(steps(&mut b, 3, 8), expected);
    // Without resources the relative folder is nowhere: refused, naming the parameter.
    let (mut c, log) = instance();
    assert_eq!(c.set_fmu_state("fmi2SetFMUstate", &state), Status::Error);
    let last = log.borrow().last().unwrap().1.clone();
    assert!(
        last.contains("subject.mesh_dir") && last.contains("subject_mesh"),
        "{last}"
    );
}

#[test]
fn c_abi_builds_on_a_mesh_directory_and_reports_a_bad_one() {
    unsafe {
        let mut c = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut c), BT_OK);
        assert!(c.subject_mesh_dir.is_null());
        c.level_of_detail = LOD as i32;
        let bad = CString::new("/nonexistent/torso_subject").unwrap();
        c.subject_mesh_dir = bad.as_ptr();
        assert!(bt_create(&c).is_null());
        let msg = CStr::from_ptr(bt_creation_error()).to_str().unwrap();
        assert!(
            msg.contains("subject.mesh_dir") && msg.contains("torso_subject"),
            "{msg}"
        );
        let good = CString::new(prepared_dir().display().to_string()).unwrap();
        c.subject_mesh_dir = good.as_ptr();
        // A String parameter by name points to the struct field.
        assert_eq!(
            bt_config_set(&mut c, c"subject.mesh_dir".as_ptr(), 1.0),
            BT_ERR_INVALID
        );
        let msg = CStr::from_ptr(bt_creation_error()).to_str().unwrap();
        assert!(msg.contains("subject_mesh_dir"), "{msg}");
        // bt_config_set keeps the pointer.
        assert_eq!(bt_config_set(&mut c, c"grid.rows".as_ptr(), 8.0), BT_OK);
        assert_eq!(c.subject_mesh_dir, good.as_ptr());
        let h = bt_create(&c);
        assert!(!h.is_null(), "{:?}", CStr::from_ptr(bt_creation_error()));
        assert_eq!(bt_advance_to(h, 0.5, std::ptr::null_mut()), BT_OK);
        bt_destroy(h);
    }
}

/// A fit on a subject mesh baked into a personalised FMU: the mesh folder goes to
/// resources/subject/mesh/ and `subject.mesh_dir` reads `subject/mesh`, found in the FMU's
/// resources when it is instantiated; the generic FMU's parameter set names the folder
/// absolutely. The fit result is the JSON `torso fit` writes, reduced to the keys the
/// personalisation reads.
#[test]
fn a_fit_on_a_subject_mesh_carries_the_mesh_in_the_fmus_resources() {
    use breathing_torso::fmi::personal::{from_fit_json, table_in};
    use breathing_torso::fmi::variables::Value;
    let dir = scratch("personal");
    let fit = dir.join("fit.json");
    let subject = breathing_torso::fit::report::subject_fmi(&Subject::default());
    let mut json = serde_json::json!({
        "subject": subject,
        "model": {
            "scene.level_of_detail": LOD,
            "grid.rows": 10,
            "grid.cols": 6,
            "slp.reference": "",
            "subject.mesh_dir": prepared_dir().display().to_string(),
        },
    });
    for (k, v) in breathing_torso::fit::report::drive_fmi(&Drive::quiet()) {
        json[k] = v;
    }
    std::fs::write(&fit, json.to_string()).unwrap();
    let personal = from_fit_json(&fit).unwrap();
    let start = |name: &str| {
        personal
            .personalisation
            .starts
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.clone())
    };
    assert_eq!(
        start("subject.mesh_dir"),
        Some(Value::String("subject/mesh".into()))
    );
    let generic = personal
        .generic
        .iter()
        .find(|(n, _)| n == "subject.mesh_dir")
        .unwrap();
    assert_eq!(
        generic.1,
        Value::String(prepared_dir().canonicalize().unwrap().display().to_string())
    );
    // The entries as the FMU's resources/ holds them.
    let root = dir.join("unpacked");
    for (name, data) in &personal.entries {
        let p = root.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, data).unwrap();
    }
    let resources = root.join("resources");
    assert!(resources.join("subject/mesh/skin.obj").is_file());
    let t = table_in(Some(&resources)).unwrap();
    assert_ne!(t.guid(), table().guid());
    let mut inst =
        Instance::with_table(&FMI2, "mesh", Some(resources.clone()), None, false, t).unwrap();
    // Kept as given (relative to resources/), found there when the model is built.
    assert_eq!(
        inst.config().subject_mesh_dir,
        Some(PathBuf::from("subject/mesh"))
    );
    assert_eq!(
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None),
        Status::Ok
    );
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    // The same relative folder in the generic FMU's resources.
    let var = table().by_name("subject.mesh_dir").unwrap().vr;
    let mut generic = Instance::new(&FMI2, "g", Some(resources.clone()), None, false);
    assert_eq!(
        generic.set_string("fmi2SetString", &[var], &["subject/mesh".to_string()]),
        Status::Ok
    );
    // Without resources, the relative folder is not there: an error naming the parameter.
    let (mut bare, log) = instance();
    assert_eq!(
        bare.set_string("fmi2SetString", &[var], &["subject/mesh".to_string()]),
        Status::Error
    );
    let last = log.borrow().last().unwrap().1.clone();
    assert!(
        last.contains("subject.mesh_dir") && last.contains("resources"),
        "{last}"
    );
}
