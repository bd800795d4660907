//! The stiff method on the torso: the block-local Jacobian (sparse plus rank 2, of the
//! right-hand side with the mass matrix's blocks alone) and the full one the stiff method
//! uses (sparse plus rank 34) against dense finite differences (level of detail 0), quiet
//! breathing with `Method::Rosenbrock` against Dormand-Prince at a tight tolerance, rest
//! stays rest, left/right symmetry, snapshot/restore, and stepping past the frames while an
//! input changes on every frame.

use breathing_torso::anatomy::MuscleGroup;
use breathing_torso::dynamics::jacobian::TorsoJacobian;
use breathing_torso::dynamics::{self, Activations, Data, Model, Params};
use breathing_torso::model::{Config, Drive, Quantity, Torso};
use breathing_torso::solver::{Jacobian, Method};

fn config(lod: u32, method: Method, rtol: f64) -> Config {
    let mut c = Config::default();
    c.scene.level_of_detail = lod;
    c.solver.method = method;
    c.solver.rtol = rtol;
    c.solver.atol = rtol * 1e-2;
    c.drive = Drive::quiet();
    c
}

fn compile(lod: u32) -> Model {
    let c = config(lod, Method::Rosenbrock, 1e-6);
    let anatomy = breathing_torso::anatomy::Anatomy::build(&c.subject, lod).unwrap();
    Model::compile(&anatomy, Params::for_posture(c.subject.posture))
}

#[test]
fn jacobian_matches_dense_finite_differences() {
    let model = compile(0);
    let mut data = Data::new(&model);
    // a breathing state: run quiet breathing for 1.2 s
    let mut torso = Torso::new(config(0, Method::Dopri5, 1e-8)).unwrap();
    torso.advance_to(1.2).unwrap();
    let y = torso.state().to_vec();
    let n = y.len();
    let mut groups = [0.0; MuscleGroup::COUNT];
    for (g, v) in groups.iter_mut().enumerate() {
        *v = 0.05 + 0.02 * g as f64;
    }
    let act = Activations::new(&groups, 1.0, 1.0);
    let mut f0 = vec![0.0; n];
    dynamics::rhs_local(&model, &mut data, &act, &y, &mut f0);
    let mut tj = TorsoJacobian::new(&model);
    let st = tj.structure();
    let mut jac = Jacobian::zeros(st.pattern.clone(), st.rank);
    let evals = tj.evaluate(&model, &mut data, &act, &y, &f0, &mut jac);
    println!(
        "n = {n}, nnz = {}, colours = {}, evaluations = {evals}",
        st.pattern.nnz(),
        tj.colours()
    );
    assert!(
        evals < n as u64 / 2,
        "colouring saves little: {evals} of {n}"
    );
    let ours = jac.to_dense();
    // central differences of the right-hand side the Jacobian approximates (global pressures
    // included; the mass matrix's block-diagonal part, as the stiff method uses it)
    let (mut yp, mut fp, mut fm) = (y.clone(), vec![0.0; n], vec![0.0; n]);
    let mut worst = 0.0f64;
    let mut dense = vec![0.0; n * n];
    for j in 0..n {
        let d = 1e-6 * y[j].abs().max(1e-2);
        yp[j] = y[j] + d;
        dynamics::rhs_local(&model, &mut data, &act, &yp, &mut fp);
        yp[j] = y[j] - d;
        dynamics::rhs_local(&model, &mut data, &act, &yp, &mut fm);
        yp[j] = y[j];
        for i in 0..n {
            dense[i * n + j] = (fp[i] - fm[i]) / (2.0 * d);
        }
    }
    for i in 0..n {
        let row = &dense[i * n..(i + 1) * n];
        let scale = row.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-9);
        for j in 0..n {
            let e = (ours[i * n + j] - row[j]).abs() / scale;
            worst = worst.max(e);
        }
    }
    println!("worst row-relative Jacobian error {worst:.2e}");
    assert!(worst < 1e-4, "worst row-relative error {worst:e}");
    // the pressures matter: without the rank-2 part the error is large
    let mut local = jac.clone();
    local.rank = 0;
    let only_s = local.to_dense();
    let mut worst_s = 0.0f64;
    for i in 0..n {
        let row = &dense[i * n..(i + 1) * n];
        let scale = row.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-9);
        for j in 0..n {
            worst_s = worst_s.max((only_s[i * n + j] - row[j]).abs() / scale);
        }
    }
    println!("without the pressure part: {worst_s:.2e}");
    assert!(worst_s > 100.0 * worst);
}

