//! `solver-demo`: a P1 (linear tetrahedron) finite-element solver for the steady heat /
//! Poisson equation `-div(k grad u) = s` on meshes written by `tptd-mesh`.
//!
//! Pipeline: read the mesh with its groups ([`tptd::io::read_mesh`]) → set up the problem
//! ([`setup`]: conductivity per tet, Dirichlet values on named node groups) → assemble the
//! system on the free nodes ([`assemble`], `sprs` triplets → CSR, parallel, deterministic) →
//! solve with preconditioned conjugate gradients ([`pcg`]) → write `u` and the element
//! gradient and flux as `.vtu` ([`output`]). [`mms`] is the manufactured-solution check and
//! [`run`] strings the stages together with timings.

#![warn(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod assemble;
pub mod mms;
pub mod output;
pub mod pcg;
pub mod run;
pub mod setup;

/// Why a problem could not be set up or solved. `Display` is one line.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// A `--dirichlet` or `--k` name that is not a group (region) of the mesh.
    #[error("the mesh has no {kind} named {name:?} (it has: {available})")]
    UnknownGroup {
        /// `node group` or `region`.
        kind: &'static str,
        /// The requested name.
        name: String,
        /// The names present, comma-separated.
        available: String,
    },
    /// A Dirichlet group without nodes.
    #[error("the Dirichlet group {0:?} has no nodes")]
    EmptyGroup(String),
    /// No Dirichlet node in some connected part of the mesh: the matrix is singular.
    #[error("singular system: {0}")]
    Singular(String),
    /// A degenerate tetrahedron or a non-finite or non-positive coefficient.
    #[error("invalid problem: {0}")]
    Invalid(String),
}
