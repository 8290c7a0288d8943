//! What the quality pass did ([`ImproveReport`]) and where it spent its time
//! ([`StageSeconds`]): plain data of [`crate::pass_report`], counted and timed here.

use std::time::Instant;

pub use crate::pass_report::{ImproveReport, StageSeconds};

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
