//! Prints how the diaphragm dome and the abdominal wall move at peak inspiration of a
//! diaphragm-only drive, binned by height on the parametric sphere.

use breathing_torso::model::{Config, Drive, Wave};
use breathing_torso::{Quantity, Torso};

fn main() {
    let mut c = Config::default();
    let amp: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.25);
    c.drive = Drive {
        frequency: 0.25,
        ribs: Wave::default(),
        diaphragm: Wave {
            amplitude: amp,
            phase: -std::f64::consts::FRAC_PI_2,
        },
        abdominals: Wave::default(),
    };
    let mut t = Torso::new(c).unwrap();
    t.advance_to(2.0).unwrap();
    let comp = t.compiled().clone();
    let ab = &comp.anatomy.abdomen;
    let model = &comp.model;
    let y = t.state().to_vec();
    let l = breathing_torso::dynamics::Layout::new(model);
    let mut bins = vec![(0.0, 0.0, 0.0, 0usize); 10];
    for (v, &a) in ab.anchor.iter().enumerate() {
        if let breathing_torso::dynamics::Carrier::Vertex(j) = model.carrier[a as usize] {
            let p = &y[l.vertex_x + 3 * j as usize..l.vertex_x + 3 * j as usize + 3];
            let r = model.rest[a as usize];
            let b = (((ab.sphere[v].y + 1.0) / 2.0 * 10.0) as usize).min(9);
            bins[b].0 += p[0] - r.x;
            bins[b].1 += p[1] - r.y;
            bins[b].2 += p[2] - r.z;
            bins[b].3 += 1;
        }
    }
    for (i, b) in bins.iter().enumerate() {
        if b.3 > 0 {
            let n = b.3 as f64;
            println!(
                "u_y {:5.2}: n {:4} mean d = ({:7.2}, {:7.2}, {:7.2}) mm",
                -1.0 + 0.2 * i as f64 + 0.1,
                b.3,
                1e3 * b.0 / n,
                1e3 * b.1 / n,
                1e3 * b.2 / n
            );
        }
    }
    // Volume sensitivity: move every free dome vertex down 1 mm at rest.
    let mut pos = model.rest.clone();
    let mut moved = 0;
    for (v, &a) in ab.anchor.iter().enumerate() {
        if ab.roles[v] == breathing_torso::anatomy::VertexRole::Dome {
            pos[a as usize].y -= 1e-3;
            moved += 1;
        }
    }
    let vt0 = breathing_torso::dynamics::volume(&model.rest, &model.thorax_triangles);
    let vt1 = breathing_torso::dynamics::volume(&pos, &model.thorax_triangles);
    let va0 = breathing_torso::dynamics::volume(&model.rest, &model.abdomen_triangles);
    let va1 = breathing_torso::dynamics::volume(&pos, &model.abdomen_triangles);
    println!(
        "dome down 1 mm ({moved} vertices): d thorax = {:.4} L, d abdomen = {:.4} L",
        (vt1 - vt0) * 1e3,
        (va1 - va0) * 1e3
    );
    for q in [
        Quantity::LungVolume,
        Quantity::AbdomenDisplaced,
        Quantity::RibCageDisplaced,
        Quantity::AbdominalPressure,
        Quantity::DiaphragmDisplacement,
    ] {
        println!("{q:?} = {:.4}", t.read(q).unwrap());
    }
}
