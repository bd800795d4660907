//! A sparse Cholesky factorisation for the build-time linear systems of the skinning (the
//! bone-heat weights): envelope (skyline) storage after a reverse Cuthill-McKee reordering,
//! factorised once and solved for many right-hand sides. Nothing here runs per frame.

/// Sparse Cholesky factor of a symmetric positive definite matrix in envelope (skyline)
/// storage after a reverse Cuthill-McKee reordering (George & Liu 1981, chapters 4-5).
#[derive(Clone, Debug)]
pub(crate) struct EnvelopeCholesky {
    perm: Vec<usize>,
    first: Vec<usize>,
    start: Vec<usize>,
    values: Vec<f64>,
}

/// Reverse Cuthill-McKee ordering of a graph (new -> old), started from a
/// pseudo-peripheral vertex of minimum degree.
fn reverse_cuthill_mckee(adj: &[Vec<(u32, f64)>]) -> Vec<usize> {
    let n = adj.len();
    let mut order = Vec::with_capacity(n);
    let mut seen = vec![false; n];
    let bfs_last = |s: usize| {
        let mut d = vec![usize::MAX; n];
        let mut q = std::collections::VecDeque::from([s]);
        d[s] = 0;
        let mut last = s;
        while let Some(v) = q.pop_front() {
            last = v;
            for &(u, _) in &adj[v] {
                if d[u as usize] == usize::MAX {
                    d[u as usize] = d[v] + 1;
                    q.push_back(u as usize);
                }
            }
        }
        last
    };
    for root in 0..n {
        if seen[root] {
            continue;
        }
        let start = bfs_last(bfs_last(root));
        let mut q = std::collections::VecDeque::from([start]);
        seen[start] = true;
        while let Some(v) = q.pop_front() {
            order.push(v);
            let mut nb: Vec<usize> = adj[v]
                .iter()
                .map(|x| x.0 as usize)
                .filter(|&u| !seen[u])
                .collect();
            nb.sort_by_key(|&u| (adj[u].len(), u));
            for u in nb {
                seen[u] = true;
                q.push_back(u);
            }
        }
    }
    order.reverse();
    order
}

impl EnvelopeCholesky {
    /// Factorises `K + diag(extra)` where K is given by `diagonal` and symmetric
    /// off-diagonal entries `-w` for each neighbour weight `w` (`neighbours[i]` lists
    /// `(k, w)`). A pivot that is not positive is returned as `Err((row, pivot))`, the row in
    /// the original ordering.
    pub(crate) fn factor(
        diagonal: &[f64],
        neighbours: &[Vec<(u32, f64)>],
        extra: &[f64],
    ) -> std::result::Result<Self, (usize, f64)> {
        let n = diagonal.len();
        let perm = reverse_cuthill_mckee(neighbours);
        let mut inv = vec![0usize; n];
        for (new, &old) in perm.iter().enumerate() {
            inv[old] = new;
        }
        let first: Vec<usize> = (0..n)
            .map(|i| {
                neighbours[perm[i]]
                    .iter()
                    .map(|x| inv[x.0 as usize])
                    .fold(i, usize::min)
            })
            .collect();
        let mut start = vec![0usize; n + 1];
        for i in 0..n {
            start[i + 1] = start[i] + (i - first[i] + 1);
        }
        let mut values = vec![0.0; start[n]];
        for i in 0..n {
            let old = perm[i];
            values[start[i] + (i - first[i])] = diagonal[old] + extra[old];
            for &(j, w) in &neighbours[old] {
                let jn = inv[j as usize];
                if jn < i {
                    values[start[i] + (jn - first[i])] -= w;
                }
            }
        }
        for i in 0..n {
            let (fi, si) = (first[i], start[i]);
            for j in fi..i {
                let (fj, sj) = (first[j], start[j]);
                let k0 = fi.max(fj);
                let mut s = values[si + (j - fi)];
                let ri = &values[si + (k0 - fi)..si + (j - fi)];
                let rj = &values[sj + (k0 - fj)..sj + (j - fj)];
                s -= ri.iter().zip(rj).map(|(a, b)| a * b).sum::<f64>();
                values[si + (j - fi)] = s / values[sj + (j - fj)];
            }
            let row = &values[si..si + (i - fi)];
            let d = values[si + (i - fi)] - row.iter().map(|a| a * a).sum::<f64>();
            if !(d > 0.0 && d.is_finite()) {
                return Err((perm[i], d));
            }
            values[si + (i - fi)] = d.sqrt();
        }
        Ok(EnvelopeCholesky {
            perm,
            first,
            start,
            values,
        })
    }

    /// Solves the factorised system for `b` (original ordering), in place.
    pub(crate) fn solve(&self, b: &mut [f64], work: &mut Vec<f64>) {
        let n = self.perm.len();
        work.clear();
        work.extend(self.perm.iter().map(|&o| b[o]));
        let y = work;
        for i in 0..n {
            let (fi, si) = (self.first[i], self.start[i]);
            let row = &self.values[si..si + (i - fi)];
            let s: f64 = row.iter().zip(&y[fi..i]).map(|(a, b)| a * b).sum();
            y[i] = (y[i] - s) / self.values[si + (i - fi)];
        }
        for i in (0..n).rev() {
            let (fi, si) = (self.first[i], self.start[i]);
            y[i] /= self.values[si + (i - fi)];
            let xi = y[i];
            for (yk, l) in y[fi..i].iter_mut().zip(&self.values[si..si + (i - fi)]) {
                *yk -= l * xi;
            }
        }
        for (i, &o) in self.perm.iter().enumerate() {
            b[o] = y[i];
        }
    }
}
