//! `bt_start_at_equilibrium`: the C ABI's way to start a run at the equilibrium of the
//! inputs it sets (docs/dynamics.md, "The start state"). Setting an input leaves the state
//! where it is; the call moves it to the static equilibrium of the applied activations, from
//! which a held input no longer moves the lungs.

use breathing_torso::capi::*;

unsafe fn lung(h: *mut BtTorso) -> f64 {
    let mut v = 0.0;
    assert_eq!(
        unsafe { bt_read_by_name(h, c"volume.lung".as_ptr(), &mut v) },
        BT_OK
    );
    v
}

#[test]
fn the_start_moves_to_the_equilibrium_of_the_inputs_only_when_asked() {
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        config.level_of_detail = 0;
        config.drive.enabled = 0;
        let h = bt_create(&config);
        assert!(!h.is_null());
        let rest = lung(h);
        assert_eq!(
            bt_set_activation_by_name(h, c"diaphragm".as_ptr(), 0.3),
            BT_OK
        );
        assert_eq!(lung(h), rest, "setting an input moved the state");
        let mut imbalance = f64::NAN;
        assert_eq!(bt_start_at_equilibrium(h, &mut imbalance), BT_OK);
        // The relaxation may stop at 40 s short of the solver's tolerance (slow modes): the
        // test is what the state does next, not the imbalance figure.
        assert!(imbalance.is_finite() && imbalance >= 0.0, "{imbalance}");
        println!("relative imbalance at the start: {imbalance:.1e}");
        let held = lung(h);
        let inspired = held - rest;
        assert!(inspired > 0.1, "the diaphragm inspired {inspired} L");
        assert_eq!(bt_advance_to(h, 2.0, std::ptr::null_mut()), BT_OK);
        let later = lung(h);
        assert!(
            (later - held).abs() < 0.01 * inspired,
            "lung volume {held} L at the start, {later} L 2 s later"
        );
        // A null imbalance pointer is allowed; a null handle is refused.
        assert_eq!(bt_start_at_equilibrium(h, std::ptr::null_mut()), BT_OK);
        assert_eq!(
            bt_start_at_equilibrium(std::ptr::null_mut(), &mut imbalance),
            BT_ERR_NULL
        );
        bt_destroy(h);
    }
}
