//! Structure and order conditions of the Butcher tableaux.
//!
//! The order conditions are checked on all rooted trees up to the order of each formula
//! (Butcher; Hairer, Norsett & Wanner, *Solving ODEs I*, Sec. II.2): Σ b_i Φ_i(τ) = 1/γ(τ)
//! for the solution and the embedded formulas, and Σ b_i(θ) Φ_i(τ) = θ^|τ|/γ(τ) for the
//! continuous extensions. The tree conditions assume c_i = Σ_j a_ij (autonomous form), so
//! that identity is checked separately: it is what makes a pair correct on time-dependent
//! problems.

use breathing_torso::solver::{Method, Tableau};

/// A rooted tree given by its children (indices into the global list, non-decreasing).
struct Tree {
    order: usize,
    gamma: f64,
    children: Vec<usize>,
}

/// All rooted trees up to `max_order`, smaller orders first.
fn trees(max_order: usize) -> Vec<Tree> {
    let mut all = vec![Tree {
        order: 1,
        gamma: 1.0,
        children: vec![],
    }];
    for n in 2..=max_order {
        let known = all.len();
        let mut found = Vec::new();
        let mut stack = Vec::new();
        children_sets(&all[..known], n - 1, 0, &mut stack, &mut found);
        for children in found {
            let gamma = n as f64 * children.iter().map(|&c| all[c].gamma).product::<f64>();
            all.push(Tree {
                order: n,
                gamma,
                children,
            });
        }
    }
    all
}

/// Multisets of trees (indices >= `from`) whose orders add up to `rest`.
fn children_sets(
    known: &[Tree],
    rest: usize,
    from: usize,
    stack: &mut Vec<usize>,
    out: &mut Vec<Vec<usize>>,
) {
    if rest == 0 {
        out.push(stack.clone());
        return;
    }
    for i in from..known.len() {
        if known[i].order <= rest {
            stack.push(i);
            children_sets(known, rest - known[i].order, i, stack, out);
            stack.pop();
        }
    }
}

/// Full (extended) coefficient matrix: the pair's stages followed by the extra dense stages.
fn full_a(tab: &Tableau) -> Vec<Vec<f64>> {
    let rows: Vec<&[f64]> = tab
        .a
        .iter()
        .copied()
        .chain(tab.dense.extra_a.iter().copied())
        .collect();
    let m = rows.len();
    rows.iter()
        .map(|r| {
            let mut v = vec![0.0; m];
            v[..r.len()].copy_from_slice(r);
            v
        })
        .collect()
}

/// Φ_i(τ) for every stage i and tree τ.
fn stage_weights(a: &[Vec<f64>], trees: &[Tree]) -> Vec<Vec<f64>> {
    let m = a.len();
    let mut phi: Vec<Vec<f64>> = Vec::with_capacity(trees.len());
    for t in trees {
        let mut g = vec![1.0; m];
        for &c in &t.children {
            for i in 0..m {
                g[i] *= (0..m).map(|j| a[i][j] * phi[c][j]).sum::<f64>();
            }
        }
        phi.push(g);
    }
    phi
}

/// Largest violation of Σ w_i Φ_i(τ) = scale^|τ| / γ(τ) over trees of order <= p.
fn worst_violation(w: &[f64], phi: &[Vec<f64>], trees: &[Tree], p: usize, scale: f64) -> f64 {
    trees
        .iter()
        .zip(phi)
        .filter(|(t, _)| t.order <= p)
        .map(|(t, g)| {
            let lhs: f64 = w.iter().zip(g).map(|(a, b)| a * b).sum();
            (lhs - scale.powi(t.order as i32) / t.gamma).abs()
        })
        .fold(0.0, f64::max)
}

/// Smallest violation among trees of exactly order p (shows the order is not higher).
fn max_violation_at(w: &[f64], phi: &[Vec<f64>], trees: &[Tree], p: usize) -> f64 {
    trees
        .iter()
        .zip(phi)
        .filter(|(t, _)| t.order == p)
        .map(|(t, g)| {
            let lhs: f64 = w.iter().zip(g).map(|(a, b)| a * b).sum();
            (lhs - 1.0 / t.gamma).abs()
        })
        .fold(0.0, f64::max)
}

fn padded(v: &[f64], m: usize) -> Vec<f64> {
    let mut out = vec![0.0; m];
    out[..v.len()].copy_from_slice(v);
    out
}

/// Weights b_j(θ) of the continuous extension, from its nested form.
fn dense_weights(tab: &Tableau, theta: f64) -> Vec<f64> {
    let s = tab.stages;
    let m = s + tab.dense.extra_c.len();
    let b = padded(tab.a[s - 1], m);
    let mut r: Vec<Vec<f64>> = Vec::new();
    r.push(b.clone());
    r.push((0..m).map(|j| f64::from(j == 0) - b[j]).collect());
    r.push(
        (0..m)
            .map(|j| 2.0 * b[j] - f64::from(j == 0) - f64::from(j == s - 1))
            .collect(),
    );
    for d in tab.dense.d {
        r.push(padded(d, m));
    }
    let mut acc = vec![0.0; m];
    for (j, rj) in r.iter().enumerate().rev() {
        let f = if j % 2 == 0 { theta } else { 1.0 - theta };
        for i in 0..m {
            acc[i] = (rj[i] + acc[i]) * f;
        }
    }
    acc
}

/// Largest |c_i - Σ_j a_ij| over all rows, the extra dense stages included.
fn worst_row_sum(c: &[f64], a: &[&[f64]]) -> f64 {
    c.iter()
        .zip(a)
        .map(|(ci, row)| (ci - row.iter().sum::<f64>()).abs())
        .fold(0.0, f64::max)
}

