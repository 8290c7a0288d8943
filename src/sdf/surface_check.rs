//! What a triangle surface is like before its signed distance is sampled: holes (boundary
//! loops, with the length of the longest), non-manifold and inconsistently oriented edges,
//! zero-area triangles, the area and enclosed volume. The edges are the triangles' directed
//! edges sorted by their undirected key; an edge of one triangle is a boundary edge, of more
//! than two a non-manifold edge.

use super::SdfError;
use crate::geom::{cross, dot, sub};
use crate::union_find::UnionFind;

/// What [`check_surface`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceFacts {
    /// Number of points.
    pub points: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Triangles of zero area (repeated corners, or corners on one line up to rounding).
    pub degenerate_triangles: usize,
    /// Edges of exactly one triangle.
    pub boundary_edges: usize,
    /// Boundary loops: connected sets of boundary edges (0 for a closed surface).
    pub holes: usize,
    /// Length of the longest boundary loop, in the surface's units (0 without holes).
    pub largest_hole: f64,
    /// Edges of more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges of two triangles that run along it in the same direction (the triangles'
    /// orientations disagree).
    pub misoriented_edges: usize,
    /// Every edge is run as often in one direction as in the other: the generalised winding
    /// number is an integer, constant between the triangles (true for closed, consistently
    /// oriented surfaces, even self-intersecting or non-manifold ones).
    pub closed: bool,
    /// Total area.
    pub area: f64,
    /// Signed enclosed volume (divergence theorem); negative for a closed surface whose
    /// triangles face inwards.
    pub volume: f64,
    /// Lower and upper corners of the points' box.
    pub bounds: [[f64; 3]; 2],
    /// Connected pieces of the surface (triangles joined through shared corners).
    pub components: usize,
    /// Pairs of triangles that cross or overlap each other ([`crate::check::crossing_pairs`]):
    /// the surface intersects itself.
    pub crossing_pairs: usize,
}

impl SurfaceFacts {
    /// Whether the surface is closed, manifold and consistently oriented.
    pub fn is_watertight(&self) -> bool {
        self.closed && self.non_manifold_edges == 0 && self.misoriented_edges == 0
    }

    /// What the solid meshed from a watertight surface that does not cross itself, with
    /// Betti numbers `betti` on a grid of voxels `voxel` wide, says about the sampling: each
    /// piece of such a surface bounds a component of the solid or one of its cavities, so
    /// `b0 + b2` must equal [`SurfaceFacts::components`]; fewer means that pieces closer than
    /// about a voxel merged (or a part thinner than that vanished), more that a part thinner
    /// than a voxel broke (a finer grid keeps them). `None` when they agree or the surface is
    /// not such a surface.
    pub fn sampling_warning(&self, betti: [usize; 3], voxel: f64) -> Option<String> {
        let found = betti[0] + betti[2];
        if !self.is_watertight() || self.crossing_pairs > 0 || found == self.components {
            return None;
        }
        let why = if found < self.components {
            "pieces of the surface closer together than about a voxel merged, or a part \
             thinner than that vanished"
        } else {
            "a part of the solid thinner than about a voxel broke apart"
        };
        Some(format!(
            "the surface has {} closed piece{} but the mesh has {} component{} and {} \
             cavit{} (Betti numbers {betti:?}): on this grid of voxels {} wide, {why}",
            self.components,
            plural(self.components),
            betti[0],
            plural(betti[0]),
            betti[2],
            if betti[2] == 1 { "y" } else { "ies" },
            short(voxel)
        ))
    }

