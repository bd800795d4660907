//! Surface repair (Peeters & Pronost 2013, section 3.5, after Jung et al. 2004): collapse of
//! edges shorter than eps_e, edge flips for sliver triangles with an angle under eps_alpha,
//! removal of opposite (duplicate, reversed) face pairs, and removal of self-intersections by
//! region growing from a seed triangle, the holes left closed again by patches whose
//! interior is relaxed with the umbrella operator.

use std::collections::{HashMap, HashSet};

use nalgebra::Point3;

use super::{Bvh, TriMesh};
use crate::{Error, Result};

/// Thresholds of the repair stage.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RepairOptions {
    /// Edges shorter than this are collapsed (eps_e), in mesh units; negative disables.
    pub eps_edge: f64,
    /// Triangles with an angle under this many degrees are flipped (eps_alpha).
    pub eps_angle_deg: f64,
    /// Rounds of intersection removal, each widening the removed band by one ring.
    pub max_rounds: usize,
}

impl RepairOptions {
    /// eps_e = 5 % of the mean edge length, eps_alpha = 5 degrees, 6 rounds.
    pub fn for_mesh(mesh: &TriMesh) -> RepairOptions {
        RepairOptions {
            eps_edge: 0.05 * mesh.mean_edge_length(),
            eps_angle_deg: 5.0,
            max_rounds: 6,
        }
    }

    fn validate(&self) -> Result<()> {
        if !self.eps_edge.is_finite() {
            return Err(Error::invalid("eps_edge", self.eps_edge, "a finite length"));
        }
        if !(0.0..60.0).contains(&self.eps_angle_deg) {
            return Err(Error::invalid(
                "eps_angle_deg",
                self.eps_angle_deg,
                "[0, 60)",
            ));
        }
        Ok(())
    }
}

/// What [`repair`] did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RepairReport {
    /// Short edges collapsed.
    pub collapsed_edges: usize,
    /// Sliver edges flipped.
    pub flipped_edges: usize,
    /// Triangles removed as opposite or duplicate pairs.
    pub opposite_faces_removed: usize,
    /// Self-intersecting triangle pairs found at the start.
    pub intersecting_pairs: usize,
    /// Triangles removed by the intersection removal.
    pub triangles_removed: usize,
    /// Triangles added to close the holes.
    pub triangles_added: usize,
    /// Self-intersecting pairs left at the end (0 on success).
    pub intersecting_pairs_left: usize,
    /// The seed triangle of the last region growing, if one was needed.
    pub seed_triangle: Option<u32>,
    /// The largest sound component replaced the eq. 5 seed's region (see
    /// [`remove_self_intersections`]).
    pub seed_fallback: bool,
}

/// Runs the whole repair: short-edge collapse, sliver flips, opposite-pair removal, then
/// self-intersection removal. Fails when intersections remain after `max_rounds`.
pub fn repair(mesh: &mut TriMesh, opts: &RepairOptions) -> Result<RepairReport> {
    mesh.validate()?;
    opts.validate()?;
    let mut rep = RepairReport::default();
    if opts.eps_edge > 0.0 {
        rep.collapsed_edges = collapse_short_edges(mesh, opts.eps_edge);
    }
    rep.flipped_edges = flip_slivers(mesh, opts.eps_angle_deg);
    rep.opposite_faces_removed = remove_opposite_faces(mesh);
    mesh.remove_unreferenced_vertices();
    let si = remove_self_intersections(mesh, opts.max_rounds);
    rep.intersecting_pairs = si.pairs_found;
    rep.triangles_removed = si.removed;
    rep.triangles_added = si.added;
    rep.intersecting_pairs_left = si.pairs_left;
    rep.seed_triangle = si.seed;
    rep.seed_fallback = si.seed_fallback;
    if si.pairs_left > 0 {
        return Err(Error::State(format!(
            "{} self-intersecting triangle pairs remain after {} removal rounds",
            si.pairs_left, opts.max_rounds
        )));
    }
    Ok(rep)
}

