//! Prints the stiffest and most damped degrees of freedom of the default model (diagonal of a
//! finite-difference Jacobian), to find what limits an explicit solver's step.

use breathing_torso::anatomy::{Anatomy, Subject};
use breathing_torso::dynamics::{self, Activations, Data, Layout, Model, Params};

fn main() {
    let lod: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let a = Anatomy::build(&Subject::default(), lod).unwrap();
    let m = Model::compile(&a, Params::for_posture(a.subject.posture));
    let l = Layout::new(&m);
    let mut d = Data::new(&m);
    let y0 = dynamics::rest_state(&m);
    let n = y0.len();
    let act = Activations::default();
    let mut f0 = vec![0.0; n];
    dynamics::rhs(&m, &mut d, &act, &y0, &mut f0);
    let nq = l.theta_dot;
    let mut diag = Vec::new();
    for i in 0..nq {
        let name = if i < 24 {
            format!("rib{}", i)
        } else if i < 31 {
            format!("sternum{}", i - 24)
        } else {
            format!("vertex{}", (i - 31) / 3)
        };
        // acceleration index for coordinate i (quaternion has 4 q's vs 3 w's: skip)
        if (27..31).contains(&i) {
            continue;
        }
        let ai = if i < 24 {
            l.theta_dot + i
        } else if i < 27 {
            l.sternum_v + i - 24
        } else {
            l.vertex_v + (i - l.vertex_x)
        };
        let mut y = y0.clone();
        let h = 1e-7;
        y[i] += h;
        let mut f = vec![0.0; n];
        dynamics::rhs(&m, &mut d, &act, &y, &mut f);
        let kq = -(f[ai] - f0[ai]) / h;
        let mut y = y0.clone();
        y[ai] += h;
        dynamics::rhs(&m, &mut d, &act, &y, &mut f);
        let cv = -(f[ai] - f0[ai]) / h;
        diag.push((kq.abs().sqrt(), cv, name));
    }
    diag.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!("largest sqrt(k/m) [rad/s]:");
    for d in diag.iter().take(8) {
        println!("  {:10.1} damping {:10.1}  {}", d.0, d.1, d.2);
    }
    diag.sort_by(|a, b| b.1.total_cmp(&a.1));
    println!("largest damping rate c/m [1/s]:");
    for d in diag.iter().take(8) {
        println!("  {:10.1} omega {:10.1}  {}", d.1, d.0, d.2);
    }
    // Sternum rotation: angular acceleration response to w.
    println!(
        "rib inertias: {:?}",
        m.rib_inertia
            .iter()
            .map(|i| format!("{i:.2e}"))
            .collect::<Vec<_>>()
    );
}
