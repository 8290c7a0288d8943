//! Marking the work of a round: the vertices of tets below the target and the level vertices
//! off their level, and the rings around them.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::ctx::Ctx;
use super::{project, thin};
use crate::mesh::TetMesh;

/// Per point: is it a corner of a tet below the target (by `quality`), or a level vertex off
/// its level (with `ring`, or a corner of a tet around one, so that its neighbours can move)?
/// Also returns, per point, whether it is a level vertex off its level.
///
/// Tets across a thin layer ([`thin`]) are not work, nor are the level vertices off their
/// level at their corners: nothing the pass does brings them to the target.
pub(super) fn needs_work(
    mesh: &TetMesh,
    ctx: &Ctx,
    quality: &[f64],
    ring: bool,
) -> (Vec<bool>, Vec<bool>) {
    let off = project::off_level_points(mesh, ctx);
    let (labels, thin) = thin::marks(mesh, ctx);
    let mut work: Vec<bool> = off.iter().zip(&thin).map(|(&o, &t)| o && !t).collect();
    let seed = work.clone();
    mark_corners(mesh, &mut work, |t| {
        let below = quality[t] < ctx.target
            && !(thin_corner(&thin, mesh.tets[t])
                && thin::across_thin_layer(mesh, ctx, &labels, t));
        below || (ring && mesh.tets[t].iter().any(|&v| seed[v as usize]))
    });
    (work, off)
}

/// Whether a corner of `tet` is a corner of a tet across a thin layer (`thin`, per point).
fn thin_corner(thin: &[bool], tet: [u32; 4]) -> bool {
    tet.iter().any(|&v| thin[v as usize])
}

/// Sets `work` at the corners of every tet `t` for which `marks(t)` holds (in parallel:
/// setting a flag twice, in any order, sets it).
pub(super) fn mark_corners(
    mesh: &TetMesh,
    work: &mut [bool],
    marks: impl Fn(usize) -> bool + Sync,
) {
    let flags: Vec<AtomicBool> = work.par_iter().map(|&w| AtomicBool::new(w)).collect();
    (0..mesh.tets.len()).into_par_iter().for_each(|t| {
        if marks(t) {
            for v in mesh.tets[t] {
                flags[v as usize].store(true, Ordering::Relaxed);
            }
        }
    });
    work.par_iter_mut()
        .zip(flags)
        .for_each(|(w, f)| *w = f.into_inner());
}

/// Marks every corner of a tet that has a marked corner.
pub(super) fn grow(mesh: &TetMesh, work: &mut [bool]) {
    let seed = work.to_vec();
    mark_corners(mesh, work, |t| {
        mesh.tets[t].iter().any(|&v| seed[v as usize])
    });
}
