//! Taubin lambda|mu smoothing (Taubin 1995; Peeters & Pronost 2013, section 3.3): a
//! low-pass filter on the surface that, unlike plain Laplacian smoothing, does not shrink
//! the volume. Each iteration applies a shrinking step `x += lambda L x` then an inflating
//! step `x += mu L x` with `mu < -lambda < 0`, L the umbrella operator (mean of the
//! neighbours minus the vertex). Pass-band frequency `k_PB = 1/lambda + 1/mu` (eq. 2 of the
//! paper).

use nalgebra::Point3;

/// Sorted, deduplicated one-ring neighbours of every vertex.
pub fn vertex_neighbours(n_vertices: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); n_vertices];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3]);
            nb[a].push(b);
            nb[b as usize].push(t[k]);
        }
    }
    for l in &mut nb {
        l.sort_unstable();
        l.dedup();
    }
    nb
}

/// Smooths the vertices flagged in `movable` by `iterations` Taubin lambda|mu passes with
/// umbrella weights; the others stay put but still act as neighbours. Typical values:
/// lambda = 0.5, mu = -0.53 (k_PB = 0.11).
pub fn taubin_smooth(
    vertices: &mut [Point3<f64>],
    neighbours: &[Vec<u32>],
    movable: &[bool],
    lambda: f64,
    mu: f64,
    iterations: usize,
) {
    let mut delta = vec![nalgebra::Vector3::zeros(); vertices.len()];
    for _ in 0..iterations {
        for factor in [lambda, mu] {
            for (i, nb) in neighbours.iter().enumerate() {
                if !movable[i] || nb.is_empty() {
                    continue;
                }
                let mean = nb.iter().fold(nalgebra::Vector3::zeros(), |acc, &j| {
                    acc + vertices[j as usize].coords
                }) / nb.len() as f64;
                delta[i] = (mean - vertices[i].coords) * factor;
            }
            for (i, v) in vertices.iter_mut().enumerate() {
                if movable[i] {
                    *v += delta[i];
                }
            }
        }
    }
}