fn lung_curve(method: Method, rtol: f64, lod: u32, seconds: f64) -> (Vec<f64>, Torso) {
    let mut torso = Torso::new(config(lod, method, rtol)).unwrap();
    let mut out = Vec::new();
    let frames = (seconds * 56.0) as usize;
    for i in 1..=frames {
        torso.advance_to(i as f64 / 56.0).unwrap();
        out.push(torso.read(Quantity::LungVolume).unwrap());
    }
    (out, torso)
}

#[test]
fn quiet_breathing_matches_dormand_prince() {
    let (reference, dp) = lung_curve(Method::Dopri5, 1e-8, 0, 3.0);
    let (stiff, ros) = lung_curve(Method::Rosenbrock, 1e-8, 0, 3.0);
    let (loose, ros6) = lung_curve(Method::Rosenbrock, 1e-6, 0, 3.0);
    let err = |v: &[f64]| {
        v.iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let swing = reference.iter().cloned().fold(f64::MIN, f64::max)
        - reference.iter().cloned().fold(f64::MAX, f64::min);
    println!(
        "tidal swing {swing:.4} L; max lung error rtol 1e-8: {:.2e} L, rtol 1e-6: {:.2e} L",
        err(&stiff),
        err(&loose)
    );
    println!(
        "dopri5 {:?}\nrosenbrock 1e-8 {:?}\nrosenbrock 1e-6 {:?}",
        dp.solver_stats(),
        ros.solver_stats(),
        ros6.solver_stats()
    );
    assert!(swing > 0.05, "no breathing: swing {swing}");
    // stated tolerances: 1e-5 L at rtol 1e-8, 1e-3 L at rtol 1e-6 (tidal volume ~0.5 L)
    assert!(err(&stiff) < 1e-5, "rtol 1e-8: {:e} L", err(&stiff));
    assert!(err(&loose) < 1e-3, "rtol 1e-6: {:e} L", err(&loose));
}

#[test]
fn rest_stays_at_rest() {
    let mut c = config(0, Method::Rosenbrock, 1e-6);
    c.drive = Drive::default();
    let mut torso = Torso::new(c).unwrap();
    let y0 = torso.state().to_vec();
    let v0 = torso.read(Quantity::LungVolume).unwrap();
    torso.advance_to(3.0).unwrap();
    let moved = torso
        .state()
        .iter()
        .zip(&y0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let v1 = torso.read(Quantity::LungVolume).unwrap();
    println!("rest: max state change {moved:e}, lung {v0} -> {v1}");
    assert!(moved < 1e-6, "rest state drifted by {moved}");
    assert!((v1 - v0).abs() < 1e-6);
}

/// Largest distance from a marker's mirror image (about the grid's mean sagittal plane)
/// to the nearest marker.
fn mirror_mismatch(torso: &mut Torso) -> f64 {
    let pts = torso.markers().unwrap().to_vec();
    let zmid = pts.iter().map(|p| p.z).sum::<f64>() / pts.len() as f64;
    let mut worst = 0.0f64;
    for p in &pts {
        let best = pts
            .iter()
            .map(|q| {
                ((q.x - p.x).powi(2) + (q.y - p.y).powi(2) + (q.z - (2.0 * zmid - p.z)).powi(2))
                    .sqrt()
            })
            .fold(f64::MAX, f64::min);
        worst = worst.max(best);
    }
    worst
}

#[test]
fn symmetry_is_kept_as_with_dormand_prince() {
    let mut ros = Torso::new(config(0, Method::Rosenbrock, 1e-7)).unwrap();
    let mut dp = Torso::new(config(0, Method::Dopri5, 1e-9)).unwrap();
    let at_rest = mirror_mismatch(&mut ros);
    ros.advance_to(2.0).unwrap();
    dp.advance_to(2.0).unwrap();
    let (a, b) = (mirror_mismatch(&mut ros), mirror_mismatch(&mut dp));
    println!("mirror mismatch: rest {at_rest:e} m, rosenbrock {a:e} m, dopri5 {b:e} m");
    // the mesh is not exactly symmetric; the stiff method must not add asymmetry
    assert!((a - b).abs() < 1e-6, "rosenbrock {a} m vs dopri5 {b} m");
}

/// With an activation set anew on every frame each call restarts the integration, and the
/// stiff method's restarts end a step on the frame rather than reading the state from the
/// cubic Hermite interpolant (not stiffly accurate: its error in a stiff component is about
/// |h lambda| / 6 times the step's error estimate, and the next restart would start from
/// it). Every call then being a restart, stepping past the frames takes the steps stepping
/// onto them takes, and gives the same states; the lung volume and the markers are checked
/// against the tolerance too: 10 rtol of the lung volume and of the largest marker
/// coordinate, the bound `tests/fast_dynamics.rs` holds the error-controlled lung volume to
/// against a tight run (two runs each within the tolerance of the truth differ by at most
/// twice that).
#[test]
fn stepping_past_matches_stepping_onto_frames_with_changing_input() {
    let rtol = 1e-6;
    let frames = 300;
    let run = |past: bool| {
        let mut c = config(0, Method::Rosenbrock, rtol);
        c.solver.step_past_outputs = past;
        let mut torso = Torso::new(c).unwrap();
        let mut out = Vec::new();
        for i in 1..=frames {
            let t = i as f64 / 56.0;
            // a slow 0.5 Hz push of the abdominal wall, a new value on every frame
            let a = 0.15 * (1.0 - (std::f64::consts::PI * t).cos());
            torso
                .set_activation(MuscleGroup::RectusAbdominis, a)
                .unwrap();
            torso.advance_to(t).unwrap();
            let lung = torso.read(Quantity::LungVolume).unwrap();
            let m = torso.markers().unwrap();
            let xyz: Vec<f64> = m.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
            out.push((lung, xyz, torso.state().to_vec()));
        }
        (out, torso.solver_stats())
    };
    let (onto, onto_stats) = run(false);
    let (past, past_stats) = run(true);
    let (mut worst_lung, mut worst_marker) = (0.0f64, 0.0f64);
    for (i, ((la, ma, ya), (lb, mb, yb))) in onto.iter().zip(&past).enumerate() {
        // every call restarts, and a restart's steps end on the frame as `integrate`'s do
        assert!(
            ya == yb,
            "frame {i}: the state differs from stepping onto the frames"
        );
        let scale = ma.iter().fold(0.0f64, |s, x| s.max(x.abs()));
        let dl = (la - lb).abs() / la;
        let dm = ma
            .iter()
            .zip(mb)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / scale;
        worst_lung = worst_lung.max(dl);
        worst_marker = worst_marker.max(dm);
        assert!(dl <= 10.0 * rtol, "frame {i}: lung {la} L against {lb} L");
        assert!(
            dm <= 10.0 * rtol,
            "frame {i}: markers differ by {dm:e} of {scale} m"
        );
    }
    println!(
        "relative differences: lung {worst_lung:e}, markers {worst_marker:e}; \
         onto {onto_stats:?}, past {past_stats:?}"
    );
}

#[test]
fn snapshot_restore_continues() {
    let mut a = Torso::new(config(0, Method::Rosenbrock, 1e-7)).unwrap();
    a.advance_to(1.0).unwrap();
    let snap = a.snapshot();
    a.advance_to(2.0).unwrap();
    let va = a.read(Quantity::LungVolume).unwrap();
    let mut b = Torso::new(config(0, Method::Rosenbrock, 1e-7)).unwrap();
    b.restore(&snap).unwrap();
    b.advance_to(2.0).unwrap();
    let vb = b.read(Quantity::LungVolume).unwrap();
    assert!((va - vb).abs() < 1e-5, "{va} vs {vb}");
    assert!(b.solver_stats().jacobian_evaluations > 0);
}

/// Model constants can be overridden from the configuration (stiff-scene studies): a stiffer
/// cartilage changes the compiled model, and a constant out of range is refused by name.
#[test]
fn params_override_is_compiled_and_validated() {
    let base = Config {
        scene: breathing_torso::model::Scene {
            level_of_detail: 0,
            ..Default::default()
        },
        ..Config::default()
    };
    let mut params = Params::for_posture(base.subject.posture);
    params.cartilage_stiffness *= 10.0;
    let stiff = Config {
        params: Some(params.clone()),
        ..base.clone()
    };
    let a = Torso::new(base).expect("default constants");
    let b = Torso::new(stiff).expect("stiffer cartilage");
    assert_ne!(a.compiled().fingerprint, b.compiled().fingerprint);
    assert_eq!(
        b.compiled().model.params.cartilage_stiffness,
        10.0 * a.compiled().model.params.cartilage_stiffness
    );
    params.bulk_modulus = -1.0;
    let bad = Config {
        params: Some(params),
        ..Config::default()
    };
    let err = Torso::new(bad)
        .err()
        .expect("negative bulk modulus refused");
    assert!(err.to_string().contains("params.bulk_modulus"), "{err}");
}

/// Row-relative error max |J_ij - D_ij| / max_j |D_ij| of `jac` against the dense matrix `d`.
fn row_relative(jac: &[f64], d: &[f64], n: usize) -> f64 {
    let mut worst = 0.0f64;
    for i in 0..n {
        let row = &d[i * n..(i + 1) * n];
        let scale = row.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-9);
        for j in 0..n {
            worst = worst.max((jac[i * n + j] - row[j]).abs() / scale);
        }
    }
    worst
}

/// The Jacobian the stiff method integrates with ([`TorsoJacobian::full`]) is that of the
/// right-hand side it integrates, the scaled mass matrix whole (the rigid bodies' coupling and
/// the cavities' volume inertances): central differences of `dynamics::rhs` at a breathing
/// state agree within 1e-4 of each row's largest entry (central differences with steps of
/// 1e-6 relative: truncation ~1e-12, round-off ~1e-10 relative to the row, so 1e-4 leaves
/// room for the sparse part's forward differences). The local Jacobian (mass blocks alone),
/// which the stiff method used before, is off by the order of the entries themselves.
#[test]
fn full_jacobian_matches_the_full_right_hand_side() {
    let model = compile(0);
    let mut data = Data::new(&model);
    let mut torso = Torso::new(config(0, Method::Dopri5, 1e-8)).unwrap();
    torso.advance_to(1.2).unwrap();
    let y = torso.state().to_vec();
    let n = y.len();
    let mut groups = [0.0; MuscleGroup::COUNT];
    for (g, v) in groups.iter_mut().enumerate() {
        *v = 0.05 + 0.02 * g as f64;
    }
    let act = Activations::new(&groups, 1.0, 1.0);
    let mut f0 = vec![0.0; n];
    dynamics::rhs(&model, &mut data, &act, &y, &mut f0);
    let dense_of = |tj: &mut TorsoJacobian, data: &mut Data| {
        let st = tj.structure();
        let mut jac = Jacobian::zeros(st.pattern.clone(), st.rank);
        tj.evaluate(&model, data, &act, &y, &f0, &mut jac);
        jac.to_dense()
    };
    let full = dense_of(&mut TorsoJacobian::full(&model), &mut data);
    let local = dense_of(&mut TorsoJacobian::new(&model), &mut data);
    let (mut yp, mut fp, mut fm) = (y.clone(), vec![0.0; n], vec![0.0; n]);
    let mut truth = vec![0.0; n * n];
    for j in 0..n {
        let d = 1e-6 * y[j].abs().max(1e-2);
        yp[j] = y[j] + d;
        dynamics::rhs(&model, &mut data, &act, &yp, &mut fp);
        yp[j] = y[j] - d;
        dynamics::rhs(&model, &mut data, &act, &yp, &mut fm);
        yp[j] = y[j];
        for i in 0..n {
            truth[i * n + j] = (fp[i] - fm[i]) / (2.0 * d);
        }
    }
    let (e_full, e_local) = (
        row_relative(&full, &truth, n),
        row_relative(&local, &truth, n),
    );
    println!("row-relative error: full {e_full:.2e}, local {e_local:.2e}");
    assert!(e_full < 1e-4, "full Jacobian: {e_full:e}");
    assert!(
        e_local > 0.1,
        "the local Jacobian should miss the mass coupling: {e_local:e}"
    );
}