#[test]
fn row_sums_equal_abscissae() {
    for m in Method::EMBEDDED {
        let tab = m.tableau().unwrap();
        assert_eq!(tab.c.len(), tab.stages, "{m:?}");
        assert_eq!(tab.a.len(), tab.stages, "{m:?}");
        for (i, row) in tab.a.iter().enumerate() {
            assert_eq!(row.len(), i, "{m:?} row {i}");
        }
        let w = worst_row_sum(tab.c, tab.a);
        assert!(w < 1e-14, "{m:?}: c_i != sum_j a_ij by {w:e}");
        let we = worst_row_sum(tab.dense.extra_c, tab.dense.extra_a);
        assert!(we < 1e-14, "{m:?} extra stages: {we:e}");
        for (i, row) in tab.dense.extra_a.iter().enumerate() {
            assert_eq!(row.len(), tab.stages + i, "{m:?} extra row {i}");
        }
    }
}

#[test]
fn row_sum_check_catches_a_wrong_abscissa() {
    // the defect of a popular crate's DOP853: c12 = 0 instead of 1
    let tab = Method::HighOrder.tableau().unwrap();
    let mut c = tab.c.to_vec();
    c[11] = 0.0;
    assert!(worst_row_sum(&c, tab.a) > 0.5);
}

#[test]
fn fsal_structure_and_estimator_consistency() {
    for m in Method::EMBEDDED {
        let tab = m.tableau().unwrap();
        let s = tab.stages;
        assert_eq!(tab.c[s - 1], 1.0, "{m:?}: last stage must be at c = 1");
        let b = tab.a[s - 1];
        assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-14, "{m:?}");
        assert_eq!(tab.e.len(), s, "{m:?}");
        assert!(
            tab.e.iter().sum::<f64>().abs() < 1e-14,
            "{m:?}: sum of error weights"
        );
        if let Some(el) = tab.e_low {
            assert_eq!(el.len(), s);
            assert!(
                el.iter().sum::<f64>().abs() < 1e-14,
                "{m:?}: sum of low error weights"
            );
        }
        for (i, d) in tab.dense.d.iter().enumerate() {
            assert_eq!(d.len(), s + tab.dense.extra_c.len(), "{m:?} d row {i}");
            assert!(d.iter().sum::<f64>().abs() < 1e-12, "{m:?} d row {i} sum");
        }
        if let Some(st) = tab.stiff_stage {
            assert!(st > 0 && st < s - 1, "{m:?}");
            assert_eq!(
                tab.c[st], 1.0,
                "{m:?}: the stiffness stage must share c = 1 with y1"
            );
        }
    }
}

#[test]
fn order_conditions_hold() {
    let all = trees(8);
    assert_eq!(all.len(), 1 + 1 + 2 + 4 + 9 + 20 + 48 + 115);
    // (method, order of b, orders of b - e and b - e_low)
    let cases = [
        (Method::Dopri5, 5, 4, 0),
        (Method::BogackiShampine3, 3, 2, 0),
        (Method::HighOrder, 8, 5, 3),
    ];
    for (m, p, p_hat, p_low) in cases {
        let tab = m.tableau().unwrap();
        let a = full_a(tab);
        let mm = a.len();
        let phi = stage_weights(&a, &all);
        let b = padded(tab.a[tab.stages - 1], mm);
        let v = worst_violation(&b, &phi, &all, p, 1.0);
        assert!(v < 1e-13, "{m:?}: order {p} conditions violated by {v:e}");
        // and not one order more (catches a transcription that is accidentally different)
        if p < 8 {
            assert!(max_violation_at(&b, &phi, &all, p + 1) > 1e-6, "{m:?}");
        }
        let e = padded(tab.e, mm);
        let bhat: Vec<f64> = b.iter().zip(&e).map(|(x, y)| x - y).collect();
        let v = worst_violation(&bhat, &phi, &all, p_hat, 1.0);
        assert!(v < 1e-13, "{m:?}: embedded order {p_hat} violated by {v:e}");
        assert!(
            max_violation_at(&bhat, &phi, &all, p_hat + 1) > 1e-6,
            "{m:?}: embedded"
        );
        if let Some(el) = tab.e_low {
            let el = padded(el, mm);
            let blow: Vec<f64> = b.iter().zip(&el).map(|(x, y)| x - y).collect();
            let v = worst_violation(&blow, &phi, &all, p_low, 1.0);
            assert!(v < 1e-13, "{m:?}: low-order estimator violated by {v:e}");
        }
    }
}

#[test]
fn continuous_extensions_have_their_order() {
    let all = trees(8);
    for m in Method::EMBEDDED {
        let tab = m.tableau().unwrap();
        let a = full_a(tab);
        let phi = stage_weights(&a, &all);
        let q = tab.dense.order as usize;
        for theta in [0.0, 0.1, 0.37, 0.5, 0.8, 1.0] {
            let w = dense_weights(tab, theta);
            let v = worst_violation(&w, &phi, &all, q, theta);
            assert!(
                v < 1e-11,
                "{m:?}: dense order {q} at theta {theta} violated by {v:e}"
            );
        }
        // θ = 1 reproduces the step's weights b
        let w1 = dense_weights(tab, 1.0);
        let b = padded(tab.a[tab.stages - 1], a.len());
        for (x, y) in w1.iter().zip(&b) {
            assert!((x - y).abs() < 1e-12, "{m:?}");
        }
    }
}
