//! Sparse linear algebra for the stiff method: a row-compressed sparsity [`Pattern`], the
//! Jacobian J = S + U V^T of a problem ([`Jacobian`]: sparse part plus an optional dense
//! low-rank part), distance-2 column colouring and finite differences by colour groups
//! ([`Colouring`], Curtis, Powell & Reid 1974), and the direct solver of
//! (I - c J) x = b ([`ShiftedSolver`]): a block-sparse LU of I - c S with a
//! minimum-degree elimination order on blocks of unknowns chosen by the problem, partial
//! pivoting inside each diagonal block, and the low-rank part added by the
//! Sherman-Morrison-Woodbury formula.
//!
//! Sources: A. R. Curtis, M. J. D. Powell & J. K. Reid, "On the estimation of sparse Jacobian
//! matrices", IMA J. Appl. Math. 13 (1974) 117-119; A. H. Gebremedhin, F. Manne & A. Pothen,
//! "What color is your Jacobian?", SIAM Review 47 (2005) 629-705 (greedy distance-2
//! colouring); T. A. Davis, *Direct Methods for Sparse Linear Systems*, SIAM 2006, ch. 7
//! (minimum degree) and ch. 6 (LU); G. H. Golub & C. F. Van Loan, *Matrix Computations*,
//! 4th ed., Sec. 2.1.4 (Sherman-Morrison-Woodbury).

// Index loops mirror the formulas (stage and row indices) in this numerical kernel.
#![allow(clippy::needless_range_loop)]

/// Sparsity pattern in compressed sparse row form (sorted, unique column indices per row).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pattern {
    n: usize,
    start: Vec<usize>,
    cols: Vec<u32>,
}

impl Pattern {
    /// A pattern of `rows.len()` rows; entry i lists the columns of row i (any order,
    /// duplicates allowed, all < number of rows).
    pub fn from_rows(rows: Vec<Vec<u32>>) -> Pattern {
        let n = rows.len();
        let mut start = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        start.push(0);
        for mut r in rows {
            r.sort_unstable();
            r.dedup();
            debug_assert!(r.iter().all(|&c| (c as usize) < n));
            cols.extend_from_slice(&r);
            start.push(cols.len());
        }
        Pattern { n, start, cols }
    }

    /// The full n x n pattern.
    pub fn dense(n: usize) -> Pattern {
        Pattern::from_rows(vec![(0..n as u32).collect(); n])
    }

    /// Number of rows (= columns).
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.cols.len()
    }

    /// Columns of row `i`.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.cols[self.start[i]..self.start[i + 1]]
    }

    /// Index range of row `i` in the value array.
    pub fn row_range(&self, i: usize) -> std::ops::Range<usize> {
        self.start[i]..self.start[i + 1]
    }

    /// Index of entry (i, j) in the value array, if stored.
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        let r = self.row_range(i);
        self.cols[r.clone()]
            .binary_search(&(j as u32))
            .ok()
            .map(|k| r.start + k)
    }
}

/// A Jacobian J = S + U V^T: S sparse on a [`Pattern`] (values in row-compressed order),
/// U and V dense n x r (column k of U at `u[k n .. (k + 1) n]`, likewise V).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Jacobian {
    /// Pattern of S.
    pub pattern: Pattern,
    /// Values of S, one per pattern entry.
    pub values: Vec<f64>,
    /// Rank r of the low-rank part (0: none).
    pub rank: usize,
    /// U, n x r, column-major.
    pub u: Vec<f64>,
    /// V, n x r, column-major.
    pub v: Vec<f64>,
}

impl Jacobian {
    /// A zero Jacobian on `pattern` with a low-rank part of rank `rank`.
    pub fn zeros(pattern: Pattern, rank: usize) -> Jacobian {
        let n = pattern.dim();
        Jacobian {
            values: vec![0.0; pattern.nnz()],
            pattern,
            rank,
            u: vec![0.0; n * rank],
            v: vec![0.0; n * rank],
        }
    }

    /// Dimension n.
    pub fn dim(&self) -> usize {
        self.pattern.dim()
    }

