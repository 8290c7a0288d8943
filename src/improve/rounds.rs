//! The rounds of a pass (or of a stage): each marks the vertices that need work and improves
//! their regions, in slabs of even and then odd parity; the rounds after the first run on a
//! copy of the part of the mesh they can reach ([`super::submesh`]).

use std::time::Instant;

use rayon::prelude::*;

use super::ctx::{Ctx, RoundFlags};
use super::mark::{grow, needs_work};
use super::pass::PassState;
use super::quality_cache::refresh_quality;
use super::region::{self, LocalMesh};
use super::report::lap;
use super::submesh::{self, SubMesh, Untouched};
use super::{project, schedule, thin, verify, ImproveReport};
use crate::mesh::TetMesh;

/// How many rounds a pass (or a stage) runs at most, whether the last one retries its stuck
/// regions ([`Ctx::retry_stuck`]), whether a second polishing round follows it with the slab
/// boundaries back in place (`polish_twice`), and within how many rings of their work the
/// rounds after the first copy the mesh ([`submesh`]; `None`: they run on the whole mesh).
#[derive(Clone, Copy)]
pub(super) struct Rounds {
    pub(super) max: usize,
    pub(super) retry_last: bool,
    pub(super) polish_twice: bool,
    pub(super) rings: Option<usize>,
}

/// Up to `rounds.max` rounds at `ctx`'s targets, until one finds nothing to do.
///
/// The last round moves the slab boundaries by half a slab: what is still below the target
/// or off its level then has mostly been stuck at a slab boundary, with corners across it
/// frozen in every round; its stuck regions are retried (with `retry_last`), and the tets it
/// leaves below the target polished ([`Ctx::polish`]). With `polish_twice`, a second
/// polishing round follows with the boundaries back where they were: a bad tet whose corners
/// straddle a shifted boundary has them all free there. A level vertex still off its level
/// after that gets one more round with the boundaries back where they were. The rounds after
/// the first run on a copy of the part of the mesh they can reach ([`submesh`]).
pub(super) fn run_rounds(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    Rounds {
        max: rounds,
        retry_last,
        polish_twice,
        rings,
    }: Rounds,
    state: &mut PassState,
    report: &mut ImproveReport,
) {
    if rounds == 0 {
        return; // none asked for (the first round's projection included)
    }
    // Only the last round retries and polishes its stuck regions (its regions are small).
    let shifted = Ctx {
        round: RoundFlags {
            slab_offset: 0.5 * region::SLAB,
            retry_stuck: retry_last,
            polish: true,
            ..ctx.round
        },
        cancel: ctx.cancel.clone(),
        ..*ctx
    };
    let mut sub = None;
    for round in 0..rounds {
        if ctx.out_of_time() {
            report.out_of_time = true;
            break;
        }
        let at = if round > 0 && round + 1 == rounds {
            &shifted
        } else {
            ctx
        };
        if !run_round_on(mesh, (&mut sub, rings), at, round, state, report) {
            break;
        }
    }
    if polish_twice && rounds > 1 && !ctx.out_of_time() {
        let unshifted = Ctx {
            round: RoundFlags {
                slab_offset: 0.0,
                ..shifted.round
            },
            ..shifted
        };
        run_round_on(mesh, (&mut sub, rings), &unshifted, rounds, state, report);
    }
    let off = match &sub {
        Some(s) => any_off_level(&s.mesh, ctx),
        None => any_off_level(mesh, ctx),
    };
    if !ctx.out_of_time() && off {
        run_round_on(mesh, (&mut sub, rings), ctx, rounds.max(1), state, report);
    }
    write_back(&mut sub, mesh, state, report);
}

/// Writes the copy `sub`, if any, back into `mesh` (a splice, in the report's stage times).
fn write_back(
    sub: &mut Option<SubMesh>,
    mesh: &mut TetMesh,
    state: &mut PassState,
    report: &mut ImproveReport,
) {
    if let Some(s) = sub.take() {
        let mut clock = Instant::now();
        s.write_back(
            mesh,
            &mut state.quality,
            &mut state.drift,
            &mut state.removed,
        );
        lap(&mut report.stage_seconds.splice, &mut clock);
    }
}

