//! Shared helpers of the mesh tests: a deterministic random generator and test surfaces.
#![allow(dead_code)]

use breathing_torso::mesh::{Bvh, TriMesh};
use nalgebra::{Point3, Vector3};

/// SplitMix64: a small deterministic generator, enough for test noise.
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^ (z >> 31)
    }

    /// Uniform in [-1, 1).
    pub fn signed(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// An ellipsoid whose vertices are moved along their normal by uniform noise of amplitude
/// `amp` (a fraction of the smallest semi-axis).
pub fn noisy_ellipsoid(
    r: Vector3<f64>,
    subdivisions: u32,
    amp: f64,
    seed: u64,
) -> (TriMesh, TriMesh) {
    let clean = TriMesh::ellipsoid(&Point3::origin(), &r, subdivisions).unwrap();
    let mut noisy = clean.clone();
    let n = clean.vertex_normals();
    let mut rng = Rng(seed);
    let a = amp * r.min();
    for (p, n) in noisy.vertices.iter_mut().zip(&n) {
        *p += n * (a * rng.signed());
    }
    (clean, noisy)
}

/// RMS of |p| - 1 over the vertices: the residual to the unit sphere.
pub fn sphere_residual(m: &TriMesh) -> f64 {
    (m.vertices
        .iter()
        .map(|p| (p.coords.norm() - 1.0).powi(2))
        .sum::<f64>()
        / m.vertices.len() as f64)
        .sqrt()
}

/// RMS distance from the vertices of `a` to the surface of `b`.
pub fn rms_distance(a: &TriMesh, b: &TriMesh) -> f64 {
    let bvh = Bvh::new(b);
    let s: f64 = a
        .vertices
        .iter()
        .map(|p| bvh.closest(p).unwrap().distance.powi(2))
        .sum();
    (s / a.vertices.len() as f64).sqrt()
}

/// A unit sphere (icosphere level `s`) with a deliberate fold: the cap z > 0.85 is pushed down
/// by 0.35 and widened 2.2 times, so that its rim cuts through the band of the sphere around
/// it. Returns the folded surface; vertices with z < 0.3 are those of the plain sphere.
pub fn folded_sphere(s: u32) -> TriMesh {
    let mut m = TriMesh::icosphere(s).unwrap();
    for p in &mut m.vertices {
        if p.z > 0.85 {
            p.x *= 2.2;
            p.y *= 2.2;
            p.z -= 0.35;
        }
    }
    m
}

/// A latitude-longitude ellipsoid (`nlon` meridians, `nlat` bands) with radial noise of
/// relative amplitude `amp`: its pole fans are made of slivers, as in many scanned or
/// exported surfaces.
pub fn uv_ellipsoid(r: Vector3<f64>, nlon: usize, nlat: usize, amp: f64, seed: u64) -> TriMesh {
    let mut rng = Rng(seed);
    let mut m = TriMesh {
        vertices: vec![Point3::new(0.0, r.y, 0.0)],
        triangles: vec![],
    };
    for i in 1..nlat {
        let th = std::f64::consts::PI * i as f64 / nlat as f64;
        for j in 0..nlon {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / nlon as f64;
            let s = 1.0 + amp * rng.signed();
            m.vertices.push(Point3::new(
                r.x * th.sin() * ph.cos() * s,
                r.y * th.cos() * s,
                r.z * th.sin() * ph.sin() * s,
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
