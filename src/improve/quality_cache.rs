//! The quality of each tet of the mesh, kept from round to round: evaluated once, and again
//! only for the tets whose corners moved.

use rayon::prelude::*;

use super::ctx::Ctx;
use crate::mesh::TetMesh;

/// The quality ([`Ctx::quality`]) of each tet.
pub(super) fn tet_qualities(mesh: &TetMesh, ctx: &Ctx) -> Vec<f64> {
    mesh.tets
        .par_iter()
        .map(|t| ctx.quality(t.map(|v| mesh.points[v as usize])))
        .collect()
}

/// Evaluates `quality` for every tet unless it is already there.
pub(super) fn ensure_quality(mesh: &TetMesh, ctx: &Ctx, quality: &mut Vec<f64>) {
    if quality.len() != mesh.tets.len() {
        *quality = tet_qualities(mesh, ctx);
    }
}

/// Re-evaluates `quality` for the tets with a corner in `moved`.
pub(super) fn refresh_quality(mesh: &TetMesh, ctx: &Ctx, moved: &[bool], quality: &mut [f64]) {
    mesh.tets.par_iter().zip(quality).for_each(|(t, q)| {
        if t.iter().any(|&v| moved[v as usize]) {
            *q = ctx.quality(t.map(|v| mesh.points[v as usize]));
        }
    });
}
