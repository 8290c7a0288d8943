//! Inspection of any tetrahedral mesh, however made (ours, TetGen's, fTetWild's, CGAL's):
//! counts, volume, element quality, and the library checker's verdict ([`check_mesh`]); with
//! the volume it models, its topology and volume against the trilinear interval
//! ([`reference()`]) and its boundary's distance to the level sets. `tptd-mesh --inspect` prints
//! it, one column per mesh.
//!
//! * **Orientation convention**: a mesh none of whose tets is positive and some negative is
//!   read in the opposite convention (two corners of every tet swapped) and marked
//!   `flipped`; any other negative tet is reported (`inverted_tet`).
//! * **Boundary labels** (for the level-set distance): a mesh whose file labels its boundary
//!   (our `.msh` and `.inp`: groups `alpha`, `beta`, `box`) keeps the file's labels, which the
//!   checker then also checks against its tets. Otherwise every face of one tet is labelled
//!   by where it lies ([`label_boundary`]): `box` when its three corners lie on one face of the
//!   grid box, else the level (`alpha` or `beta`) nearer in value to the field at its centroid
//!   (to first order, the nearer level set).
//! * **Dihedral percentiles** are nearest-rank percentiles of each tet's smallest angle (1 %,
//!   5 %, 50 %) and of each tet's largest (50 %, 95 %, 99 %).

mod labels;
mod reference;
mod table;

use rayon::prelude::*;
use serde::Serialize;

use crate::check::{check_mesh, CheckOptions, LevelSummary, Problem, ProblemKind, WindingSummary};
use crate::geom::signed_volume;
use crate::grid::ScalarGrid;
use crate::levels::Levels;
use crate::mesh::{TetMesh, NUM_LABELS};
use crate::quality::{dihedral_angles, summarize, ABOVE_ANGLES, BELOW_ANGLES};

pub use labels::label_boundary;
pub use reference::{reference, trilinear_volume, Reference, ReferenceOptions, TrilinearVolume};
pub use table::table;

/// Percentiles of each tet's smallest dihedral angle in [`Dihedral::min_percentiles`].
pub const MIN_PERCENTILES: [f64; 3] = [1.0, 5.0, 50.0];
/// Percentiles of each tet's largest dihedral angle in [`Dihedral::max_percentiles`].
pub const MAX_PERCENTILES: [f64; 3] = [50.0, 95.0, 99.0];

/// What to inspect against.
#[derive(Clone, Copy, Debug)]
pub struct InspectOptions<'a> {
    /// The volume the mesh models, with the interval `(alpha, beta)` and the reference of
    /// that interval; `None`: the mesh alone.
    pub volume: Option<(&'a ScalarGrid, &'a Reference)>,
    /// Largest distance (voxels) of an alpha or beta triangle from its level set before the
    /// checker reports it (`off_level`).
    pub level_distance_bound: f64,
}

impl Default for InspectOptions<'_> {
    fn default() -> Self {
        InspectOptions {
            volume: None,
            level_distance_bound: CheckOptions::default().level_distance_bound,
        }
    }
}

/// Dihedral angles (degrees).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Dihedral {
    /// Smallest over the mesh.
    pub min: f64,
    /// Largest over the mesh.
    pub max: f64,
    /// Nearest-rank percentiles [`MIN_PERCENTILES`] of each tet's smallest angle.
    pub min_percentiles: [f64; 3],
    /// Nearest-rank percentiles [`MAX_PERCENTILES`] of each tet's largest angle.
    pub max_percentiles: [f64; 3],
}

/// Element quality besides the dihedral angles.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Quality {
    /// Smallest radius ratio `3 r_in / r_circ` (1 for the regular tet).
    pub min_radius_ratio: f64,
    /// Smallest SICN (Gmsh's `minSICN`).
    pub min_sicn: f64,
    /// Smallest gamma (Gmsh's `gamma`).
    pub min_gamma: f64,
    /// Tets whose smallest dihedral angle is below 5°, 10°, 15°, 20°.
    pub below: [usize; 4],
    /// Tets whose largest dihedral angle is above 150°, 155°, 160°, 170°.
    pub above: [usize; 4],
    /// Counts of all dihedral angles (6 per tet) per whole degree.
    pub histogram: Vec<u64>,
}

/// The boundary labels the level-set distance used.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Labels {
    /// `file` (the file's alpha/beta/box groups) or `nearest_level` ([`label_boundary`]).
    pub source: &'static str,
    /// Triangles labelled alpha, beta and box.
    pub counts: [usize; NUM_LABELS],
}

