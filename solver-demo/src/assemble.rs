//! P1 assembly of `-div(k grad u) = s` on the free (non-Dirichlet) nodes.
//!
//! Element matrices `K_ab = k V grad(phi_a) . grad(phi_b)` and loads `F_a = int s phi_a`
//! (exact for a constant `s`, 4-point degree-2 quadrature for a function) are computed in
//! parallel. Two assemblies give the same CSR matrix (`sprs`) up to rounding:
//! * [`assemble`] (the default, measured faster: docs/QUALITY-LOG.md, *Solver demo*) builds
//!   each row in parallel from the tets around its node, in tet order, and sums equal columns
//!   in that order;
//! * [`assemble_triplets`] concatenates the chunks' triplets in chunk order and lets `sprs`
//!   sum duplicates (`TriMat::to_csr`).
//!
//! The Dirichlet lifting `-K_ab g_b` goes to the right-hand side. Both are bitwise identical
//! for any thread count.

use rayon::prelude::*;
use sprs::{CsMat, TriMat};
use tptd::nalgebra::{Matrix3, Point3};
use tptd::TetMesh;

use crate::SolveError;

/// Tets per parallel work item.
const CHUNK: usize = 4096;

/// Marks a node without an unknown (a Dirichlet node) in [`System::dof`].
pub const FIXED: u32 = u32::MAX;

/// The right-hand side `s`.
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// A constant source.
    Constant(f64),
    /// A source given at every point (integrated with 4-point quadrature).
    Function(&'a (dyn Fn([f64; 3]) -> f64 + Sync)),
}

/// The linear system on the free nodes.
pub struct System {
    /// Symmetric positive definite matrix (CSR) on the free nodes.
    pub a: CsMat<f64>,
    /// Right-hand side, including the Dirichlet lifting.
    pub b: Vec<f64>,
    /// For every node its unknown index, or [`FIXED`].
    pub dof: Vec<u32>,
}

/// Volume and barycentric gradients of a tetrahedron.
#[derive(Clone, Copy, Debug)]
pub struct TetGeometry {
    /// Volume (positive, whatever the orientation).
    pub volume: f64,
    /// `grad(phi_a)` of the four barycentric functions.
    pub grad: [[f64; 3]; 4],
}

/// Dot product of two 3-vectors.
pub fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The geometry of the tet with corners `p`, or `None` when it is degenerate.
///
/// With the edge vectors `e_k = p_k − p_0` as the rows of `E`, `e_j · grad(phi_k) = δ_jk`:
/// the gradients `grad(phi_1..3)` are the columns of `E⁻¹`, `grad(phi_0)` is minus their sum
/// and the volume is `|det E| / 6`. (`E⁻¹`'s cofactors are the cross products `e_2 × e_3`,
/// `e_3 × e_1`, `e_1 × e_2` over `det E`, bit for bit.)
pub fn tet_geometry(p: [[f64; 3]; 4]) -> Option<TetGeometry> {
    let edge = |k: usize| (Point3::from(p[k]) - Point3::from(p[0])).transpose();
    let e = Matrix3::from_rows(&[edge(1), edge(2), edge(3)]);
    let det = e.determinant();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = e.try_inverse()?;
    let [g1, g2, g3] = [0, 1, 2].map(|k| {
        let c = inv.column(k);
        [c[0], c[1], c[2]]
    });
    let g0 = [0, 1, 2].map(|k| -(g1[k] + g2[k] + g3[k]));
    Some(TetGeometry {
        volume: det.abs() / 6.0,
        grad: [g0, g1, g2, g3],
    })
}

/// The corners of tet `t`.
pub fn corners(mesh: &TetMesh, t: usize) -> [[f64; 3]; 4] {
    mesh.tets[t].map(|i| mesh.points[i as usize])
}

/// Barycentric coordinates of the 4-point degree-2 rule: `A` at one corner, `B` at the others.
pub const QUAD_A: f64 = 0.585_410_196_624_968_5;
/// See [`QUAD_A`].
pub const QUAD_B: f64 = 0.138_196_601_125_010_5;

/// The 4 quadrature points of tet `p` (weight `V/4` each); point `q` is nearest corner `q`.
pub fn quad_points(p: &[[f64; 3]; 4]) -> [[f64; 3]; 4] {
    std::array::from_fn(|q| {
        std::array::from_fn(|k| {
            (0..4)
                .map(|c| p[c][k] * if c == q { QUAD_A } else { QUAD_B })
                .sum()
        })
    })
}

/// Element load vector.
fn element_load(p: &[[f64; 3]; 4], volume: f64, source: Source) -> [f64; 4] {
    match source {
        Source::Constant(s) => [s * volume / 4.0; 4],
        Source::Function(f) => {
            let vals = quad_points(p).map(f);
            std::array::from_fn(|a| {
                let sum: f64 = (0..4)
                    .map(|q| vals[q] * if q == a { QUAD_A } else { QUAD_B })
                    .sum();
                sum * volume / 4.0
            })
        }
    }
}

