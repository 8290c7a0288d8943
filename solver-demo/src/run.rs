//! The solve stages strung together, with timings: set-up, assembly, PCG, and for the
//! manufactured solution the error norms.

use std::time::Instant;

use tptd::io::MeshFile;

use crate::assemble::{assemble, assemble_triplets, Problem, Source, FIXED};
use crate::mms::{self, Errors};
use crate::pcg::{pcg, PcgOptions, PcgReport};
use crate::setup::{boundary_nodes, check_solvable, conductivity, dirichlet_values};
use crate::SolveError;

/// What to solve; [`Options::default`] is `k = 1`, `s = 0`, no Dirichlet group.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Conductivity everywhere, unless overridden per region.
    pub k: f64,
    /// Conductivity per named region.
    pub k_regions: Vec<(String, f64)>,
    /// Constant source.
    pub source: f64,
    /// Dirichlet values on named node groups, applied in order.
    pub dirichlet: Vec<(String, f64)>,
    /// Solver options.
    pub pcg: PcgOptions,
    /// Assemble from `sprs` triplets instead of row by row (the two agree up to rounding).
    pub triplets: bool,
    /// Manufactured solution instead of `source` and `dirichlet` ([`crate::mms`]):
    /// Dirichlet data from the exact solution on every boundary node.
    pub mms: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            k: 1.0,
            k_regions: Vec::new(),
            source: 0.0,
            dirichlet: Vec::new(),
            pcg: PcgOptions::default(),
            mms: false,
            triplets: false,
        }
    }
}

/// The result of [`solve`].
#[derive(Clone, Debug, Default)]
pub struct Solution {
    /// Nodal solution.
    pub u: Vec<f64>,
    /// Conductivity per tet.
    pub k: Vec<f64>,
    /// Number of unknowns (free nodes).
    pub unknowns: usize,
    /// Matrix non-zeros.
    pub nonzeros: usize,
    /// The PCG report.
    pub report: PcgReport,
    /// Seconds per stage: `setup`, `assemble`, `solve`.
    pub times: Vec<(&'static str, f64)>,
    /// L2 and H1 errors in manufactured-solution mode.
    pub mms: Option<Errors>,
}

/// Sets up, assembles and solves the problem `opts` on `file`; `progress(iteration,
/// residual)` is called by the solver after every iteration.
///
/// # Errors
/// [`SolveError`]: an unknown or empty group, an invalid coefficient, a singular system.
pub fn solve(
    file: &MeshFile,
    opts: &Options,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Solution, SolveError> {
    let mesh = &file.mesh;
    let mut sol = Solution::default();
    let t = Instant::now();
    sol.k = conductivity(file, opts.k, &opts.k_regions)?;
    let g = if opts.mms {
        if !opts.k_regions.is_empty() {
            return Err(SolveError::Invalid("--mms needs one constant k".into()));
        }
        let mut g = vec![f64::NAN; mesh.points.len()];
        for v in boundary_nodes(mesh) {
            g[v as usize] = mms::exact(mesh.points[v as usize]);
        }
        g
    } else {
        dirichlet_values(file, &opts.dirichlet)?
    };
    check_solvable(mesh, &g)?;
    sol.times.push(("setup", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let k = opts.k;
    let f = move |p: [f64; 3]| mms::LAPLACE_FACTOR * k * mms::exact(p);
    let source = if opts.mms {
        Source::Function(&f)
    } else {
        Source::Constant(opts.source)
    };
    let pb = Problem {
        mesh,
        k: &sol.k,
        source,
        dirichlet: &g,
    };
    let system = if opts.triplets {
        assemble_triplets(&pb)?
    } else {
        assemble(&pb)?
    };
    sol.times.push(("assemble", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let mut x = vec![0.0; system.b.len()];
    sol.report = pcg(&system.a, &system.b, &mut x, &opts.pcg, progress);
    sol.times.push(("solve", t.elapsed().as_secs_f64()));
    sol.unknowns = x.len();
    sol.nonzeros = system.a.nnz();
    sol.u = system
        .dof
        .iter()
        .zip(&g)
        .map(|(&d, &gv)| if d == FIXED { gv } else { x[d as usize] })
        .collect();
    if opts.mms {
        sol.mms = Some(mms::errors(mesh, &sol.u, &mms::exact, &mms::exact_grad));
    }
    Ok(sol)
}
