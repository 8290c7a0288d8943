//! Shared helpers of the independent test harness (reference topology, MC33 configurations,
//! mesh invariants, a tiny deterministic RNG), of the external round trips of written meshes
//! and small file helpers.
#![allow(dead_code)]

pub mod external;
pub mod files;
pub mod invariants;
pub mod mc33;
pub mod mc33_table;
pub mod output;
pub mod reference;
pub mod soup;

/// splitmix64: tiny, seedable, good enough for test data.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }
    /// Uniform integer in [lo, hi] (inclusive).
    pub fn int(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % ((hi - lo + 1) as u64)) as i64
    }
    pub fn usize(&mut self, lo: usize, hi: usize) -> usize {
        self.int(lo as i64, hi as i64) as usize
    }
}

use reference::Field;
use tptd::{mesh_interval, MeshOptions, Method, ScalarGrid, TetMesh};

pub const ALL_METHODS: [Method; 5] = [
    Method::Five,
    Method::Six,
    Method::Tptd,
    Method::Std,
    Method::Ctd,
];

/// Mesh a reference field with the crate under test.
pub fn run_mesh(
    field: &Field,
    alpha: f64,
    beta: f64,
    method: Method,
    threads: Option<usize>,
) -> Result<TetMesh, String> {
    let grid = ScalarGrid::new(field.dims, field.values.clone())
        .map_err(|e| format!("ScalarGrid::new failed: {e:?}"))?;
    let mut opts = MeshOptions::new(alpha, beta, method);
    opts.threads = threads;
    mesh_interval(&grid, &opts)
        .map(|o| o.mesh)
        .map_err(|e| format!("mesh_interval failed: {e}"))
}

/// Grid box extent (unit spacing, origin 0).
pub fn extent(field: &Field) -> [f64; 3] {
    let c = field.cell_dims();
    [c[0] as f64, c[1] as f64, c[2] as f64]
}

/// Number of random cases: `TPTD_STRESS` (default `default`).
pub fn stress(default: usize) -> usize {
    std::env::var("TPTD_STRESS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// Every problem found with a mesh of `field` for the interval: invariants, labels, and (when
/// given) Betti numbers against the reference.
pub fn verify(
    field: &Field,
    alpha: f64,
    beta: f64,
    mesh: &TetMesh,
    expected: Option<[usize; 3]>,
) -> Vec<String> {
    let mut errs = invariants::mesh_errors(mesh);
    errs.extend(invariants::label_errors(mesh, alpha, beta, extent(field)));
    if let Some(b) = expected {
        let got = invariants::mesh_betti(mesh);
        if got != b {
            errs.push(format!("Betti numbers: mesh {got:?}, reference {b:?}"));
        }
    }
    errs
}
