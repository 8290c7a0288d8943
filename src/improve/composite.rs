//! Collapse, then move: a composite operation for tets that no single operation frees.
//!
//! Every other operation of the pass must raise the worst tet it touches by itself. Some
//! tets left below the target need two steps: a short edge whose collapse alone leaves a
//! poor tet, which a move of the surviving vertex or its neighbours then lifts (on the 40³
//! thin shell of the benchmark the worst tet is such a cap: no move of a corner frees it,
//! and the collapse of its shortest edge alone leaves 10.5°; docs/QUALITY-LOG.md). Stellar
//! judges such sequences as one; so does this: on a copy of the region, the collapse of an
//! edge at a corner of the bad tet (either way; legal and positive, whatever its quality;
//! the polishing round frees the corners' neighbours for it, `improve::grow`), then the
//! smoothing and the compass search of the survivor and of the corners of the tets below
//! the target around it, kept only if the region's worst tet ends higher, or as high with
//! fewer tets below the target. It copies the region per try, so it runs only where the
//! pass is otherwise stuck ([`super::schedule`], the polish of small stuck regions).

use super::collapse::{apply_collapse, legal_collapse};
use super::region::LocalMesh;
use super::search::search_vertex;
use super::smooth::smooth_vertex;
use super::Ctx;
use crate::geom::{dot, sub};

/// Rounds of moves after the collapse.
const ROUNDS: usize = 3;

/// Tries the composite on the edges at the corners of tet `t` (its own edges first, then the
/// others, each group shortest first, at most [`EDGES`]); returns whether one was kept.
pub fn collapse_then_move(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    t: u32,
    settle: impl Fn(&mut LocalMesh),
) -> bool {
    let before = worst(lm, ctx.target);
    for (a, b) in candidate_edges(lm, t) {
        for (from, to) in [(a, b), (b, a)] {
            if !legal_collapse(lm, ctx, (from, to), true) {
                continue;
            }
            let mut trial = lm.clone();
            apply_collapse(&mut trial, from, to);
            move_around(&mut trial, ctx, to);
            settle(&mut trial);
            let after = worst(&trial, ctx.target);
            if better(after, before) {
                *lm = trial;
                return true;
            }
        }
    }
    false
}

/// Edges tried per tet at most.
const EDGES: usize = 16;

/// The edges at the corners of `t`: its own six first, then the others, each group by
/// length (ties by ids), at most [`EDGES`].
fn candidate_edges(lm: &LocalMesh, t: u32) -> Vec<(u32, u32)> {
    let tet = lm.tets[t as usize];
    let mut pairs: Vec<(u32, u32)> = tet
        .iter()
        .flat_map(|&a| lm.star[a as usize].iter().map(move |&s| (a, s)))
        .flat_map(|(a, s)| lm.tets[s as usize].map(|b| (a.min(b), a.max(b))))
        .filter(|&(lo, hi)| lo != hi)
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    let len = |(a, b): (u32, u32)| {
        let d = sub(lm.x[a as usize], lm.x[b as usize]);
        dot(d, d)
    };
    // Not the tet's own edge first, then by length, then by ids.
    let mut edges: Vec<(bool, f64, (u32, u32))> = pairs
        .into_iter()
        .map(|e| (!(tet.contains(&e.0) && tet.contains(&e.1)), len(e), e))
        .collect();
    edges.sort_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)).then(x.2.cmp(&y.2)));
    edges.into_iter().take(EDGES).map(|e| e.2).collect()
}

/// Whether `after` (worst quality, tets below the target) beats `before`.
fn better(after: (f64, usize), before: (f64, usize)) -> bool {
    after.0 > before.0 * (1.0 + 1e-9) + 1e-12 || (after.0 >= before.0 && after.1 < before.1)
}

/// Smooths, then compass-searches, `v` and the corners of the tets below the target around
/// it, for [`ROUNDS`] rounds or until none moves.
fn move_around(lm: &mut LocalMesh, ctx: &Ctx, v: u32) {
    for _ in 0..ROUNDS {
        let mut verts: Vec<u32> = lm.star[v as usize]
            .iter()
            .filter(|&&t| lm.q[t as usize] < ctx.target)
            .flat_map(|&t| lm.tets[t as usize])
            .collect();
        verts.push(v);
        verts.sort_unstable();
        verts.dedup();
        let mut moved = 0;
        for w in verts {
            moved += usize::from(smooth_vertex(lm, ctx, w));
            moved += usize::from(search_vertex(lm, ctx, w));
        }
        if moved == 0 {
            break;
        }
    }
}

/// The worst quality of the region's alive tets, and how many are below `target`.
pub(super) fn worst(lm: &LocalMesh, target: f64) -> (f64, usize) {
    (0..lm.tets.len())
        .filter(|&t| lm.alive[t])
        .fold((f64::INFINITY, 0), |(w, n), t| {
            (w.min(lm.q[t]), n + usize::from(lm.q[t] < target))
        })
}
