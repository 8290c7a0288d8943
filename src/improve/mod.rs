//! The quality pass: improves the elements of a mesh while keeping its topology, its boundary
//! labels and its boundary on the level sets of the trilinear field.
//!
//! Pipeline position: `extract` → **improve** → write. Work is proportional to what needs
//! work: each round marks the vertices of tets below the target quality and the level
//! vertices off the trilinear level set, copies their stars out (`local`), improves them
//! there (projection, edge collapse, flips, edge removal, smoothing; one operation per file)
//! and splices the result back. A last stage after the rounds splits the boundary edges whose
//! chord sags from a curved level set (`split`) and gives back the volume the operations moved
//! (`restore`); with targets above the default, every target stage ends with it (`stages`).
//! Everything runs in a fixed order, so the output does not depend on the number of threads.

pub(crate) mod collapse;
mod composite;
pub(crate) mod constraint;
pub(crate) mod edge_removal;
pub(crate) mod embed;
mod face_grid;
#[cfg(test)]
pub(crate) mod fixtures;
pub(crate) mod flip;
pub mod forced;
pub(crate) mod local;
pub mod outcome;
pub(crate) mod project;
pub(crate) mod restore;
mod schedule;
pub(crate) mod search;
pub(crate) mod smooth;
pub(crate) mod split;
pub mod stages;
pub(crate) mod submesh;
mod thin;
mod verify;
pub(crate) mod warped;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;
use serde::Serialize;

use crate::extract::MeshOutput;
use crate::field::Field;
use crate::grid::ScalarGrid;
use crate::mesh::TetMesh;
use crate::quality::biased_min_sine;
use crate::warp::Snapped;
use local::LocalMesh;
use stages::{run_stage, stage_targets, Stage};
use submesh::{SubMesh, Untouched};

/// The warping threshold ([`crate::MeshOptions::warp`]) to mesh with before improving: grid
/// vertices that a level passes within this fraction of an edge from are put on the level
/// while clipping (when that keeps the topology), so most slivers never appear.
pub const DEFAULT_WARP: f64 = 0.3;

/// The default of [`QualityOptions::split_sag`].
pub const DEFAULT_SPLIT_SAG: f64 = 0.03;

/// The default [`QualityOptions::boundary_collapse_ratio`].
const DEFAULT_COLLAPSE_RATIO: f64 = 3.0;

/// Knobs of the quality pass.
#[derive(Clone, Debug, PartialEq)]
pub struct QualityOptions {
    /// Target smallest dihedral angle (degrees).
    pub min_angle: f64,
    /// Target largest dihedral angle (degrees).
    pub max_angle: f64,
    /// Improvement rounds at most (each re-marks what still needs work).
    pub max_rounds: usize,
    /// Stop improving after this much time (checked between sweeps over a region and between
    /// rounds; the mesh is valid whenever it stops).
    pub time_budget: Option<Duration>,
    /// Boundary vertices are projected until `|f - level| <= level_tolerance · (data range)`.
    pub level_tolerance: f64,
    /// Two boundary vertices are merged only along an edge shorter than this times the mean
    /// length of the edges at the removed vertex (`f64::INFINITY`: no limit). Long merges
    /// coarsen the boundary: a thin layer is left with long, flat elements, and a convex
    /// boundary shrinks (the surface is inscribed in the level set). The default, 3, brings
    /// the thin shell of the benchmarks from 14.2° to 15.0° and leaves no `unexplained`
    /// element on the noisy 256³ field (docs/QUALITY-LOG.md).
    pub boundary_collapse_ratio: f64,
    /// Give back the volume that a region's collapses and moves added or took, by moving its
    /// level vertices along their level sets where no tet falls below the target
    /// (`improve/restore.rs`). Without it, the small analytic domains of `tests/quality.rs`
    /// shrink or grow by up to 0.6 % (docs/QUALITY-LOG.md).
    pub restore_volume: bool,
    /// A boundary edge on a level set whose chord sags from the level set by more than this
    /// fraction of its length is split at the end, with the new node on the level set, where
    /// no tet gets worse than the target (`improve/split.rs`; `f64::INFINITY`: never). Nodes
    /// on a curved level set inscribe the surface in it, so thin tubes lose volume: the 32³
    /// genus-3 solid of the benchmark (tubes 1.9 voxels in radius) lost 1.08 % without it,
    /// and loses 0.32 % with it.
    pub split_sag: f64,
    /// Tets whose smallest dihedral angle stays below this (degrees) after the pass are listed
    /// with a reason ([`forced::classify_forced`]).
    pub forced_floor: f64,
    /// A critical value within this of alpha or beta (relative to the data range) explains a
    /// bad tet in a cell with that critical point (`near_critical`).
    pub forced_critical_tol: f64,
    /// At most this many of the listed tets are given one by one (worst first); the counts
    /// per reason cover all.
    pub forced_list_cap: usize,
}

