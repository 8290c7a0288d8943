//! The plain data of what the quality pass did, as the report shows it: the operation counts
//! and stage times ([`ImproveReport`]), the stages of a climb to high targets ([`Stage`]),
//! the counts against the targets ([`TargetCounts`], [`KeptBetter`]) and the elements left
//! below the floor with their reasons ([`ForcedReport`]). The pass ([`crate::improve`])
//! fills them in; the report ([`crate::report`]) reads them without depending on the pass.

use serde::Serialize;

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
    /// Level-vertex moves that gave volume back ([`QualityOptions::restore_volume`](crate::improve::QualityOptions::restore_volume)).
    pub restored: usize,
    /// Boundary edges split where their chord sagged from the level set
    /// ([`QualityOptions::split_sag`](crate::improve::QualityOptions::split_sag)).
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
    /// because it had left a small mesh's volume off ([`improve`](crate::improve::improve)).
    pub volume_retries: usize,
    /// With targets above the default, the pass climbs to them in stages ([`improve`](crate::improve::improve)): each
    /// stage's target and whether it was kept. Empty for a single pass.
    pub stages: Vec<Stage>,
    /// When the time budget ran out, or on a curvilinear grid (whose quality the pass measures
    /// in parameter space): the mesh before the pass against the one it stopped at, through the
    /// grid's map, and which was kept ([`keep_better`](crate::improve::outcome::keep_better)).
    pub budget: Option<KeptBetter>,
}

/// Where the quality pass spends its time (wall-clock seconds, summed over rounds).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageSeconds {
    /// Projecting the level vertices of the whole mesh onto their level sets.
    pub project: f64,
    /// Marking the vertices that need work.
    pub mark: f64,
    /// Copying the regions out (and the rounds' copy of the mesh, [`submesh`](crate::improve::submesh)).
    pub extract: f64,
    /// Improving the regions.
    pub local: f64,
    /// Writing the regions back (and the rounds' copy).
    pub splice: f64,
    /// The last stage after the rounds (of each target stage): splitting the boundary edges
    /// that sag from the level set ([`QualityOptions::split_sag`](crate::improve::QualityOptions::split_sag)) and giving the volume back
    /// ([`QualityOptions::restore_volume`](crate::improve::QualityOptions::restore_volume)).
    pub finish: f64,
    /// Measuring whole meshes to choose between runs: the runs again for the volume
    /// ([`improve`](crate::improve::improve)) and the mesh before a pass stopped by its time budget
    /// ([`keep_better`](crate::improve::outcome::keep_better)).
    pub compare: f64,
    /// The rest (seeding the warping's volume, the copies of the mesh, the last check of the
    /// level vertices): [`ImproveReport::seconds`] less the stages above, so that they add up.
    pub other: f64,
}

/// One stage of a pass towards targets above the default ([`crate::improve::improve`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stage {
    /// Its target dihedral angles (degrees).
    pub target_degrees: [f64; 2],
    /// The worst tet quality in this stage's measure before it (`None` for the first stage,
    /// which is kept whatever it does).
    pub worst_before: Option<f64>,
    /// The worst tet quality in this stage's measure after it.
    pub worst_after: f64,
    /// Whether its result was kept (it did not lower the worst quality).
    pub kept: bool,
}

/// How many tets of a mesh miss the pass's targets, and its extreme dihedral angles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TargetCounts {
    /// Tets.
    pub tets: usize,
    /// Tets whose smallest dihedral angle is below the floor ([`crate::improve::QualityOptions::forced_floor`]).
    pub below_floor: usize,
    /// Tets whose smallest dihedral angle is below the target ([`crate::improve::QualityOptions::min_angle`]).
    pub below_min: usize,
    /// Tets whose largest dihedral angle is above the target ([`crate::improve::QualityOptions::max_angle`]).
    pub above_max: usize,
    /// Tets below the smallest or above the largest target angle (either or both).
    pub off_target: usize,
    /// Smallest dihedral angle (degrees; 180 for no tet).
    pub min_dihedral: f64,
    /// Largest dihedral angle (degrees; 0 for no tet).
    pub max_dihedral: f64,
}

