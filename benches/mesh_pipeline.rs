//! Benchmark of the mesh preparation pipeline on a surface of about 50,000 triangles (a noisy
//! ellipsoid of torso size with an overlapping abdominal cavity), and of the stages one by
//! one: median wall time over repeated runs.
//!
//! Run with `cargo bench --bench mesh_pipeline` (add `-- N` for N repeats, default 5).

use std::time::Instant;

use breathing_torso::mesh::pipeline::{PrepareOptions, prepare};
use breathing_torso::mesh::{
    Bvh, OverlapOptions, Relation, RepairOptions, StuffOptions, Taubin, TriMesh, repair,
    resolve_overlap, stuff,
};
use nalgebra::{Point3, Vector3};

fn noisy(r: Vector3<f64>, c: Vector3<f64>, subdivisions: u32, amp: f64, seed: u64) -> TriMesh {
    let mut m = TriMesh::ellipsoid(&Point3::from(c), &r, subdivisions).expect("ellipsoid");
    let n = m.vertex_normals();
    let mut s = seed;
    for (p, n) in m.vertices.iter_mut().zip(&n) {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let u = (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
        *p += n * (amp * r.min() * u);
    }
    m
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let r = f();
    (r, t.elapsed().as_secs_f64() * 1e3)
}

fn main() {
    let repeats: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(5);
    // Icospheres come in 20 x 4^s triangles: two inputs bracket the 50,000-triangle target,
    // a level-5 skin with a level-5 abdominal cavity (40,960 triangles) and a level-6 skin
    // with a level-4 cavity (87,040 triangles); a third has a 50,000-triangle
    // latitude-longitude skin.
    let skin = noisy(Vector3::new(0.16, 0.32, 0.12), Vector3::zeros(), 5, 0.02, 1);
    let abdomen = noisy(
        Vector3::new(0.11, 0.14, 0.125),
        Vector3::new(0.0, -0.1, 0.0),
        5,
        0.01,
        2,
    );
    run_case(
        "icosphere skin (level 5) + abdomen (level 5)",
        skin,
        abdomen,
        repeats,
    );
    let skin = noisy(Vector3::new(0.16, 0.32, 0.12), Vector3::zeros(), 6, 0.02, 1);
    let abdomen = noisy(
        Vector3::new(0.11, 0.14, 0.125),
        Vector3::new(0.0, -0.1, 0.0),
        4,
        0.01,
        2,
    );
    run_case(
        "icosphere skin (level 6) + abdomen (level 4)",
        skin,
        abdomen,
        repeats,
    );
    // exactly 50,000 skin triangles, with the sliver pole fans of a latitude-longitude mesh
    let skin = uv(Vector3::new(0.16, 0.32, 0.12), 250, 101, 0.01, 3);
    let abdomen = noisy(
        Vector3::new(0.11, 0.14, 0.125),
        Vector3::new(0.0, -0.1, 0.0),
        4,
        0.01,
        2,
    );
    run_case(
        "latitude-longitude skin (50,000) + abdomen (level 4)",
        skin,
        abdomen,
        repeats,
    );
}

/// A noisy latitude-longitude ellipsoid: 2 nlon (nlat - 1) triangles.
fn uv(r: Vector3<f64>, nlon: usize, nlat: usize, amp: f64, seed: u64) -> TriMesh {
    let mut s = seed;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut m = TriMesh {
        vertices: vec![Point3::new(0.0, r.y, 0.0)],
        triangles: vec![],
    };
    for i in 1..nlat {
        let th = std::f64::consts::PI * i as f64 / nlat as f64;
        for j in 0..nlon {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / nlon as f64;
            let k = 1.0 + amp * rnd();
            m.vertices.push(Point3::new(
                r.x * th.sin() * ph.cos() * k,
                r.y * th.cos() * k,
                r.z * th.sin() * ph.sin() * k,
            ));
        }
    }
    m.vertices.push(Point3::new(0.0, -r.y, 0.0));
    let south = (m.vertices.len() - 1) as u32;
    let idx = |i: usize, j: usize| (1 + (i - 1) * nlon + j % nlon) as u32;
    for j in 0..nlon {
        m.triangles.push([0, idx(1, j + 1), idx(1, j)]);
        m.triangles
            .push([south, idx(nlat - 1, j), idx(nlat - 1, j + 1)]);
    }
    for i in 1..nlat - 1 {
        for j in 0..nlon {
            let (a0, a1, b0, b1) = (idx(i, j), idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1));
            m.triangles.push([a0, a1, b1]);
            m.triangles.push([a0, b1, b0]);
        }
    }
    m
}

fn run_case(label: &str, skin: TriMesh, abdomen: TriMesh, repeats: usize) {
    println!(
        "\n{label}: skin {} triangles, abdomen {} triangles, together {}",
        skin.num_triangles(),
        abdomen.num_triangles(),
        skin.num_triangles() + abdomen.num_triangles()
    );
    let (mut ts, mut tr, mut to, mut tp) = (vec![], vec![], vec![], vec![]);
    for _ in 0..repeats {
        let (mut s, mut a) = (skin.clone(), abdomen.clone());
        let (_, t) = time(|| {
            Taubin::default().smooth(&mut s).expect("smooth");
            Taubin::default().smooth(&mut a).expect("smooth");
        });
        ts.push(t);
        let (_, t) = time(|| {
            let ro = RepairOptions::for_mesh(&s);
            repair(&mut s, &ro).expect("repair");
            let ro = RepairOptions::for_mesh(&a);
            repair(&mut a, &ro).expect("repair");
        });
        tr.push(t);
        let (_, t) = time(|| {
            {
                let oo = OverlapOptions::for_mesh(&a, Relation::Inside);
                resolve_overlap(&mut a, &s, &oo)
            }
            .expect("overlap")
        });
        to.push(t);
        let (_, t) = time(|| {
            prepare(
                skin.clone(),
                Some(abdomen.clone()),
                &PrepareOptions::default(),
            )
            .expect("prepare")
        });
        tp.push(t);
    }
    println!("median over {repeats} runs [ms]:");
    println!(
        "  smoothing (Taubin N=50)        {:9.1}",
        median(ts.clone())
    );
    println!(
        "  repair (incl. BVH self-test)   {:9.1}",
        median(tr.clone())
    );
    println!(
        "  overlap resolution             {:9.1}",
        median(to.clone())
    );
    println!(
        "  sum of stages                  {:9.1}",
        median(ts) + median(tr) + median(to)
    );
    println!("  prepare() end to end (+report) {:9.1}", median(tp));
    let bvh_t: Vec<f64> = (0..repeats)
        .map(|_| time(|| Bvh::new(&skin).self_intersections().len()).1)
        .collect();
    println!("  self-intersection test, skin   {:9.1}", median(bvh_t));
    let tet: Vec<f64> = (0..repeats.min(3))
        .map(|_| {
            time(|| stuff(&abdomen, &StuffOptions::with_cells(&abdomen, 30)).expect("stuff")).1
        })
        .collect();
    let tm = stuff(&abdomen, &StuffOptions::with_cells(&abdomen, 30)).expect("stuff");
    let q = tm.quality();
    println!(
        "  isosurface stuffing, 30 cells  {:9.1}  ({} tets, dihedral {:.1}..{:.1} deg, max radius-edge {:.2})",
        median(tet),
        q.tets,
        q.min_dihedral_deg,
        q.max_dihedral_deg,
        q.max_radius_edge
    );
}
