//! Preconditioned conjugate gradients on a CSR matrix.
//!
//! The matrix-vector product runs in parallel over fixed blocks of rows (each row summed in
//! order) and dot products add fixed-size blocks' partial sums in order, so the iterates are
//! bitwise identical for any thread count.

use rayon::prelude::*;
use sprs::CsMat;

/// Rows (or vector entries) per parallel work item.
const BLOCK: usize = 8192;

/// The preconditioner of [`pcg`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Preconditioner {
    /// None (plain CG).
    None,
    /// Diagonal scaling.
    #[default]
    Jacobi,
}

/// Options of [`pcg`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcgOptions {
    /// Stop when `|b - A x| <= tol |b|`.
    pub tol: f64,
    /// Stop after this many iterations.
    pub max_iter: usize,
    /// The preconditioner.
    pub preconditioner: Preconditioner,
}

impl Default for PcgOptions {
    fn default() -> Self {
        PcgOptions {
            tol: 1e-10,
            max_iter: 20_000,
            preconditioner: Preconditioner::Jacobi,
        }
    }
}

/// What [`pcg`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PcgReport {
    /// Iterations run.
    pub iterations: usize,
    /// Final relative residual `|b - A x| / |b|`, recomputed from `x`.
    pub residual: f64,
    /// Whether the tolerance was reached.
    pub converged: bool,
}

/// `y = A x`, in parallel, deterministic.
pub fn spmv(a: &CsMat<f64>, x: &[f64], y: &mut [f64]) {
    let ptr = a.indptr();
    let ptr = ptr.raw_storage();
    let (idx, val) = (a.indices(), a.data());
    y.par_chunks_mut(BLOCK).enumerate().for_each(|(c, ys)| {
        for (k, yi) in ys.iter_mut().enumerate() {
            let r = c * BLOCK + k;
            let mut s = 0.0;
            for j in ptr[r]..ptr[r + 1] {
                s += val[j] * x[idx[j]];
            }
            *yi = s;
        }
    });
}

/// `x . y`, summed in fixed blocks (independent of the thread count).
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    let partial: Vec<f64> = x
        .par_chunks(BLOCK)
        .zip(y.par_chunks(BLOCK))
        .map(|(a, b)| a.iter().zip(b).fold(0.0, |s, (p, q)| s + p * q))
        .collect();
    // A fold from +0.0 (an empty `sum` of f64 is -0.0).
    partial.iter().fold(0.0, |s, x| s + x)
}

/// The diagonal of `a`.
pub fn diagonal(a: &CsMat<f64>) -> Vec<f64> {
    (0..a.rows())
        .map(|r| a.get(r, r).copied().unwrap_or(0.0))
        .collect()
}

/// `z = M^-1 r`.
fn precondition(p: Preconditioner, inv_diag: &[f64], r: &[f64], z: &mut [f64]) {
    match p {
        Preconditioner::None => z.copy_from_slice(r),
        Preconditioner::Jacobi => z
            .par_chunks_mut(BLOCK)
            .zip(r.par_chunks(BLOCK))
            .zip(inv_diag.par_chunks(BLOCK))
            .for_each(|((z, r), d)| {
                z.iter_mut()
                    .zip(r)
                    .zip(d)
                    .for_each(|((z, r), d)| *z = r * d)
            }),
    }
}

/// `y += s x`, in parallel.
fn axpy(s: f64, x: &[f64], y: &mut [f64]) {
    y.par_chunks_mut(BLOCK)
        .zip(x.par_chunks(BLOCK))
        .for_each(|(y, x)| y.iter_mut().zip(x).for_each(|(y, x)| *y += s * x));
}

/// The relative residual `|b - A x| / |b|` (0 when `b = 0` and `A x = 0`).
pub fn relative_residual(a: &CsMat<f64>, b: &[f64], x: &[f64]) -> f64 {
    let mut r = vec![0.0; b.len()];
    spmv(a, x, &mut r);
    r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r);
    let nb = dot(b, b).sqrt();
    let nr = dot(&r, &r).sqrt();
    if nb == 0.0 {
        nr
    } else {
        nr / nb
    }
}

/// Solves `A x = b` (A symmetric positive definite) by preconditioned conjugate gradients
/// from the initial guess in `x`. `progress(iteration, relative residual)` is called after
/// every iteration.
pub fn pcg(
    a: &CsMat<f64>,
    b: &[f64],
    x: &mut [f64],
    opts: &PcgOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> PcgReport {
    let n = b.len();
    let inv_diag: Vec<f64> = diagonal(a).iter().map(|d| 1.0 / d).collect();
    let nb = dot(b, b).sqrt();
    let mut r = vec![0.0; n];
    spmv(a, x, &mut r);
    r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r);
    let mut z = vec![0.0; n];
    precondition(opts.preconditioner, &inv_diag, &r, &mut z);
    let mut p = z.clone();
    let mut q = vec![0.0; n];
    let mut rz = dot(&r, &z);
    let target = opts.tol * nb;
    let mut it = 0;
    let mut rn = dot(&r, &r).sqrt();
    while rn > target && it < opts.max_iter {
        spmv(a, &p, &mut q);
        let alpha = rz / dot(&p, &q);
        axpy(alpha, &p, x);
        axpy(-alpha, &q, &mut r);
        precondition(opts.preconditioner, &inv_diag, &r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        p.par_chunks_mut(BLOCK)
            .zip(z.par_chunks(BLOCK))
            .for_each(|(p, z)| p.iter_mut().zip(z).for_each(|(p, z)| *p = z + beta * *p));
        it += 1;
        rn = dot(&r, &r).sqrt();
        progress(it, if nb > 0.0 { rn / nb } else { rn });
    }
    let residual = relative_residual(a, b, x);
    PcgReport {
        iterations: it,
        residual,
        converged: rn <= target,
    }
}
