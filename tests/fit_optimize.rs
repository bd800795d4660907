//! The optimisers on test functions: Rosenbrock, bounded quadratics with the minimum on a
//! bound, a multimodal function for the robust methods, budgets and bad input.

use breathing_torso::numeric::optimize::{
    Bounds, NelderMeadOptions, cmaes, multistart, nelder_mead,
};

fn quiet(_: usize, _: f64) {}

fn rosenbrock(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

#[test]
fn nelder_mead_solves_rosenbrock_2d() {
    let b = Bounds::new(&[(-2.0, 2.0), (-2.0, 2.0)]).unwrap();
    let o = NelderMeadOptions {
        max_evals: 400,
        x_tol: 1e-6,
        f_tol: 1e-14,
        ..NelderMeadOptions::default()
    };
    let mut calls = 0;
    let mut f = |x: &[f64]| {
        calls += 1;
        Ok(rosenbrock(x))
    };
    let m = nelder_mead(&mut f, &[-1.2, 1.0], &b, &o, &mut quiet).unwrap();
    assert!(m.converged, "{m:?}");
    assert!(
        (m.x[0] - 1.0).abs() < 1e-3 && (m.x[1] - 1.0).abs() < 2e-3,
        "{m:?}"
    );
    assert!(m.evaluations <= 400);
    assert_eq!(calls, m.evaluations);
    assert_eq!(m.f_start, rosenbrock(&[-1.2, 1.0]));
}

#[test]
fn nelder_mead_solves_rosenbrock_4d() {
    let b = Bounds::new(&[(-2.0, 2.0); 4]).unwrap();
    let o = NelderMeadOptions {
        max_evals: 3000,
        x_tol: 1e-7,
        f_tol: 1e-14,
        ..NelderMeadOptions::default()
    };
    let mut f = |x: &[f64]| Ok(rosenbrock(x));
    let m = nelder_mead(&mut f, &[-1.0, 1.5, -0.5, 0.5], &b, &o, &mut quiet).unwrap();
    assert!(m.f < 1e-6, "{m:?}");
}

#[test]
fn nelder_mead_respects_the_budget() {
    let b = Bounds::new(&[(-2.0, 2.0); 4]).unwrap();
    let o = NelderMeadOptions {
        max_evals: 37,
        x_tol: 0.0,
        f_tol: 0.0,
        ..NelderMeadOptions::default()
    };
    let mut calls = 0;
    let mut f = |x: &[f64]| {
        calls += 1;
        Ok(rosenbrock(x))
    };
    let m = nelder_mead(&mut f, &[0.0; 4], &b, &o, &mut quiet).unwrap();
    assert!(!m.converged);
    assert_eq!(m.evaluations, calls);
    assert!(calls <= 37, "{calls}");
}

#[test]
fn bounded_quadratic_minimum_on_the_bounds() {
    // Unconstrained minimum at (-1, 0.3, 2, 0.5); the box is [0, 1]^4 -> (0, 0.3, 1, 0.5).
    let c = [-1.0, 0.3, 2.0, 0.5];
    let w = [1.0, 4.0, 0.5, 2.0];
    let b = Bounds::new(&[(0.0, 1.0); 4]).unwrap();
    let mut f = |x: &[f64]| {
        assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "outside: {x:?}");
        Ok(x.iter()
            .zip(c)
            .zip(w)
            .map(|((x, c), w)| w * (x - c).powi(2))
            .sum::<f64>())
    };
    let m = nelder_mead(
        &mut f,
        &[0.5; 4],
        &b,
        &NelderMeadOptions::default(),
        &mut quiet,
    )
    .unwrap();
    let want = [0.0, 0.3, 1.0, 0.5];
    for (x, w) in m.x.iter().zip(want) {
        assert!((x - w).abs() < 1e-2, "{m:?}");
    }
    assert!(m.evaluations <= 120);
}

#[test]
fn start_outside_the_box_is_projected() {
    let b = Bounds::new(&[(0.0, 1.0), (0.0, 1.0)]).unwrap();
    let mut f = |x: &[f64]| Ok((x[0] - 0.2).powi(2) + (x[1] - 0.7).powi(2));
    let m = nelder_mead(
        &mut f,
        &[5.0, -3.0],
        &b,
        &NelderMeadOptions::default(),
        &mut quiet,
    )
    .unwrap();
    assert!(
        (m.x[0] - 0.2).abs() < 5e-3 && (m.x[1] - 0.7).abs() < 5e-3,
        "{m:?}"
    );
}

/// Two basins: a shallow local one at (0.2, 0.2) and the global one at (0.8, 0.75).
fn two_basins(x: &[f64]) -> f64 {
    let a = (x[0] - 0.2).powi(2) + (x[1] - 0.2).powi(2);
    let b = (x[0] - 0.8).powi(2) + (x[1] - 0.75).powi(2);
    (0.5 + 10.0 * a).min(10.0 * b)
}

