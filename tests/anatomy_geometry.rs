//! Geometry of the default subject's anatomy: closed, consistently oriented cavities with
//! plausible volumes, ribs and muscles where anatomy puts them.

use breathing_torso::anatomy::{Anatomy, MuscleGroup, Subject};
use breathing_torso::mesh::TriMesh;

fn mesh(anatomy: &Anatomy, tris: Vec<[u32; 3]>) -> TriMesh {
    let verts = anatomy.anchors.iter().map(|a| a.rest).collect();
    TriMesh {
        vertices: verts,
        triangles: tris,
    }
}

#[test]
fn cavities_are_closed_and_oriented() {
    for lod in 0..3 {
        let a = Anatomy::build(&Subject::default(), lod).unwrap();
        let abd = mesh(&a, a.abdomen.anchor_triangles().collect());
        let tho = mesh(&a, a.thorax_triangles());
        for (name, m) in [("abdomen", &abd), ("thorax", &tho)] {
            let topo = m.topology();
            println!(
                "lod {lod} {name}: V = {:.3} L, closed {}, manifold {}, oriented {}",
                m.volume() * 1e3,
                m.is_closed(),
                m.is_edge_manifold(),
                m.is_consistently_oriented()
            );
            let _ = topo;
            assert!(m.is_closed(), "{name} at lod {lod} not closed");
            assert!(
                m.is_consistently_oriented(),
                "{name} at lod {lod} not oriented"
            );
            assert!(m.volume() > 0.0, "{name} at lod {lod} has negative volume");
        }
        let counts: Vec<(MuscleGroup, usize, usize)> = MuscleGroup::ALL
            .iter()
            .map(|g| (*g, a.muscles.iter().filter(|m| m.group == *g).count()))
            .collect();
        println!(
            "lod {lod}: abdomen vertices {}, muscles {:?}",
            a.abdomen.len(),
            counts
        );
    }
}