    /// out = J x.
    pub fn mul_vec(&self, x: &[f64], out: &mut [f64]) {
        let n = self.dim();
        for (i, o) in out.iter_mut().enumerate().take(n) {
            let r = self.pattern.row_range(i);
            *o = self.pattern.cols[r.clone()]
                .iter()
                .zip(&self.values[r])
                .map(|(&j, &a)| a * x[j as usize])
                .sum();
        }
        for k in 0..self.rank {
            let vk = &self.v[k * n..(k + 1) * n];
            let s: f64 = vk.iter().zip(x).map(|(a, b)| a * b).sum();
            for (o, &uk) in out.iter_mut().zip(&self.u[k * n..(k + 1) * n]) {
                *o += uk * s;
            }
        }
    }

    /// The dense matrix S + U V^T, row-major (for tests and small problems).
    pub fn to_dense(&self) -> Vec<f64> {
        let n = self.dim();
        let mut d = vec![0.0; n * n];
        for i in 0..n {
            for (e, &j) in self.pattern.row_range(i).zip(self.pattern.row(i)) {
                d[i * n + j as usize] += self.values[e];
            }
        }
        for k in 0..self.rank {
            for i in 0..n {
                for j in 0..n {
                    d[i * n + j] += self.u[k * n + i] * self.v[k * n + j];
                }
            }
        }
        d
    }
}

/// A distance-2 colouring of the columns of a pattern: no two columns of one colour share
/// a row, so one function evaluation per colour gives all their finite differences
/// (Curtis, Powell & Reid 1974). Greedy, columns in natural order (Gebremedhin et al. 2005).
#[derive(Clone, Debug, Default)]
pub struct Colouring {
    /// Colour of each column.
    pub colour: Vec<u32>,
    /// Number of colours.
    pub colours: usize,
    /// Columns of each colour: `members[member_start[c]..member_start[c + 1]]`.
    member_start: Vec<usize>,
    members: Vec<u32>,
    /// Column-compressed view of the pattern: rows of column j and their value indices.
    col_start: Vec<usize>,
    col_rows: Vec<u32>,
    col_entry: Vec<usize>,
}

impl Colouring {
    /// Colours the columns of `pattern`.
    pub fn new(pattern: &Pattern) -> Colouring {
        let n = pattern.dim();
        let mut count = vec![0usize; n + 1];
        for &j in &pattern.cols {
            count[j as usize + 1] += 1;
        }
        for j in 0..n {
            count[j + 1] += count[j];
        }
        let col_start = count.clone();
        let mut col_rows = vec![0u32; pattern.nnz()];
        let mut col_entry = vec![0usize; pattern.nnz()];
        let mut fill = count;
        for i in 0..n {
            for e in pattern.row_range(i) {
                let j = pattern.cols[e] as usize;
                col_rows[fill[j]] = i as u32;
                col_entry[fill[j]] = e;
                fill[j] += 1;
            }
        }
        let mut colour = vec![u32::MAX; n];
        let mut mark = vec![usize::MAX; n + 1];
        let mut colours = 0usize;
        for j in 0..n {
            for &i in &col_rows[col_start[j]..col_start[j + 1]] {
                for &k in pattern.row(i as usize) {
                    let c = colour[k as usize];
                    if c != u32::MAX {
                        mark[c as usize] = j;
                    }
                }
            }
            let c = (0..).find(|&c| mark[c] != j).unwrap_or(0);
            colour[j] = c as u32;
            colours = colours.max(c + 1);
        }
        let mut member_start = vec![0usize; colours + 1];
        for &c in &colour {
            member_start[c as usize + 1] += 1;
        }
        for c in 0..colours {
            member_start[c + 1] += member_start[c];
        }
        let mut members = vec![0u32; n];
        let mut fill = member_start.clone();
        for (j, &c) in colour.iter().enumerate() {
            members[fill[c as usize]] = j as u32;
            fill[c as usize] += 1;
        }
        Colouring {
            colour,
            colours,
            member_start,
            members,
            col_start,
            col_rows,
            col_entry,
        }
    }

    /// Columns of colour `c`.
    pub fn members(&self, c: usize) -> &[u32] {
        &self.members[self.member_start[c]..self.member_start[c + 1]]
    }