#[test]
fn multistart_escapes_a_local_minimum() {
    let b = Bounds::new(&[(0.0, 1.0), (0.0, 1.0)]).unwrap();
    let o = NelderMeadOptions::default();
    let mut f = |x: &[f64]| Ok(two_basins(x));
    let local = nelder_mead(&mut f, &[0.15, 0.1], &b, &o, &mut quiet).unwrap();
    assert!(
        local.f > 0.4,
        "plain Nelder-Mead should stay in the local basin: {local:?}"
    );
    let m = multistart(&mut f, &[0.15, 0.1], &b, &o, 4, 3, &mut quiet).unwrap();
    assert!(m.f < 1e-4, "{m:?}");
    assert!((m.x[0] - 0.8).abs() < 5e-3 && (m.x[1] - 0.75).abs() < 5e-3);
    assert!(m.evaluations <= 120);
}

#[test]
fn cmaes_solves_a_rotated_ellipsoid_and_rosenbrock() {
    let b = Bounds::new(&[(-3.0, 3.0); 4]).unwrap();
    let mut f = |x: &[f64]| {
        let s = x[0] + x[1];
        let d = x[2] - 0.5 * x[3];
        Ok(s * s + 30.0 * d * d + (x[0] - 1.0).powi(2) + (x[3] - 1.0).powi(2))
    };
    // Stops when the step is below 1e-3 of the range (6e-3 here).
    let m = cmaes(&mut f, &[2.0, 2.0, -2.0, 0.0], &b, 2000, 0.3, 5, &mut quiet).unwrap();
    assert!(m.f < 1e-4, "{m:?}");
    let want = [1.0, -1.0, 0.5, 1.0];
    assert!(
        m.x.iter().zip(want).all(|(x, w)| (x - w).abs() < 1e-2),
        "{m:?}"
    );
    assert!(m.evaluations <= 2000);
    let b2 = Bounds::new(&[(-2.0, 2.0); 2]).unwrap();
    let mut g = |x: &[f64]| Ok(rosenbrock(x));
    let m = cmaes(&mut g, &[-1.2, 1.0], &b2, 3000, 0.3, 9, &mut quiet).unwrap();
    assert!(m.f < 1e-4, "{m:?}");
}

#[test]
fn cmaes_stays_in_the_box_and_finds_a_bound_minimum() {
    let b = Bounds::new(&[(0.0, 1.0); 3]).unwrap();
    let mut f = |x: &[f64]| {
        assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "outside: {x:?}");
        Ok((x[0] + 0.5).powi(2) + (x[1] - 0.4).powi(2) + (x[2] - 1.5).powi(2))
    };
    let m = cmaes(&mut f, &[0.5; 3], &b, 600, 0.3, 2, &mut quiet).unwrap();
    assert!(
        m.x[0] < 1e-2 && (m.x[1] - 0.4).abs() < 1e-2 && m.x[2] > 0.99,
        "{m:?}"
    );
}

#[test]
fn objective_errors_stop_the_search() {
    let b = Bounds::new(&[(0.0, 1.0); 2]).unwrap();
    let mut n = 0;
    let mut f = |_: &[f64]| {
        n += 1;
        if n == 5 {
            Err(breathing_torso::Error::State("model failed".into()))
        } else {
            Ok(1.0)
        }
    };
    let e = nelder_mead(
        &mut f,
        &[0.5, 0.5],
        &b,
        &NelderMeadOptions::default(),
        &mut quiet,
    )
    .unwrap_err();
    assert!(e.to_string().contains("model failed"));
}

#[test]
fn bad_bounds_and_starts_are_rejected() {
    assert!(Bounds::new(&[(1.0, 1.0)]).is_err());
    assert!(Bounds::new(&[(0.0, f64::NAN)]).is_err());
    let b = Bounds::new(&[(0.0, 1.0); 2]).unwrap();
    let mut f = |_: &[f64]| Ok(0.0);
    let o = NelderMeadOptions::default();
    assert!(nelder_mead(&mut f, &[0.5], &b, &o, &mut quiet).is_err());
    assert!(nelder_mead(&mut f, &[0.5, f64::NAN], &b, &o, &mut quiet).is_err());
}

#[test]
fn progress_reports_every_evaluation_with_the_best_so_far() {
    let b = Bounds::new(&[(-2.0, 2.0); 2]).unwrap();
    let mut f = |x: &[f64]| Ok(rosenbrock(x));
    let mut seen = Vec::new();
    let m = nelder_mead(
        &mut f,
        &[0.0, 0.0],
        &b,
        &NelderMeadOptions::default(),
        &mut |n, best| seen.push((n, best)),
    )
    .unwrap();
    assert_eq!(seen.len(), m.evaluations);
    assert!(
        seen.windows(2)
            .all(|w| w[1].0 == w[0].0 + 1 && w[1].1 <= w[0].1)
    );
    assert_eq!(seen.last().unwrap().1, m.f);
}