impl Default for QualityOptions {
    fn default() -> Self {
        QualityOptions {
            min_angle: 15.0,
            max_angle: 155.0,
            max_rounds: 4,
            time_budget: None,
            level_tolerance: 1e-9,
            boundary_collapse_ratio: DEFAULT_COLLAPSE_RATIO,
            restore_volume: true,
            split_sag: DEFAULT_SPLIT_SAG,
            forced_floor: 5.0,
            forced_critical_tol: 1e-5,
            forced_list_cap: 1000,
        }
    }
}

/// What the quality pass did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ImproveReport {
    /// Rounds run.
    pub rounds: usize,
    /// Tets in the worked-on regions, summed over rounds.
    pub region_tets: usize,
    /// Boundary vertices moved onto their level set.
    pub projected: usize,
    /// Boundary vertices left off their level set at the end (farther than the tolerance).
    pub unprojected: usize,
    /// Boundary vertices that could not be moved onto their level set and were merged into a
    /// neighbour on it instead.
    pub merged_off_level: usize,
    /// Edge collapses.
    pub collapses: usize,
    /// 2-3 and 3-2 flips.
    pub flips: usize,
    /// Edges removed (4 to 7 tets around an edge replaced; `edge_removal.rs`).
    pub edge_removals: usize,
    /// Vertex moves by smoothing.
    pub smoothed: usize,
    /// Level-vertex moves that gave volume back ([`QualityOptions::restore_volume`]).
    pub restored: usize,
    /// Boundary edges split where their chord sagged from the level set
    /// ([`QualityOptions::split_sag`]).
    pub splits: usize,
    /// Regions put back as they started because their boundary would have crossed itself or
    /// left its level set (`verify.rs`).
    pub regions_undone: usize,
    /// Seconds spent.
    pub seconds: f64,
    /// Seconds spent in each stage, summed over rounds.
    pub stage_seconds: StageSeconds,
    /// The time budget ran out before the pass was done.
    pub out_of_time: bool,
    /// Times the pass was run again from the start with boundary collapses limited further,
    /// because it had left a small mesh's volume off ([`improve`]).
    pub volume_retries: usize,
    /// With targets above the default, the pass climbs to them in stages ([`improve`]): each
    /// stage's target and whether it was kept. Empty for a single pass.
    pub stages: Vec<Stage>,
    /// When the time budget ran out, or on a curvilinear grid (whose quality the pass measures
    /// in parameter space): the mesh before the pass against the one it stopped at, through the
    /// grid's map, and which was kept ([`outcome::keep_better`]).
    pub budget: Option<outcome::KeptBetter>,
}

/// Where the quality pass spends its time (wall-clock seconds, summed over rounds).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageSeconds {
    /// Projecting the level vertices of the whole mesh onto their level sets.
    pub project: f64,
    /// Marking the vertices that need work.
    pub mark: f64,
    /// Copying the regions out (and the rounds' copy of the mesh, [`submesh`]).
    pub extract: f64,
    /// Improving the regions.
    pub local: f64,
    /// Writing the regions back (and the rounds' copy).
    pub splice: f64,
    /// The last stage after the rounds (of each target stage): splitting the boundary edges
    /// that sag from the level set ([`QualityOptions::split_sag`]) and giving the volume back
    /// ([`QualityOptions::restore_volume`]).
    pub finish: f64,
    /// Measuring whole meshes to choose between runs: the runs again for the volume
    /// ([`improve`]) and the mesh before a pass stopped by its time budget
    /// ([`outcome::keep_better`]).
    pub compare: f64,
    /// The rest (seeding the warping's volume, the copies of the mesh, the last check of the
    /// level vertices): [`ImproveReport::seconds`] less the stages above, so that they add up.
    pub other: f64,
}