    /// Forward differences of `f` by colour groups into `values` (row-compressed order of
    /// the pattern this colouring was built from): column j is perturbed by
    /// δ_j = sqrt(ε) max(|y_j|, `floor[j]`), all columns of one colour at once. `f0` = f(y);
    /// `ypert` and `f1` are scratch of length n. Returns the number of evaluations of `f`.
    #[allow(clippy::too_many_arguments)]
    pub fn differences(
        &self,
        f: &mut dyn FnMut(&[f64], &mut [f64]),
        y: &[f64],
        f0: &[f64],
        floor: &[f64],
        ypert: &mut [f64],
        f1: &mut [f64],
        values: &mut [f64],
    ) -> u64 {
        let eps = f64::EPSILON.sqrt();
        ypert.copy_from_slice(y);
        for c in 0..self.colours {
            for &j in self.members(c) {
                let j = j as usize;
                ypert[j] = y[j] + eps * y[j].abs().max(floor[j]);
            }
            f(ypert, f1);
            for &j in self.members(c) {
                let j = j as usize;
                let d = ypert[j] - y[j];
                for k in self.col_start[j]..self.col_start[j + 1] {
                    let i = self.col_rows[k] as usize;
                    values[self.col_entry[k]] = (f1[i] - f0[i]) / d;
                }
                ypert[j] = y[j];
            }
        }
        self.colours as u64
    }
}

/// The linear system could not be factored: a pivot vanished.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Singular;

/// Block-sparse LU factorisation of A = I - c S with a fixed structure.
///
/// The unknowns are partitioned into blocks (`groups`: block id per unknown, e.g. the six
/// position and velocity components of one mesh vertex). The blocks are ordered by minimum
/// degree on the block graph of S + S^T (Davis 2006, ch. 7, with the elimination graph kept
/// explicitly and degrees weighted by block sizes); the fill pattern is the graph at
/// elimination. Numerical factorisation is right-looking by blocks, with partial pivoting
/// inside each diagonal block (static pivoting between blocks: I - c S is dominated by its
/// block diagonal for the step sizes a stiff integrator takes; a vanishing pivot is reported
/// as [`Singular`] and the integrator shortens the step).
#[derive(Clone, Debug, Default)]
pub struct BlockLu {
    n: usize,
    /// Unknowns of each block, by elimination position: `dofs[dof_start[p]..dof_start[p+1]]`.
    dof_start: Vec<usize>,
    dofs: Vec<u32>,
    /// Blocks coupled to block p that are eliminated later (positions, ascending).
    adj_start: Vec<usize>,
    adj: Vec<u32>,
    /// Offset of block p's diagonal block in `data`.
    diag_off: Vec<usize>,
    /// Offset of the L block (q, p) for the k-th entry q of adj(p); the U block (p, q)
    /// follows it.
    off_diag: Vec<usize>,
    /// Where each entry of S goes in `data`.
    scatter: Vec<usize>,
    /// Where each unknown's diagonal entry is in `data`.
    diagonal: Vec<usize>,
    /// Row interchanges of each diagonal block, by unknown position.
    pivots: Vec<u32>,
    data: Vec<f64>,
    scratch: Vec<f64>,
    /// Eigenvalues of the symmetric parts of the eliminated diagonal blocks (the pivots
    /// D_k of a block L D L^T) that were positive, zero and negative, in the last
    /// factorisation: the inertia of a symmetric matrix by Sylvester's law (Golub & Van Loan,
    /// Sec. 4.2); counted only when [`BlockLu::count_inertia`] is set.
    inertia: [usize; 3],
    count_inertia: bool,
}

impl BlockLu {
    /// Whether factorisations count the inertia of the pivot blocks ([`BlockLu::inertia`]).
    pub fn count_inertia(&mut self, on: bool) {
        self.count_inertia = on;
    }

