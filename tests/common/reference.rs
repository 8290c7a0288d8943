//! Independent ground truth for the topology and volume of interval volumes of a
//! piecewise-trilinear field.
//!
//! Nothing here uses the `tptd` crate: the trilinear interpolant is evaluated directly from
//! the corner values, densely sampled (N samples per cell edge, at sub-voxel centres
//! `(a + 0.5) / N`), samples with `alpha < f < beta` (STRICT) are marked, and the Betti
//! numbers of the union of the closed sub-voxels around marked samples are computed:
//!
//! * b0 = 26-connected components of marked voxels;
//! * b2 = 6-connected components of unmarked voxels in a grid padded by one unmarked layer, − 1;
//! * χ  = V − E + F − C of the cubical complex (the union of closed voxels), counted on the lattice;
//! * b1 = b0 + b2 − χ.
//!
//! Sampling cannot resolve levels arbitrarily close to critical values, so
//! [`reference_betti`] (a) refuses levels within a margin of a critical value of the
//! interpolant (vertex values, face saddles, body saddles), except exact ties, which are
//! resolved like the mesher's perturbation (a value equal to a level is "outside") by
//! shifting the level inwards by the margin when no other critical value is near, and
//! (b) demands that two different sampling resolutions agree.

/// Values of a grid: dims = vertex counts, x fastest (`idx = i + nx*(j + ny*k)`).
#[derive(Clone, Debug)]
pub struct Field {
    pub dims: [usize; 3],
    pub values: Vec<f64>,
}

impl Field {
    pub fn new(dims: [usize; 3], values: Vec<f64>) -> Self {
        assert_eq!(dims[0] * dims[1] * dims[2], values.len());
        assert!(dims.iter().all(|&d| d >= 2));
        Field { dims, values }
    }

    /// A single cell from 8 corner values (corner c = (c&1, (c>>1)&1, (c>>2)&1)).
    pub fn cell(v: [f64; 8]) -> Self {
        Field::new([2, 2, 2], v.to_vec())
    }

    pub fn from_fn(dims: [usize; 3], f: impl Fn(f64, f64, f64) -> f64) -> Self {
        let mut values = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    values.push(f(i as f64, j as f64, k as f64));
                }
            }
        }
        Field::new(dims, values)
    }

    pub fn at(&self, i: usize, j: usize, k: usize) -> f64 {
        self.values[i + self.dims[0] * (j + self.dims[1] * k)]
    }

    pub fn cell_dims(&self) -> [usize; 3] {
        [self.dims[0] - 1, self.dims[1] - 1, self.dims[2] - 1]
    }

    pub fn num_cells(&self) -> usize {
        let c = self.cell_dims();
        c[0] * c[1] * c[2]
    }

    /// Corner values of cell (i,j,k), corner c at offset (c&1, (c>>1)&1, (c>>2)&1).
    pub fn corners(&self, i: usize, j: usize, k: usize) -> [f64; 8] {
        let mut v = [0.0; 8];
        for (c, vc) in v.iter_mut().enumerate() {
            *vc = self.at(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        }
        v
    }

    /// The trilinear interpolant at a point of the grid box (direct formula).
    pub fn eval(&self, p: [f64; 3]) -> f64 {
        let mut ijk = [0usize; 3];
        let mut loc = [0.0; 3];
        for a in 0..3 {
            let c = (p[a].floor().max(0.0) as usize).min(self.dims[a] - 2);
            ijk[a] = c;
            loc[a] = p[a] - c as f64;
        }
        trilinear(
            &self.corners(ijk[0], ijk[1], ijk[2]),
            loc[0],
            loc[1],
            loc[2],
        )
    }
}

/// The textbook trilinear formula.
#[inline]
pub fn trilinear(v: &[f64; 8], x: f64, y: f64, z: f64) -> f64 {
    let (ux, uy, uz) = (1.0 - x, 1.0 - y, 1.0 - z);
    v[0] * ux * uy * uz
        + v[1] * x * uy * uz
        + v[2] * ux * y * uz
        + v[3] * x * y * uz
        + v[4] * ux * uy * z
        + v[5] * x * uy * z
        + v[6] * ux * y * z
        + v[7] * x * y * z
}

/// Marked sub-voxels of a sampled field.
#[derive(Clone, Debug)]
pub struct Sampled {
    /// Sub-voxel counts per axis.
    pub dims: [usize; 3],
    /// Sub-voxels per cell edge.
    pub n: usize,
    pub mark: Vec<bool>,
}

