//! Gravity as an input (issue 35, deliverable 4): the `gravity` parameter [m/s^2] reaches the
//! model through the library's configuration, the FMU, the C ABI and the command line, every
//! route refuses a value outside [0, 3 g] with an error naming the variable and its range,
//! and each route builds the same model as the library.

use breathing_torso::capi::*;
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
