//! A validity checker for tetrahedral meshes, independent of how the mesh was made: it reads
//! only a [`TetMesh`] (and optionally the grid whose interval volume the mesh models).
//!
//! [`check_mesh`] runs, in order:
//! 1. **conformity**: no duplicate tets, every face in one tet (the boundary) or two (on
//!    opposite sides), the faces of one tet equal to the mesh's labelled boundary triangles
//!    as sets, outward like them (`conformity.rs`);
//! 2. **orientation**: every tet positive by the exact orientation predicate (`conformity.rs`);
//! 3. **closed manifold boundary**: every boundary edge in two triangles run in opposite
//!    directions, every boundary vertex's link one cycle (`boundary.rs`);
//! 4. **Betti numbers** (when the boundary is a closed manifold; [`crate::topology`]);
//! 5. **embedding**: the boundary surface does not meet itself (exact triangle tests over
//!    buckets, `intersect.rs`), and the winding number of the boundary at sampled tet
//!    centroids is 1: the tets cover the domain once (`winding.rs`); the tets' volume equals
//!    the volume the labelled boundary encloses;
//! 6. **regions** (a mesh of several intervals): the faces between tets of two regions are
//!    exactly the listed interfaces, each on the level between consecutive regions and
//!    oriented out of the region below (`regions.rs`);
//! 7. **level-set distance** (with a grid): level triangles (boundary and interfaces) within
//!    [`CheckOptions::level_distance_bound`] voxels of their trilinear level set, box
//!    triangles on the grid box (`level.rs`);
//! 8. **volume**: the sum of the tet volumes, reported for the caller to compare.
//!
//! Every pass that matters runs in parallel, and the report is the same for any thread count.

mod boundary;
mod buckets;
mod conformity;
mod intersect;
mod level;
mod predicates;
mod regions;
mod winding;

#[cfg(test)]
mod tests;

use rayon::prelude::*;
use serde::Serialize;

use crate::grid::ScalarGrid;
use crate::levels::Levels;
use crate::mesh::TetMesh;
use crate::Method;

pub(crate) use intersect::triangles_cross;

/// The number of pairs of triangles of a surface (`points`, `triangles`) that cross or
/// overlap each other, by the checker's bucketed search with exact predicates (flat
/// triangles take no part): a surface that intersects itself has some.
pub fn crossing_pairs(points: &[[f64; 3]], triangles: &[[u32; 3]]) -> usize {
    let tris: Vec<[[f64; 3]; 3]> = triangles
        .iter()
        .map(|t| t.map(|i| points[i as usize]))
        .collect();
    let buckets = buckets::Buckets::new(&tris);
    intersect::contacts(triangles, &tris, &buckets).len()
}
pub use level::LevelSummary;
pub use winding::{WindingSummary, WINDING_TOLERANCE};

/// Memory [`check_mesh`] needs beyond the mesh, per tet: the sorted faces (4 × 16 B) and
/// their group starts; estimated from those buffers, not measured.
pub const CHECK_BYTES_PER_TET: u64 = 80;

/// What [`check_mesh`] checks against, and how much it samples.
#[derive(Clone, Copy, Debug)]
pub struct CheckOptions<'a> {
    /// The grid whose interval volume the mesh models, in the mesh's physical coordinates
    /// (its origin, spacing and direction map index space to them); `None` skips the
    /// level-set distance check.
    pub grid: Option<&'a ScalarGrid>,
    /// The levels of the level-labelled triangles (used with `grid`).
    pub levels: Levels,
    /// Where the level-set distance is measured, per point of the mesh, when the mesh's
    /// points are not in `grid`'s coordinates: a curvilinear grid's mesh, mapped to
    /// physical space, is measured at its points in parameter space (`None`: the mesh's
    /// points; one per point of the mesh, else the level-set distance is not checked).
    pub level_points: Option<&'a [[f64; 3]]>,
    /// Largest distance (index units: voxels) allowed between a point of an alpha or beta
    /// triangle and its trilinear level set. Must be positive. [`level_bound`] gives the one
    /// each method promises.
    pub level_distance_bound: f64,
    /// Tet centroids at which the winding number is computed (every k-th tet; all of them
    /// when the mesh has no more tets than this).
    pub winding_samples: usize,
    /// Triangle–sample pairs of the brute-force generalised winding number (solid angles):
    /// it is computed at `gwn_budget / boundary triangles` samples (at least one).
    pub gwn_budget: usize,
    /// Example ids kept per problem kind.
    pub max_examples: usize,
}