/// Collapses every edge shorter than `eps_e` to its midpoint (v_i = (v_i + v_j) / 2, faces of
/// v_j renumbered to v_i), skipping collapses that would pinch the surface (link condition:
/// the two end vertices share exactly the vertices opposite the edge) or that would make
/// the joined star intersect its surroundings. Returns the number of collapses.
pub fn collapse_short_edges(mesh: &mut TriMesh, eps_e: f64) -> usize {
    let mut total = 0;
    for _ in 0..32 {
        let adj = mesh.adjacency();
        let mut short: Vec<(f64, u32, u32)> = mesh
            .edges()
            .into_iter()
            .map(|[a, b]| {
                (
                    (mesh.vertices[a as usize] - mesh.vertices[b as usize]).norm(),
                    a,
                    b,
                )
            })
            .filter(|e| e.0 < eps_e)
            .collect();
        if short.is_empty() {
            break;
        }
        short.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut locked = vec![false; mesh.vertices.len()];
        let mut map: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let mut done = 0;
        for (_, i, j) in short {
            if locked[i as usize] || locked[j as usize] {
                continue;
            }
            let (ni, nj) = (
                &adj.vertex_neighbours[i as usize],
                &adj.vertex_neighbours[j as usize],
            );
            let common = ni.iter().filter(|v| nj.binary_search(v).is_ok()).count();
            if common != adj.faces_of_edge(i, j).len() {
                continue;
            }
            let mid = nalgebra::center(&mesh.vertices[i as usize], &mesh.vertices[j as usize]);
            if collapse_intersects(mesh, &adj, i, j, &mid) {
                continue;
            }
            mesh.vertices[i as usize] = mid;
            map[j as usize] = i;
            for v in ni.iter().chain(nj.iter()).chain([&i, &j]) {
                locked[*v as usize] = true;
            }
            done += 1;
        }
        if done == 0 {
            break;
        }
        for t in &mut mesh.triangles {
            for v in t.iter_mut() {
                *v = map[*v as usize];
            }
        }
        mesh.triangles
            .retain(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0]);
        total += done;
    }
    total
}