/// Adds the seconds since `*since` to `*to` and restarts the clock.
fn lap(to: &mut f64, since: &mut Instant) {
    let now = Instant::now();
    *to += (now - *since).as_secs_f64();
    *since = now;
}

impl ImproveReport {
    /// Adds the operation counts of `o` (a region's) to these.
    fn add(&mut self, o: &ImproveReport) {
        self.region_tets += o.region_tets;
        self.projected += o.projected;
        self.collapses += o.collapses;
        self.flips += o.flips;
        self.edge_removals += o.edge_removals;
        self.smoothed += o.smoothed;
        self.restored += o.restored;
        self.merged_off_level += o.merged_off_level;
        self.regions_undone += o.regions_undone;
        self.out_of_time |= o.out_of_time;
    }
}

/// Everything an operation needs besides the local mesh.
pub struct Ctx<'a> {
    /// The trilinear field.
    pub field: Field<'a>,
    /// `[alpha, beta]`.
    pub levels: [f64; 2],
    /// Absolute tolerance on `|f - level|` for boundary vertices.
    pub tol: f64,
    /// Weight of obtuse angles in [`biased_min_sine`].
    pub obtuse_weight: f64,
    /// Biased-sine quality of the target angles: tets below it need work.
    pub target: f64,
    /// [`QualityOptions::boundary_collapse_ratio`].
    pub boundary_collapse_ratio: f64,
    /// When the time budget runs out.
    pub deadline: Option<Instant>,
    /// Where the slabs that split the work into regions start along the grid's longest axis
    /// (index units; [`local::SLAB`]).
    pub slab_offset: f64,
    /// Smoothing tries the steepest ascent direction first ([`smooth`]).
    pub steepest: bool,
    /// Smoothing tries the centroid of the neighbours where its line searches fail
    /// ([`smooth`]).
    pub centroid: bool,
    /// Per point: pinned (frozen in every region), as the rim of a [`submesh::SubMesh`] is.
    pub pinned: Option<&'a [bool]>,
    /// On a copy: per point, what the whole mesh said of it when the copy was cut
    /// ([`thin::rim_marks`]; the rim's faces and tets outside the copy are missing from it).
    pub rim_marks: Option<&'a [u8]>,
    /// A region that ends with a few tets below the target is improved again from its start
    /// with other smoothing ([`Ctx::steepest`], [`Ctx::centroid`]), and the best end is kept
    /// ([`schedule::improve_local`]). Set for the last round of a single pass and of the
    /// first stage of a ladder ([`stages`]).
    pub retry_stuck: bool,
    /// A region that ends with tets below the target gets a compass search over their
    /// corners ([`search`], [`schedule::improve_local`]). Set for the last round of every
    /// stage.
    pub polish: bool,
}

impl Ctx<'_> {
    /// Whether the time budget has run out.
    pub fn out_of_time(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    /// The quality the pass maximises (biased minimum sine).
    #[inline]
    pub fn quality(&self, p: [[f64; 3]; 4]) -> f64 {
        biased_min_sine(p, self.obtuse_weight)
    }

    /// Whether index point `u` lies strictly inside the interval (where interior vertices
    /// must stay).
    pub fn inside_interval(&self, u: [f64; 3]) -> bool {
        let f = self.field.value(u);
        f > self.levels[0] && f < self.levels[1]
    }
}

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
/// ([`finish_stage`]). A small mesh left off its plain volume by more than 0.4 % is improved
/// again from the start with shorter boundary collapses ([`ImproveReport::volume_retries`]).
pub fn improve(
    mesh: &mut TetMesh,
    grid: &ScalarGrid,
    alpha: f64,
    beta: f64,
    opts: &QualityOptions,
) -> ImproveReport {
    outcome::improve_keeping_better(mesh, grid, [alpha, beta], opts, &[], None)
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
    outcome::improve_meshed_mapped(out, grid, alpha, beta, opts, None)
}