/// Everything an inspection found about one mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Inspection {
    /// The mesh's name (its file).
    pub file: String,
    /// Nodes and tets.
    pub nodes: usize,
    /// See `nodes`.
    pub tets: usize,
    /// Faces of one tet.
    pub boundary_faces: usize,
    /// Sum of the tets' volumes (after the orientation convention).
    pub volume: f64,
    /// Every tet was negative in the file: read in the opposite orientation convention.
    pub flipped: bool,
    /// Dihedral angles (`None` without tets).
    pub dihedral: Option<Dihedral>,
    /// Radius ratio, SICN, gamma, counts below and above thresholds.
    pub quality: Quality,
    /// Betti numbers `[b0, b1, b2]` (`None` when the boundary is not a closed manifold).
    pub betti: Option<[usize; 3]>,
    /// The checker found no problem.
    pub valid: bool,
    /// Every problem the checker found, one entry per kind.
    pub problems: Vec<Problem>,
    /// The winding numbers at sampled tets.
    pub winding: Option<WindingSummary>,
    /// With the volume: the boundary labels used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub labels: Option<Labels>,
    /// With the volume: the level-set distances of the alpha and beta triangles (voxels).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level: Option<LevelSummary>,
    /// With the volume: the Betti numbers of the trilinear interval.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_betti: Option<[usize; 3]>,
    /// With the volume: `betti == reference_betti`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matches_reference: Option<bool>,
    /// With the volume: the trilinear interval's volume (estimate and bounds).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trilinear_volume: Option<TrilinearVolume>,
    /// With the volume: `volume / trilinear estimate - 1`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub volume_error: Option<f64>,
}

/// Inspects `mesh`, named `file` (see the module documentation). Takes the mesh to flip it
/// and label it in place when needed.
pub fn inspect(file: &str, mut mesh: TetMesh, opts: &InspectOptions) -> Inspection {
    let flipped = flip_if_all_negative(&mut mesh);
    let mut check_opts = CheckOptions {
        level_distance_bound: opts.level_distance_bound,
        ..CheckOptions::default()
    };
    let mut labels = None;
    if let Some((grid, r)) = opts.volume {
        check_opts.grid = Some(grid);
        check_opts.levels = Levels::interval(r.levels.0, r.levels.1);
        let source = if mesh.boundary.is_empty() {
            label_boundary(&mut mesh, grid, r.levels);
            "nearest_level"
        } else {
            "file"
        };
        let mut counts = [0; NUM_LABELS];
        for &l in &mesh.boundary_labels {
            counts[l.index()] += 1;
        }
        labels = Some(Labels { source, counts });
    }
    let report = check_mesh(&mesh, &check_opts);
    let q = summarize(&mesh);
    let reference = opts.volume.map(|(_, r)| r);
    Inspection {
        file: file.to_string(),
        nodes: mesh.points.len(),
        tets: mesh.tets.len(),
        boundary_faces: report.boundary_faces,
        volume: report.volume,
        flipped,
        dihedral: dihedral(&mesh),
        quality: Quality {
            min_radius_ratio: q.min_radius_ratio,
            min_sicn: q.min_sicn,
            min_gamma: q.min_gamma,
            below: q.below,
            above: q.above,
            histogram: q.histogram,
        },
        betti: report.betti,
        valid: report.valid,
        problems: report.problems,
        winding: report.winding,
        labels,
        level: report.level,
        reference_betti: reference.map(|r| r.betti),
        matches_reference: reference.map(|r| report.betti == Some(r.betti)),
        trilinear_volume: reference.map(|r| r.volume),
        volume_error: reference.map(|r| report.volume / r.volume.estimate - 1.0),
    }
}

/// The rows of `tptd-mesh --inspect` the checker's problems are shown in.
pub const PROBLEM_GROUPS: [&str; 5] = [
    "conformity",
    "orientation",
    "manifold boundary",
    "embedding",
    "level sets",
];

