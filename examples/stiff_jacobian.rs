//! How well the stiff method's Jacobian approximates the true one at a state of quiet
//! breathing: central differences of the full right-hand side (the scaled mass matrix whole,
//! volume inertances included) against [`TorsoJacobian::full`] (sparse part, rank-two
//! pressure part and the mass matrix's 32 rank-one terms, as the stiff method uses it) and
//! against [`TorsoJacobian::new`] (the mass matrix block by block, as the equilibrium's Newton
//! uses it), per block of rows and columns (positions, velocities), as the relative Frobenius
//! error. The activations are fixed (0.05 + 0.02 g for group g), not the drive's.
//!
//! `cargo run --release --example stiff_jacobian -- LOD TIME [DIR]`: the default subject at
//! level of detail `LOD`, quiet drive, state after `TIME` seconds; with `DIR`, also writes the
//! dense matrices (`true.f64`, `ours.f64`, `local.f64`, row-major, f64 little-endian) and the
//! state's layout (`layout.txt`) for an eigenvalue analysis.

use breathing_torso::Torso;
use breathing_torso::dynamics::jacobian::TorsoJacobian;
use breathing_torso::dynamics::{self, Activations, Data, Layout, Model, Params};
use breathing_torso::model::{Config, Drive, Scene};
use breathing_torso::solver::Jacobian;
use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        return Err("usage: stiff_jacobian LOD TIME [DIR]".into());
    }
    let lod: u32 = args[1].parse()?;
    let t: f64 = args[2].parse()?;
    let config = Config {
        drive: Drive::quiet(),
        scene: Scene {
            level_of_detail: lod,
            ..Scene::default()
        },
        ..Config::default()
    };
    let anatomy = breathing_torso::anatomy::Anatomy::build(&config.subject, lod)?;
    let model = Model::compile(&anatomy, Params::for_posture(config.subject.posture));
    let mut torso = Torso::new(config)?;
    torso.advance_to(t)?;
    let y = torso.state().to_vec();
    let n = y.len();
    let l = Layout::new(&model);
    let mut groups = [0.0; breathing_torso::anatomy::MuscleGroup::COUNT];
    for (g, v) in groups.iter_mut().enumerate() {
        *v = 0.05 + 0.02 * g as f64;
    }
    let act = Activations::new(&groups, 1.0, 1.0);
    let mut data = Data::new(&model);
    let mut f0 = vec![0.0; n];
    dynamics::rhs(&model, &mut data, &act, &y, &mut f0);
    let mut tj = TorsoJacobian::full(&model);
    let st = tj.structure();
    let mut jac = Jacobian::zeros(st.pattern.clone(), st.rank);
    tj.evaluate(&model, &mut data, &act, &y, &f0, &mut jac);
    let ours = jac.to_dense();
    // the local Jacobian (block-diagonal mass, as before the full one)
    let mut tl = TorsoJacobian::new(&model);
    let sl = tl.structure();
    let mut jl = Jacobian::zeros(sl.pattern.clone(), sl.rank);
    tl.evaluate(&model, &mut data, &act, &y, &f0, &mut jl);
    let local = jl.to_dense();
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
    let blocks = [
        ("ribs angle", l.theta..l.sternum_x),
        ("sternum pose", l.sternum_x..l.vertex_x),
        ("vertex pos", l.vertex_x..l.theta_dot),
        ("ribs rate", l.theta_dot..l.sternum_v),
        ("sternum vel", l.sternum_v..l.vertex_v),
        ("vertex vel", l.vertex_v..n),
    ];
    for (label, m) in [
        ("full (stiff method)", &ours),
        ("local (mass blocks only)", &local),
    ] {
        println!("n = {n}; {label}: relative Frobenius error ||J - J_fd|| / ||J_fd|| per block");
        print!("{:>14}", "rows \\ cols");
        for (name, _) in &blocks {
            print!("{name:>14}");
        }
        println!();
        for (rn, rr) in &blocks {
            print!("{rn:>14}");
            for (_, cr) in &blocks {
                let (mut e, mut s) = (0.0, 0.0);
                for i in rr.clone() {
                    for j in cr.clone() {
                        let d = m[i * n + j] - truth[i * n + j];
                        e += d * d;
                        s += truth[i * n + j] * truth[i * n + j];
                    }
                }
                if s == 0.0 && e == 0.0 {
                    print!("{:>14}", "0");
                } else {
                    print!("{:>14.2e}", (e / s.max(1e-300)).sqrt());
                }
            }
            println!();
        }
    }
    if let Some(dir) = args.get(3) {
        for (name, m) in [
            ("true.f64", &truth),
            ("ours.f64", &ours),
            ("local.f64", &local),
        ] {
            let mut f = std::io::BufWriter::new(std::fs::File::create(format!("{dir}/{name}"))?);
            for v in m.iter() {
                f.write_all(&v.to_le_bytes())?;
            }
        }
        std::fs::write(
            format!("{dir}/layout.txt"),
            format!(
                "{} {} {} {} {} {} {} {} {}\n",
                n,
                l.theta,
                l.sternum_x,
                l.sternum_q,
                l.vertex_x,
                l.theta_dot,
                l.sternum_v,
                l.sternum_w,
                l.vertex_v
            ),
        )?;
    }
    Ok(())
}