/// Meshes of at most this many tets are run again ([`improve_keeping_volume`]) when the pass
/// leaves them off their plain volume by more than [`VOLUME_RETRY`]. On a large mesh the
/// regions' leftover drift averages out (every full-size run of the benchmarks ends within
/// [`RESIDUAL`] before the last stage); keeping a copy of it would only cost memory.
const VOLUME_RETRY_TETS: usize = 1 << 20;

/// The share of the plain volume beyond which a small mesh's pass is run again (the quality goal
/// allows 0.5 %).
const VOLUME_RETRY: f64 = 4e-3;

/// The boundary-collapse ratios ([`QualityOptions::boundary_collapse_ratio`]) of the runs
/// again, as multiples of the one asked for (the third took a torus of tube radius 1.76
/// voxels at 22³ from -0.52 % to -0.44 % of its plain volume).
const VOLUME_RETRY_RATIOS: [f64; 3] = [0.5, 0.25, 0.125];

/// [`improve_in`] with the rounds on copies ([`submesh::RINGS`]). On a small mesh
/// ([`VOLUME_RETRY_TETS`]) that the pass leaves off its plain volume by more than
/// [`VOLUME_RETRY`] (with [`QualityOptions::restore_volume`]), the pass runs again from the
/// start with boundary collapses limited to shorter edges ([`VOLUME_RETRY_RATIOS`]): merging
/// boundary nodes far apart is what shrinks thin parts beyond what the restoration can give
/// back (the benchmark's genus-3 solid at 20³, tubes a voxel thick: −0.65 % at the default
/// ratio 3). Which run ends nearest its volume is chaotic (that solid ends at +0.00 %,
/// −0.32 % and −0.12 % with ratios 1.5, 1 and 0.5, but −0.82 % with 2), so the run kept is
/// the one nearest the plain volume among those whose worst tet is at least the first run's
/// (or the target). `copy` is the mesh before the pass, given when
/// [`runs_again_for_volume`]; the stage seconds are summed over all runs.
fn improve_keeping_volume(
    mesh: &mut TetMesh,
    grid: &ScalarGrid,
    levels: [f64; 2],
    opts: &QualityOptions,
    (snapped, copy): (&[Snapped], Option<&TetMesh>),
) -> ImproveReport {
    let start = Instant::now();
    let rings = Some(submesh::RINGS);
    let (mut report, plain) = improve_in(mesh, grid, levels, opts, rings, snapped);
    let Some(copy) = copy else {
        return report;
    };
    let mut spent = report.stage_seconds.clone();
    let mut clock = Instant::now();
    let off = |m: &TetMesh| (m.volume() - plain).abs() / plain.abs();
    let ctx = context(grid, levels[0], levels[1], opts, start);
    let worst = |m: &TetMesh| {
        tet_qualities(m, &ctx)
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    };
    // The first run's worst tet (or the target), found only if a run again is needed.
    let mut floor = None;
    let mut best = off(mesh);
    lap(&mut spent.compare, &mut clock);
    for ratio in VOLUME_RETRY_RATIOS {
        let left = opts.time_budget.map(|b| b.saturating_sub(start.elapsed()));
        if best.is_nan()
            || best <= VOLUME_RETRY
            || report.out_of_time
            || left.is_some_and(|l| l.is_zero())
        {
            break;
        }
        let again = QualityOptions {
            boundary_collapse_ratio: ratio
                * opts.boundary_collapse_ratio.min(DEFAULT_COLLAPSE_RATIO),
            time_budget: left,
            ..opts.clone()
        };
        clock = Instant::now();
        let floor = *floor.get_or_insert_with(|| worst(mesh).min(ctx.target));
        lap(&mut spent.compare, &mut clock);
        let mut other = copy.clone();
        let (r, _) = improve_in(&mut other, grid, levels, &again, rings, snapped);
        spent.add(&r.stage_seconds);
        report.volume_retries += 1;
        clock = Instant::now();
        let now = off(&other);
        let better = now < best && worst(&other) >= floor && !r.out_of_time;
        lap(&mut spent.compare, &mut clock);
        if better {
            best = now;
            *mesh = other;
            report = ImproveReport {
                volume_retries: report.volume_retries,
                ..r
            };
        }
    }
    report.stage_seconds = spent;
    report.seconds = start.elapsed().as_secs_f64();
    report
}

