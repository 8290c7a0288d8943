//! Critical points and critical regions of the piecewise-trilinear field (after “Exploring
//! scalar fields using critical isovalues” and “Detecting critical regions in scalar fields”),
//! with a persistence for each, and the contour spectrum (Betti numbers of `{f >= w}` between
//! consecutive critical values).
//!
//! * [`vertex`]: grid vertices from their six edge-connected neighbours (the 64-entry table).
//! * [`face`]: face saddles by Lemma 4 of “Exploring scalar fields using critical isovalues”.
//! * [`body`]: saddles inside cells.
//! * [`plateau`]: plateaus (edge-connected equal values) by flood fill, labels kept for their
//!   vertices only.
//! * [`region`]: which plateaus are critical: the neighbourhood graph of “Detecting critical
//!   regions in scalar fields”.
//! * [`complex`]: the second route, the TPTD tetrahedral complex of the grid (a
//!   piecewise-linear field whose level sets have the trilinear topology): Betti numbers of
//!   its superlevel and sublevel sets.
//! * [`persistence`]: union–find over the superlevel and sublevel sets of that complex.
//! * [`spectrum`]: Betti numbers between consecutive critical values.
//! * [`safe`]: the critical values near a chosen bound and the nearest safe bounds.
//! * [`transfer`]: colour/opacity transfer functions from the critical values (“Exploring scalar
//!   fields using critical isovalues” §5).
//!
//! Points on the grid box are classified with the part of their neighbourhood inside the box,
//! so the box itself creates critical points (a box vertex whose inward neighbour is lower
//! opens a hole in `{f >= w}`). Such points may change only one of the two filtrations; each
//! [`CriticalPoint`] says which ([`CriticalPoint::superlevel`], [`CriticalPoint::sublevel`]).

pub mod body;
pub mod complex;
pub mod face;
pub mod find;
pub mod persistence;
pub mod plateau;
pub mod region;
pub mod safe;
pub mod spectrum;
pub mod transfer;
pub mod vertex;

pub use find::{find_critical, find_critical_with_options};
pub use safe::{near_critical, NearCritical};
pub use spectrum::{contour_spectrum, SpectrumStep};
pub use transfer::{transfer_function, TransferDesign, TransferFunction, TransferOptions};

use serde::Serialize;

use crate::grid::ScalarGrid;
use vertex::LinkClass;

/// What kind of critical point or region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CriticalKind {
    /// A grid vertex with no lower value around it.
    Minimum,
    /// A grid vertex with no higher value around it.
    Maximum,
    /// A grid vertex where several higher or lower parts meet.
    Saddle,
    /// A saddle of the bilinear interpolant on a grid face that is critical for the field.
    FaceSaddle,
    /// A saddle of the trilinear interpolant inside a cell.
    BodySaddle,
    /// A plateau (edge-connected vertices of equal value) with no lower value around it.
    RegionMinimum,
    /// A plateau with no higher value around it.
    RegionMaximum,
    /// A plateau where several higher or lower parts meet.
    RegionSaddle,
}

impl CriticalKind {
    /// All kinds.
    pub const ALL: [CriticalKind; 8] = [
        CriticalKind::Minimum,
        CriticalKind::Maximum,
        CriticalKind::Saddle,
        CriticalKind::FaceSaddle,
        CriticalKind::BodySaddle,
        CriticalKind::RegionMinimum,
        CriticalKind::RegionMaximum,
        CriticalKind::RegionSaddle,
    ];

    /// The name used in tables and JSON (`minimum`, `face_saddle`, ...).
    pub fn name(self) -> &'static str {
        match self {
            CriticalKind::Minimum => "minimum",
            CriticalKind::Maximum => "maximum",
            CriticalKind::Saddle => "saddle",
            CriticalKind::FaceSaddle => "face_saddle",
            CriticalKind::BodySaddle => "body_saddle",
            CriticalKind::RegionMinimum => "region_minimum",
            CriticalKind::RegionMaximum => "region_maximum",
            CriticalKind::RegionSaddle => "region_saddle",
        }
    }

    /// The kind with this name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Whether this is a plateau region.
    pub fn is_region(self) -> bool {
        matches!(
            self,
            CriticalKind::RegionMinimum | CriticalKind::RegionMaximum | CriticalKind::RegionSaddle
        )
    }
}

/// Extent of a critical region.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegionInfo {
    /// Number of grid vertices in the region.
    pub vertices: usize,
    /// Physical centroid of the region's vertices (it may lie outside the region, e.g. in
    /// the hole of a ring; the point's `position` is a vertex of the region).
    pub centroid: [f64; 3],
    /// Smallest physical coordinates of the region's vertices.
    pub bbox_min: [f64; 3],
    /// Largest physical coordinates of the region's vertices.
    pub bbox_max: [f64; 3],
}