impl Sampled {
    pub fn count(&self) -> usize {
        self.mark.iter().filter(|&&m| m).count()
    }
    /// Sampled volume: count × voxel volume.
    pub fn volume(&self) -> f64 {
        self.count() as f64 / (self.n * self.n * self.n) as f64
    }
}

/// Sample `field` at N×N×N sub-voxel centres per cell and mark `alpha < f < beta`.
pub fn sample(field: &Field, n: usize, alpha: f64, beta: f64) -> Sampled {
    let cd = field.cell_dims();
    let dims = [cd[0] * n, cd[1] * n, cd[2] * n];
    let mut mark = vec![false; dims[0] * dims[1] * dims[2]];
    let t: Vec<f64> = (0..n).map(|a| (a as f64 + 0.5) / n as f64).collect();
    for ck in 0..cd[2] {
        for cj in 0..cd[1] {
            for ci in 0..cd[0] {
                let v = field.corners(ci, cj, ck);
                for (c, &z) in t.iter().enumerate() {
                    for (b, &y) in t.iter().enumerate() {
                        let row = ci * n + dims[0] * (cj * n + b + dims[1] * (ck * n + c));
                        for (a, &x) in t.iter().enumerate() {
                            let f = trilinear(&v, x, y, z);
                            mark[row + a] = alpha < f && f < beta;
                        }
                    }
                }
            }
        }
    }
    Sampled { dims, n, mark }
}

/// Betti numbers (b0, b1, b2) of the union of closed marked voxels.
pub fn betti(s: &Sampled) -> [usize; 3] {
    let b0 = components26(&s.mark, s.dims);
    let b2 = complement_components6(&s.mark, s.dims) - 1;
    let chi = euler_closed_union(&s.mark, s.dims);
    let b1 = b0 as i64 + b2 as i64 - chi;
    assert!(b1 >= 0, "negative b1: b0={b0} b2={b2} chi={chi}");
    [b0, b1 as usize, b2]
}

fn components26(mark: &[bool], d: [usize; 3]) -> usize {
    let mut seen = vec![false; mark.len()];
    let mut stack: Vec<usize> = Vec::new();
    let mut comps = 0;
    for start in 0..mark.len() {
        if !mark[start] || seen[start] {
            continue;
        }
        comps += 1;
        seen[start] = true;
        stack.push(start);
        while let Some(p) = stack.pop() {
            let i = p % d[0];
            let j = (p / d[0]) % d[1];
            let k = p / (d[0] * d[1]);
            for dk in -1i64..=1 {
                let kk = k as i64 + dk;
                if kk < 0 || kk >= d[2] as i64 {
                    continue;
                }
                for dj in -1i64..=1 {
                    let jj = j as i64 + dj;
                    if jj < 0 || jj >= d[1] as i64 {
                        continue;
                    }
                    for di in -1i64..=1 {
                        let ii = i as i64 + di;
                        if ii < 0 || ii >= d[0] as i64 {
                            continue;
                        }
                        let q = ii as usize + d[0] * (jj as usize + d[1] * kk as usize);
                        if mark[q] && !seen[q] {
                            seen[q] = true;
                            stack.push(q);
                        }
                    }
                }
            }
        }
    }
    comps
}

/// The mark array padded with one layer of `false` on every side.
fn padded(mark: &[bool], d: [usize; 3]) -> (Vec<bool>, [usize; 3]) {
    let pd = [d[0] + 2, d[1] + 2, d[2] + 2];
    let mut p = vec![false; pd[0] * pd[1] * pd[2]];
    for k in 0..d[2] {
        for j in 0..d[1] {
            let src = d[0] * (j + d[1] * k);
            let dst = 1 + pd[0] * (j + 1 + pd[1] * (k + 1));
            p[dst..dst + d[0]].copy_from_slice(&mark[src..src + d[0]]);
        }
    }
    (p, pd)
}

fn complement_components6(mark: &[bool], d: [usize; 3]) -> usize {
    let (p, pd) = padded(mark, d);
    let mut seen = p.clone(); // marked voxels are never visited
    let mut stack: Vec<usize> = Vec::new();
    let mut comps = 0;
    let strides = [1usize, pd[0], pd[0] * pd[1]];
    for start in 0..p.len() {
        if seen[start] {
            continue;
        }
        comps += 1;
        seen[start] = true;
        stack.push(start);
        while let Some(q) = stack.pop() {
            let ijk = [q % pd[0], (q / pd[0]) % pd[1], q / (pd[0] * pd[1])];
            for a in 0..3 {
                if ijk[a] > 0 && !seen[q - strides[a]] {
                    seen[q - strides[a]] = true;
                    stack.push(q - strides[a]);
                }
                if ijk[a] + 1 < pd[a] && !seen[q + strides[a]] {
                    seen[q + strides[a]] = true;
                    stack.push(q + strides[a]);
                }
            }
        }
    }
    comps
}

