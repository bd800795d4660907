//! `bt_advance_to` steps with the physiological check the FMU steps with
//! (`model::bounds`): a step that ends with a cavity outside its bounds relative to the rest
//! volumes fails with `BT_ERR_NUMERICAL`, `bt_last_error` names the volume and the bounds, and
//! the model is back where the step started, state and time, as an FMU discards the step.
//! An ordinary step passes.

use breathing_torso::anatomy::Subject;
use breathing_torso::capi::*;
use breathing_torso::model::bounds::cavity_bounds;
use std::ffi::CStr;

unsafe fn read(h: *mut BtTorso, name: &CStr) -> f64 {
    let mut v = f64::NAN;
    assert_eq!(unsafe { bt_read_by_name(h, name.as_ptr(), &mut v) }, BT_OK);
    v
}

unsafe fn time(h: *mut BtTorso) -> f64 {
    let mut t = f64::NAN;
    assert_eq!(unsafe { bt_time(h, &mut t) }, BT_OK);
    t
}

#[test]
fn a_step_leaving_the_physiological_bounds_fails_and_rolls_back() {
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        config.level_of_detail = 0;
        let h = bt_create(&config);
        assert!(!h.is_null());
        let h_step = 1.0 / 56.0;
        assert_eq!(bt_advance_to(h, 2.0 * h_step, std::ptr::null_mut()), BT_OK);
        let t = time(h);
        let rest = read(h, c"volume.thorax");
        // Every rib turned 0.6 rad caudally, far into expiration: the thorax is crushed to
        // about a quarter of its volume (as in tests/stress_fmi_collapse.rs). A microsecond
        // step still ends outside the bounds.
        let mut n = 0;
        assert_eq!(bt_state_dim(h, &mut n), BT_OK);
        let mut y = vec![0.0; n];
        assert_eq!(bt_get_state(h, y.as_mut_ptr(), n), BT_OK);
        for theta in &mut y[..24] {
            *theta -= 0.6;
        }
        assert_eq!(bt_set_state(h, t, y.as_ptr(), n), BT_OK);
        let crushed = read(h, c"volume.thorax");
        let (lo, hi) = cavity_bounds(&Subject::default())[0];
        assert!(crushed < lo * rest, "{crushed} L of {rest} L");

        assert_eq!(
            bt_advance_to(h, t + 1e-6, std::ptr::null_mut()),
            BT_ERR_NUMERICAL
        );
        let message = CStr::from_ptr(bt_last_error(h)).to_string_lossy();
        println!("{message}");
        assert!(
            message.contains("volume.thorax")
                && message.contains(&format!("[{lo:.3}, {hi:.3}] x rest")),
            "{message}"
        );
        assert_eq!(time(h), t, "the model stays at the start of the step");
        assert_eq!(
            read(h, c"volume.thorax"),
            crushed,
            "the state is rolled back"
        );
        let mut back = vec![0.0; n];
        assert_eq!(bt_get_state(h, back.as_mut_ptr(), n), BT_OK);
        assert_eq!(back, y, "the state vector is the one the step started from");
        bt_destroy(h);
    }
}