/// Round `round` of [`run_rounds`]: the first on `mesh`, the later ones on the copy `sub`
/// within `rings` rings of the work (cut when there is none, and cut again when the work
/// reaches its rim; on `mesh` for `rings == None`). Returns false when nothing needed work.
fn run_round_on(
    mesh: &mut TetMesh,
    (sub, rings): (&mut Option<SubMesh>, Option<usize>),
    ctx: &Ctx,
    round: usize,
    state: &mut PassState,
    report: &mut ImproveReport,
) -> bool {
    let Some(rings) = rings.filter(|_| round > 0) else {
        let progress = Progress {
            quality: &mut state.quality,
            drift: &mut state.drift,
            removed: &mut state.removed,
            report,
        };
        return run_round(mesh, ctx, (round, 0), progress, None) != Round::Idle;
    };
    let mut phase = 0;
    loop {
        if sub.is_none() {
            let (mut work, _) = needs_work(mesh, ctx, &state.quality, true);
            if phase == 0 && !work.iter().any(|&w| w) {
                return false;
            }
            if ctx.round.polish {
                // The copy holds the work as `run_round` marks it: with one ring, a copy cut
                // around the ungrown work has the grown work on its rim at once, and cutting
                // it again around the same work never ended.
                grow(mesh, &mut work);
            }
            let mut clock = Instant::now();
            let marks = thin::rim_marks(mesh, ctx);
            *sub = Some(SubMesh::cut(
                mesh,
                &work,
                rings,
                (&state.quality, &state.drift),
                &marks,
            ));
            // Copying out is part of extracting.
            lap(&mut report.stage_seconds.extract, &mut clock);
        }
        let Some(s) = sub.as_mut() else {
            return false;
        };
        let pinned = Ctx {
            round: RoundFlags {
                pinned: Some(&s.rim),
                rim_marks: Some(&s.rim_marks),
                ..ctx.round
            },
            cancel: ctx.cancel.clone(),
            ..*ctx
        };
        let progress = Progress {
            quality: &mut s.quality,
            drift: &mut s.drift,
            removed: &mut s.removed,
            report,
        };
        match run_round(
            &mut s.mesh,
            &pinned,
            (round, phase),
            progress,
            Some(&mut s.untouched),
        ) {
            Round::Idle => return false,
            Round::Done => return true,
            Round::Rim(at) => {
                // Written back and cut again around the work of phase `at`.
                write_back(sub, mesh, state, report);
                phase = at;
            }
        }
    }
}

/// Whether some level vertex is off its level set.
fn any_off_level(mesh: &TetMesh, ctx: &Ctx) -> bool {
    project::off_level_points(mesh, ctx).contains(&true)
}

/// What the rounds carry from one to the next.
struct Progress<'a> {
    /// Per tet: its quality.
    quality: &'a mut Vec<f64>,
    /// Per point: the volume the operations merged into it or moving it added.
    drift: &'a mut Vec<f64>,
    /// Points merged away.
    removed: &'a mut Vec<u32>,
    report: &'a mut ImproveReport,
}

/// How [`run_round`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Round {
    /// Nothing needed work.
    Idle,
    /// It ran.
    Done,
    /// On a copy, the work of this phase reached the copy's rim ([`submesh`]); the phases
    /// before it ran.
    Rim(u32),
}

