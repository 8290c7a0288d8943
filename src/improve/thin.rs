//! Thin layers: where the alpha and beta level sets come closer than the tets between them
//! can span at the target, the pass leaves the mesh as it is.
//!
//! A tet with a corner on alpha and one on beta spans the layer; its longest edge `L` is
//! about the boundary's node spacing, which the pass does not make finer inside a layer. Where
//! the layer is thinner than `L · sin(target)` and than the distance the embedding guards let a
//! boundary face drift ([`super::embed`]), what such a tet would need (collapses, moves and
//! projections across the layer) is what the guards refuse, after the work is done: on a band
//! a fraction of a grey level wide in MRI data nearly every tet is one, and working on them
//! cost minutes that were all thrown away. So these tets are not marked as work, and neither
//! are the level vertices off their level at their corners (their projection would cross the
//! other sheet). What is left below the floor there is listed as `thin_layer` by
//! [`super::forced`].

use rayon::prelude::*;

use super::Ctx;
use crate::field::GUARD_DISTANCE;
use crate::geom::{distance, dot, norm};
use crate::mesh::{LabelBits, TetMesh};

/// The bit of [`rim_marks`] that says a point is a corner of a tet across a thin layer (the
/// bits below it are [`TetMesh::vertex_label_bits`]).
const THIN: LabelBits = 1 << 31;

/// Per point: its boundary label bits and whether it is a corner of a tet across a thin layer
/// ([`THIN`]). A copy of part of the mesh ([`super::submesh`]) keeps them for its rim, whose
/// faces and tets outside the copy it lacks: its marks are then the whole mesh's, and the
/// copy marks the same work as the whole mesh would.
pub(crate) fn rim_marks(mesh: &TetMesh, ctx: &Ctx) -> Vec<LabelBits> {
    let (labels, thin) = marks(mesh, ctx);
    labels
        .iter()
        .zip(&thin)
        .map(|(&l, &t)| if t { l | THIN } else { l })
        .collect()
}

/// Per point: its boundary label bits ([`TetMesh::vertex_label_bits`]) and whether it is a
/// corner of a tet across a thin layer; on a copy, with the marks it was cut with
/// ([`Ctx::rim_marks`]) added.
pub(crate) fn marks(mesh: &TetMesh, ctx: &Ctx) -> (Vec<LabelBits>, Vec<bool>) {
    let mut labels = mesh.vertex_label_bits();
    if let Some(rim) = ctx.round.rim_marks {
        for (l, &r) in labels.iter_mut().zip(rim) {
            *l |= r & !THIN;
        }
    }
    let mut thin = thin_layer_points(mesh, ctx, &labels);
    if let Some(rim) = ctx.round.rim_marks {
        for (t, &r) in thin.iter_mut().zip(rim) {
            *t |= r & THIN != 0;
        }
    }
    (labels, thin)
}

/// Per point: a corner of a tet across a thin layer ([`across_thin_layer`]). All false for a
/// one-sided interval.
fn thin_layer_points(mesh: &TetMesh, ctx: &Ctx, labels: &[LabelBits]) -> Vec<bool> {
    let mut thin = vec![false; mesh.points.len()];
    if layers(ctx) == 0 {
        return thin;
    }
    let tets: Vec<usize> = (0..mesh.tets.len())
        .into_par_iter()
        .filter(|&t| across_thin_layer(mesh, ctx, labels, t))
        .collect();
    for t in tets {
        for v in mesh.tets[t] {
            thin[v as usize] = true;
        }
    }
    thin
}

/// The bits of the levels `l` whose region `[l, l + 1]` is bounded on both sides (both
/// levels finite): where a layer can be thin.
fn layers(ctx: &Ctx) -> LabelBits {
    (0..ctx.levels.len() - 1)
        .filter(|&l| ctx.levels[l].is_finite() && ctx.levels[l + 1].is_finite())
        .fold(0, |bits, l| bits | 1 << l)
}

/// Whether tet `t` has a corner on a level and another on the next (alpha and beta for one
/// interval; `labels`: per point, [`TetMesh::vertex_label_bits`]) closer together across the layer (along the
/// gradient at its centroid: the layer's thickness there, for a flat layer) than its longest
/// edge times the target's sine, and than [`GUARD_DISTANCE`].
///
/// The first is what the angle needs (a tet of the target's angles can be flatter than that,
/// a needle whose cross-section is a good triangle, but the pass does not make such shapes
/// out of a layer's nodes). The second is where the guards bite: within it of one sheet lies
/// the other, so the moves and collapses a spanning tet needs cross it. On the MNI T1 band
/// a fraction of a grey level wide the guards threw away all the work on such tets; a shell
/// 1.2 voxels thick reaches 30° only with its spanning tets worked on.
pub(crate) fn across_thin_layer(mesh: &TetMesh, ctx: &Ctx, labels: &[LabelBits], t: usize) -> bool {
    let tet = mesh.tets[t];
    let on = |i: usize, bit: LabelBits| labels[tet[i] as usize] & bit != 0;
    let all = tet.iter().fold(0, |b, &v| b | labels[v as usize]);
    // The first level of a layer the tet spans (for one interval: alpha).
    let spans = all & (all >> 1) & layers(ctx);
    if spans == 0 {
        return false;
    }
    let l = spans.trailing_zeros();
    let (lo, hi) = (1 << l, 1 << (l + 1));
    let p = tet.map(|v| ctx.field.to_index(mesh.points[v as usize]));
    let longest = (0..4)
        .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
        .map(|(i, j)| distance(p[i], p[j]))
        .fold(0.0, f64::max);
    let centroid = [0, 1, 2].map(|a| p.iter().map(|q| q[a]).sum::<f64>() / 4.0);
    let (_, g) = ctx.field.value_gradient(centroid);
    let n = norm(g);
    let across = |i: usize, j: usize| {
        let d = [0, 1, 2].map(|a| p[j][a] - p[i][a]);
        if n > 0.0 && n.is_finite() {
            (dot(d, g) / n).abs()
        } else {
            norm(d)
        }
    };
    let limit = (longest * ctx.target).min(GUARD_DISTANCE);
    (0..4).any(|i| on(i, lo) && (0..4).any(|j| j != i && on(j, hi) && across(i, j) < limit))
}
