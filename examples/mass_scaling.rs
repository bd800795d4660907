//! The selective mass scaling of the default subject (`dynamics::inertia`): how much inertia
//! the scaling adds to each kind of body (trace of its block over the true one) and the two
//! cavities' volume inertances.
//!
//! `cargo run --release --example mass_scaling -- [LOD]`

use breathing_torso::anatomy::{Anatomy, Subject, VertexRole};
use breathing_torso::dynamics::{Carrier, Model, Params, RIBS};

fn summary(name: &str, v: &mut [f64]) {
    if v.is_empty() {
        return;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    println!(
        "{name:>20}: {n:4}, scaled / true inertia min {:8.2}  median {:8.2}  max {:8.2}",
        v[0],
        v[n / 2],
        v[n - 1]
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let lod: u32 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(1);
    let anatomy = Anatomy::build(&Subject::default(), lod)?;
    let model = Model::compile(&anatomy, Params::for_posture(anatomy.subject.posture));
    let m = &model.mass;
    let cmh2o_s2_per_l = 98.0665e3;
    println!(
        "LOD {lod}, inertia frequency {} Hz: volume inertances abdomen {:.4} and thorax {:.4} cmH2O s^2/L",
        model.params.inertia_frequency,
        m.inertance[0] / cmh2o_s2_per_l,
        m.inertance[1] / cmh2o_s2_per_l
    );
    summary("rib angles", &mut m.rigid_ratio[..RIBS].to_vec());
    summary(
        "sternum translation",
        &mut m.rigid_ratio[RIBS..RIBS + 3].to_vec(),
    );
    summary("sternum rotation", &mut m.rigid_ratio[RIBS + 3..].to_vec());
    let ab = &anatomy.abdomen;
    let (mut dome, mut wall) = (Vec::new(), Vec::new());
    for (v, &a) in ab.anchor.iter().enumerate() {
        if let Carrier::Vertex(j) = model.carrier[a as usize] {
            let f = m.vertex_ratio[j as usize];
            match ab.roles[v] {
                VertexRole::Dome => dome.push(f),
                _ => wall.push(f),
            }
        }
    }
    summary("dome vertices", &mut dome);
    summary("wall vertices", &mut wall);
    for id in std::env::args().skip(2) {
        let j: usize = id.parse()?;
        let anchor = model.vertex_anchor[j];
        let v = ab
            .anchor
            .iter()
            .position(|&a| a == anchor)
            .expect("a vertex of the abdomen");
        let el = &model.elements;
        let attached: Vec<usize> = (0..el.len())
            .filter(|&e| el.path_of(e).contains(&anchor))
            .collect();
        let muscles = attached.iter().filter(|&&e| e < model.muscle_count).count();
        let paths = attached
            .iter()
            .filter(|&&e| el.path_of(e).len() > 2)
            .count();
        println!(
            "vertex {j}: {:?}, true mass {:.4} kg, ratio {:.2}, {} elements ({muscles} muscles, {paths} via paths), at {:?}",
            ab.roles[v],
            model.vertex_mass[j],
            m.vertex_ratio[j],
            attached.len(),
            model.rest[anchor as usize]
        );
    }
    Ok(())
}

/// Prints what is known of the free vertices named on the command line after the level of
/// detail (true mass, inertia ratio, role, number of elements attached).
#[allow(dead_code)]
fn describe() {}