/// One round (`round`, from phase `first_phase`): marks the vertices that need work and
/// improves their regions, in slabs of even and then odd parity. On a copy (`ctx.pinned`
/// set), `untouched` follows what its splices keep, and the round stops when the work reaches
/// the rim.
fn run_round(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    (round, first_phase): (usize, u32),
    p: Progress,
    mut untouched: Option<&mut Untouched>,
) -> Round {
    let mut clock = Instant::now();
    // Later rounds find few vertices off their level, all marked as work: the regions
    // project them, so the whole-mesh scan runs once.
    if round == 0 {
        // Qualities kept from an earlier stage are refreshed where corners moved; otherwise
        // the projection gives them all.
        let kept = p.quality.len() == mesh.tets.len();
        let fill = (!kept).then_some(&mut *p.quality);
        let moved = project::project_mesh(mesh, ctx, p.drift, fill);

        p.report.projected += moved.iter().filter(|&&m| m).count();
        if kept {
            refresh_quality(mesh, ctx, &moved, p.quality);
        }
    }
    lap(&mut p.report.stage_seconds.project, &mut clock);
    for phase in first_phase..2 {
        clock = Instant::now();
        let (mut work, off) = needs_work(mesh, ctx, p.quality, round > 0);
        if ctx.round.polish {
            // The polishing round frees the neighbours of the work too, so that its
            // composite collapses may merge into them.
            grow(mesh, &mut work);
        }
        lap(&mut p.report.stage_seconds.mark, &mut clock);
        if ctx
            .round
            .pinned
            .is_some_and(|rim| submesh::reaches_rim(&work, rim))
        {
            return Round::Rim(phase);
        }
        if phase == 0 {
            if !work.iter().any(|&w| w) {
                return Round::Idle;
            }
            p.report.rounds += 1;
        } else if ctx.out_of_time() {
            p.report.out_of_time = true;
            break;
        }
        let regions = improve_phase(mesh, ctx, phase, (&work, &off), p.quality, p.report);
        collect_drift(&regions, p.drift);
        if let Some(u) = untouched.as_deref_mut() {
            u.before_splice(mesh, &regions.1);
        }
        p.removed
            .extend(splice_phase(mesh, regions, p.quality, p.report));
    }
    Round::Done
}

/// One phase of a round: improves the regions of the `work` vertices in slabs of parity
/// `phase` (splice them back with [`splice_phase`]); `off` marks the level vertices off their
/// levels.
fn improve_phase(
    mesh: &TetMesh,
    ctx: &Ctx,
    phase: u32,
    (work, off): (&[bool], &[bool]),
    quality: &[f64],
    report: &mut ImproveReport,
) -> (Vec<LocalMesh>, region::Regions) {
    let mut clock = Instant::now();
    let (mut regions, bookkeeping) =
        region::extract_regions(mesh, (work, Some(off)), quality, ctx, phase);
    lap(&mut report.stage_seconds.extract, &mut clock);
    let starts = regions.clone();
    let counts: Vec<ImproveReport> = regions
        .par_iter_mut()
        .map(|lm| {
            let mut r = ImproveReport {
                region_tets: lm.tets.len(),
                ..Default::default()
            };
            // A region reached after the budget ran out stays as it was copied out.
            if ctx.out_of_time() {
                r.out_of_time = true;
            } else {
                schedule::improve_local(lm, ctx, &mut r);
            }
            r
        })
        .collect();
    for c in counts {
        report.add(&c);
    }
    report.regions_undone +=
        verify::keep_embedded(mesh, ctx, &mut regions, starts, &bookkeeping, true);
    lap(&mut report.stage_seconds.local, &mut clock);
    (regions, bookkeeping)
}

/// Writes improved regions back; returns the points merged away.
fn splice_phase(
    mesh: &mut TetMesh,
    (regions, bookkeeping): (Vec<LocalMesh>, region::Regions),
    quality: &mut Vec<f64>,
    report: &mut ImproveReport,
) -> Vec<u32> {
    let mut clock = Instant::now();
    let removed = region::splice(mesh, regions, bookkeeping, quality);
    lap(&mut report.stage_seconds.splice, &mut clock);
    removed
}

/// Adds the regions' per-vertex volume drift to `drift` (per point).
fn collect_drift((regions, _): &(Vec<LocalMesh>, region::Regions), drift: &mut [f64]) {
    for lm in regions {
        for (&g, &d) in lm.global.iter().zip(&lm.drift) {
            if g != region::NEW_POINT {
                drift[g as usize] += d;
            }
        }
    }
}