impl Default for CheckOptions<'_> {
    fn default() -> Self {
        CheckOptions {
            grid: None,
            levels: Levels::interval(f64::NEG_INFINITY, f64::INFINITY),
            level_points: None,
            level_distance_bound: HALF_VOXEL,
            winding_samples: 2000,
            gwn_budget: 20_000_000,
            max_examples: 5,
        }
    }
}

/// The level-set bound of the methods that keep the trilinear topology (ctd, tptd).
pub const HALF_VOXEL: f64 = 0.5;

/// The level-set bound of the methods that interpolate linearly across a cell (std, six,
/// five): a cell's diagonal, √3 voxels.
pub const CELL_DIAGONAL: f64 = 1.732_050_807_568_877_2;

/// The largest distance between a boundary triangle and its trilinear level set that meshes
/// of `method` keep. Ctd and tptd keep the trilinear topology and split the edges whose
/// linear cut sags from the level set: half a voxel. Std, six and five change the topology
/// where a level passes a saddle, so their boundary can follow a level set the trilinear
/// field does not have there; as every point of it is a convex combination of points of one
/// cell, the trilinear level set crosses the segment to one of them: within a cell's
/// diagonal.
pub fn level_bound(method: Method) -> f64 {
    match method {
        Method::Ctd | Method::Tptd => HALF_VOXEL,
        Method::Std | Method::Six | Method::Five => CELL_DIAGONAL,
    }
}

impl<'a> CheckOptions<'a> {
    /// Options that also check the level-set distance against `grid` and the interval
    /// `[alpha, beta]`.
    pub fn with_grid(grid: &'a ScalarGrid, alpha: f64, beta: f64) -> Self {
        CheckOptions {
            grid: Some(grid),
            levels: Levels::interval(alpha, beta),
            ..CheckOptions::default()
        }
    }

    /// Options that also check the level-set distance against `grid` and the `levels` of a
    /// mesh of several regions (its labels name them by index).
    pub fn with_levels(grid: &'a ScalarGrid, levels: Levels) -> Self {
        CheckOptions {
            grid: Some(grid),
            levels,
            ..CheckOptions::default()
        }
    }

    /// [`CheckOptions::with_grid`] with the level-set bound `method` keeps ([`level_bound`]).
    pub fn for_method(grid: &'a ScalarGrid, alpha: f64, beta: f64, method: Method) -> Self {
        CheckOptions {
            level_distance_bound: level_bound(method),
            ..CheckOptions::with_grid(grid, alpha, beta)
        }
    }
}

/// A kind of problem [`check_mesh`] finds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ProblemKind {
    /// A tet or triangle names a point that does not exist (ids: tet or triangle).
    BadIndex,
    /// A point has a NaN or infinite coordinate (ids: point).
    NonFinitePoint,
    /// `boundary_labels` is not as long as `boundary`.
    LabelCount,
    /// The mesh has too many tets for the checker (2^30 or more).
    TooLarge,
    /// Two tets with the same corners (ids: the two tets).
    DuplicateTet,
    /// A face shared by three or more tets (ids: the tets).
    FaceInThreeOrMoreTets,
    /// Two tets share a face and lie on the same side of it (ids: the two tets).
    TetsOnSameSideOfFace,
    /// A face of one tet that is not among the labelled boundary triangles (ids: the tet).
    BoundaryFaceUnlisted,
    /// A labelled boundary triangle that is not a face of exactly one tet (ids: triangle).
    ListedFaceNotBoundary,
    /// A labelled boundary triangle oriented into its tet (ids: triangle).
    BoundaryTriangleInward,
    /// A tet with negative volume (ids: tet).
    InvertedTet,
    /// A tet with zero volume or a repeated corner (ids: tet).
    DegenerateTet,
    /// A boundary edge in one boundary triangle only (ids: the edge's points).
    OpenBoundaryEdge,
    /// A boundary edge in three or more boundary triangles (ids: the edge's points).
    NonManifoldBoundaryEdge,
    /// A boundary vertex whose link is not one cycle (ids: point).
    NonManifoldBoundaryVertex,
    /// Two boundary triangles run their common edge the same way (ids: the edge's points).
    InconsistentBoundaryOrientation,
    /// Two boundary triangles cross or touch where they share no corner or edge (ids: their
    /// tets).
    BoundarySelfIntersection,
    /// Two coplanar boundary triangles overlap in area: a fold, or tets glued without a
    /// common face (ids: their tets).
    BoundaryOverlap,
    /// The boundary's winding number at a tet centroid is not 1 (ids: tet).
    WindingNumber,
    /// The tets' volume differs from the volume the labelled boundary encloses.
    VolumeMismatch,
    /// An alpha or beta triangle strays from its level set by more than the bound (ids:
    /// labelled triangle).
    OffLevel,
    /// An alpha or beta triangle reaches outside the grid box (ids: labelled triangle).
    OutsideGrid,
    /// A box triangle not on a face of the grid box (ids: labelled triangle).
    BoxTriangleOffBox,
    /// The region lists are not as long as the tets, boundary or interface lists, or a
    /// region number is not below the number of regions (ids: tet, when it is one).
    RegionCount,
    /// Two tets of different regions share a face that is not a listed interface on the
    /// level between them, oriented out of the region below (ids: the two tets).
    UnlistedInterface,
    /// A listed interface that is not a face between tets of the two regions its level
    /// separates, oriented out of the region below (ids: interface).
    InterfaceNotBetweenRegions,
}

