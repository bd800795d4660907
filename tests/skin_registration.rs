//! Registration of a recording's first frame to the skin and skin fitting.

use breathing_torso::anatomy::Subject;
use breathing_torso::anatomy::skin::{
    FitOptions, MarkerGrid, RigidTransform, Skin, register_rigid,
};
use nalgebra::{Point3, UnitQuaternion, Vector3};

/// Deterministic pseudo-random numbers (xorshift64*), uniform in [-1, 1].
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    fn gauss(&mut self) -> f64 {
        // Sum of uniforms, unit variance.
        (0..12).map(|_| 0.5 * (self.next() + 1.0)).sum::<f64>() - 6.0
    }
}

/// A recording frame: model markers moved by `truth^-1` (recording = truth^-1(model)) plus
/// isotropic Gaussian noise of `sigma` metres; every 7th point untracked.
fn recording(
    model: &[Point3<f64>],
    truth: &RigidTransform,
    sigma: f64,
    rng: &mut Rng,
) -> Vec<Option<Point3<f64>>> {
    model
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if i % 7 == 3 {
                return None;
            }
            let q = truth.apply_inverse(p);
            Some(q + Vector3::new(rng.gauss(), rng.gauss(), rng.gauss()) * sigma)
        })
        .collect()
}

#[test]
fn known_rigid_transforms_are_recovered() {
    let skin = Skin::generate(&Subject::default()).unwrap();
    let grid = MarkerGrid::place(&skin, 10, 6).unwrap();
    let model = grid.positions(&skin.vertices, &skin.triangles);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for case in 0..20 {
        let axis = Vector3::new(rng.next(), rng.next(), rng.next()).normalize();
        let angle = (30.0f64).to_radians() * (0.2 + 0.8 * 0.5 * (rng.next() + 1.0));
        let truth = RigidTransform {
            rotation: UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle),
            translation: Vector3::new(rng.next(), rng.next(), rng.next()).normalize()
                * 0.5
                * (0.5 * (rng.next() + 1.0)),
            scale: 1.0,
        };
        let rec = recording(&model, &truth, 0.0005, &mut rng);
        let (est, rms) = register_rigid(&model, &rec, false).unwrap();
        let dangle = (est.rotation.inverse() * truth.rotation)
            .angle()
            .to_degrees();
        // Position error of the registered grid (noise-free recording points mapped back):
        // the translation vector alone depends on where the origin lies (1.2 m below).
        let dt = model
            .iter()
            .map(|p| (est.apply(&truth.apply_inverse(p)) - p).norm())
            .fold(0.0, f64::max);
        assert!(dangle < 0.5, "case {case}: rotation error {dangle} deg");
        assert!(dt < 0.001, "case {case}: grid position error {dt} m");
        assert!(rms < 0.0015, "case {case}: rms {rms}");
        // Outputs in the recording's frame: the inverse maps model markers back.
        let back = est.inverse().apply(&model[0]);
        assert!((back - truth.apply_inverse(&model[0])).norm() < 0.001);
    }
}

#[test]
fn uniform_scale_is_recovered() {
    let skin = Skin::generate(&Subject::default()).unwrap();
    let grid = MarkerGrid::place(&skin, 10, 6).unwrap();
    let model = grid.positions(&skin.vertices, &skin.triangles);
    let truth = RigidTransform {
        rotation: UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3),
        translation: Vector3::new(0.2, -0.1, 0.3),
        scale: 0.8,
    };
    let rec: Vec<Option<Point3<f64>>> =
        model.iter().map(|p| Some(truth.apply_inverse(p))).collect();
    let (est, _) = register_rigid(&model, &rec, true).unwrap();
    assert!((est.scale - 0.8).abs() < 1e-9, "{}", est.scale);
}

#[test]
fn skin_fitting_lowers_the_error() {
    let subject = Subject::default();
    let mut skin = Skin::generate(&subject).unwrap();
    let grid = MarkerGrid::place(&skin, 10, 6).unwrap();
    let model = grid.positions(&skin.vertices, &skin.triangles);
    let volume = skin.volume();
    // A "real" torso: the model's markers displaced by a smooth field of a few millimetres
    // (a fuller abdomen, a flatter upper chest), then seen from a moved recording frame.
    let mut rng = Rng(42);
    let truth = RigidTransform {
        rotation: UnitQuaternion::from_euler_angles(0.2, 0.3, -0.1),
        translation: Vector3::new(0.3, -0.2, 0.1),
        scale: 1.0,
    };
    let rec: Vec<Option<Point3<f64>>> = model
        .iter()
        .map(|p| {
            let y = p.y - skin.landmarks.omphalion_height;
            let bulge = Vector3::new(
                0.008 * (-(y / 0.12).powi(2)).exp() - 0.003 * (p.z / 0.1).powi(2),
                0.0,
                0.0,
            );
            Some(
                truth.apply_inverse(&(p + bulge))
                    + Vector3::new(rng.gauss(), rng.gauss(), rng.gauss()) * 0.0005,
            )
        })
        .collect();
    let reg = skin.register(&grid, &rec, &FitOptions::default()).unwrap();
    println!("{:?}", reg.fit);
    assert!(
        reg.fit.mean_after < 0.5 * reg.fit.mean_before,
        "{:?}",
        reg.fit
    );
    assert!(reg.fit.mean_after < 0.0015);
    skin.check().unwrap();
    // Taubin smoothing keeps the volume (the fit itself adds a few millilitres).
    assert!((skin.volume() - volume).abs() < 0.01 * volume);
    // Markers expressed in the recording frame land on the recording.
    let fitted = grid.positions(&skin.vertices, &skin.triangles);
    let mean: f64 = fitted
        .iter()
        .zip(&rec)
        .map(|(m, q)| (reg.to_recording(m) - q.unwrap()).norm())
        .sum::<f64>()
        / 60.0;
    assert!(mean < 0.002, "{mean}");
}

#[test]
fn bad_frames_are_rejected() {
    let skin = Skin::generate(&Subject::default()).unwrap();
    let grid = MarkerGrid::place(&skin, 10, 6).unwrap();
    let model = grid.positions(&skin.vertices, &skin.triangles);
    assert!(register_rigid(&model, &[None; 3], false).is_err());
    let mut rec: Vec<Option<Point3<f64>>> = vec![None; 60];
    rec[0] = Some(Point3::origin());
    rec[1] = Some(Point3::new(1.0, 0.0, 0.0));
    rec[2] = Some(Point3::new(2.0, 0.0, 0.0));
    assert!(
        register_rigid(&model, &rec, false).is_err(),
        "collinear points"
    );
    assert!(MarkerGrid::place(&skin, 17, 6).is_err());
    assert!(MarkerGrid::place(&skin, 16, 16).is_ok());
}
