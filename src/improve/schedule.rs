//! The order in which the operations run on a region (after Stellar: cheap, safe moves first,
//! topology changes where moves are not enough, then smoothing again).

use super::collapse::{apply_collapse, apply_evaluated, best_collapse, evaluate_merge, star_floor};
use super::composite::{collapse_then_move, worst};
use super::edge_removal::try_remove_edge;
use super::flip::{try_flip23, try_flip32};
use super::project::{absorb_and_project, merge_and_untangle, project_levels, untangle_around};
use super::region::{LocalMesh, TetOp};
use super::search::search_vertex;
use super::smooth::smooth_vertex;
use super::{Ctx, ImproveReport, RoundFlags};

/// Passes over the region at most.
const SWEEPS: usize = 6;

/// Sweeps after level vertices were untangled onto their level sets at the end.
const SWEEPS_AFTER_UNTANGLING: usize = 2;

/// Improves the region `lm` in place. With [`Ctx::retry_stuck`], a stuck region ([`stuck`])
/// is improved again from its start with each smoothing variant of [`RETRIES`] in turn while
/// it stays stuck, and the best end is kept (higher worst tet, then fewer below the target):
/// which tets stay stuck depends on small differences in the moves, and any variant can win.
/// With [`Ctx::polish`], a region still left with tets below the target then gets the compass
/// search over their corners ([`polish`]; its cost is proportional to those tets).
pub fn improve_local(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) {
    let mut done = ImproveReport::default();
    if ctx.round.retry_stuck {
        retry(lm, ctx, &mut done);
    } else {
        improve_once(lm, ctx, &mut done);
    }
    if ctx.round.polish && worst(lm, ctx.target).0 < ctx.target {
        polish(lm, ctx, &mut done);
    }
    report.add(&done);
}

/// [`improve_once`], then again from the start with each variant of [`RETRIES`] while the
/// region is [`stuck`]; keeps the best end and its counts in `report`.
fn retry(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) {
    let start = lm.clone();
    improve_once(lm, ctx, report);
    for (steepest, centroid) in RETRIES {
        if !stuck(lm, ctx) {
            break;
        }
        let now = worst(lm, ctx.target);
        let mut other = start.clone();
        let mut r = ImproveReport::default();
        let variant = Ctx {
            round: RoundFlags {
                steepest,
                centroid,
                ..ctx.round
            },
            cancel: ctx.cancel.clone(),
            ..*ctx
        };
        improve_once(&mut other, &variant, &mut r);
        let then = worst(&other, ctx.target);
        if then.0 > now.0 || (then.0 == now.0 && then.1 < now.1) {
            *lm = other;
            *report = r;
        }
    }
}

/// Whether the region has tets below the target, but at most [`RETRY_MAX_BELOW`] of them.
fn stuck(lm: &LocalMesh, ctx: &Ctx) -> bool {
    let (w, n) = worst(lm, ctx.target);
    w < ctx.target && n <= RETRY_MAX_BELOW
}

/// Rounds of [`polish`] at most.
const POLISH_ROUNDS: usize = 2;

/// Compass search ([`search_vertex`]) on the corners of the tets still below the target, each
/// round followed by short sweeps, while it moves a vertex.
fn polish(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) {
    for _ in 0..POLISH_ROUNDS {
        let moved = bad_corners(lm, ctx)
            .into_iter()
            .filter(|&v| search_vertex(lm, ctx, v))
            .count();
        report.smoothed += moved;
        if moved == 0 {
            break;
        }
        sweeps(lm, ctx, report, SWEEPS_AFTER_UNTANGLING);
    }
    if stuck(lm, ctx) {
        composites(lm, ctx, report);
    }
}

/// [`collapse_then_move`] on the tets below the target, worst first, while one is kept (at
/// most [`COMPOSITE_TRIES`] tets), each kept one followed by short sweeps.
fn composites(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) {
    let settle = |trial: &mut LocalMesh| {
        let mut ignored = ImproveReport::default();
        sweeps(trial, ctx, &mut ignored, SWEEPS_AFTER_UNTANGLING)
    };
    let mut tried = 0;
    'next: while tried < COMPOSITE_TRIES {
        let bad: Vec<u32> = bad_tets(lm, ctx).collect();
        for t in bad {
            if tried == COMPOSITE_TRIES || ctx.out_of_time() {
                return;
            }
            if !lm.alive[t as usize] {
                continue;
            }
            tried += 1;
            if collapse_then_move(lm, ctx, t, settle) {
                report.collapses += 1;
                sweeps(lm, ctx, report, SWEEPS_AFTER_UNTANGLING);
                continue 'next;
            }
        }
        return;
    }
}

/// Bad tets a stuck region tries [`collapse_then_move`] on at most (each try copies the
/// region).
const COMPOSITE_TRIES: usize = 8;

/// A region left with more tets below the target than this is not retried: its tets are
/// stuck for reasons of their own (mostly near critical values, as on the noisy 256³ field
/// and the T1 band, where nearly every slab's region is left with many; retrying them all
/// made the full-size passes 6–9 % longer in unpaired runs).
const RETRY_MAX_BELOW: usize = 16;

