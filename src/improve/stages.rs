//! Targets above the default, climbed to in stages (`docs/ARCHITECTURE.md`, *Stages*): the
//! default pass first, then passes at targets raised by at most [`STAGE_STEP`], each undone
//! if it leaves the worst tet worse in its own measure, and each ending with the splits and
//! the volume restoration at its own targets.
//!
//! Why: one pass aimed straight at a high target works on every tet below it and collapses
//! more, and on a thin layer that left it worse than the default target (the benchmark's 32³
//! shell: 12.5° for `--min-angle 20`, against 15.0° by default). In stages, a ladder's first
//! stages are those of every lower target on the same line and no stage lowers the worst tet
//! in its own measure; a higher target ended at least where a lower one did on every domain
//! measured (docs/QUALITY-LOG.md, *Higher targets*). Giving the volume back after every stage, rather than
//! once after the last, gave the higher minimum on 35 and the lower one on 15 of 72 runs, and
//! the smaller volume change on 56 and the larger on 9 (the domains of
//! `benchmarks/quality.py` at N = 24, 28, 36, 40 and targets 20°, 25°, 30°;
//! `benchmarks/stages_matrix.py`), and there every domain's minimum rose (or
//! stayed) from target to target and none ended below 15° (given back once: the 28³ shell
//! 12.6° at 20°). The drift left to the end had grown past what the restoration can give back
//! without taking a tet below the higher target. With edge removal every
//! minimum still rises or stays with the target. The first stage is the default pass, with
//! the single pass's retry of stuck regions (`schedule::improve_local`); later stages do not
//! retry (retrying in every stage: higher minimum on 5, lower on 10 of the 72 runs). Without
//! the retries in the first stage a ladder could end below the default pass (the 24³ shell:
//! 14.84° at 20°, 15.00° by default); with them, no run of 96 (the default added) does.

pub use crate::pass_report::Stage;

use super::pass::PassState;
use super::rounds::{run_rounds, Rounds};
use super::{Ctx, ImproveReport, QualityOptions};
use crate::mesh::TetMesh;

/// Largest raise of the target angles from one stage of [`super::improve`] to the next
/// (degrees).
pub const STAGE_STEP: f64 = 2.5;

/// The targets `[min, max]` (degrees) of the stages of [`super::improve`]: just `opts`' own
/// when they are not above the default; else the default, then equal steps of at most
/// [`STAGE_STEP`] in each angle up to `opts`' (a requested target below the default in one
/// angle stays where it is requested in every stage).
pub(super) fn stage_targets(opts: &QualityOptions) -> Vec<[f64; 2]> {
    let d = QualityOptions::default();
    let (lo0, hi0) = (
        d.min_angle.min(opts.min_angle),
        d.max_angle.max(opts.max_angle),
    );
    let rise = (opts.min_angle - lo0).max(hi0 - opts.max_angle);
    if rise <= 0.0 {
        return vec![[opts.min_angle, opts.max_angle]];
    }
    let n = (rise / STAGE_STEP).ceil() as usize;
    (0..=n)
        .map(|i| {
            let f = i as f64 / n as f64;
            [
                lo0 + f * (opts.min_angle - lo0),
                hi0 + f * (opts.max_angle - hi0),
            ]
        })
        .collect()
}

/// One stage of [`super::improve`]: [`run_rounds`] at `ctx`'s targets (`target_degrees`, with
/// `state.quality` in its measure), undone (mesh and state) if the worst tet ends worse than
/// it started, unless it is the `first` (the default pass, which retries its stuck regions
/// as the single pass does). Returns the stage's outcome.
pub(super) fn run_stage(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    rounds: Rounds,
    (first, target_degrees): (bool, [f64; 2]),
    state: &mut PassState,
    report: &mut ImproveReport,
) -> Stage {
    let worst = |q: &[f64]| q.iter().copied().fold(f64::INFINITY, f64::min);
    let before = (!first).then(|| worst(&state.quality));
    let snapshot = before.map(|_| (mesh.clone(), state.clone()));
    run_rounds(mesh, ctx, rounds, state, report);
    let after = worst(&state.quality);
    let kept = before.is_none_or(|b| after >= b);
    if let (false, Some((old_mesh, old_state))) = (kept, snapshot) {
        *mesh = old_mesh;
        *state = old_state;
    }
    Stage {
        target_degrees,
        worst_before: before,
        worst_after: after,
        kept,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::QualityOptions;

    fn targets(min_angle: f64, max_angle: f64) -> Vec<[f64; 2]> {
        stage_targets(&QualityOptions {
            min_angle,
            max_angle,
            ..QualityOptions::default()
        })
    }

    #[test]
    fn stages_start_at_the_default_and_climb_by_at_most_a_step() {
        // The default and lower targets: one pass.
        assert_eq!(targets(15.0, 155.0), vec![[15.0, 155.0]]);
        assert_eq!(targets(10.0, 170.0), vec![[10.0, 170.0]]);
        // Both angles in equal steps of at most STAGE_STEP.
        assert_eq!(
            targets(20.0, 150.0),
            vec![[15.0, 155.0], [17.5, 152.5], [20.0, 150.0]]
        );
        let t = targets(23.0, 141.0);
        assert_eq!((t[0], t[t.len() - 1]), ([15.0, 155.0], [23.0, 141.0]));
        assert_eq!(t.len(), 7, "{t:?}");
        for w in t.windows(2) {
            assert!(w[1][0] - w[0][0] <= STAGE_STEP + 1e-12 && w[1][0] >= w[0][0]);
            assert!(w[0][1] - w[1][1] <= STAGE_STEP + 1e-12 && w[1][1] <= w[0][1]);
        }
        // A target below the default in one angle stays as requested in every stage.
        assert_eq!(
            targets(20.0, 170.0),
            vec![[15.0, 170.0], [17.5, 170.0], [20.0, 170.0]]
        );
        // The ladder of a lower target on the same line is a prefix of a higher one's.
        assert_eq!(targets(25.0, 145.0)[..3], targets(20.0, 150.0)[..]);
    }
}