/// Triplets and lifted loads of one chunk of tets.
#[derive(Default)]
struct Part {
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
    /// (unknown, contribution) pairs in tet order.
    rhs: Vec<(u32, f64)>,
}

/// Everything assembly needs: the mesh, `k` per tet, the source, and per node its Dirichlet
/// value (`NaN` for a free node).
pub struct Problem<'a> {
    /// The mesh.
    pub mesh: &'a TetMesh,
    /// Conductivity of every tet (> 0).
    pub k: &'a [f64],
    /// Right-hand side.
    pub source: Source<'a>,
    /// Dirichlet value of every node, `NaN` where `u` is unknown.
    pub dirichlet: &'a [f64],
}

fn chunk_part(pb: &Problem, dof: &[u32], first: usize, n: usize) -> Result<Part, SolveError> {
    let mut part = Part::default();
    for t in first..first + n {
        let p = corners(pb.mesh, t);
        let g = tet_geometry(p)
            .ok_or_else(|| SolveError::Invalid(format!("tetrahedron {} is degenerate", t + 1)))?;
        let load = element_load(&p, g.volume, pb.source);
        let nodes = pb.mesh.tets[t];
        for a in 0..4 {
            let ra = dof[nodes[a] as usize];
            if ra == FIXED {
                continue;
            }
            let mut lifted = load[a];
            for b in 0..4 {
                let kab = pb.k[t] * g.volume * dot3(g.grad[a], g.grad[b]);
                let rb = dof[nodes[b] as usize];
                if rb == FIXED {
                    lifted -= kab * pb.dirichlet[nodes[b] as usize];
                } else {
                    part.rows.push(ra as usize);
                    part.cols.push(rb as usize);
                    part.vals.push(kab);
                }
            }
            part.rhs.push((ra, lifted));
        }
    }
    Ok(part)
}

/// Unknown numbering: free nodes in node order.
pub fn number_dofs(dirichlet: &[f64]) -> (Vec<u32>, usize) {
    let mut n = 0u32;
    let dof = dirichlet
        .iter()
        .map(|g| {
            if g.is_nan() {
                n += 1;
                n - 1
            } else {
                FIXED
            }
        })
        .collect();
    (dof, n as usize)
}

/// Assembles the system of `pb` on its free nodes from `sprs` triplets (see the module
/// documentation).
///
/// # Errors
/// [`SolveError::Invalid`] for a degenerate tetrahedron.
pub fn assemble_triplets(pb: &Problem) -> Result<System, SolveError> {
    let (dof, n) = number_dofs(pb.dirichlet);
    let n_tets = pb.mesh.tets.len();
    let parts = (0..n_tets.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| chunk_part(pb, &dof, c * CHUNK, CHUNK.min(n_tets - c * CHUNK)))
        .collect::<Result<Vec<Part>, _>>()?;
    let nnz: usize = parts.iter().map(|p| p.vals.len()).sum();
    let (mut rows, mut cols, mut vals) = (
        Vec::with_capacity(nnz),
        Vec::with_capacity(nnz),
        Vec::with_capacity(nnz),
    );
    let mut b = vec![0.0; n];
    for p in parts {
        rows.extend_from_slice(&p.rows);
        cols.extend_from_slice(&p.cols);
        vals.extend_from_slice(&p.vals);
        for (r, v) in p.rhs {
            b[r as usize] += v;
        }
    }
    let a = TriMat::from_triplets((n, n), rows, cols, vals).to_csr();
    Ok(System { a, b, dof })
}

/// For every node the (tet, local index) pairs of the tets around it, in tet order, packed
/// as `4 t + a`, in CSR form (`ptr`, `items`).
fn node_tets(mesh: &TetMesh) -> (Vec<usize>, Vec<u32>) {
    let mut ptr = vec![0usize; mesh.points.len() + 1];
    for &v in mesh.tets.iter().flatten() {
        ptr[v as usize + 1] += 1;
    }
    for i in 0..mesh.points.len() {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut items = vec![0u32; ptr[mesh.points.len()]];
    for (t, tet) in mesh.tets.iter().enumerate() {
        for (a, &v) in tet.iter().enumerate() {
            items[fill[v as usize]] = (4 * t + a) as u32;
            fill[v as usize] += 1;
        }
    }
    (ptr, items)
}

/// The tets around every node (see [`node_tets`]).
struct Around<'a> {
    ptr: &'a [usize],
    items: &'a [u32],
}