    /// One line per thing worth a warning (open surface, non-manifold or misoriented edges,
    /// degenerate triangles, inward orientation); empty for a clean closed surface.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        let s = plural;
        if self.holes > 0 {
            w.push(format!(
                "the surface is open: {} hole{} ({} boundary edge{}), the longest boundary {} long; \
                 inside and outside are told by the winding number",
                self.holes,
                s(self.holes),
                self.boundary_edges,
                s(self.boundary_edges),
                short(self.largest_hole)
            ));
        }
        if self.non_manifold_edges > 0 {
            let n = self.non_manifold_edges;
            w.push(format!(
                "{n} non-manifold edge{} (of more than two triangles)",
                s(n)
            ));
        }
        if self.misoriented_edges > 0 {
            let n = self.misoriented_edges;
            w.push(format!(
                "{n} edge{} where neighbouring triangles disagree in orientation",
                s(n)
            ));
        }
        if self.degenerate_triangles > 0 {
            let n = self.degenerate_triangles;
            w.push(format!("{n} degenerate (zero-area) triangle{}", s(n)));
        }
        if self.crossing_pairs > 0 {
            let n = self.crossing_pairs;
            w.push(format!(
                "the surface intersects itself ({n} pair{} of triangles cross); the solid is \
                 where the winding number is at least one half, so overlapping parts are joined",
                s(n)
            ));
        }
        if self.volume < 0.0 {
            w.push(
                "the triangles face inwards; the surface is read with the opposite orientation"
                    .into(),
            );
        }
        w
    }
}

/// `"s"` unless `n` is 1.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// Four significant digits.
fn short(x: f64) -> String {
    format!("{}", (x * 1e4).round() / 1e4)
        .chars()
        .take(12)
        .collect()
}

/// Checks a surface and gathers its [`SurfaceFacts`].
///
/// # Errors
/// [`SdfError::Surface`] when the surface has no triangles, a triangle names a missing point,
/// a point has a coordinate that is not finite, or every triangle has zero area.
pub fn check_surface(
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<SurfaceFacts, SdfError> {
    if triangles.is_empty() {
        return Err(SdfError::Surface("the surface has no triangles".into()));
    }
    if let Some(t) = triangles
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= points.len()))
    {
        return Err(SdfError::Surface(format!(
            "triangle {} names a point that does not exist",
            t + 1
        )));
    }
    if let Some(p) = points.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
        return Err(SdfError::Surface(format!(
            "point {} has a coordinate that is not finite",
            p + 1
        )));
    }
    let mut facts = SurfaceFacts {
        points: points.len(),
        triangles: triangles.len(),
        ..SurfaceFacts::default()
    };
    measure(points, triangles, &mut facts);
    if facts.degenerate_triangles == triangles.len() {
        return Err(SdfError::Surface(
            "every triangle of the surface has zero area".into(),
        ));
    }
    edges(points, triangles, &mut facts);
    facts.components = components(points.len(), triangles);
    facts.crossing_pairs = crate::check::crossing_pairs(points, triangles);
    Ok(facts)
}

/// Area, volume, bounds and degenerate triangles.
fn measure(points: &[[f64; 3]], triangles: &[[u32; 3]], f: &mut SurfaceFacts) {
    let mut bounds = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for t in triangles {
        let [a, b, c] = t.map(|i| points[i as usize]);
        for p in [a, b, c] {
            for k in 0..3 {
                bounds[0][k] = bounds[0][k].min(p[k]);
                bounds[1][k] = bounds[1][k].max(p[k]);
            }
        }
        let (ab, ac) = (sub(b, a), sub(c, a));
        let n = cross(ab, ac);
        let twice_area = dot(n, n).sqrt();
        let longest2 = dot(ab, ab).max(dot(ac, ac)).max(dot(sub(c, b), sub(c, b)));
        if twice_area <= 1e-12 * longest2 || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            f.degenerate_triangles += 1;
        }
        f.area += 0.5 * twice_area;
        f.volume += dot(a, cross(b, c)) / 6.0;
    }
    f.bounds = bounds;
}

/// Connected pieces of the triangles, through shared corners.
fn components(points: usize, triangles: &[[u32; 3]]) -> usize {
    let mut uf = UnionFind::new(points);
    let mut used = vec![false; points];
    for t in triangles {
        uf.union(t[0], t[1]);
        uf.union(t[1], t[2]);
        t.iter().for_each(|&i| used[i as usize] = true);
    }
    let mut roots: Vec<u32> = (0..points as u32)
        .filter(|&i| used[i as usize])
        .map(|i| uf.find(i))
        .collect();
    roots.sort_unstable();
    roots.dedup();
    roots.len()
}