impl ProblemKind {
    /// The kind's name in reports (`snake_case`).
    pub fn name(self) -> &'static str {
        use ProblemKind::*;
        match self {
            BadIndex => "bad_index",
            NonFinitePoint => "non_finite_point",
            LabelCount => "label_count",
            TooLarge => "too_large",
            DuplicateTet => "duplicate_tet",
            FaceInThreeOrMoreTets => "face_in_three_or_more_tets",
            TetsOnSameSideOfFace => "tets_on_same_side_of_face",
            BoundaryFaceUnlisted => "boundary_face_unlisted",
            ListedFaceNotBoundary => "listed_face_not_boundary",
            BoundaryTriangleInward => "boundary_triangle_inward",
            InvertedTet => "inverted_tet",
            DegenerateTet => "degenerate_tet",
            OpenBoundaryEdge => "open_boundary_edge",
            NonManifoldBoundaryEdge => "non_manifold_boundary_edge",
            NonManifoldBoundaryVertex => "non_manifold_boundary_vertex",
            InconsistentBoundaryOrientation => "inconsistent_boundary_orientation",
            BoundarySelfIntersection => "boundary_self_intersection",
            BoundaryOverlap => "boundary_overlap",
            WindingNumber => "winding_number",
            VolumeMismatch => "volume_mismatch",
            OffLevel => "off_level",
            OutsideGrid => "outside_grid",
            BoxTriangleOffBox => "box_triangle_off_box",
            RegionCount => "region_count",
            UnlistedInterface => "unlisted_interface",
            InterfaceNotBetweenRegions => "interface_not_between_regions",
        }
    }
}

/// One kind of problem: how often it was found, and the first few examples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Problem {
    /// What was found.
    pub kind: ProblemKind,
    /// How many times (tets, faces, pairs, points, triangles: see the kind).
    pub count: usize,
    /// The ids of the first examples, in the order found (see the kind for what they name).
    pub examples: Vec<Vec<usize>>,
}

/// Problems gathered by the checks, one entry per kind in the order first found.
pub(crate) struct Problems {
    max_examples: usize,
    list: Vec<Problem>,
}

impl Problems {
    fn new(max_examples: usize) -> Self {
        Problems {
            max_examples,
            list: Vec::new(),
        }
    }

    /// Records one more problem of `kind`, with its ids.
    pub(crate) fn add(&mut self, kind: ProblemKind, ids: Vec<usize>) {
        let i = match self.list.iter().position(|p| p.kind == kind) {
            Some(i) => i,
            None => {
                self.list.push(Problem {
                    kind,
                    count: 0,
                    examples: Vec::new(),
                });
                self.list.len() - 1
            }
        };
        let p = &mut self.list[i];
        p.count += 1;
        if p.examples.len() < self.max_examples {
            p.examples.push(ids);
        }
    }

    /// Problems recorded so far, all kinds.
    pub(crate) fn total(&self) -> usize {
        self.list.iter().map(|p| p.count).sum()
    }
}