/// Row `a` of the element matrix of tet `t` and its load `F_a`.
fn element_row(pb: &Problem, t: usize, a: usize) -> Result<([f64; 4], f64), SolveError> {
    let p = corners(pb.mesh, t);
    let g = tet_geometry(p)
        .ok_or_else(|| SolveError::Invalid(format!("tetrahedron {} is degenerate", t + 1)))?;
    let kv = pb.k[t] * g.volume;
    let row = std::array::from_fn(|b| kv * dot3(g.grad[a], g.grad[b]));
    let load = match pb.source {
        Source::Constant(s) => s * g.volume / 4.0,
        source => element_load(&p, g.volume, source)[a],
    };
    Ok((row, load))
}

/// The CSR rows of the free nodes `nodes` (see [`assemble`]); element rows are computed
/// where they are needed, which is cheaper than storing all element matrices.
fn row_block(
    pb: &Problem,
    dof: &[u32],
    around: &Around,
    nodes: &[u32],
) -> Result<Rows, SolveError> {
    let mut out = Rows::default();
    let mut row: Vec<(usize, f64)> = Vec::with_capacity(64);
    for &v in nodes {
        row.clear();
        let mut rhs = 0.0;
        for &item in &around.items[around.ptr[v as usize]..around.ptr[v as usize + 1]] {
            let (t, a) = (item as usize / 4, item as usize % 4);
            let (m, f) = element_row(pb, t, a)?;
            rhs += f;
            for (b, &w) in pb.mesh.tets[t].iter().enumerate() {
                match dof[w as usize] {
                    FIXED => rhs -= m[b] * pb.dirichlet[w as usize],
                    c => row.push((c as usize, m[b])),
                }
            }
        }
        // Stable: equal columns are summed in tet order.
        row.sort_by_key(|e| e.0);
        let start = out.cols.len();
        for &(c, x) in &row {
            if out.cols.len() > start && out.cols.last() == Some(&c) {
                *out.vals.last_mut().unwrap() += x;
            } else {
                out.cols.push(c);
                out.vals.push(x);
            }
        }
        out.lens.push(out.cols.len() - start);
        out.rhs.push(rhs);
    }
    Ok(out)
}

/// One block of CSR rows: column indices, values, row lengths and right-hand sides.
#[derive(Default)]
struct Rows {
    cols: Vec<usize>,
    vals: Vec<f64>,
    lens: Vec<usize>,
    rhs: Vec<f64>,
}

/// Assembles the system of `pb` on its free nodes row by row, in parallel (see the module
/// documentation). Needs `4 #T < 2^32`.
///
/// # Errors
/// [`SolveError::Invalid`] for a degenerate tetrahedron or a mesh too large.
pub fn assemble(pb: &Problem) -> Result<System, SolveError> {
    if pb.mesh.tets.len() >= (u32::MAX / 4) as usize {
        return Err(SolveError::Invalid("too many tetrahedra".into()));
    }
    let (dof, n) = number_dofs(pb.dirichlet);
    let (ptr, items) = node_tets(pb.mesh);
    let free: Vec<u32> = (0..dof.len() as u32)
        .filter(|&v| dof[v as usize] != FIXED)
        .collect();
    let around = Around {
        ptr: &ptr,
        items: &items,
    };
    let blocks: Vec<Rows> = free
        .par_chunks(1024)
        .map(|nodes| row_block(pb, &dof, &around, nodes))
        .collect::<Result<_, _>>()?;
    let nnz = blocks.iter().map(|b| b.cols.len()).sum();
    let (mut indptr, mut cols, mut vals) = (
        Vec::with_capacity(n + 1),
        Vec::with_capacity(nnz),
        Vec::with_capacity(nnz),
    );
    let mut b = Vec::with_capacity(n);
    indptr.push(0);
    for blk in blocks {
        for len in blk.lens {
            indptr.push(indptr.last().unwrap() + len);
        }
        cols.extend_from_slice(&blk.cols);
        vals.extend_from_slice(&blk.vals);
        b.extend_from_slice(&blk.rhs);
    }
    let a = CsMat::new((n, n), indptr, cols, vals);
    Ok(System { a, b, dof })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }

    /// The gradients are the cross-product formulas of the element, to the last bit.
    #[test]
    fn gradients_are_the_scaled_cross_products() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..1000 {
            let p: [[f64; 3]; 4] = std::array::from_fn(|_| [next(), next(), next()]);
            let e = [1, 2, 3].map(|k| [0, 1, 2].map(|a| p[k][a] - p[0][a]));
            let det = dot3(e[0], cross(e[1], e[2]));
            let g = tet_geometry(p).unwrap();
            assert_eq!(g.volume, det.abs() / 6.0);
            for (k, (a, b)) in [(1, 2), (2, 0), (0, 1)].into_iter().enumerate() {
                assert_eq!(g.grad[k + 1], cross(e[a], e[b]).map(|x| x / det));
            }
        }
        assert!(
            tet_geometry([[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).is_none()
        );
    }
}
