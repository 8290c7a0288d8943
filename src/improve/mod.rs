//! The quality pass: improves the elements of a mesh while keeping its topology, its boundary
//! labels and its boundary on the level sets of the trilinear field.
//!
//! Pipeline position: `extract` → **improve** → write. Work is proportional to what needs
//! work: each round marks the vertices of tets below the target quality and the level
//! vertices off the trilinear level set, copies their stars out (`region`), improves them
//! there (projection, edge collapse, flips, edge removal, smoothing; one operation per file)
//! and splices the result back. A last stage after the rounds splits the boundary edges whose
//! chord sags from a curved level set (`split`) and gives back the volume the operations moved
//! (`restore`); with targets above the default, every target stage ends with it (`stages`).
//! Everything runs in a fixed order, so the output does not depend on the number of threads.
//!
//! The drivers: `pass` runs a pass over the target stages (and again for the volume),
//! `rounds` its rounds, `finish` the last stage of each; `ctx` holds what every operation
//! needs ([`Ctx`]), `mark` finds a round's work and `quality_cache` keeps each tet's quality.

pub(crate) mod collapse;
mod composite;
pub(crate) mod constraint;
mod ctx;
pub(crate) mod edge_removal;
pub(crate) mod embed;
mod face_grid;
mod finish;
#[cfg(test)]
pub(crate) mod fixtures;
pub(crate) mod flip;
pub mod forced;
pub(crate) mod interfaces;
mod mark;
mod options;
pub mod outcome;
mod pass;
pub(crate) mod project;
mod quality_cache;
pub(crate) mod region;
mod report;
pub(crate) mod restore;
mod rounds;
mod schedule;
pub(crate) mod search;
pub(crate) mod smooth;
pub(crate) mod split;
pub mod stages;
pub(crate) mod submesh;
mod thin;
mod verify;
mod volumes;
pub(crate) mod warped;

pub use ctx::{Ctx, RoundFlags};
pub use options::{QualityOptions, DEFAULT_SPLIT_SAG};
pub use report::{ImproveReport, StageSeconds};

use crate::extract::MeshOutput;
use crate::grid::ScalarGrid;
use crate::levels::Levels;
use crate::mesh::TetMesh;

/// The warping threshold ([`crate::MeshOptions::warp`]) to mesh with before improving: grid
/// vertices that a level passes within this fraction of an edge from are put on the level
/// while clipping (when that keeps the topology), so most slivers never appear.
pub const DEFAULT_WARP: f64 = 0.3;

/// Improves `mesh`, a mesh of `{alpha <= f <= beta}` of `grid`'s trilinear field as made by
/// [`crate::mesh_interval`], in place.
///
/// Every operation keeps each tet positive, the topology (vertex moves are homeomorphisms,
/// flips keep the underlying space, collapses obey the link condition), the labels, the box
/// faces (box vertices stay on their planes) and the level sets (level vertices stay on the
/// trilinear level set once projected).
///
/// Targets above the default ([`QualityOptions::default`]: 15° and 155°) are climbed to in
/// stages ([`stages`]); each ends with the splits and the volume restoration at its targets
/// ([`finish::finish_stage`]). A small mesh left off its plain volume by more than 0.4 % is
/// improved again from the start with shorter boundary collapses
/// ([`ImproveReport::volume_retries`]).
pub fn improve(
    mesh: &mut TetMesh,
    grid: &ScalarGrid,
    alpha: f64,
    beta: f64,
    opts: &QualityOptions,
) -> ImproveReport {
    let levels = Levels::interval(alpha, beta);
    outcome::improve_keeping_better(mesh, grid, &levels, opts, &[], None)
}

/// [`improve`] on the output of [`crate::mesh_interval`]: the volume that its warping moved
/// ([`crate::MeshOptions::warp`]) is given back too, where the quality allows ([`warped`]).
pub fn improve_meshed(
    out: &mut MeshOutput,
    grid: &ScalarGrid,
    alpha: f64,
    beta: f64,
    opts: &QualityOptions,
) -> ImproveReport {
    let levels = Levels::interval(alpha, beta);
    outcome::improve_meshed_mapped(out, grid, &levels, opts, None)
}

/// [`improve`] for a mesh of several regions made by [`crate::mesh_interval`] with levels
/// (`levels` the run's, `mesh.regions` set; one interval works too): every interface stays on
/// its level set and every tet in its region, and each region keeps its topology.
pub fn improve_levels(
    mesh: &mut TetMesh,
    grid: &ScalarGrid,
    levels: &Levels,
    opts: &QualityOptions,
) -> ImproveReport {
    outcome::improve_keeping_better(mesh, grid, levels, opts, &[], None)
}