    /// The numbers of positive, zero and negative eigenvalues of the factored matrix's
    /// symmetric part, read off the pivot blocks of the last factorisation (exact for a
    /// symmetric matrix, which block elimination without pivoting between blocks keeps
    /// congruent to its block diagonal of pivots). All zero unless counted.
    pub fn inertia(&self) -> [usize; 3] {
        self.inertia
    }
    /// Symbolic analysis for `pattern` with unknowns grouped by `groups` (any ids; unknowns
    /// with equal ids form one block).
    pub fn new(pattern: &Pattern, groups: &[u32]) -> BlockLu {
        let n = pattern.dim();
        // compact the block ids
        let mut id_map = std::collections::HashMap::new();
        let block_of: Vec<usize> = groups
            .iter()
            .map(|g| {
                let next = id_map.len();
                *id_map.entry(*g).or_insert(next)
            })
            .collect();
        let nb = id_map.len();
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); nb];
        for (i, &b) in block_of.iter().enumerate() {
            members[b].push(i as u32);
        }
        // block graph of S + S^T
        let mut graph: Vec<Vec<u32>> = vec![Vec::new(); nb];
        for i in 0..n {
            for &j in pattern.row(i) {
                let (a, b) = (block_of[i], block_of[j as usize]);
                if a != b {
                    graph[a].push(b as u32);
                    graph[b].push(a as u32);
                }
            }
        }
        for g in graph.iter_mut() {
            g.sort_unstable();
            g.dedup();
        }
        let size: Vec<usize> = members.iter().map(Vec::len).collect();
        let (order, fill) = minimum_degree(graph, &size);
        let mut position = vec![0usize; nb];
        for (p, &b) in order.iter().enumerate() {
            position[b] = p;
        }
        let mut lu = BlockLu {
            n,
            ..BlockLu::default()
        };
        lu.dof_start.push(0);
        lu.adj_start.push(0);
        let mut off = 0;
        for (p, &b) in order.iter().enumerate() {
            lu.dofs.extend_from_slice(&members[b]);
            lu.dof_start.push(lu.dofs.len());
            let mut later: Vec<u32> = fill[b]
                .iter()
                .map(|&q| position[q as usize] as u32)
                .collect();
            later.sort_unstable();
            debug_assert!(later.iter().all(|&q| q as usize > p));
            lu.adj.extend_from_slice(&later);
            lu.adj_start.push(lu.adj.len());
            let s = size[b];
            lu.diag_off.push(off);
            off += s * s;
            for &q in &later {
                lu.off_diag.push(off);
                off += 2 * s * size[order[q as usize]];
            }
        }
        lu.data = vec![0.0; off];
        lu.pivots = vec![0; n];
        // local index and position of each unknown
        let mut pos_of = vec![0usize; n];
        let mut local = vec![0usize; n];
        for p in 0..nb {
            for (k, &i) in lu.block_dofs(p).iter().enumerate() {
                pos_of[i as usize] = p;
                local[i as usize] = k;
            }
        }
        lu.scatter = Vec::with_capacity(pattern.nnz());
        for i in 0..n {
            for &j in pattern.row(i) {
                let j = j as usize;
                let at = lu.entry(pos_of[i], local[i], pos_of[j], local[j]);
                lu.scatter.push(at);
            }
        }
        lu.diagonal = (0..n)
            .map(|i| lu.entry(pos_of[i], local[i], pos_of[i], local[i]))
            .collect();
        lu.scratch = vec![0.0; n];
        lu
    }

    /// Dimension n.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Stored entries of the factors (fill included).
    pub fn factor_entries(&self) -> usize {
        self.data.len()
    }

    fn block_dofs(&self, p: usize) -> &[u32] {
        &self.dofs[self.dof_start[p]..self.dof_start[p + 1]]
    }

    fn size(&self, p: usize) -> usize {
        self.dof_start[p + 1] - self.dof_start[p]
    }

    /// Offset of the block at (row block a, column block b) in `data`, a and b positions.
    fn block(&self, a: usize, b: usize) -> usize {
        if a == b {
            return self.diag_off[a];
        }
        let (p, q) = if a < b { (a, b) } else { (b, a) };
        let r = self.adj_start[p]..self.adj_start[p + 1];
        let k = self.adj[r.clone()]
            .binary_search(&(q as u32))
            .expect("block in the fill pattern");
        let l_off = self.off_diag[r.start + k];
        if a > b {
            l_off
        } else {
            l_off + self.size(q) * self.size(p)
        }
    }

    /// Offset of element (local row li of block a, local column lj of block b). Every block
    /// is row-major with the rows of a and the columns of b.
    fn entry(&self, a: usize, li: usize, b: usize, lj: usize) -> usize {
        self.block(a, b) + li * self.size(b) + lj
    }

    /// Factors I - c S, S given by its values on the analysed pattern.
    pub fn factor(&mut self, values: &[f64], c: f64) -> Result<(), Singular> {
        self.factor_general(values, 1.0, c)
    }

    /// Factors d I - c S: with d = 0 and c = -1 the matrix S itself (a Newton iteration's
    /// Jacobian, whose block diagonal must then be non-singular on its own).
    pub fn factor_general(&mut self, values: &[f64], d: f64, c: f64) -> Result<(), Singular> {
        self.data.fill(0.0);
        for (&at, &v) in self.scatter.iter().zip(values) {
            self.data[at] -= c * v;
        }
        for &at in &self.diagonal {
            self.data[at] += d;
        }
        self.inertia = [0; 3];
        let nb = self.diag_off.len();
        for p in 0..nb {
            let s = self.size(p);
            let d = self.diag_off[p];
            let piv_base = self.dof_start[p];
            if self.count_inertia {
                let block = nalgebra::DMatrix::from_fn(s, s, |i, j| {
                    0.5 * (self.data[d + i * s + j] + self.data[d + j * s + i])
                });
                let scale = block.amax();
                for e in block.symmetric_eigenvalues().iter() {
                    let k = if *e > 1e-12 * scale {
                        0
                    } else if *e < -1e-12 * scale {
                        2
                    } else {
                        1
                    };
                    self.inertia[k] += 1;
                }
            }
            // dense LU with partial pivoting of the diagonal block
            let norm = self.data[d..d + s * s]
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..s {
                let (mut best, mut at) = (0.0, k);
                for i in k..s {
                    let v = self.data[d + i * s + k].abs();
                    if v > best {
                        best = v;
                        at = i;
                    }
                }
                if best <= 1e-13 * norm || !best.is_finite() {
                    return Err(Singular);
                }
                self.pivots[piv_base + k] = at as u32;
                if at != k {
                    for j in 0..s {
                        self.data.swap(d + k * s + j, d + at * s + j);
                    }
                }
                let pk = self.data[d + k * s + k];
                for i in k + 1..s {
                    let l = self.data[d + i * s + k] / pk;
                    self.data[d + i * s + k] = l;
                    if l != 0.0 {
                        for j in k + 1..s {
                            self.data[d + i * s + j] -= l * self.data[d + k * s + j];
                        }
                    }
                }
            }
            let r = self.adj_start[p]..self.adj_start[p + 1];
            // L_qp <- A_qp U_pp^{-1};  U_pq <- L_pp^{-1} P A_pq
            for k in r.clone() {
                let q = self.adj[k] as usize;
                let sq = self.size(q);
                let lo = self.off_diag[k];
                let uo = lo + sq * s;
                for row in 0..sq {
                    let base = lo + row * s;
                    for j in 0..s {
                        let mut v = self.data[base + j];
                        for m in 0..j {
                            v -= self.data[base + m] * self.data[d + m * s + j];
                        }
                        self.data[base + j] = v / self.data[d + j * s + j];
                    }
                }
                for kk in 0..s {
                    let at = self.pivots[piv_base + kk] as usize;
                    if at != kk {
                        for j in 0..sq {
                            self.data.swap(uo + kk * sq + j, uo + at * sq + j);
                        }
                    }
                }
                for i in 1..s {
                    for m in 0..i {
                        let l = self.data[d + i * s + m];
                        if l != 0.0 {
                            for j in 0..sq {
                                self.data[uo + i * sq + j] -= l * self.data[uo + m * sq + j];
                            }
                        }
                    }
                }
            }
            // Schur complement: A_ab -= L_ap U_pb. Block p's L and U blocks lie before the
            // blocks of later positions in `data`, so sources and targets can be split.
            let split = self.diag_off.get(p + 1).copied().unwrap_or(self.data.len());
            let mut data = std::mem::take(&mut self.data);
            let (head, tail) = data.split_at_mut(split);
            for ka in r.clone() {
                let a = self.adj[ka] as usize;
                let sa = self.size(a);
                let la = self.off_diag[ka];
                for kb in r.clone() {
                    let b = self.adj[kb] as usize;
                    let sb = self.size(b);
                    let ub = self.off_diag[kb] + sb * s;
                    let t = self.block(a, b) - split;
                    for i in 0..sa {
                        let dst = &mut tail[t + i * sb..t + (i + 1) * sb];
                        for m in 0..s {
                            let l = head[la + i * s + m];
                            if l == 0.0 {
                                continue;
                            }
                            let src = &head[ub + m * sb..ub + (m + 1) * sb];
                            for (d, &u) in dst.iter_mut().zip(src) {
                                *d -= l * u;
                            }
                        }
                    }
                }
            }
            self.data = data;
        }
        Ok(())
    }

    /// Solves (I - c S) x = b in place (after [`BlockLu::factor`]). Works on a copy of
    /// x permuted to elimination order, so that every block is a contiguous slice.
    pub fn solve(&mut self, x: &mut [f64]) {
        let nb = self.diag_off.len();
        let mut z = std::mem::take(&mut self.scratch);
        z.resize(self.n, 0.0);
        for (k, &i) in self.dofs.iter().enumerate() {
            z[k] = x[i as usize];
        }
        for p in 0..nb {
            let (b0, b1) = (self.dof_start[p], self.dof_start[p + 1]);
            let s = b1 - b0;
            let d = self.diag_off[p];
            let (head, rest) = z.split_at_mut(b1);
            let zp = &mut head[b0..];
            for k in 0..s {
                zp.swap(k, self.pivots[b0 + k] as usize);
            }
            for i in 1..s {
                let row = &self.data[d + i * s..d + i * s + i];
                let v: f64 = row.iter().zip(&zp[..i]).map(|(a, b)| a * b).sum();
                zp[i] -= v;
            }
            for k in self.adj_start[p]..self.adj_start[p + 1] {
                let q = self.adj[k] as usize;
                let (q0, q1) = (self.dof_start[q] - b1, self.dof_start[q + 1] - b1);
                let lo = self.off_diag[k];
                for (row, zq) in rest[q0..q1].iter_mut().enumerate() {
                    let l = &self.data[lo + row * s..lo + (row + 1) * s];
                    let v: f64 = l.iter().zip(zp.iter()).map(|(a, b)| a * b).sum();
                    *zq -= v;
                }
            }
        }
        for p in (0..nb).rev() {
            let (b0, b1) = (self.dof_start[p], self.dof_start[p + 1]);
            let s = b1 - b0;
            let d = self.diag_off[p];
            let (head, rest) = z.split_at_mut(b1);
            let zp = &mut head[b0..];
            for k in self.adj_start[p]..self.adj_start[p + 1] {
                let q = self.adj[k] as usize;
                let (q0, q1) = (self.dof_start[q] - b1, self.dof_start[q + 1] - b1);
                let sq = q1 - q0;
                let uo = self.off_diag[k] + sq * s;
                let xq = &rest[q0..q1];
                for (row, zr) in zp.iter_mut().enumerate() {
                    let u = &self.data[uo + row * sq..uo + (row + 1) * sq];
                    let v: f64 = u.iter().zip(xq).map(|(a, b)| a * b).sum();
                    *zr -= v;
                }
            }
            for i in (0..s).rev() {
                let row = &self.data[d + i * s + i + 1..d + (i + 1) * s];
                let v: f64 = row.iter().zip(&zp[i + 1..]).map(|(a, b)| a * b).sum();
                zp[i] = (zp[i] - v) / self.data[d + i * s + i];
            }
        }
        for (k, &i) in self.dofs.iter().enumerate() {
            x[i as usize] = z[k];
        }
        self.scratch = z;
    }
}