impl TargetCounts {
    /// Whether the targets are missed: some tet is below or above them.
    pub fn missed(&self) -> bool {
        self.off_target > 0
    }

    /// Whether these are better than `other`'s: fewer tets below the floor, then fewer off
    /// target, then a larger smallest angle, then a smaller largest angle.
    pub fn better_than(&self, other: &TargetCounts) -> bool {
        let key = |c: &TargetCounts| (c.below_floor, c.off_target);
        match key(self).cmp(&key(other)) {
            std::cmp::Ordering::Less => true,
            std::cmp::Ordering::Greater => false,
            std::cmp::Ordering::Equal => {
                (self.min_dihedral, -self.max_dihedral) > (other.min_dihedral, -other.max_dihedral)
            }
        }
    }
}

/// What the last step of a pass stopped by its time budget found ([`keep_better`](crate::improve::outcome::keep_better)).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KeptBetter {
    /// The mesh before the pass.
    pub before: TargetCounts,
    /// The mesh the pass stopped at.
    pub after: TargetCounts,
    /// The mesh before the pass was kept: the pass had left it worse
    /// ([`TargetCounts::better_than`]).
    pub kept_before: bool,
}

/// Why an element stays below the floor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ForcedReason {
    /// A critical value of the field near a bound pinches the domain in a cell it touches.
    NearCritical,
    /// The layer between the alpha and beta level sets is thinner than the element can span
    /// above the floor.
    ThinLayer,
    /// A level set meets the grid box at an angle below the floor at the element.
    BoxAngle,
    /// A curvilinear grid's geometry map flattens the element, which is above the floor in
    /// the grid's parameter space (where the pass works).
    GridMapping,
    /// No domain reason found: the pass failed there.
    Unexplained,
}

/// One element below the floor.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ForcedElement {
    /// Tet index (in the mesh after the pass).
    pub tet: usize,
    /// Smallest dihedral angle (degrees).
    pub min_dihedral: f64,
    /// Largest dihedral angle (degrees).
    pub max_dihedral: f64,
    /// Why.
    pub reason: ForcedReason,
    /// Centroid, physical coordinates.
    pub point: [f64; 3],
    /// Smallest `|critical value − bound|` over the cells the tet touches, relative to the
    /// data range (`None`: no critical point there).
    pub critical_distance: Option<f64>,
    /// Narrowest neck or gap (voxels) the nearer level leaves at those critical points,
    /// measured across them (see [`crate::improve::forced`]).
    pub neck_width: Option<f64>,
    /// Thickness (voxels) of the layer between the alpha and beta level sets at the tet (see
    /// [`ForcedReason::ThinLayer`]; `None` for a one-sided interval).
    pub layer_thickness: Option<f64>,
    /// Smallest interior dihedral angle (degrees) between a box plane and a level set at the
    /// tet, when it has an edge on each.
    pub box_angle: Option<f64>,
}

/// Elements below the floor, per reason.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ForcedCounts {
    /// [`ForcedReason::NearCritical`].
    pub near_critical: usize,
    /// [`ForcedReason::ThinLayer`].
    pub thin_layer: usize,
    /// [`ForcedReason::BoxAngle`].
    pub box_angle: usize,
    /// [`ForcedReason::GridMapping`].
    pub grid_mapping: usize,
    /// [`ForcedReason::Unexplained`].
    pub unexplained: usize,
}

/// The elements below the floor after the pass, with their reasons.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ForcedReport {
    /// The floor (degrees), [`crate::improve::QualityOptions::forced_floor`].
    pub floor_degrees: f64,
    /// [`crate::improve::QualityOptions::forced_critical_tol`] (relative to the data range).
    pub critical_tolerance: f64,
    /// Counts per reason (of all elements below the floor).
    pub counts: ForcedCounts,
    /// The elements, worst first, at most [`crate::improve::QualityOptions::forced_list_cap`].
    pub elements: Vec<ForcedElement>,
}

impl ForcedReport {
    /// Elements below the floor in all.
    pub fn total(&self) -> usize {
        self.counts.near_critical
            + self.counts.thin_layer
            + self.counts.box_angle
            + self.counts.grid_mapping
            + self.counts.unexplained
    }
}
