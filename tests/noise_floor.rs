//! The noise floor a fit is judged against, estimated from a recording alone
//! (`fit::fitting::estimated_noise_floor`), against the truth a synthetic recording states
//! (the mean length of the noise vectors it added): within 10 % for 0.2-1 mm of noise at 30
//! and 56 Hz, with 2 % of the samples dropped, forced breathing included.

use breathing_torso::Config;
use breathing_torso::fit::fitting::estimated_noise_floor;
use breathing_torso::fit::{Camera, SynthOptions, TorsoMarkers, synthesize};
use breathing_torso::model::Drive;

#[test]
fn the_noise_floor_is_found_from_the_recording() {
    let mut c = Config::default();
    c.scene.level_of_detail = 0;
    c.solver.rtol = 1e-4;
    for (noise, rate, drive) in [
        (0.5e-3, 56.0, Drive::quiet()),
        (0.2e-3, 30.0, Drive::quiet()),
        (1.0e-3, 56.0, Drive::forced()),
    ] {
        let mut source = TorsoMarkers::new(c.clone()).unwrap();
        let s = synthesize(
            &mut source,
            &SynthOptions {
                drive,
                noise,
                rate,
                duration: 8.0,
                dropout: 0.02,
                seed: 11,
                camera: Camera::Random,
                ..SynthOptions::default()
            },
        )
        .unwrap();
        let r = &s.recording;
        let estimate = estimated_noise_floor(&r.times, &r.frames);
        let ratio = estimate / s.noise_floor_m;
        println!(
            "noise {:.1} mm at {rate} Hz: floor {:.4} mm, estimated {:.4} mm ({ratio:.3})",
            noise * 1e3,
            s.noise_floor_m * 1e3,
            estimate * 1e3
        );
        assert!(
            (ratio - 1.0).abs() < 0.1,
            "estimate {estimate} against {}",
            s.noise_floor_m
        );
    }
    // Too short to say: NaN rather than a number.
    assert!(estimated_noise_floor(&[0.0, 0.1], &[vec![], vec![]]).is_nan());
}