/// OR of each entry with its successor along `axis`; the result is one shorter on that axis.
fn or_shift(a: &[bool], d: [usize; 3], axis: usize) -> (Vec<bool>, [usize; 3]) {
    let mut nd = d;
    nd[axis] -= 1;
    let stride = [1, d[0], d[0] * d[1]][axis];
    let mut out = vec![false; nd[0] * nd[1] * nd[2]];
    let mut o = 0;
    for k in 0..nd[2] {
        for j in 0..nd[1] {
            for i in 0..nd[0] {
                let q = i + d[0] * (j + d[1] * k);
                out[o] = a[q] || a[q + stride];
                o += 1;
            }
        }
    }
    (out, nd)
}

fn count(a: &[bool]) -> i64 {
    a.iter().filter(|&&b| b).count() as i64
}

/// Euler characteristic of the union of closed unit cubes at the marked voxels.
///
/// With P the padded marks: a lattice vertex is in the union iff one of its 8 voxels is
/// marked (OR over x, y and z shifts), an x-edge iff one of its 4 voxels is (OR over y, z),
/// an x-face iff one of its 2 voxels is (OR over x). Pad entries are false, so whole arrays
/// can be counted.
pub fn euler_closed_union(mark: &[bool], d: [usize; 3]) -> i64 {
    let (p, pd) = padded(mark, d);
    let cubes = count(&p);
    let (ox, dx) = or_shift(&p, pd, 0);
    let (oy, dy) = or_shift(&p, pd, 1);
    let (oz, dz) = or_shift(&p, pd, 2);
    let faces = count(&ox) + count(&oy) + count(&oz);
    let (oxy, dxy) = or_shift(&ox, dx, 1);
    let (oyz, _) = or_shift(&oy, dy, 2);
    let (ozx, _) = or_shift(&oz, dz, 0);
    // x-edges: OR over y and z = oyz; y-edges: OR over z and x = ozx; z-edges: OR over x, y = oxy
    let edges = count(&oxy) + count(&oyz) + count(&ozx);
    let (oxyz, _) = or_shift(&oxy, dxy, 2);
    let verts = count(&oxyz);
    verts - edges + faces - cubes
}

/// Betti numbers of {alpha < f < beta} sampled at resolution n (no safety checks).
pub fn sampled_betti(field: &Field, n: usize, alpha: f64, beta: f64) -> [usize; 3] {
    betti(&sample(field, n, alpha, beta))
}

// ---------------------------------------------------------------------------------------
// Critical values
// ---------------------------------------------------------------------------------------

/// Value of the bilinear saddle of a face (a00, a10, a01, a11) if it lies strictly inside.
pub fn face_saddle(a00: f64, a10: f64, a01: f64, a11: f64) -> Option<f64> {
    let d = a00 - a10 - a01 + a11;
    if d == 0.0 {
        return None;
    }
    let u = (a00 - a01) / d;
    let v = (a00 - a10) / d;
    if u > 0.0 && u < 1.0 && v > 0.0 && v < 1.0 {
        Some((a00 * a11 - a10 * a01) / d)
    } else {
        None
    }
}

/// Face saddle values of a cell (faces listed as corner quadruples (00, 10, 01, 11)).
pub const CELL_FACES: [[usize; 4]; 6] = [
    [0, 2, 4, 6], // x = 0
    [1, 3, 5, 7], // x = 1
    [0, 1, 4, 5], // y = 0
    [2, 3, 6, 7], // y = 1
    [0, 1, 2, 3], // z = 0
    [4, 5, 6, 7], // z = 1
];

pub fn face_saddles(v: &[f64; 8]) -> Vec<f64> {
    CELL_FACES
        .iter()
        .filter_map(|f| face_saddle(v[f[0]], v[f[1]], v[f[2]], v[f[3]]))
        .collect()
}