/// Minimum-degree ordering of a graph whose vertices weigh `size` unknowns each: repeatedly
/// eliminates the vertex of least weighted degree and joins its neighbours into a clique.
/// Returns the elimination order and, per vertex, its neighbours when it was eliminated
/// (the fill pattern of its column of L).
fn minimum_degree(mut graph: Vec<Vec<u32>>, size: &[usize]) -> (Vec<usize>, Vec<Vec<u32>>) {
    let nb = graph.len();
    let weight = |g: &[u32]| g.iter().map(|&q| size[q as usize]).sum::<usize>();
    let mut degree: Vec<usize> = graph.iter().map(|g| weight(g)).collect();
    let mut done = vec![false; nb];
    let mut order = Vec::with_capacity(nb);
    let mut fill = vec![Vec::new(); nb];
    for _ in 0..nb {
        let v = (0..nb)
            .filter(|&v| !done[v])
            .min_by_key(|&v| (degree[v], v))
            .unwrap_or(0);
        done[v] = true;
        order.push(v);
        let nbrs = std::mem::take(&mut graph[v]);
        for &u in &nbrs {
            let u = u as usize;
            let mut merged: Vec<u32> = graph[u]
                .iter()
                .copied()
                .chain(nbrs.iter().copied())
                .filter(|&w| w as usize != u && w as usize != v)
                .collect();
            merged.sort_unstable();
            merged.dedup();
            degree[u] = weight(&merged);
            graph[u] = merged;
        }
        fill[v] = nbrs;
    }
    (order, fill)
}

