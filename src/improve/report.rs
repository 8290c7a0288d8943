//! What the quality pass did ([`ImproveReport`]) and where it spent its time
//! ([`StageSeconds`]).

use std::time::Instant;

use serde::Serialize;

use super::outcome;
use super::stages::Stage;

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
    /// Level-vertex moves that gave volume back ([`QualityOptions::restore_volume`](super::QualityOptions::restore_volume)).
    pub restored: usize,
    /// Boundary edges split where their chord sagged from the level set
    /// ([`QualityOptions::split_sag`](super::QualityOptions::split_sag)).
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
    /// because it had left a small mesh's volume off ([`improve`](super::improve)).
    pub volume_retries: usize,
    /// With targets above the default, the pass climbs to them in stages ([`improve`](super::improve)): each
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
    /// Copying the regions out (and the rounds' copy of the mesh, [`submesh`](super::submesh)).
    pub extract: f64,
    /// Improving the regions.
    pub local: f64,
    /// Writing the regions back (and the rounds' copy).
    pub splice: f64,
    /// The last stage after the rounds (of each target stage): splitting the boundary edges
    /// that sag from the level set ([`QualityOptions::split_sag`](super::QualityOptions::split_sag)) and giving the volume back
    /// ([`QualityOptions::restore_volume`](super::QualityOptions::restore_volume)).
    pub finish: f64,
    /// Measuring whole meshes to choose between runs: the runs again for the volume
    /// ([`improve`](super::improve)) and the mesh before a pass stopped by its time budget
    /// ([`outcome::keep_better`]).
    pub compare: f64,
    /// The rest (seeding the warping's volume, the copies of the mesh, the last check of the
    /// level vertices): [`ImproveReport::seconds`] less the stages above, so that they add up.
    pub other: f64,
}

/// Adds the seconds since `*since` to `*to` and restarts the clock.
pub(super) fn lap(to: &mut f64, since: &mut Instant) {
    let now = Instant::now();
    *to += (now - *since).as_secs_f64();
    *since = now;
}

impl ImproveReport {
    /// Adds the operation counts of `o` (a region's) to these.
    pub(super) fn add(&mut self, o: &ImproveReport) {
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