/// Whether [`improve_keeping_volume`] may run the pass again for the volume on `mesh` (and so
/// needs a copy of it from before the pass).
fn runs_again_for_volume(mesh: &TetMesh, opts: &QualityOptions) -> bool {
    opts.restore_volume && mesh.tets.len() <= VOLUME_RETRY_TETS
}

/// [`improve`], the rounds after the first on a copy within `rings` rings of their work
/// ([`submesh`]; `None`: on the whole mesh, which gives the same mesh), owing the volume of
/// the warping's `snapped` vertices.
fn improve_in(
    mesh: &mut TetMesh,
    grid: &ScalarGrid,
    [alpha, beta]: [f64; 2],
    opts: &QualityOptions,
    rings: Option<usize>,
    snapped: &[Snapped],
) -> (ImproveReport, f64) {
    let start = Instant::now();
    let mut report = ImproveReport::default();
    let mut state = PassState {
        quality: Vec::new(),
        drift: vec![0.0; mesh.points.len()],
        removed: Vec::new(),
    };
    let ladder = stage_targets(opts);
    let mut ctx = context(grid, alpha, beta, opts, start);
    warped::seed(mesh, &ctx.field, snapped, &mut state.drift);
    // The volume of the mesh before warping, which the restoration aims at.
    let plain = mesh.volume() - state.drift.iter().sum::<f64>();
    for (i, &[lo, hi]) in ladder.iter().enumerate() {
        let stage = QualityOptions {
            min_angle: lo,
            max_angle: hi,
            ..opts.clone()
        };
        ctx = context(grid, alpha, beta, &stage, start);
        // Per tet: its quality. Kept up to date through projections and splices, so that
        // each round evaluates only the tets that changed, and the regions copy it out. In a
        // single stage the first round's projection fills it (its inversion check evaluates
        // every tet with the moves made); `ensure_quality` covers a pass in which no round
        // ran.
        state.quality = if ladder.len() == 1 {
            Vec::new()
        } else {
            tet_qualities(mesh, &ctx)
        };
        // Stuck regions are retried in the single pass and in a ladder's first stage (the
        // same pass) only: in later stages, which regions end stuck at one stage changes
        // where the next starts, and the stages got worse (docs/QUALITY-LOG.md).
        // A second polishing round only in the stages above the default: on the default
        // pass it cost the noisy field a tenth more time (docs/QUALITY-LOG.md).
        let rounds = Rounds {
            max: opts.max_rounds,
            retry_last: i == 0,
            polish_twice: i > 0,
            rings,
        };
        if ladder.len() == 1 {
            run_rounds(mesh, &ctx, rounds, &mut state, &mut report);
            // No round ran (out of time, or no rounds asked for).
            ensure_quality(mesh, &ctx, &mut state.quality);
        } else {
            let stage = run_stage(
                mesh,
                &ctx,
                rounds,
                (i == 0, [lo, hi]),
                &mut state,
                &mut report,
            );
            report.stages.push(stage);
        }
        if report.out_of_time {
            break;
        }
        if opts.restore_volume || opts.split_sag.is_finite() {
            // The drift is given back only where the mesh's volume is off the plain one by
            // more than RESIDUAL: splits alone otherwise.
            let off = (mesh.volume() - plain).abs() > RESIDUAL * plain.abs();
            let finish = QualityOptions {
                restore_volume: opts.restore_volume && off,
                ..opts.clone()
            };
            let PassState { quality, drift, .. } = &mut state;
            finish_stage(mesh, &ctx, &finish, drift, quality, &mut report);
            // The drift is given back: the next stage starts from none (and from the points
            // the splits added).
            drift.iter_mut().for_each(|d| *d = 0.0);
            drift.resize(mesh.points.len(), 0.0);
            if opts.restore_volume {
                let last = i + 1 == ladder.len();
                restore_residual(mesh, &ctx, opts, (plain, last), &mut state, &mut report);
            }
        }
    }
    // `ctx` is now at the requested targets (the last stage's).
    state.removed.sort_unstable();
    local::drop_points(mesh, &state.removed);
    report.unprojected = project::off_level_points(mesh, &ctx)
        .iter()
        .filter(|&&o| o)
        .count();
    report.seconds = start.elapsed().as_secs_f64();
    (report, plain)
}

