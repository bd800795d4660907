//! The quasi-static mode's reduced right-hand side through the C ABI (`bt_quasi_rate`,
//! `bt_quasi_set_volume`): the rate is the facade's (`Torso::quasi_rate`, the function the
//! library's own integrator steps) bit for bit, and the airflow output's; a set volume is read
//! back with the markers of the model that integrated to it; wrong modes and bad arguments
//! are clear errors, never a panic.

use breathing_torso::capi::*;
use breathing_torso::model::{Config, Drive, Quantity, Torso};
use breathing_torso::solver::Method;
use std::ffi::CStr;

/// Mid-breath of the quiet drive (0.25 Hz): the airflow is far from zero.
const T: f64 = 1.3;

unsafe fn read(h: *mut BtTorso, name: &CStr) -> f64 {
    let mut v = f64::NAN;
    assert_eq!(unsafe { bt_read_by_name(h, name.as_ptr(), &mut v) }, BT_OK);
    v
}

unsafe fn message(h: *mut BtTorso) -> String {
    unsafe { CStr::from_ptr(bt_last_error(h)) }
        .to_string_lossy()
        .into_owned()
}

/// A level-0 handle of the default (quiet) scene with `method`.
unsafe fn handle(method: i32) -> *mut BtTorso {
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        config.level_of_detail = 0;
        config.solver_method = method;
        let h = bt_create(&config);
        assert!(!h.is_null());
        h
    }
}

unsafe fn markers(h: *mut BtTorso) -> Vec<f64> {
    let mut n = 0;
    assert_eq!(unsafe { bt_marker_count(h, &mut n) }, BT_OK);
    let mut xyz = vec![0.0; 3 * n];
    assert_eq!(
        unsafe { bt_read_markers(h, xyz.as_mut_ptr(), xyz.len(), std::ptr::null_mut()) },
        BT_OK
    );
    xyz
}

#[test]
fn the_c_abi_rate_is_the_facades() {
    let mut c = Config::default();
    c.scene.level_of_detail = 0;
    c.solver.method = Method::QuasiStatic;
    c.drive = Drive::quiet();
    let mut torso = Torso::new(c).unwrap();
    torso.advance_to(T).unwrap();
    let volume = torso.read(Quantity::LungVolume).unwrap();
    let facade = torso.quasi_rate(T, volume).unwrap();
    // the airflow output solves the same equilibrium (the one just solved) and applies the
    // same law, through the output's unit conversions
    let flow = torso.read(Quantity::AirwayFlow).unwrap();
    assert!(
        (flow - facade).abs() <= 1e-12 * facade.abs(),
        "{flow} against {facade}"
    );
    unsafe {
        let h = handle(4);
        assert_eq!(bt_advance_to(h, T, std::ptr::null_mut()), BT_OK);
        let v = read(h, c"volume.lung");
        assert_eq!(v.to_bits(), volume.to_bits());
        let mut rate = f64::NAN;
        assert_eq!(bt_quasi_rate(h, T, v, &mut rate), BT_OK, "{}", message(h));
        println!("t = {T} s: V_L = {v} L, dV_L/dt = {rate} L/s");
        assert_eq!(rate.to_bits(), facade.to_bits(), "{rate} against {facade}");
        assert!(rate.abs() > 0.1, "mid-breath: {rate} L/s");
        // the model's own time and volume did not move
        assert_eq!(read(h, c"volume.lung").to_bits(), v.to_bits());
        let mut t = f64::NAN;
        assert_eq!(bt_time(h, &mut t), BT_OK);
        assert_eq!(t, T);
        // the alveolar pressure rises with the volume, so the inflow falls
        let mut fuller = f64::NAN;
        assert_eq!(bt_quasi_rate(h, T, v + 0.05, &mut fuller), BT_OK);
        assert!(fuller < rate, "{fuller} against {rate}");
        bt_destroy(h);
    }
}

