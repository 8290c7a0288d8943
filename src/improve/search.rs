//! Compass search: a derivative-free move of one vertex for tets the smoothing leaves stuck.
//!
//! The smoothing ([`super::smooth`]) steps along the gradients of the worst tets of a star;
//! where those gradients oppose each other (a kink of the max–min), it finds no way up even
//! when a better position lies a fraction of an edge away. The compass search tries the 26
//! directions of the cube around the vertex (over the axes it may move along; a level vertex
//! is put back on its level set), moves to the best point that raises the star's worst
//! quality (and leaves no more tets below the target), and halves the step when none does.
//! It is dear (dozens of star evaluations per step), so it runs only in the last round of a
//! stage, on the corners of the tets a region leaves below the target ([`super::schedule`]).

use super::constraint::Constraint;
use super::region::{LocalMesh, StarCorners, StarVec};
use super::smooth::{local_scale, move_by, place, rise_over, stepped, worst_of};
use super::Ctx;

/// Step halvings at most.
const HALVINGS: usize = 8;

/// Moves to the best point at most (each after a full scan of the directions).
const MOVES: usize = 16;

/// Moves `v` by compass search where that raises the worst quality of its star and leaves no
/// more of its tets below the target. Returns whether it moved.
pub fn search_vertex(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> bool {
    move_by(lm, ctx, v, true, |lm, star, qs| {
        compass(lm, ctx, v, star, qs)
    })
    .is_some()
}

/// The compass search of `v` (star `star`, qualities `qs`) from where it is: the point it
/// ends at if it moved, with the qualities there left in `qs`.
fn compass(
    lm: &LocalMesh,
    ctx: &Ctx,
    v: u32,
    star: &StarCorners,
    qs: &mut StarVec<f64>,
) -> Option<[f64; 3]> {
    let c = lm.con[v as usize];
    let mut probe = Probe {
        ctx,
        star,
        c,
        dirs: directions(c.free_axes()),
        hint: 0,
        next: StarVec::new(),
    };
    let from = lm.u[v as usize];
    let (mut u, mut q0) = (from, worst_of(qs));
    let mut step = 0.25 * local_scale(lm, v, from);
    let (mut halvings, mut moves) = (0, 0);
    let mut best_qs = StarVec::new();
    while halvings < HALVINGS && moves < MOVES {
        match probe.best_around(u, step, q0, qs, &mut best_qs) {
            Some((p, q)) => {
                (u, q0) = (p, q);
                std::mem::swap(qs, &mut best_qs);
                moves += 1;
            }
            None => {
                step *= 0.5;
                halvings += 1;
            }
        }
    }
    (moves > 0).then_some(u)
}

/// What the search of one vertex evaluates its star with.
struct Probe<'a> {
    ctx: &'a Ctx<'a>,
    /// The vertex's star.
    star: &'a StarCorners,
    /// Where the vertex may move.
    c: Constraint,
    /// [`directions`] over its free axes.
    dirs: Vec<[f64; 3]>,
    /// The tet that failed last, tried first.
    hint: usize,
    /// Scratch qualities.
    next: StarVec<f64>,
}

impl Probe<'_> {
    /// The best of the points `step` away from index point `u` along the directions (the star's
    /// qualities at `u` are `qs`, its worst `q0`) that raises the worst quality and leaves no
    /// more tets below the target, with that worst; the qualities there go to `best_qs`.
    fn best_around(
        &mut self,
        u: [f64; 3],
        step: f64,
        q0: f64,
        qs: &[f64],
        best_qs: &mut StarVec<f64>,
    ) -> Option<([f64; 3], f64)> {
        let ctx = self.ctx;
        let mut best: Option<([f64; 3], f64)> = None;
        for &d in &self.dirs {
            let Some(p) = place(ctx, self.c, stepped(ctx, u, d, step)) else {
                continue;
            };
            let floor = rise_over(best.map_or(q0, |b| b.1));
            let x = ctx.field.to_physical(p);
            if self
                .star
                .qualities_above(x, ctx, floor, &mut self.next, &mut self.hint)
                && below(&self.next, ctx.target) <= below(qs, ctx.target)
            {
                best = Some((p, worst_of(&self.next)));
                std::mem::swap(best_qs, &mut self.next);
            }
        }
        best
    }
}

/// How many of the qualities `qs` are below `target`.
fn below(qs: &[f64], target: f64) -> usize {
    qs.iter().filter(|&&q| q < target).count()
}

/// The unit directions of the cube's 26 neighbours over the free axes (bit `a` of `free`).
fn directions(free: u8) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(26);
    for code in 0..27 {
        let d = [code % 3, code / 3 % 3, code / 9].map(|k| k as f64 - 1.0);
        let moves_fixed = (0..3).any(|a| d[a] != 0.0 && free & (1 << a) == 0);
        let n = crate::geom::norm(d);
        if n > 0.0 && !moves_fixed {
            out.push(d.map(|x| x / n));
        }
    }
    out
}