/// Whether collapsing edge (i, j) to `mid` would make a triangle of the joined star
/// intersect another triangle of the star or of its surroundings (two-ring).
fn collapse_intersects(
    mesh: &TriMesh,
    adj: &super::Adjacency,
    i: u32,
    j: u32,
    mid: &Point3<f64>,
) -> bool {
    let pos = |v: u32| {
        if v == i || v == j {
            *mid
        } else {
            mesh.vertices[v as usize]
        }
    };
    let rename = |t: [u32; 3]| t.map(|v| if v == j { i } else { v });
    let mut star: Vec<usize> = adj.vertex_faces[i as usize]
        .iter()
        .chain(&adj.vertex_faces[j as usize])
        .map(|&f| f as usize)
        .collect();
    star.sort_unstable();
    star.dedup();
    let changed: Vec<[u32; 3]> = star
        .iter()
        .map(|&f| rename(mesh.triangles[f]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    let mut near: Vec<usize> = Vec::new();
    for &v in adj.vertex_neighbours[i as usize]
        .iter()
        .chain(&adj.vertex_neighbours[j as usize])
    {
        near.extend(adj.vertex_faces[v as usize].iter().map(|&f| f as usize));
    }
    near.sort_unstable();
    near.dedup();
    near.retain(|f| star.binary_search(f).is_err());
    let corners = |t: &[u32; 3]| t.map(pos);
    for (a, ta) in changed.iter().enumerate() {
        let ca = corners(ta);
        for tb in changed.iter().skip(a + 1) {
            if super::geom::triangles_intersect(&ca, ta, &corners(tb), tb) {
                return true;
            }
        }
        for &f in &near {
            let tf = mesh.triangles[f];
            if super::geom::triangles_intersect(&ca, ta, &corners(&tf), &tf) {
                return true;
            }
        }
    }
    false
}

fn min_angle(p: &[Point3<f64>; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let (u, v) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            u.angle(&v)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Flips, for every triangle f_k = (v_h, v_i, v_j) with an angle under `eps_alpha_deg`, its
/// longest edge (v_i, v_j) with the neighbour f_m = (v_g, v_j, v_i): f_k becomes (v_h, v_i,
/// v_g) and f_m becomes (v_g, v_j, v_h) (section 3.5). A flip is made only when the edge
/// (v_h, v_g) does not exist yet, neither new triangle turns over, the smallest angle
/// improves, and neither new triangle intersects a triangle of its two-ring. Returns the number of flips.
pub fn flip_slivers(mesh: &mut TriMesh, eps_alpha_deg: f64) -> usize {
    let eps = eps_alpha_deg.to_radians();
    let mut total = 0;
    for _ in 0..8 {
        let mut adj = mesh.adjacency();
        let mut touched = vec![false; mesh.triangles.len()];
        let mut done = 0;
        for k in 0..mesh.triangles.len() {
            if touched[k] || min_angle(&mesh.corners(k)) >= eps {
                continue;
            }
            let tri = mesh.triangles[k];
            let c = mesh.corners(k);
            let h = (0..3)
                .max_by(|&a, &b| {
                    let la = (c[(a + 1) % 3] - c[(a + 2) % 3]).norm();
                    let lb = (c[(b + 1) % 3] - c[(b + 2) % 3]).norm();
                    la.total_cmp(&lb)
                })
                .unwrap_or(0);
            let (vh, vi, vj) = (tri[h], tri[(h + 1) % 3], tri[(h + 2) % 3]);
            let faces = adj.faces_of_edge(vi, vj);
            if faces.len() != 2 {
                continue;
            }
            let m = if faces[0] as usize == k {
                faces[1]
            } else {
                faces[0]
            } as usize;
            if touched[m] {
                continue;
            }
            let tm = mesh.triangles[m];
            let Some(vg) = tm.iter().copied().find(|&v| v != vi && v != vj) else {
                continue;
            };
            // f_m must traverse the edge as (v_j, v_i) for a consistent flip
            let pos = tm.iter().position(|&v| v == vg).unwrap_or(0);
            if tm[(pos + 1) % 3] != vj
                || vg == vh
                || adj.vertex_neighbours[vh as usize]
                    .binary_search(&vg)
                    .is_ok()
            {
                continue;
            }
            let nk = [vh, vi, vg];
            let nm = [vg, vj, vh];
            let p = |t: [u32; 3]| t.map(|i| mesh.vertices[i as usize]);
            let n_old = mesh.face_cross(k) + mesh.face_cross(m);
            let cross = |q: [Point3<f64>; 3]| (q[1] - q[0]).cross(&(q[2] - q[0]));
            if cross(p(nk)).dot(&n_old) <= 0.0 || cross(p(nm)).dot(&n_old) <= 0.0 {
                continue;
            }
            let before = min_angle(&c).min(min_angle(&mesh.corners(m)));
            let after = min_angle(&p(nk)).min(min_angle(&p(nm)));
            if after <= before {
                continue;
            }
            if creates_intersection(mesh, &adj, &[(k, nk), (m, nm)]) {
                continue;
            }
            mesh.triangles[k] = nk;
            mesh.triangles[m] = nm;
            touched[k] = true;
            touched[m] = true;
            // keep the vertex-to-face lists current for the checks of later flips
            let vf = &mut adj.vertex_faces;
            vf[vj as usize].retain(|&f| f as usize != k);
            vf[vg as usize].push(k as u32);
            vf[vi as usize].retain(|&f| f as usize != m);
            vf[vh as usize].push(m as u32);
            for (a, b) in [(vh, vg), (vg, vh)] {
                let nb = &mut adj.vertex_neighbours[a as usize];
                if let Err(pos) = nb.binary_search(&b) {
                    nb.insert(pos, b);
                }
            }
            done += 1;
        }
        if done == 0 {
            break;
        }
        total += done;
    }
    total
}

/// Whether replacing triangles `changes` (index, new corners) would make one of them
/// intersect a triangle around it (the faces of the two-ring of the new corners).
fn creates_intersection(
    mesh: &TriMesh,
    adj: &super::Adjacency,
    changes: &[(usize, [u32; 3])],
) -> bool {
    let mut near: Vec<u32> = Vec::new();
    for (_, tri) in changes {
        for &v in tri {
            for &w in adj.vertex_neighbours[v as usize]
                .iter()
                .chain(std::iter::once(&v))
            {
                near.extend_from_slice(&adj.vertex_faces[w as usize]);
            }
        }
    }
    near.sort_unstable();
    near.dedup();
    let corners = |t: &[u32; 3]| t.map(|i| mesh.vertices[i as usize]);
    for &(_, tri) in changes {
        let ck = corners(&tri);
        for &f in &near {
            let f = f as usize;
            if changes.iter().any(|c| c.0 == f) {
                continue;
            }
            let tf = mesh.triangles[f];
            if super::geom::triangles_intersect(&ck, &tri, &corners(&tf), &tf) {
                return true;
            }
        }
    }
    // the two new triangles against each other
    if let [(_, a), (_, b)] = changes {
        return super::geom::triangles_intersect(&corners(a), a, &corners(b), b);
    }
    false
}

/// Removes triangle pairs on the same three vertices: opposite pairs (reversed order) are
/// both removed, since they bound no volume; of same-order duplicates one is kept. Returns
/// the number of triangles removed.
pub fn remove_opposite_faces(mesh: &mut TriMesh) -> usize {
    let mut groups: HashMap<[u32; 3], Vec<usize>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut key = *tri;
        key.sort_unstable();
        groups.entry(key).or_default().push(t);
    }
    let mut remove = vec![false; mesh.triangles.len()];
    for list in groups.values().filter(|l| l.len() > 1) {
        let parity = |t: usize| {
            let tri = mesh.triangles[t];
            let m = tri
                .iter()
                .enumerate()
                .min_by_key(|x| x.1)
                .map(|x| x.0)
                .unwrap_or(0);
            tri[(m + 1) % 3] < tri[(m + 2) % 3]
        };
        let (mut pos, mut neg): (Vec<usize>, Vec<usize>) = list.iter().partition(|&&t| parity(t));
        while let (Some(_), Some(_)) = (pos.last(), neg.last()) {
            remove[pos.pop().unwrap_or(0)] = true;
            remove[neg.pop().unwrap_or(0)] = true;
        }
        for rest in [pos, neg] {
            for &t in rest.iter().skip(1) {
                remove[t] = true;
            }
        }
    }
    let n = remove.iter().filter(|r| **r).count();
    let mut k = 0;
    mesh.triangles.retain(|_| {
        k += 1;
        !remove[k - 1]
    });
    n
}

/// All self-intersecting triangle pairs of `mesh` (BVH plus Moller's test).
pub fn self_intersections(mesh: &TriMesh) -> Vec<(u32, u32)> {
    Bvh::new(mesh).self_intersections()
}

/// Outcome of [`remove_self_intersections`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct IntersectionRemoval {
    /// Intersecting pairs at the start.
    pub pairs_found: usize,
    /// Triangles removed in all rounds.
    pub removed: usize,
    /// Triangles added by hole filling.
    pub added: usize,
    /// Intersecting pairs left.
    pub pairs_left: usize,
    /// Seed triangle of the last round.
    pub seed: Option<u32>,
    /// The seed of eq. 5 grew a region of less than half the sound area, and the largest
    /// sound component was kept instead.
    pub seed_fallback: bool,
}

/// The seed of the region growing (section 3.5): among triangles with no intersection in
/// their neighbourhood, the one whose centroid is nearest to the vertex mean p_com (eq. 5)
/// and which faces away from it (n . (c - p_com) > 0), so that neither a triangle of the
/// convex hull nor an inverted one is required.
pub fn seed_triangle(mesh: &TriMesh, bad: &[bool]) -> Option<u32> {
    let com = mesh.vertex_mean();
    let mut near_bad = vec![false; mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if bad[t] {
            for &v in tri {
                near_bad[v as usize] = true;
            }
        }
    }
    (0..mesh.triangles.len())
        .filter(|&t| !bad[t] && mesh.triangles[t].iter().all(|&v| !near_bad[v as usize]))
        .filter(|&t| mesh.face_cross(t).dot(&(mesh.face_centroid(t) - com)) > 0.0)
        .min_by(|&a, &b| {
            let da = (mesh.face_centroid(a) - com).norm_squared();
            let db = (mesh.face_centroid(b) - com).norm_squared();
            da.total_cmp(&db)
        })
        .map(|t| t as u32)
}

/// Removes self-intersections: marks intersecting triangles (widened by one ring per round),
/// grows the valid region from [`seed_triangle`] over manifold edges without entering marked
/// triangles, drops everything the growth did not reach, and closes the holes this made
/// with the patches of [`fill_holes`] (openings the surface had before stay open). When the region grown from the seed of eq. 5 covers less than half of the
/// sound area (a folded part can lie nearest the centre of mass), the largest sound
/// component is kept instead. Repeats until no intersection is left or `max_rounds` is spent.
pub fn remove_self_intersections(mesh: &mut TriMesh, max_rounds: usize) -> IntersectionRemoval {
    let mut out = IntersectionRemoval::default();
    let mut pairs = self_intersections(mesh);
    out.pairs_found = pairs.len();
    let mut round = 0;
    while !pairs.is_empty() && round < max_rounds {
        let adj = mesh.adjacency();
        let mut bad = vec![false; mesh.triangles.len()];
        for &(a, b) in &pairs {
            bad[a as usize] = true;
            bad[b as usize] = true;
        }
        for _ in 0..=round {
            let mut grown = bad.clone();
            for (t, tri) in mesh.triangles.iter().enumerate() {
                if bad[t] {
                    for &v in tri {
                        for &f in &adj.vertex_faces[v as usize] {
                            grown[f as usize] = true;
                        }
                    }
                }
            }
            bad = grown;
        }
        let Some(mut seed) = seed_triangle(mesh, &bad) else {
            break;
        };
        let mut keep = grow_region(mesh, &adj, seed as usize, &bad);
        let area = |mask: &[bool]| {
            (0..mask.len())
                .filter(|&t| mask[t])
                .map(|t| mesh.face_area(t))
                .sum::<f64>()
        };
        let sound: Vec<bool> = bad.iter().map(|b| !b).collect();
        if area(&keep) < 0.5 * area(&sound) {
            // the seed sits on a small island (e.g. a folded-in cap near the centre of mass):
            // grow from the largest sound component instead
            if let Some((s, k)) = largest_component(mesh, &adj, &bad) {
                seed = s;
                keep = k;
                out.seed_fallback = true;
            }
        }
        out.seed = Some(seed);
        let was_boundary = adj.boundary_vertices();
        let before = mesh.triangles.len();
        let mut k = 0;
        mesh.triangles.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        out.removed += before - mesh.triangles.len();
        let map = mesh.remove_unreferenced_vertices();
        // close the holes the removal made, not the surface's own openings
        let mut on_old_boundary = vec![false; mesh.vertices.len()];
        for (old, &new) in map.iter().enumerate() {
            if new != u32::MAX && was_boundary[old] {
                on_old_boundary[new as usize] = true;
            }
        }
        let loops: Vec<Vec<u32>> = boundary_loops(mesh)
            .into_iter()
            .filter(|l| l.iter().any(|&v| !on_old_boundary[v as usize]))
            .collect();
        out.added += fill_loops(mesh, loops);
        pairs = self_intersections(mesh);
        round += 1;
    }
    out.pairs_left = pairs.len();
    out
}

/// The sound component of largest area: its triangle nearest the vertex mean, and its mask.
fn largest_component(
    mesh: &TriMesh,
    adj: &super::Adjacency,
    bad: &[bool],
) -> Option<(u32, Vec<bool>)> {
    let mut seen = vec![false; mesh.triangles.len()];
    let mut best: Option<(f64, u32, Vec<bool>)> = None;
    let com = mesh.vertex_mean();
    for t in 0..mesh.triangles.len() {
        if seen[t] || bad[t] {
            continue;
        }
        let comp = grow_region(mesh, adj, t, bad);
        let mut area = 0.0;
        let mut nearest = (f64::INFINITY, t as u32);
        for (f, &inside) in comp.iter().enumerate() {
            if inside {
                seen[f] = true;
                area += mesh.face_area(f);
                let d = (mesh.face_centroid(f) - com).norm_squared();
                if d < nearest.0 {
                    nearest = (d, f as u32);
                }
            }
        }
        if best.as_ref().is_none_or(|b| area > b.0) {
            best = Some((area, nearest.1, comp));
        }
    }
    best.map(|b| (b.1, b.2))
}

fn grow_region(mesh: &TriMesh, adj: &super::Adjacency, seed: usize, bad: &[bool]) -> Vec<bool> {
    let mut keep = vec![false; mesh.triangles.len()];
    keep[seed] = true;
    let mut stack = vec![seed];
    while let Some(t) = stack.pop() {
        let [a, b, c] = mesh.triangles[t];
        for (u, v) in [(a, b), (b, c), (c, a)] {
            let f = adj.faces_of_edge(u, v);
            if f.len() != 2 {
                continue;
            }
            for &g in f {
                let g = g as usize;
                if !keep[g] && !bad[g] {
                    keep[g] = true;
                    stack.push(g);
                }
            }
        }
    }
    keep
}

/// Closed loops of boundary edges, each listed in the direction its triangles traverse it.
pub fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut count: HashMap<(u32, u32), i32> = HashMap::new();
    for &[a, b, c] in &mesh.triangles {
        for (u, v) in [(a, b), (b, c), (c, a)] {
            *count.entry((u, v)).or_insert(0) += 1;
        }
    }
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut keys: Vec<(u32, u32)> = count
        .keys()
        .copied()
        .filter(|&(u, v)| !count.contains_key(&(v, u)))
        .collect();
    keys.sort_unstable();
    for &(u, v) in &keys {
        next.entry(u).or_default().push(v);
    }
    let mut used: HashSet<(u32, u32)> = HashSet::new();
    let mut loops = Vec::new();
    for &(u0, v0) in &keys {
        if used.contains(&(u0, v0)) {
            continue;
        }
        let mut lp = vec![u0];
        used.insert((u0, v0));
        let mut cur = v0;
        while cur != u0 {
            lp.push(cur);
            let Some(n) = next
                .get(&cur)
                .and_then(|l| l.iter().copied().find(|&w| !used.contains(&(cur, w))))
            else {
                break;
            };
            used.insert((cur, n));
            cur = n;
        }
        if cur == u0 && lp.len() >= 3 {
            loops.push(lp);
        }
    }
    loops
}

/// Closes every boundary loop with a patch of concentric rings shrinking to the loop's
/// centre (about one ring per mean edge length of the loop's radius), then relaxes the new
/// vertices with 100 umbrella steps (a discrete membrane spanning the loop) and fairs them
/// with the bi-Laplacian so that the patch continues the curvature around the hole. Returns
/// the number of triangles added.
pub fn fill_holes(mesh: &mut TriMesh) -> usize {
    let loops = boundary_loops(mesh);
    fill_loops(mesh, loops)
}

/// [`fill_holes`] for the given loops only.
fn fill_loops(mesh: &mut TriMesh, loops: Vec<Vec<u32>>) -> usize {
    let first_new = mesh.vertices.len();
    let before = mesh.triangles.len();
    for lp in loops {
        let pts: Vec<Point3<f64>> = lp.iter().map(|&i| mesh.vertices[i as usize]).collect();
        let n = pts.len();
        let centre =
            Point3::from(pts.iter().map(|p| p.coords).sum::<nalgebra::Vector3<f64>>() / n as f64);
        let edge = (0..n)
            .map(|i| (pts[(i + 1) % n] - pts[i]).norm())
            .sum::<f64>()
            / n as f64;
        let radius = pts.iter().map(|p| (p - centre).norm()).sum::<f64>() / n as f64;
        let rings = if edge > 0.0 {
            ((radius / edge).round() as usize).saturating_sub(1).min(50)
        } else {
            0
        };
        let mut outer = lp.clone();
        for r in 1..=rings {
            let s = r as f64 / (rings + 1) as f64;
            let inner: Vec<u32> = pts
                .iter()
                .map(|p| {
                    mesh.vertices.push(p + (centre - p) * s);
                    (mesh.vertices.len() - 1) as u32
                })
                .collect();
            for i in 0..n {
                let (a, b) = (outer[i], outer[(i + 1) % n]);
                let (a2, b2) = (inner[i], inner[(i + 1) % n]);
                mesh.triangles.push([b, a, a2]);
                mesh.triangles.push([b, a2, b2]);
            }
            outer = inner;
        }
        mesh.vertices.push(centre);
        let c = (mesh.vertices.len() - 1) as u32;
        for i in 0..n {
            mesh.triangles.push([outer[(i + 1) % n], outer[i], c]);
        }
    }
    let added = mesh.triangles.len() - before;
    if added > 0 {
        relax(mesh, first_new, 100);
        fair(mesh, first_new, FAIRING_STEPS);
    }
    added
}

/// Largest number of conjugate-gradient iterations of the hole-patch fairing.
const FAIRING_STEPS: usize = 1000;

/// Bi-Laplacian (thin-plate) fairing of the vertices from index `first` on, the others fixed:
/// solves L^2 x = 0 on the patch with the graph Laplacian (L v)_i = deg_i v_i - sum_j v_j by
/// conjugate gradients (L^2 restricted to the patch is symmetric positive definite), so the
/// patch continues the curvature of the surface around the hole where a membrane (L x = 0)
/// would span it flat. Starts from the membrane solution.
fn fair(mesh: &mut TriMesh, first: usize, max_iter: usize) {
    type V = nalgebra::Vector3<f64>;
    let n = mesh.vertices.len();
    if first >= n {
        return;
    }
    let adj = mesh.adjacency();
    let nb = &adj.vertex_neighbours;
    let lap = |v: &[V], out: &mut [V]| {
        for i in 0..n {
            let mut s = v[i] * nb[i].len() as f64;
            for &j in &nb[i] {
                s -= v[j as usize];
            }
            out[i] = s;
        }
    };
    // M x_p = L L restricted to the patch, applied to a vector living on the patch
    let apply = |xp: &[V], tmp: &mut Vec<V>, tmp2: &mut Vec<V>| -> Vec<V> {
        tmp.iter_mut().for_each(|v| *v = V::zeros());
        tmp[first..].copy_from_slice(xp);
        lap(tmp, tmp2);
        lap(tmp2, tmp);
        tmp[first..].to_vec()
    };
    let mut t1 = vec![V::zeros(); n];
    let mut t2 = vec![V::zeros(); n];
    // right-hand side b = -(L L [0_p, x_b])_p
    let mut fixed: Vec<V> = mesh.vertices.iter().map(|p| p.coords).collect();
    fixed[first..].iter_mut().for_each(|v| *v = V::zeros());
    lap(&fixed, &mut t1);
    lap(&t1, &mut t2);
    let b: Vec<V> = t2[first..].iter().map(|v| -v).collect();
    let dot = |a: &[V], c: &[V]| a.iter().zip(c).map(|(x, y)| x.dot(y)).sum::<f64>();
    let mut x: Vec<V> = mesh.vertices[first..].iter().map(|p| p.coords).collect();
    let ax = apply(&x, &mut t1, &mut t2);
    let mut r: Vec<V> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let mut p = r.clone();
    let mut rr = dot(&r, &r);
    let stop = 1e-24 * dot(&b, &b).max(1e-300);
    for _ in 0..max_iter {
        if rr <= stop {
            break;
        }
        let ap = apply(&p, &mut t1, &mut t2);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            break;
        }
        let alpha = rr / pap;
        for k in 0..x.len() {
            x[k] += alpha * p[k];
            r[k] -= alpha * ap[k];
        }
        let rr_new = dot(&r, &r);
        let beta = rr_new / rr;
        rr = rr_new;
        for k in 0..p.len() {
            p[k] = r[k] + beta * p[k];
        }
    }
    if x.iter().all(|v| v.iter().all(|c| c.is_finite())) {
        for (k, v) in x.into_iter().enumerate() {
            mesh.vertices[first + k] = Point3::from(v);
        }
    }
}

/// Plain umbrella relaxation of the vertices from index `first` on (others fixed).
fn relax(mesh: &mut TriMesh, first: usize, steps: usize) {
    let adj = mesh.adjacency();
    for _ in 0..steps {
        for i in first..mesh.vertices.len() {
            let nb = &adj.vertex_neighbours[i];
            if nb.is_empty() {
                continue;
            }
            let c = nb
                .iter()
                .map(|&j| mesh.vertices[j as usize].coords)
                .sum::<nalgebra::Vector3<f64>>()
                / nb.len() as f64;
            mesh.vertices[i] = Point3::from(c);
        }
    }
}