/// Boundary, non-manifold and misoriented edges, holes and closedness.
fn edges(points: &[[f64; 3]], triangles: &[[u32; 3]], f: &mut SurfaceFacts) {
    // (low, high, +1 when run low → high)
    let mut e: Vec<(u32, u32, i8)> = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                e.push((a.min(b), a.max(b), if a < b { 1 } else { -1 }));
            }
        }
    }
    e.sort_unstable();
    let mut holes = UnionFind::new(points.len());
    let mut boundary: Vec<(u32, u32)> = Vec::new();
    f.closed = true;
    for group in e.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let balance: i64 = group.iter().map(|x| i64::from(x.2)).sum();
        f.closed &= balance == 0;
        match group.len() {
            1 => {
                boundary.push((group[0].0, group[0].1));
                holes.union(group[0].0, group[0].1);
            }
            2 if balance != 0 => f.misoriented_edges += 1,
            2 => {}
            _ => f.non_manifold_edges += 1,
        }
    }
    f.boundary_edges = boundary.len();
    let mut length: rustc_hash::FxHashMap<u32, f64> = Default::default();
    for &(a, b) in &boundary {
        let d = sub(points[a as usize], points[b as usize]);
        *length.entry(holes.find(a)).or_default() += dot(d, d).sqrt();
    }
    f.holes = length.len();
    f.largest_hole = length.values().copied().fold(0.0, f64::max);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron, outward.
    fn tet() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (p, t)
    }

    #[test]
    fn closed_tetrahedron() {
        let (p, t) = tet();
        let f = check_surface(&p, &t).unwrap();
        assert!(f.is_watertight() && f.warnings().is_empty(), "{f:?}");
        assert!((f.volume - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!((f.components, f.crossing_pairs), (1, 0));
        assert_eq!(f.sampling_warning([1, 0, 0], 0.1), None);
        let merged = f.sampling_warning([0, 0, 0], 0.1).unwrap();
        assert!(
            merged.contains("1 closed piece but the mesh has 0 components"),
            "{merged}"
        );
        let broke = f.sampling_warning([2, 0, 0], 0.1).unwrap();
        assert!(broke.contains("broke apart"), "{broke}");
    }

    /// Two closed tetrahedra as one surface, the second shifted by `o`.
    fn two(o: [f64; 3]) -> SurfaceFacts {
        let (mut p, mut t) = tet();
        let (q, u) = tet();
        p.extend(q.iter().map(|x| [x[0] + o[0], x[1] + o[1], x[2] + o[2]]));
        t.extend(u.iter().map(|x| x.map(|i| i + 4)));
        check_surface(&p, &t).unwrap()
    }

    #[test]
    fn pieces_and_crossings_of_two_tetrahedra() {
        let apart = two([1.5, 0.0, 0.0]);
        assert_eq!((apart.components, apart.crossing_pairs), (2, 0));
        let overlapping = two([0.2, 0.2, 0.2]);
        assert!(overlapping.crossing_pairs > 0, "{overlapping:?}");
        assert!(overlapping.warnings()[0].contains("intersects itself"));
        // touching at a corner counts: the surface meets itself there
        assert!(two([1.0, 0.0, 0.0]).crossing_pairs > 0);
    }

    #[test]
    fn one_face_removed_is_one_hole() {
        let (p, mut t) = tet();
        t.pop();
        let f = check_surface(&p, &t).unwrap();
        assert_eq!((f.holes, f.boundary_edges, f.closed), (1, 3, false));
        assert!((f.largest_hole - 3.0 * 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(f.warnings().len(), 1);
    }

    #[test]
    fn errors_and_orientation() {
        let (p, mut t) = tet();
        assert!(check_surface(&p, &[]).is_err());
        assert!(check_surface(&p, &[[0, 1, 9]]).is_err());
        assert!(check_surface(&p, &[[0, 1, 1]]).is_err());
        t[0] = [0, 1, 2];
        let f = check_surface(&p, &t).unwrap();
        assert_eq!((f.misoriented_edges, f.closed), (3, false));
        let (_, mut t) = tet();
        for x in &mut t {
            x.swap(0, 1);
        }
        let f = check_surface(&p, &t).unwrap();
        assert!(f.volume < 0.0 && f.closed);
    }
}