/// The smoothing variants ([`Ctx::steepest`], [`Ctx::centroid`]) a stuck region is retried
/// with, in order.
const RETRIES: [(bool, bool); 2] = [(true, false), (true, true)];

/// [`improve_local`] once.
fn improve_once(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) {
    report.projected += project_levels(lm, ctx);
    sweeps(lm, ctx, report, SWEEPS);
    report.projected += project_levels(lm, ctx);
    let (merged, untangled) = settle_off_level(lm, ctx);
    report.merged_off_level += merged;
    report.projected += untangled;
    if untangled > 0 {
        // Untangling leaves poor tets around the vertex; the next round may not come.
        sweeps(lm, ctx, report, SWEEPS_AFTER_UNTANGLING);
    }
}

/// Up to `n` sweeps of collapses, flips and edge removals, smoothing and projection over the
/// region's bad tets, until one changes nothing.
fn sweeps(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport, n: usize) {
    for _ in 0..n {
        if ctx.out_of_time() {
            report.out_of_time = true;
            break;
        }
        // Collapse first: most bad tets have a short edge, and removing it does more than
        // any move (measured on analytic tori: 15.0° after collapse–flip–smooth sweeps,
        // 9.9° after smooth–flip–collapse).
        let mut changed = collapse_pass(lm, ctx, report);
        changed += flip_pass(lm, ctx, report);
        changed += smooth_pass(lm, ctx, report);
        let moved = project_levels(lm, ctx);
        report.projected += moved;
        changed += moved;
        if changed == 0 {
            break;
        }
    }
}

/// Level vertices that could not be moved onto their level (a tet around them would invert)
/// are merged into a neighbour on the same surfaces, when the link condition allows and every
/// remaining tet stays positive; failing that, put on their level with their neighbours moved
/// out of the way ([`untangle_around`]), after absorbing a neighbour
/// ([`absorb_and_project`]), or merged into a neighbour on its level with the tets this
/// inverts untangled ([`merge_and_untangle`]). So every boundary node ends on its level set
/// where the region allows. Returns how many were merged and how many untangled.
fn settle_off_level(lm: &mut LocalMesh, ctx: &Ctx) -> (usize, usize) {
    let (mut merged, mut untangled) = (0, 0);
    for v in 0..lm.u.len() as u32 {
        if !off_level(lm, ctx, v) {
            continue;
        }
        let mut nbrs: Vec<u32> = lm.star[v as usize]
            .iter()
            .flat_map(|&t| lm.tets[t as usize])
            .filter(|&w| w != v && !off_level(lm, ctx, w))
            .collect();
        nbrs.sort_unstable();
        nbrs.dedup();
        let best = nbrs
            .into_iter()
            .filter_map(|b| evaluate_merge(lm, ctx, v, b).map(|q| (q, b)))
            .max_by(|x, y| x.0.total_cmp(&y.0).then(y.1.cmp(&x.1)));
        if let Some((_, b)) = best {
            apply_collapse(lm, v, b);
            merged += 1;
        } else if untangle_around(lm, ctx, v) || absorb_and_project(lm, ctx, v) {
            untangled += 1;
        } else if merge_and_untangle(lm, ctx, v) {
            merged += 1;
        }
    }
    (merged, untangled)
}

/// Whether `v` is a free level vertex away from its level.
fn off_level(lm: &LocalMesh, ctx: &Ctx, v: u32) -> bool {
    lm.is_free(v) && !lm.con[v as usize].pinned && lm.off_its_level(v, ctx)
}

/// Alive tets below the target, worst first (ties by id).
fn bad_tets(lm: &mut LocalMesh, ctx: &Ctx) -> impl Iterator<Item = u32> {
    let mut bad: Vec<(i64, u32)> = lm
        .tets_below(ctx.target)
        .into_iter()
        .map(|t| (total_order(lm.q[t as usize]), t))
        .collect();
    // The keys are distinct (tet ids are), so an unstable sort gives the one order.
    bad.sort_unstable();
    bad.into_iter().map(|(_, t)| t)
}

/// `x` as an integer in the order of [`f64::total_cmp`] (its definition), so that sorting
/// by it is sorting integers.
fn total_order(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    b ^ (((b >> 63) as u64) >> 1) as i64
}

/// Calls `op` (of kind `kind`) on every alive bad tet (worst first) until the time budget
/// runs out; returns how many calls changed something. Skips the tets on which `kind` failed
/// since the last change around them ([`LocalMesh::settled_tet`]).
fn for_each_bad_tet(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    kind: TetOp,
    mut op: impl FnMut(&mut LocalMesh, u32) -> bool,
) -> usize {
    let mut n = 0;
    for (i, t) in bad_tets(lm, ctx).enumerate() {
        if i % 64 == 63 && ctx.out_of_time() {
            break;
        }
        if !lm.alive[t as usize] || lm.settled_tet(t, kind) {
            continue;
        }
        if op(lm, t) {
            n += 1;
        } else {
            lm.tet_failed(t, kind);
        }
    }
    n
}