/// Solver of (I - c J) x = b for J = S + U V^T: a [`BlockLu`] of A = I - c S plus the
/// Sherman-Morrison-Woodbury correction (Golub & Van Loan, Sec. 2.1.4):
/// (A - X V^T)^{-1} b = z + W (I - V^T W)^{-1} V^T z, with X = c U, W = A^{-1} X,
/// z = A^{-1} b.
#[derive(Clone, Debug, Default)]
pub struct ShiftedSolver {
    lu: BlockLu,
    /// The shift c of the current factorisation (0: none).
    shift: f64,
    rank: usize,
    w: Vec<f64>,
    v: Vec<f64>,
    /// LU of the r x r capacitance matrix I - V^T W (row-major, with row pivots).
    cap: Vec<f64>,
    cap_piv: Vec<usize>,
    small: Vec<f64>,
}

impl ShiftedSolver {
    /// Symbolic analysis for Jacobians on `pattern`, unknowns grouped by `groups`.
    pub fn new(pattern: &Pattern, groups: &[u32]) -> ShiftedSolver {
        ShiftedSolver {
            lu: BlockLu::new(pattern, groups),
            ..ShiftedSolver::default()
        }
    }

    /// The shift c of the current factorisation, 0 if none.
    pub fn shift(&self) -> f64 {
        self.shift
    }