/// What a pass carries from round to round and from stage to stage.
#[derive(Clone)]
struct PassState {
    /// Per tet: its quality (in the current stage's measure).
    quality: Vec<f64>,
    /// Per point: the volume the operations merged into it or moving it added. Given back at
    /// the end of each stage ([`finish_stage`]).
    drift: Vec<f64>,
    /// Points merged away. They stay (unused) until the end: renumbering once keeps every
    /// round's work proportional to what it touches, and keeps the relative order of ids.
    removed: Vec<u32>,
}

/// How many rounds a pass (or a stage) runs at most, whether the last one retries its stuck
/// regions ([`Ctx::retry_stuck`]), whether a second polishing round follows it with the slab
/// boundaries back in place (`polish_twice`), and within how many rings of their work the
/// rounds after the first copy the mesh ([`submesh`]; `None`: they run on the whole mesh).
#[derive(Clone, Copy)]
struct Rounds {
    max: usize,
    retry_last: bool,
    polish_twice: bool,
    rings: Option<usize>,
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
fn run_rounds(
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
        slab_offset: 0.5 * local::SLAB,
        retry_stuck: retry_last,
        polish: true,
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
            slab_offset: 0.0,
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
            if ctx.polish {
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
            pinned: Some(&s.rim),
            rim_marks: Some(&s.rim_marks),
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
        if ctx.polish {
            // The polishing round frees the neighbours of the work too, so that its
            // composite collapses may merge into them.
            grow(mesh, &mut work);
        }
        lap(&mut p.report.stage_seconds.mark, &mut clock);
        if ctx
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

fn context<'a>(
    grid: &'a ScalarGrid,
    alpha: f64,
    beta: f64,
    opts: &QualityOptions,
    start: Instant,
) -> Ctx<'a> {
    let (lo, hi) = grid.value_range();
    let range = (hi - lo).max(f64::MIN_POSITIVE);
    let lo_s = opts.min_angle.to_radians().sin();
    let hi_s = (180.0 - opts.max_angle).to_radians().sin();
    let obtuse_weight = (lo_s / hi_s).min(1.0);
    Ctx {
        field: Field::new(grid),
        levels: [alpha, beta],
        tol: opts.level_tolerance * range,
        obtuse_weight,
        target: lo_s.min(obtuse_weight * hi_s),
        boundary_collapse_ratio: opts.boundary_collapse_ratio,
        deadline: opts.time_budget.map(|b| start + b),
        slab_offset: 0.0,
        steepest: false,
        centroid: false,
        retry_stuck: false,
        polish: false,
        pinned: None,
        rim_marks: None,
    }
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
) -> (Vec<LocalMesh>, local::Regions) {
    let mut clock = Instant::now();
    let (mut regions, bookkeeping) =
        local::extract_regions(mesh, (work, Some(off)), quality, ctx, phase);
    lap(&mut report.stage_seconds.extract, &mut clock);
    let starts = regions.clone();
    let counts: Vec<ImproveReport> = regions
        .par_iter_mut()
        .map(|lm| {
            let mut r = ImproveReport {
                region_tets: lm.tets.len(),
                ..Default::default()
            };
            schedule::improve_local(lm, ctx, &mut r);
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
    (regions, bookkeeping): (Vec<LocalMesh>, local::Regions),
    quality: &mut Vec<f64>,
    report: &mut ImproveReport,
) -> Vec<u32> {
    let mut clock = Instant::now();
    let removed = local::splice(mesh, regions, bookkeeping, quality);
    lap(&mut report.stage_seconds.splice, &mut clock);
    removed
}

/// Adds the regions' per-vertex volume drift to `drift` (per point).
fn collect_drift((regions, _): &(Vec<LocalMesh>, local::Regions), drift: &mut [f64]) {
    for lm in regions {
        for (&g, &d) in lm.global.iter().zip(&lm.drift) {
            if g != local::NEW_POINT {
                drift[g as usize] += d;
            }
        }
    }
}

/// The last stage after the rounds (of each target stage), region by region: splits the
/// boundary edges whose chord sags from the level set ([`split::split_sagging_edges`]), then,
/// around the points that carry volume drift, gives it back by moving level vertices along
/// their level sets ([`restore::restore_volume`]). Neither lets a tet fall below the target
/// (or below where it was), so nothing they do needs improving again. New points are appended
/// to the mesh, so point ids stay valid.
fn finish_stage(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    opts: &QualityOptions,
    drift: &[f64],
    quality: &mut Vec<f64>,
    report: &mut ImproveReport,
) {
    let mut clock = Instant::now();
    let split = opts.split_sag.is_finite();
    let sagging = if split {
        split::sagging_points(mesh, ctx, opts.split_sag)
    } else {
        vec![false; mesh.points.len()]
    };
    let owed = if opts.restore_volume {
        restore::largest_drift(drift)
    } else {
        Vec::new()
    };
    // The points that owe drift and their neighbours, which share the moves that give it
    // back (without them the T1 at [51.5, 101.5] was still 0.43 % off, and the whole
    // boundary was restored again by `restore_residual`).
    let mut work: Vec<bool> = owed.iter().map(|&d| d != 0.0).collect();
    work.resize(mesh.points.len(), false);
    if work.contains(&true) {
        grow(mesh, &mut work);
    }
    for (w, &s) in work.iter_mut().zip(&sagging) {
        *w |= s;
    }
    for phase in 0..2 {
        // The points the first phase added need nothing.
        work.resize(mesh.points.len(), false);
        let (mut regions, bookkeeping) =
            local::extract_regions(mesh, (&work, None), quality, ctx, phase);
        let starts = regions.clone();
        let (splits, moves) = regions
            .par_iter_mut()
            .map(|lm| finish_region(lm, ctx, opts, (&owed, &sagging)))
            .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1));
        report.regions_undone +=
            verify::keep_embedded(mesh, ctx, &mut regions, starts, &bookkeeping, false);
        report.splits += splits;
        report.restored += moves;
        if splits > 0 {
            local::splice(mesh, regions, bookkeeping, quality);
        } else {
            local::write_positions(mesh, &regions, &bookkeeping, quality);
        }
    }
    lap(&mut report.stage_seconds.finish, &mut clock);
}

/// The share of the plain volume that the mesh may be off by without the restoration
/// (before the last stage), or after it without [`restore_residual`] (half of what the quality goal
/// allows, 0.5 %).
const RESIDUAL: f64 = 2.5e-3;

/// The rungs of [`restore_residual`], as multiples of [`QualityOptions::split_sag`]: first no
/// splits, then (after the last stage only) splits of the chords that sag by a third and by
/// a tenth of it. A moved node only shifts volume along the level set: where a small convex
/// part lost boundary nodes (the benchmark's two balls 0.3 voxel apart, radius 4.4 voxels at
/// 20³: −0.70 % after the first rung), only more nodes on the level set give it back (−0.39 %
/// after the third).
const RESIDUAL_RUNGS: [f64; 3] = [f64::INFINITY, 1.0 / 3.0, 0.1];

/// Where the last stage left the mesh's volume off `plain` by more than [`RESIDUAL`] of it
/// (the regions around the drift could not give it all back where it arose: their tets
/// were at the target), books the rest evenly on every level vertex and restores once more
/// around all of them, rung by rung of [`RESIDUAL_RUNGS`] while it stays off (the splits
/// only after the `last` stage: splits in an earlier one change where the next starts). The
/// full-size volumes of the benchmarks never get here; small analytic domains (a boundary
/// of a few thousand nodes) do.
fn restore_residual(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    opts: &QualityOptions,
    (plain, last): (f64, bool),
    state: &mut PassState,
    report: &mut ImproveReport,
) {
    let rungs = if last && opts.split_sag.is_finite() {
        &RESIDUAL_RUNGS[..]
    } else {
        &RESIDUAL_RUNGS[..1]
    };
    for &rung in rungs {
        let split_sag = rung * opts.split_sag;
        let residual = mesh.volume() - plain;
        if residual.abs() <= RESIDUAL * plain.abs() || ctx.out_of_time() {
            return;
        }
        spread_residual(mesh, residual, &mut state.drift);
        let rung_opts = QualityOptions {
            split_sag,
            ..opts.clone()
        };
        let PassState { quality, drift, .. } = &mut *state;
        finish_stage(mesh, ctx, &rung_opts, drift, quality, report);
        // The next rung (or stage) starts from no drift, and from the points splits added.
        drift.iter_mut().for_each(|d| *d = 0.0);
        drift.resize(mesh.points.len(), 0.0);
    }
}

/// Books `residual` evenly on every level vertex of `mesh` (`drift`, per point; left as it
/// is when there is none).
fn spread_residual(mesh: &TetMesh, residual: f64, drift: &mut [f64]) {
    let labels = mesh.vertex_label_bits();
    let level = |v: usize| labels[v] & 3 != 0;
    let n = (0..mesh.points.len()).filter(|&v| level(v)).count();
    if n == 0 {
        return;
    }
    for (v, d) in drift.iter_mut().enumerate() {
        *d = if level(v) { residual / n as f64 } else { 0.0 };
    }
}

/// [`finish_stage`] in one region (`drift` and the [`split::sagging_points`] per point of the
/// mesh): returns its splits and its restoring moves.
fn finish_region(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    opts: &QualityOptions,
    (drift, sagging): (&[f64], &[bool]),
) -> (usize, usize) {
    let (splits, added) = if opts.split_sag.is_finite() {
        split::split_sagging_edges(lm, ctx, opts.split_sag, Some(sagging))
    } else {
        (0, 0.0)
    };
    if !opts.restore_volume {
        return (splits, 0);
    }
    // Points added by splits (here, or in the first phase) carry no drift.
    let drifted: f64 = (0..lm.u.len())
        .filter(|&v| lm.is_free(v as u32))
        .filter_map(|v| drift.get(lm.global[v] as usize))
        .sum();
    // Volume the splits added pays back volume the region lost, and volume they took pays
    // back volume it gained; beyond that (or the other way) they are a correction towards the
    // level set, which is kept.
    let mut owed = if drifted * added >= 0.0 {
        drifted
    } else if drifted < 0.0 {
        (drifted + added).min(0.0)
    } else {
        (drifted + added).max(0.0)
    };
    (splits, restore::restore_volume(lm, ctx, &mut owed))
}

/// The quality ([`Ctx::quality`]) of each tet.
fn tet_qualities(mesh: &TetMesh, ctx: &Ctx) -> Vec<f64> {
    mesh.tets
        .par_iter()
        .map(|t| ctx.quality(t.map(|v| mesh.points[v as usize])))
        .collect()
}

/// Evaluates `quality` for every tet unless it is already there.
fn ensure_quality(mesh: &TetMesh, ctx: &Ctx, quality: &mut Vec<f64>) {
    if quality.len() != mesh.tets.len() {
        *quality = tet_qualities(mesh, ctx);
    }
}

/// Re-evaluates `quality` for the tets with a corner in `moved`.
fn refresh_quality(mesh: &TetMesh, ctx: &Ctx, moved: &[bool], quality: &mut [f64]) {
    mesh.tets.par_iter().zip(quality).for_each(|(t, q)| {
        if t.iter().any(|&v| moved[v as usize]) {
            *q = ctx.quality(t.map(|v| mesh.points[v as usize]));
        }
    });
}

/// Per point: is it a corner of a tet below the target (by `quality`), or a level vertex off
/// its level (with `ring`, or a corner of a tet around one, so that its neighbours can move)?
/// Also returns, per point, whether it is a level vertex off its level.
///
/// Tets across a thin layer ([`thin`]) are not work, nor are the level vertices off their
/// level at their corners: nothing the pass does brings them to the target.
fn needs_work(mesh: &TetMesh, ctx: &Ctx, quality: &[f64], ring: bool) -> (Vec<bool>, Vec<bool>) {
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
fn mark_corners(mesh: &TetMesh, work: &mut [bool], marks: impl Fn(usize) -> bool + Sync) {
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
fn grow(mesh: &TetMesh, work: &mut [bool]) {
    let seed = work.to_vec();
    mark_corners(mesh, work, |t| {
        mesh.tets[t].iter().any(|&v| seed[v as usize])
    });
}