/// The entry of [`PROBLEM_GROUPS`] a problem kind belongs to.
pub fn problem_group(kind: ProblemKind) -> &'static str {
    use ProblemKind::*;
    match kind {
        BadIndex
        | NonFinitePoint
        | LabelCount
        | TooLarge
        | DuplicateTet
        | FaceInThreeOrMoreTets
        | TetsOnSameSideOfFace
        | BoundaryFaceUnlisted
        | ListedFaceNotBoundary
        | BoundaryTriangleInward
        | RegionCount
        | UnlistedInterface
        | InterfaceNotBetweenRegions => PROBLEM_GROUPS[0],
        InvertedTet | DegenerateTet => PROBLEM_GROUPS[1],
        OpenBoundaryEdge
        | NonManifoldBoundaryEdge
        | NonManifoldBoundaryVertex
        | InconsistentBoundaryOrientation => PROBLEM_GROUPS[2],
        BoundarySelfIntersection | BoundaryOverlap | WindingNumber | VolumeMismatch => {
            PROBLEM_GROUPS[3]
        }
        OffLevel | OutsideGrid | BoxTriangleOffBox => PROBLEM_GROUPS[4],
    }
}

/// The thresholds of [`Quality::below`] and [`Quality::above`] (degrees).
pub const QUALITY_THRESHOLDS: ([f64; 4], [f64; 4]) = (BELOW_ANGLES, ABOVE_ANGLES);

/// Swaps two corners of every tet when none is positive and some is negative; whether it did.
fn flip_if_all_negative(mesh: &mut TetMesh) -> bool {
    let p = &mesh.points;
    let (pos, neg) = mesh
        .tets
        .par_iter()
        .map(|t| {
            let v = signed_volume(
                p[t[0] as usize],
                p[t[1] as usize],
                p[t[2] as usize],
                p[t[3] as usize],
            );
            (usize::from(v > 0.0), usize::from(v < 0.0))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    if pos > 0 || neg == 0 {
        return false;
    }
    for t in &mut mesh.tets {
        t.swap(2, 3);
    }
    for b in &mut mesh.boundary {
        b.swap(1, 2);
    }
    true
}

/// The dihedral extremes and percentiles of `mesh` (`None` without tets).
fn dihedral(mesh: &TetMesh) -> Option<Dihedral> {
    let (mut lo, mut hi): (Vec<f64>, Vec<f64>) = mesh
        .tets
        .par_iter()
        .map(|t| {
            let a = dihedral_angles(t.map(|v| mesh.points[v as usize]));
            let lo = a.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = a.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo, hi)
        })
        .unzip();
    if lo.is_empty() {
        return None;
    }
    lo.par_sort_unstable_by(f64::total_cmp);
    hi.par_sort_unstable_by(f64::total_cmp);
    let rank = |v: &[f64], p: f64| {
        let k = ((p / 100.0 * v.len() as f64).ceil() as usize).clamp(1, v.len());
        v[k - 1]
    };
    let range = crate::quality::dihedral_range(mesh);
    let (min, max) = range.unwrap_or((lo[0], hi[hi.len() - 1]));
    Some(Dihedral {
        min,
        max,
        min_percentiles: MIN_PERCENTILES.map(|p| rank(&lo, p)),
        max_percentiles: MAX_PERCENTILES.map(|p| rank(&hi, p)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_tets() -> TetMesh {
        TetMesh {
            points: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ],
            values: vec![0.0; 5],
            tets: vec![[0, 1, 2, 3], [1, 2, 3, 4]],
            ..Default::default()
        }
    }

    #[test]
    fn a_mesh_in_the_opposite_convention_is_flipped_and_valid() {
        let mut m = two_tets();
        for t in &mut m.tets {
            t.swap(0, 1);
        }
        let i = inspect("m", m, &InspectOptions::default());
        assert!(i.flipped && i.valid, "{:?}", i.problems);
        assert_eq!(i.betti, Some([1, 0, 0]));
        assert!((i.volume - 0.5).abs() < 1e-12, "{}", i.volume);
    }

    #[test]
    fn one_inverted_tet_is_reported() {
        let mut m = two_tets();
        m.tets[1].swap(0, 1);
        let i = inspect("m", m, &InspectOptions::default());
        assert!(!i.flipped && !i.valid);
        assert!(i
            .problems
            .iter()
            .any(|p| p.kind == crate::check::ProblemKind::InvertedTet));
    }

    #[test]
    fn percentiles_are_nearest_rank() {
        let i = inspect("m", two_tets(), &InspectOptions::default());
        let d = i.dihedral.unwrap();
        assert!(d.min <= d.min_percentiles[0] && d.min_percentiles[2] <= d.max);
        assert!(d.max_percentiles[2] <= d.max + 1e-12);
        assert_eq!(d.min_percentiles[0], d.min);
    }
}