    /// Forgets the factorisation.
    pub fn clear(&mut self) {
        self.shift = 0.0;
    }

    /// Stored entries of the sparse factors.
    pub fn factor_entries(&self) -> usize {
        self.lu.factor_entries()
    }

    /// The sparse part's LU, for its inertia ([`BlockLu::count_inertia`]).
    pub fn lu_mut(&mut self) -> &mut BlockLu {
        &mut self.lu
    }

    /// Factors I - c J.
    pub fn factor(&mut self, jac: &Jacobian, c: f64) -> Result<(), Singular> {
        self.factor_general(jac, 1.0, c)
    }

    /// Factors d I - c J (d = 0, c = -1: J itself, for Newton's method on a static
    /// equilibrium); [`ShiftedSolver::solve`] then solves (d I - c J) x = b.
    pub fn factor_general(&mut self, jac: &Jacobian, d: f64, c: f64) -> Result<(), Singular> {
        self.shift = 0.0;
        let n = jac.dim();
        self.lu.factor_general(&jac.values, d, c)?;
        let r = jac.rank;
        self.rank = r;
        self.w.resize(n * r, 0.0);
        self.v.clear();
        self.v.extend_from_slice(&jac.v[..n * r]);
        for k in 0..r {
            let wk = &mut self.w[k * n..(k + 1) * n];
            for (w, &u) in wk.iter_mut().zip(&jac.u[k * n..(k + 1) * n]) {
                *w = c * u;
            }
            self.lu.solve(wk);
        }
        self.cap = vec![0.0; r * r];
        for i in 0..r {
            for j in 0..r {
                let vw: f64 = self.v[i * n..(i + 1) * n]
                    .iter()
                    .zip(&self.w[j * n..(j + 1) * n])
                    .map(|(a, b)| a * b)
                    .sum();
                self.cap[i * r + j] = f64::from(u8::from(i == j)) - vw;
            }
        }
        self.cap_piv = (0..r).collect();
        for k in 0..r {
            let at = (k..r)
                .max_by(|&a, &b| {
                    self.cap[a * r + k]
                        .abs()
                        .total_cmp(&self.cap[b * r + k].abs())
                })
                .unwrap_or(k);
            let pk = self.cap[at * r + k];
            if pk.abs() <= 1e-14 || !pk.is_finite() {
                return Err(Singular);
            }
            self.cap_piv[k] = at;
            for j in 0..r {
                self.cap.swap(k * r + j, at * r + j);
            }
            for i in k + 1..r {
                let l = self.cap[i * r + k] / pk;
                self.cap[i * r + k] = l;
                for j in k + 1..r {
                    self.cap[i * r + j] -= l * self.cap[k * r + j];
                }
            }
        }
        self.small = vec![0.0; r];
        self.shift = c;
        Ok(())
    }