/// A second model set to the first's time and lung volume reads the first's markers, to the
/// static solves' tolerance: each solve stops within 1e-8 m (`statics_tolerance` at rtol
/// 1e-6), rotations counted at a 0.2 m lever; skin points lie up to about 0.4 m from a rib's
/// hinge, so each marker is within 2e-8 m of the exact equilibrium's, 4e-8 m between two solves;
/// 1e-7 m is asked.
#[test]
fn a_set_volume_reads_the_markers_of_the_integrated_model() {
    unsafe {
        let a = handle(4);
        assert_eq!(bt_advance_to(a, T, std::ptr::null_mut()), BT_OK);
        let v = read(a, c"volume.lung");
        let ma = markers(a);
        let b = handle(4);
        let rest = markers(b);
        assert_eq!(bt_quasi_set_volume(b, T, v), BT_OK, "{}", message(b));
        assert_eq!(read(b, c"volume.lung").to_bits(), v.to_bits());
        let mb = markers(b);
        let largest = |x: &[f64], y: &[f64]| {
            x.chunks(3)
                .zip(y.chunks(3))
                .map(|(p, q)| {
                    p.iter()
                        .zip(q)
                        .map(|(a, b)| (a - b).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0f64, f64::max)
        };
        let moved = largest(&rest, &ma);
        let diff = largest(&ma, &mb);
        println!("markers moved {moved:.3e} m from the start; set-volume model {diff:.3e} m off");
        assert!(moved > 1e-3, "the breath moves the markers: {moved} m");
        assert!(diff < 1e-7, "{diff} m");
        // and it steps on from there as the first does: two integrations of the same
        // contracting scalar ODE (the inflow falls as the volume rises) from the same point
        // differ by at most the sum of their local errors, each at most rtol |V| + atol
        let mut sa = std::mem::zeroed::<BtAdvanceStats>();
        let mut sb = std::mem::zeroed::<BtAdvanceStats>();
        assert_eq!(bt_advance_to(a, T + 0.1, &mut sa), BT_OK);
        assert_eq!(bt_advance_to(b, T + 0.1, &mut sb), BT_OK);
        let (va, vb) = (read(a, c"volume.lung"), read(b, c"volume.lung"));
        let bound = (sa.steps + sb.steps) as f64 * (1e-6 * va.max(vb) + 1e-8);
        println!(
            "0.1 s on: {va} against {vb} L ({} + {} steps, bound {bound:.2e} L)",
            sa.steps, sb.steps
        );
        assert!((va - vb).abs() <= bound, "{va} against {vb} L");
        bt_destroy(a);
        bt_destroy(b);
    }
}

#[test]
fn wrong_mode_and_bad_arguments_are_clear_errors() {
    unsafe {
        let mut rate = f64::NAN;
        assert_eq!(
            bt_quasi_rate(std::ptr::null_mut(), 0.0, 3.0, &mut rate),
            BT_ERR_NULL
        );
        let inertial = handle(0);
        assert_eq!(bt_quasi_rate(inertial, 0.0, 3.0, &mut rate), BT_ERR_STATE);
        assert!(
            message(inertial).contains("quasi-static"),
            "{}",
            message(inertial)
        );
        assert_eq!(bt_quasi_set_volume(inertial, 0.0, 3.0), BT_ERR_STATE);
        bt_destroy(inertial);

        let h = handle(4);
        let v = read(h, c"volume.lung");
        assert_eq!(bt_quasi_rate(h, 0.0, v, std::ptr::null_mut()), BT_ERR_NULL);
        assert_eq!(bt_quasi_rate(h, f64::NAN, v, &mut rate), BT_ERR_INVALID);
        assert!(message(h).contains("time"), "{}", message(h));
        for bad in [-1.0, 0.0, f64::INFINITY, f64::NAN] {
            assert_eq!(bt_quasi_rate(h, 0.0, bad, &mut rate), BT_ERR_INVALID);
            assert!(message(h).contains("lung volume"), "{}", message(h));
            assert_eq!(bt_quasi_set_volume(h, 0.0, bad), BT_ERR_INVALID);
        }
        assert!(rate.is_nan(), "nothing written on error");
        // a rejected volume changed nothing
        assert_eq!(read(h, c"volume.lung").to_bits(), v.to_bits());
        // the full-state right-hand side is the inertial formulation's
        let mut n = 0;
        assert_eq!(bt_state_dim(h, &mut n), BT_OK);
        let mut y = vec![0.0; n];
        let mut dy = vec![0.0; n];
        assert_eq!(bt_get_state(h, y.as_mut_ptr(), n), BT_OK);
        assert_eq!(bt_rhs(h, 0.0, y.as_ptr(), dy.as_mut_ptr(), n), BT_ERR_STATE);
        assert!(message(h).contains("lung volume"), "{}", message(h));
        bt_destroy(h);
    }
}