/// Body saddles strictly inside the cell: (position, value).
pub fn body_saddles(v: &[f64; 8]) -> Vec<([f64; 3], f64)> {
    // f = k0 + k1 x + k2 y + k3 z + k4 xy + k5 yz + k6 xz + k7 xyz
    let k1 = v[1] - v[0];
    let k2 = v[2] - v[0];
    let k3 = v[4] - v[0];
    let k4 = v[3] - v[2] - v[1] + v[0];
    let k5 = v[6] - v[4] - v[2] + v[0];
    let k6 = v[5] - v[4] - v[1] + v[0];
    let k7 = v[7] - v[6] - v[5] - v[3] + v[4] + v[2] + v[1] - v[0];
    let mut cands: Vec<[f64; 3]> = Vec::new();
    let scale = v.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
    if k7.abs() > 1e-12 * scale {
        // X = x + k5/k7, Y = y + k6/k7, Z = z + k4/k7:  YZ = A, XZ = B, XY = C
        let h2 = k7 * k7;
        let a = (k4 * k6 - k1 * k7) / h2;
        let b = (k4 * k5 - k2 * k7) / h2;
        let c = (k6 * k5 - k3 * k7) / h2;
        if a * b * c > 0.0 {
            let xx = (b * c / a).sqrt();
            for s in [xx, -xx] {
                let y = c / s;
                let z = b / s;
                cands.push([s - k5 / k7, y - k6 / k7, z - k4 / k7]);
            }
        }
    } else {
        // grad = 0 is linear: [[0,k4,k6],[k4,0,k5],[k6,k5,0]] (x,y,z) = -(k1,k2,k3)
        let det = 2.0 * k4 * k5 * k6;
        if det.abs() > 1e-12 * scale * scale * scale {
            let m = [[0.0, k4, k6], [k4, 0.0, k5], [k6, k5, 0.0]];
            let rhs = [-k1, -k2, -k3];
            let mut sol = [0.0; 3];
            for (col, s) in sol.iter_mut().enumerate() {
                let mut mm = m;
                for r in 0..3 {
                    mm[r][col] = rhs[r];
                }
                *s = det3(&mm) / det;
            }
            cands.push(sol);
        }
    }
    cands
        .into_iter()
        .filter(|p| p.iter().all(|&t| t > 0.0 && t < 1.0))
        .map(|p| (p, trilinear(v, p[0], p[1], p[2])))
        .collect()
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// All critical values of the piecewise-trilinear field: vertex values, face saddles, body
/// saddles (sorted, not deduplicated).
pub fn critical_values(field: &Field) -> Vec<f64> {
    let mut out = field.values.clone();
    let cd = field.cell_dims();
    for k in 0..cd[2] {
        for j in 0..cd[1] {
            for i in 0..cd[0] {
                let v = field.corners(i, j, k);
                out.extend(face_saddles(&v));
                out.extend(body_saddles(&v).into_iter().map(|(_, s)| s));
            }
        }
    }
    out.sort_by(|a, b| a.partial_cmp(b).unwrap());
    out
}

/// Outcome of a guarded reference computation.
#[derive(Clone, Debug, PartialEq)]
pub enum RefBetti {
    /// Betti numbers, and whether an exact tie was resolved by shifting a level.
    Resolved { betti: [usize; 3], tie: bool },
    /// The sampler cannot decide; reason given.
    Unresolved(String),
}

/// Choose the effective level for sampling: `Some((level', tie))` or `None` if too close.
/// `inward` is +1 for alpha (the set lies above it), −1 for beta.
fn effective_level(level: f64, crit: &[f64], margin: f64, inward: f64) -> Option<(f64, bool)> {
    if !level.is_finite() || crit.iter().all(|c| (c - level).abs() >= margin) {
        return Some((level, false));
    }
    if crit.contains(&level) {
        // exact tie: a value equal to the level counts as outside, so the open set has the
        // topology of the set at a level shifted inwards, provided no other critical value
        // lies between them (or near the shifted level)
        let shifted = level + inward * margin;
        if crit
            .iter()
            .all(|&c| c == level || (c - shifted).abs() >= margin)
        {
            return Some((shifted, true));
        }
    }
    None
}

/// Guarded reference Betti numbers of the interval {alpha < f < beta}.
///
/// `margin`: minimum distance (in value) between an effective level and any critical value;
/// `ns`: sampling resolutions which must all agree.
pub fn reference_betti(
    field: &Field,
    alpha: f64,
    beta: f64,
    margin: f64,
    ns: &[usize],
) -> RefBetti {
    let crit = critical_values(field);
    let Some((a, ta)) = effective_level(alpha, &crit, margin, 1.0) else {
        return RefBetti::Unresolved(format!("alpha={alpha} within {margin} of a critical value"));
    };
    let Some((b, tb)) = effective_level(beta, &crit, margin, -1.0) else {
        return RefBetti::Unresolved(format!("beta={beta} within {margin} of a critical value"));
    };
    if a >= b {
        return RefBetti::Unresolved(format!(
            "interval ({alpha},{beta}) too thin for margin {margin}"
        ));
    }
    let mut first: Option<[usize; 3]> = None;
    for &n in ns {
        let bt = sampled_betti(field, n, a, b);
        match first {
            None => first = Some(bt),
            Some(f) if f != bt => {
                return RefBetti::Unresolved(format!(
                    "resolutions disagree: {f:?} vs {bt:?} (n={n})"
                ));
            }
            _ => {}
        }
    }
    RefBetti::Resolved {
        betti: first.expect("at least one resolution"),
        tie: ta || tb,
    }
}

// ---------------------------------------------------------------------------------------
// Volumes
// ---------------------------------------------------------------------------------------

/// Exact volume of {x ∈ [0,L0]×[0,L1]×[0,L2] : a·x ≤ t}, all a_i ≠ 0.
///
/// Reflect coordinates so that every a_i > 0 (x_i → L_i − x_i shifts t), then
/// inclusion–exclusion over the corners: V = Σ_S (−1)^|S| max(0, t − Σ_{i∈S} a_i L_i)³ / (6 a0 a1 a2).
pub fn halfspace_box_volume(a: [f64; 3], t: f64, l: [f64; 3]) -> f64 {
    let mut a = a;
    let mut t = t;
    for i in 0..3 {
        assert!(a[i] != 0.0, "coefficient must be non-zero");
        if a[i] < 0.0 {
            // a_i x_i = a_i (L_i - y_i) = a_i L_i - a_i y_i
            t -= a[i] * l[i];
            a[i] = -a[i];
        }
    }
    let full = l[0] * l[1] * l[2];
    let total = a[0] * l[0] + a[1] * l[1] + a[2] * l[2];
    if t <= 0.0 {
        return 0.0;
    }
    if t >= total {
        return full;
    }
    // use the smaller side for accuracy
    let mut sum = 0.0;
    let tt = if t <= total / 2.0 { t } else { total - t };
    for s in 0..8usize {
        let mut r = tt;
        for i in 0..3 {
            if s >> i & 1 == 1 {
                r -= a[i] * l[i];
            }
        }
        if r > 0.0 {
            let sign = if s.count_ones() % 2 == 1 { -1.0 } else { 1.0 };
            sum += sign * r * r * r;
        }
    }
    let v = sum / (6.0 * a[0] * a[1] * a[2]);
    if t <= total / 2.0 {
        v
    } else {
        full - v
    }
}

/// Exact volume of {alpha < a·x + d < beta} ∩ box for a linear field.
pub fn linear_interval_volume(a: [f64; 3], d: f64, alpha: f64, beta: f64, l: [f64; 3]) -> f64 {
    let below = |lvl: f64| -> f64 {
        if lvl == f64::INFINITY {
            l[0] * l[1] * l[2]
        } else if lvl == f64::NEG_INFINITY {
            0.0
        } else {
            halfspace_box_volume(a, lvl - d, l)
        }
    };
    (below(beta) - below(alpha)).max(0.0)
}

/// Exact bounds on the mesh volume from corner values alone: cells with all corners strictly
/// inside (alpha, beta) are entirely inside (the trilinear interpolant and every linear
/// interpolant of values in the corner range stay within [min, max] of the corners); cells with
/// max corner ≤ alpha or min corner ≥ beta are entirely outside.
/// Returns (per-cell class: 0 = outside, 1 = full, 2 = partial, count full, count partial).
pub fn cell_classes(field: &Field, alpha: f64, beta: f64) -> (Vec<u8>, usize, usize) {
    let cd = field.cell_dims();
    let mut cls = Vec::with_capacity(field.num_cells());
    let (mut full, mut part) = (0, 0);
    for k in 0..cd[2] {
        for j in 0..cd[1] {
            for i in 0..cd[0] {
                let v = field.corners(i, j, k);
                let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let c = if hi <= alpha || lo >= beta {
                    0
                } else if lo > alpha && hi < beta {
                    full += 1;
                    1
                } else {
                    part += 1;
                    2
                };
                cls.push(c);
            }
        }
    }
    (cls, full, part)
}