    /// Solves (I - c J) x = b in place with the current factorisation.
    pub fn solve(&mut self, x: &mut [f64]) {
        self.lu.solve(x);
        let (n, r) = (x.len(), self.rank);
        if r == 0 {
            return;
        }
        for i in 0..r {
            self.small[i] = self.v[i * n..(i + 1) * n]
                .iter()
                .zip(x.iter())
                .map(|(a, b)| a * b)
                .sum();
        }
        for k in 0..r {
            self.small.swap(k, self.cap_piv[k]);
        }
        for i in 1..r {
            for m in 0..i {
                self.small[i] -= self.cap[i * r + m] * self.small[m];
            }
        }
        for i in (0..r).rev() {
            for m in i + 1..r {
                self.small[i] -= self.cap[i * r + m] * self.small[m];
            }
            self.small[i] /= self.cap[i * r + i];
        }
        for k in 0..r {
            let s = self.small[k];
            for (xi, &w) in x.iter_mut().zip(&self.w[k * n..(k + 1) * n]) {
                *xi += w * s;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

    /// A random sparse Jacobian of a chain-like structure plus a rank-2 part; the solve is
    /// checked against the residual with the dense matrix.
    #[test]
    fn shifted_solve_matches_dense_residual() {
        let n = 60;
        let mut st = 7u64;
        let rows: Vec<Vec<u32>> = (0..n)
            .map(|i| {
                let mut r = vec![i as u32];
                for d in [1usize, 2, 7, 13] {
                    r.push(((i + d) % n) as u32);
                    r.push(((i + n - d) % n) as u32);
                }
                r
            })
            .collect();
        let pattern = Pattern::from_rows(rows);
        let mut jac = Jacobian::zeros(pattern.clone(), 2);
        for v in jac.values.iter_mut() {
            *v = 10.0 * lcg(&mut st);
        }
        for v in jac.u.iter_mut().chain(jac.v.iter_mut()) {
            *v = lcg(&mut st);
        }
        let groups: Vec<u32> = (0..n as u32).map(|i| i / 3).collect();
        let mut solver = ShiftedSolver::new(&pattern, &groups);
        let c = 0.05;
        solver.factor(&jac, c).unwrap();
        let b: Vec<f64> = (0..n).map(|_| lcg(&mut st)).collect();
        let mut x = b.clone();
        solver.solve(&mut x);
        let mut jx = vec![0.0; n];
        jac.mul_vec(&x, &mut jx);
        let res = (0..n)
            .map(|i| (x[i] - c * jx[i] - b[i]).abs())
            .fold(0.0, f64::max);
        assert!(res < 1e-12, "residual {res}");
        // the same with the dense product
        let d = jac.to_dense();
        for i in 0..n {
            let mut s = x[i];
            for j in 0..n {
                s -= c * d[i * n + j] * x[j];
            }
            assert!((s - b[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn colouring_is_distance_two_and_differences_are_exact_for_linear_maps() {
        let n = 40;
        let rows: Vec<Vec<u32>> = (0..n)
            .map(|i| vec![i as u32, ((i + 1) % n) as u32, ((i + 5) % n) as u32])
            .collect();
        let pattern = Pattern::from_rows(rows);
        let col = Colouring::new(&pattern);
        for i in 0..n {
            let r = pattern.row(i);
            for a in 0..r.len() {
                for b in a + 1..r.len() {
                    assert_ne!(col.colour[r[a] as usize], col.colour[r[b] as usize]);
                }
            }
        }
        assert!(col.colours <= 6, "{} colours", col.colours);
        let a: Vec<f64> = (0..pattern.nnz()).map(|k| 1.0 + k as f64).collect();
        let pat = pattern.clone();
        let mut f = |y: &[f64], out: &mut [f64]| {
            for i in 0..n {
                out[i] = pat
                    .row_range(i)
                    .zip(pat.row(i))
                    .map(|(e, &j)| a[e] * y[j as usize])
                    .sum();
            }
        };
        let y: Vec<f64> = (0..n).map(|i| i as f64 * 0.1).collect();
        let mut f0 = vec![0.0; n];
        f(&y, &mut f0);
        let (mut yp, mut f1, mut vals) = (vec![0.0; n], vec![0.0; n], vec![0.0; pattern.nnz()]);
        let evals = col.differences(&mut f, &y, &f0, &vec![1.0; n], &mut yp, &mut f1, &mut vals);
        assert_eq!(evals as usize, col.colours);
        for (v, w) in vals.iter().zip(&a) {
            assert!((v - w).abs() < 1e-6 * w, "{v} vs {w}");
        }
    }
}