/// One critical point or critical region.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CriticalPoint {
    /// The critical value.
    pub value: f64,
    /// What it is.
    pub kind: CriticalKind,
    /// Physical position (a region: its vertex nearest to its centroid, see
    /// [`RegionInfo::centroid`]).
    pub position: [f64; 3],
    /// Position in index coordinates (grid vertex `(i, j, k)` is `[i, j, k]`), of
    /// `position`.
    pub index: [f64; 3],
    /// Whether the point (or some vertex of the region) lies on the grid box.
    pub on_box: bool,
    /// Whether crossing the value here changes the topology of `{f >= w}`.
    pub superlevel: bool,
    /// Whether crossing the value here changes the topology of `{f <= w}`.
    pub sublevel: bool,
    /// A face saddle whose two cells cannot decide it (Lemma 4's derivative is zero: a curve
    /// of critical points crosses the cell). The value is critical; the kind of change is not
    /// known locally.
    pub degenerate: bool,
    /// Isovalue span of the component (of a superlevel or sublevel set, cavities included)
    /// the point creates or destroys; the value range for the points where the first
    /// component of a filtration is born; `None` for points that change no component count
    /// (tunnel saddles).
    pub persistence: Option<f64>,
    /// Extent, for regions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<RegionInfo>,
    /// Keys (see [`complex`]) of the vertices of the TPTD complex the point is made of: one
    /// for a point, every vertex for a region. Used to look up the persistence.
    #[serde(skip)]
    pub keys: Vec<u64>,
}

impl CriticalPoint {
    /// A critical point at index position `index` (`class`: how its neighbourhood splits;
    /// `degenerate`: the kind of change is not known, so the point counts for both
    /// filtrations), with no persistence, region or keys yet.
    pub fn new(
        grid: &ScalarGrid,
        kind: CriticalKind,
        value: f64,
        index: [f64; 3],
        class: LinkClass,
        degenerate: bool,
    ) -> Self {
        let on_box = (0..3).any(|a| index[a] == 0.0 || index[a] == (grid.dims[a] - 1) as f64);
        Self {
            value,
            kind,
            position: grid.to_physical(index),
            index,
            on_box,
            superlevel: degenerate || class.superlevel(),
            sublevel: degenerate || class.sublevel(),
            degenerate,
            persistence: None,
            region: None,
            keys: Vec::new(),
        }
    }
}

/// Why critical points could not be computed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CriticalError {
    /// Every grid value is the same: no isovalue changes anything.
    #[error("the volume is constant (every value is {0}): it has no critical isovalue")]
    Constant(f64),
    /// The value range of a filter contains no data value.
    #[error("the value range [{lo}, {hi}] contains no data (values span [{min}, {max}])")]
    EmptyRange {
        /// Requested lower end.
        lo: f64,
        /// Requested upper end.
        hi: f64,
        /// Smallest data value.
        min: f64,
        /// Largest data value.
        max: f64,
    },
    /// A filter is malformed (NaN bound, lower end above upper end, negative persistence).
    #[error("{0}")]
    BadFilter(String),
}

/// Which critical points to keep.
#[derive(Clone, Debug, PartialEq)]
pub struct CriticalOptions {
    /// Keep points with value `>= min_value`.
    pub min_value: f64,
    /// Keep points with value `<= max_value`.
    pub max_value: f64,
    /// Keep these kinds (all when empty).
    pub kinds: Vec<CriticalKind>,
    /// Keep points with persistence `>= min_persistence` (0 keeps everything; points without a
    /// persistence are dropped when this is positive).
    pub min_persistence: f64,
    /// Worker threads (`None`: rayon's default pool).
    pub threads: Option<usize>,
    /// Compute the persistence (a union–find over the whole grid; off, every persistence is
    /// `None`, which is enough to check bounds).
    pub persistence: bool,
}

impl Default for CriticalOptions {
    fn default() -> Self {
        CriticalOptions {
            min_value: f64::NEG_INFINITY,
            max_value: f64::INFINITY,
            kinds: Vec::new(),
            min_persistence: 0.0,
            threads: None,
            persistence: true,
        }
    }
}

impl CriticalOptions {
    /// Whether `p` passes the filters.
    pub fn keeps(&self, p: &CriticalPoint) -> bool {
        p.value >= self.min_value
            && p.value <= self.max_value
            && (self.kinds.is_empty() || self.kinds.contains(&p.kind))
            && (self.min_persistence <= 0.0
                || p.persistence.is_some_and(|x| x >= self.min_persistence))
    }
}