/// What [`check_mesh`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CheckReport {
    /// No problem found.
    pub valid: bool,
    /// Points, tets and boundary faces (faces of one tet) of the mesh.
    pub points: usize,
    /// See `points`.
    pub tets: usize,
    /// See `points`.
    pub boundary_faces: usize,
    /// Sum of the signed tet volumes.
    pub volume: f64,
    /// Volume enclosed by the labelled boundary triangles (divergence theorem), or by the
    /// faces of one tet when the mesh lists none; equals `volume` for a conforming mesh.
    pub enclosed_volume: f64,
    /// Betti numbers `[b0, b1, b2]`, when the boundary is a closed manifold.
    pub betti: Option<[usize; 3]>,
    /// The winding numbers at the sampled tet centroids (`None` when the checks before did
    /// not get that far).
    pub winding: Option<WindingSummary>,
    /// The level-set distances (with a grid).
    pub level: Option<LevelSummary>,
    /// Every problem found, one entry per kind.
    pub problems: Vec<Problem>,
}

impl CheckReport {
    /// Whether a problem of `kind` was found.
    pub fn has(&self, kind: ProblemKind) -> bool {
        self.problems.iter().any(|p| p.kind == kind)
    }

    /// The kinds found, sorted.
    pub fn kinds(&self) -> Vec<ProblemKind> {
        let mut k: Vec<ProblemKind> = self.problems.iter().map(|p| p.kind).collect();
        k.sort_unstable();
        k
    }

    /// One line: `valid`, or the count of each problem kind.
    pub fn summary_line(&self) -> String {
        if self.valid {
            return "valid".into();
        }
        let parts: Vec<String> = self
            .problems
            .iter()
            .map(|p| format!("{} {}", p.count, p.kind.name()))
            .collect();
        parts.join(", ")
    }
}

/// Relative tolerance between the tets' volume and the enclosed volume.
const VOLUME_TOLERANCE: f64 = 1e-9;

/// Checks `mesh` (see the module documentation for what). Works on any mesh: indices out of
/// range, non-finite points and a label list of the wrong length are reported, not assumed
/// away; checks that need what an earlier one found broken are skipped (their fields `None`).
pub fn check_mesh(mesh: &TetMesh, opts: &CheckOptions) -> CheckReport {
    let mut problems = Problems::new(opts.max_examples);
    let mut report = CheckReport {
        valid: false,
        points: mesh.points.len(),
        tets: mesh.tets.len(),
        boundary_faces: 0,
        volume: 0.0,
        enclosed_volume: 0.0,
        betti: None,
        winding: None,
        level: None,
        problems: Vec::new(),
    };
    if !basics(mesh, &mut problems) {
        report.problems = problems.list;
        return report;
    }
    conformity::orientation(mesh, &mut problems);
    let faces = conformity::faces(mesh, &mut problems);
    let labels_ok = mesh.boundary_labels.len() == mesh.boundary.len();
    if !mesh.boundary.is_empty() && labels_ok {
        conformity::labelled(mesh, &faces, &mut problems);
    }
    regions::regions(mesh, &mut problems);
    report.boundary_faces = faces.len();
    let ids: Vec<[u32; 3]> = faces.iter().map(|f| f.tri).collect();
    let tet_of: Vec<u32> = faces.iter().map(|f| f.tet).collect();
    let closed = boundary::manifold(&ids, &mut problems);
    if closed {
        report.betti = Some(crate::topology::betti_with_boundary(mesh, &ids));
    }
    report.volume = mesh.volume();
    report.enclosed_volume = if mesh.boundary.is_empty() {
        enclosed(mesh, &ids)
    } else {
        enclosed(mesh, &mesh.boundary)
    };
    let scale = magnitude(mesh);
    if (report.volume - report.enclosed_volume).abs() > VOLUME_TOLERANCE * scale {
        problems.add(ProblemKind::VolumeMismatch, Vec::new());
    }
    let pos: Vec<[[f64; 3]; 3]> = ids
        .par_iter()
        .map(|t| t.map(|v| mesh.points[v as usize]))
        .collect();
    let buckets = buckets::Buckets::new(&pos);
    intersect::self_intersections(&ids, &pos, &tet_of, &buckets, &mut problems);
    let samples = winding_samples(mesh, opts.winding_samples);
    report.winding = Some(winding::winding(
        &samples,
        &pos,
        &buckets,
        closed,
        opts.gwn_budget,
        &mut problems,
    ));
    let points = opts.level_points.unwrap_or(&mesh.points);
    if let Some(grid) = opts.grid.filter(|_| points.len() == mesh.points.len()) {
        if labels_ok {
            report.level = Some(level::level_distance(
                (mesh, points),
                grid,
                &opts.levels,
                opts.level_distance_bound,
                &mut problems,
            ));
        }
    }
    report.valid = problems.list.is_empty();
    report.problems = problems.list;
    report
}