/// Collapses the shortest edges of bad tets where that helps.
fn collapse_pass(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) -> usize {
    let n = for_each_bad_tet(lm, ctx, TetOp::Collapse, |lm, t| {
        collapse_shortest(lm, ctx, t)
    });
    report.collapses += n;
    n
}

/// Collapses the shortest edge of tet `t` (either way) that can be collapsed with a gain.
fn collapse_shortest(lm: &mut LocalMesh, ctx: &Ctx, t: u32) -> bool {
    let tet = lm.tets[t as usize];
    let mut edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)].map(|(i, j)| {
        let d = crate::geom::sub(lm.x[tet[i] as usize], lm.x[tet[j] as usize]);
        (crate::geom::dot(d, d), tet[i], tet[j])
    });
    edges.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
    // Each corner's floor is found when a collapse from it first passes the cheap tests.
    let floors = [const { std::cell::Cell::new(None) }; 4];
    let floor = |v: u32| {
        let i = tet.iter().position(|&w| w == v).unwrap_or(0);
        floors[i].get().unwrap_or_else(|| {
            let f = star_floor(lm, v);
            floors[i].set(Some(f));
            f
        })
    };
    for (_, a, b) in edges {
        if let Some(c) = best_collapse(lm, ctx, a, b, floor) {
            apply_evaluated(lm, c);
            return true;
        }
    }
    false
}

/// 2-3 flips of the faces, 3-2 flips and removals of the edges of bad tets.
fn flip_pass(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) -> usize {
    let mut removals = 0;
    let n = for_each_bad_tet(lm, ctx, TetOp::Flip, |lm, t| match flip_tet(lm, ctx, t) {
        Some(Flipped::EdgeRemoved) => {
            removals += 1;
            true
        }
        Some(Flipped::Flip) => true,
        None => false,
    });
    report.flips += n - removals;
    report.edge_removals += removals;
    n
}

/// What [`flip_tet`] did.
enum Flipped {
    /// A 2-3 or 3-2 flip.
    Flip,
    /// An edge removal.
    EdgeRemoved,
}

/// The first improving 2-3 flip of a face of `t`, else 3-2 flip of an edge of `t`, else
/// removal of an edge of `t` with 4 to 7 tets around it.
fn flip_tet(lm: &mut LocalMesh, ctx: &Ctx, t: u32) -> Option<Flipped> {
    let tet = lm.tets[t as usize];
    // The tets around each edge, found once for all kinds (nothing changes while the
    // attempts fail; an edge with both ends frozen is refused by both edge operations).
    let around = lm.tet_edge_tets(tet);
    if (0..4).any(|i| try_flip23(lm, ctx, (t, i), &around)) {
        return Some(Flipped::Flip);
    }
    let edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)].map(|(i, j)| (tet[i], tet[j]));
    let mut tries = edges.iter().zip(&around);
    if tries.any(|(&(p, q), e)| try_flip32(lm, ctx, (t, p, q), e)) {
        return Some(Flipped::Flip);
    }
    let mut tries = edges.iter().zip(&around);
    tries
        .any(|(&(p, q), e)| try_remove_edge(lm, ctx, (t, p, q), e))
        .then_some(Flipped::EdgeRemoved)
}

/// The corners of the alive tets below the target, ascending.
fn bad_corners(lm: &mut LocalMesh, ctx: &Ctx) -> Vec<u32> {
    // In tet order (sorted after): the order of `bad_tets` is not needed here.
    let mut verts: Vec<u32> = lm
        .tets_below(ctx.target)
        .into_iter()
        .flat_map(|t| lm.tets[t as usize])
        .collect();
    verts.sort_unstable();
    verts.dedup();
    verts
}

/// Smooths every free vertex of a bad tet once, in vertex order.
fn smooth_pass(lm: &mut LocalMesh, ctx: &Ctx, report: &mut ImproveReport) -> usize {
    let mut n = 0;
    for (i, v) in bad_corners(lm, ctx).into_iter().enumerate() {
        if i % 64 == 63 && ctx.out_of_time() {
            break;
        }
        if lm.settled_vertex(v) {
            continue;
        }
        if smooth_vertex(lm, ctx, v) {
            n += 1;
        } else {
            lm.vertex_failed(v);
        }
    }
    report.smoothed += n;
    n
}

#[cfg(test)]
mod tests {
    use super::total_order;

    #[test]
    fn total_order_sorts_as_total_cmp() {
        let mut xs = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            -f64::NAN,
            0.258,
            0.2580000000000001,
            -3.5e300,
        ];
        let mut seed = 7u64;
        for _ in 0..500 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            xs.push(f64::from_bits(seed));
        }
        let mut by_cmp = xs.clone();
        by_cmp.sort_by(f64::total_cmp);
        xs.sort_by_key(|&x| total_order(x));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&xs), bits(&by_cmp));
    }
}