/// The faces of one tet of `mesh` (its boundary as its tets give it), each oriented out of
/// its tet when the tet is positive, in the checker's order. Every index must be in range.
pub(crate) fn boundary_faces(mesh: &TetMesh) -> Vec<[u32; 3]> {
    let mut scratch = Problems::new(0);
    conformity::faces(mesh, &mut scratch)
        .into_iter()
        .map(|f| f.tri)
        .collect()
}

/// Indices in range, points finite, labels as many as triangles, not too many tets; false
/// when the other checks cannot run.
fn basics(mesh: &TetMesh, problems: &mut Problems) -> bool {
    let n = mesh.points.len();
    let before = problems.total();
    if mesh.tets.len() >= 1 << 30 {
        problems.add(ProblemKind::TooLarge, vec![mesh.tets.len()]);
    }
    let bad_tets: Vec<usize> = (0..mesh.tets.len())
        .into_par_iter()
        .filter(|&t| mesh.tets[t].iter().any(|&v| v as usize >= n))
        .collect();
    let bad_tris: Vec<usize> = (0..mesh.boundary.len())
        .into_par_iter()
        .filter(|&t| mesh.boundary[t].iter().any(|&v| v as usize >= n))
        .collect();
    for t in bad_tets.into_iter().chain(bad_tris) {
        problems.add(ProblemKind::BadIndex, vec![t]);
    }
    let bad_points: Vec<usize> = (0..n)
        .into_par_iter()
        .filter(|&p| mesh.points[p].iter().any(|x| !x.is_finite()))
        .collect();
    for p in bad_points {
        problems.add(ProblemKind::NonFinitePoint, vec![p]);
    }
    let fatal = problems.total() > before;
    if mesh.boundary_labels.len() != mesh.boundary.len() {
        problems.add(
            ProblemKind::LabelCount,
            vec![mesh.boundary_labels.len(), mesh.boundary.len()],
        );
    }
    !fatal
}

/// Volume enclosed by the outward triangles `tris` (divergence theorem), about the centre of
/// the points' box for accuracy, summed in fixed blocks (deterministic).
fn enclosed(mesh: &TetMesh, tris: &[[u32; 3]]) -> f64 {
    let c = centre(&mesh.points);
    let parts: Vec<f64> = tris
        .par_chunks(1 << 14)
        .map(|ch| {
            ch.iter()
                .map(|t| {
                    let [a, b, d] = t.map(|v| mesh.points[v as usize]);
                    crate::geom::signed_volume(c, a, b, d)
                })
                .sum()
        })
        .collect();
    parts.iter().sum()
}

/// Sum of the tets' absolute volumes, in fixed blocks (deterministic).
fn magnitude(mesh: &TetMesh) -> f64 {
    let parts: Vec<f64> = mesh
        .tets
        .par_chunks(1 << 14)
        .map(|ch| {
            ch.iter()
                .map(|t| {
                    let [a, b, c, d] = t.map(|v| mesh.points[v as usize]);
                    crate::geom::signed_volume(a, b, c, d).abs()
                })
                .sum()
        })
        .collect();
    parts.iter().sum()
}

/// Centre of the bounding box of `points`.
fn centre(points: &[[f64; 3]]) -> [f64; 3] {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if points.is_empty() {
        return [0.0; 3];
    }
    [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]))
}

/// Every k-th tet's centroid, `(tet, point)`, at most about `max` of them (all tets when the
/// mesh has no more).
fn winding_samples(mesh: &TetMesh, max: usize) -> Vec<(usize, [f64; 3])> {
    let step = mesh.tets.len().div_ceil(max.max(1)).max(1);
    (0..mesh.tets.len())
        .step_by(step)
        .map(|t| {
            let p = mesh.tets[t].map(|v| mesh.points[v as usize]);
            (
                t,
                [0, 1, 2].map(|k| 0.25 * (p[0][k] + p[1][k] + p[2][k] + p[3][k])),
            )
        })
        .collect()
}
