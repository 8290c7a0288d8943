//! Element-quality measures of one tetrahedron and of a whole mesh: dihedral angles, the
//! biased minimum sine that the quality pass optimises, radius ratio, Gmsh's SICN and gamma,
//! and histograms.
//!
//! Every measure takes the four corners `p` of a tetrahedron `[a, b, c, d]`, positively
//! oriented when `(b-a)·((c-a)×(d-a)) > 0`. Measures that can be signed (biased sine, SICN)
//! are negative for inverted elements.

use nalgebra::{Matrix3, Point3};
use rayon::prelude::*;
use serde::Serialize;

use crate::geom::{cross, dot, signed_volume, sub};
use crate::mesh::TetMesh;

/// Edge `(i, j)` of a tet and the two other corners `(k, l)`: the dihedral angle at edge
/// `(i, j)` lies between the faces opposite `k` and `l`.
pub const TET_EDGES: [(usize, usize, usize, usize); 6] = [
    (0, 1, 2, 3),
    (0, 2, 1, 3),
    (0, 3, 1, 2),
    (1, 2, 0, 3),
    (1, 3, 0, 2),
    (2, 3, 0, 1),
];

/// Outward area normals of the faces opposite each corner (length twice the face area) of a
/// positively oriented tet (inward for an inverted one).
#[inline]
fn face_normals(p: &[[f64; 3]; 4]) -> [[f64; 3]; 4] {
    [
        cross(sub(p[2], p[1]), sub(p[3], p[1])),
        cross(sub(p[3], p[0]), sub(p[2], p[0])),
        cross(sub(p[1], p[0]), sub(p[3], p[0])),
        cross(sub(p[2], p[0]), sub(p[1], p[0])),
    ]
}

/// Cosines of the six dihedral angles, in [`TET_EDGES`] order (the angle grows as the cosine
/// falls). Degenerate faces give a cosine of 1 (angle 0).
#[inline]
pub fn dihedral_cosines(p: [[f64; 3]; 4]) -> [f64; 6] {
    let n = face_normals(&p);
    TET_EDGES.map(|(_, _, k, l)| {
        let d = (dot(n[k], n[k]) * dot(n[l], n[l])).sqrt();
        if d > 0.0 {
            (-dot(n[k], n[l]) / d).clamp(-1.0, 1.0)
        } else {
            1.0
        }
    })
}

/// The six dihedral angles of a tet in degrees, in [`TET_EDGES`] order.
pub fn dihedral_angles(p: [[f64; 3]; 4]) -> [f64; 6] {
    dihedral_cosines(p).map(|c| c.acos().to_degrees())
}

/// Smallest and largest dihedral angle of one tet, in degrees.
pub fn tet_dihedral_range(p: [[f64; 3]; 4]) -> (f64, f64) {
    let c = dihedral_cosines(p);
    let hi = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lo = c.iter().copied().fold(f64::INFINITY, f64::min);
    (hi.acos().to_degrees(), lo.acos().to_degrees())
}

/// The minimum over the six dihedral angles θ of `sin θ`, with the sines of obtuse angles
/// multiplied by `obtuse_weight` (≤ 1), so that large angles count as bad as small ones at the
/// chosen balance: with `obtuse_weight = sin(θ_min) / sin(180° − θ_max)`, an angle of
/// `θ_min` and one of `θ_max` score the same. Negative for inverted tets, 0 for flat ones.
/// This is the objective of the quality pass (Klingner and Shewchuk's biased minimum sine).
///
/// The hot path of the pass. At edge `ij`, `sin² θ = (6V)² |e_ij|² / (|n_k|² |n_l|²)` with
/// `n_k`, `n_l` the area normals of the two faces at the edge (those opposite the other two
/// corners); since `|n_k|² |n_l|² = P / (|n_i|² |n_j|²)` with `P` the product of all four,
/// the smallest of `|e_ij|² |n_i|² |n_j|²` over `P` is found with one division. Where `P`
/// is zero or leaves the normal range (a flat face, or lengths far from 1), the same measure
/// is taken edge by edge (`biased_min_sine_by_edge`).
#[inline]
pub fn biased_min_sine(p: [[f64; 3]; 4], obtuse_weight: f64) -> f64 {
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    // Inward area normals of the faces opposite corners 1, 2, 3 of a positive tet; the four
    // of a closed surface sum to zero.
    let (m1, m2, m3) = (cross(b, c), cross(c, a), cross(a, b));
    let m0 = [0, 1, 2].map(|i| -(m1[i] + m2[i] + m3[i]));
    let m = [m0, m1, m2, m3];
    let n2 = m.map(|x| dot(x, x));
    let product = n2[0] * n2[1] * n2[2] * n2[3];
    if !product.is_normal() {
        return biased_min_sine_by_edge(p, obtuse_weight);
    }
    let six_v = dot(a, m1);
    let e = [a, b, c, sub(b, a), sub(c, a), sub(c, b)];
    let w = [1.0, obtuse_weight * obtuse_weight];
    let mut q2 = f64::INFINITY;
    for (e, (i, j, k, l)) in e.iter().zip(TET_EDGES) {
        // Both normals inward: the angle is obtuse when they point the same way.
        let s2 = dot(*e, *e) * n2[i] * n2[j] * w[(dot(m[k], m[l]) > 0.0) as usize];
        q2 = if s2 < q2 { s2 } else { q2 };
    }
    six_v * (q2 / product).sqrt()
}

/// [`biased_min_sine`] edge by edge, with a division per edge: for flat faces and for
/// lengths whose products of four squared areas would overflow or underflow.
fn biased_min_sine_by_edge(p: [[f64; 3]; 4], obtuse_weight: f64) -> f64 {
    let n = face_normals(&p);
    let n2 = n.map(|x| dot(x, x));
    let six_v = 6.0 * signed_volume(p[0], p[1], p[2], p[3]);
    // Minimise sin² θ = (6V)² |e|² / (|n_k|² |n_l|²) and take one square root at the end.
    let w2 = obtuse_weight * obtuse_weight;
    let mut q2 = f64::INFINITY;
    for (i, j, k, l) in TET_EDGES {
        let e = sub(p[j], p[i]);
        let d = n2[k] * n2[l];
        if d <= 0.0 {
            return 0.0_f64.min(six_v);
        }
        let mut s2 = dot(e, e) / d;
        if dot(n[k], n[l]) > 0.0 {
            s2 *= w2;
        }
        q2 = q2.min(s2);
    }
    six_v * q2.sqrt()
}

/// Radius ratio `3 r_in / r_circ`: 1 for the regular tetrahedron, 0 for a flat one, negative
/// for an inverted one.
pub fn radius_ratio(p: [[f64; 3]; 4]) -> f64 {
    let v = signed_volume(p[0], p[1], p[2], p[3]);
    let n = face_normals(&p);
    let area: f64 = n.iter().map(|x| 0.5 * dot(*x, *x).sqrt()).sum();
    if area <= 0.0 {
        return 0.0;
    }
    let r_in = 3.0 * v.abs() / area;
    // Circumradius: |a|² (b×c) + |b|² (c×a) + |c|² (a×b) over 12 V, edges from corner 0.
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let num = [0, 1, 2].map(|i| {
        dot(a, a) * cross(b, c)[i] + dot(b, b) * cross(c, a)[i] + dot(c, c) * cross(a, b)[i]
    });
    if v == 0.0 {
        return 0.0;
    }
    let r_circ = dot(num, num).sqrt() / (12.0 * v.abs());
    (3.0 * r_in / r_circ).copysign(v)
}

/// Gmsh's signed inverse condition number (`minSICN`): the inverse of the condition number of
/// the map from the regular tetrahedron onto this one, with the sign of the volume. 1 for the
/// regular tetrahedron, 0 for a flat one, negative for an inverted one.
pub fn sicn(p: [[f64; 3]; 4]) -> f64 {
    // Regular tet with corners 0, e_x, (1/2, √3/2, 0), (1/2, √3/6, √(2/3)): J = E W⁻¹ where E
    // holds the edge vectors from corner 0 (columns) and W those of the regular tet.
    let w_inv = Matrix3::new(
        1.0,
        -0.577_350_269_189_625_8,
        -0.408_248_290_463_863,
        0.0,
        1.154_700_538_379_251_7,
        -0.408_248_290_463_863,
        0.0,
        0.0,
        1.224_744_871_391_589,
    );
    let e = Matrix3::from_columns(&[1, 2, 3].map(|k| Point3::from(p[k]) - Point3::from(p[0])));
    let j = e * w_inv;
    let det = j.determinant();
    // ||J||_F ||J⁻¹||_F = ||J||_F ||adj J||_F / |det J|: the adjugate's entries are J's 2×2
    // minors (squared, their signs do not matter). Both sums run over the entries row by row.
    let fro2: f64 = j.transpose().iter().map(|x| x * x).sum();
    let minor = |r: usize, c: usize| j.remove_row(r).remove_column(c).determinant();
    let adj2: f64 = (0..9).map(|i| minor(i / 3, i % 3).powi(2)).sum();
    if det == 0.0 || adj2 == 0.0 {
        return 0.0;
    }
    3.0 * det / (fro2 * adj2).sqrt()
}

/// Gmsh's gamma: inscribed radius over longest edge, normalised so that the regular
/// tetrahedron scores 1 (`gamma = 2√6 · r_in / l_max`), with the sign of the volume.
pub fn gamma(p: [[f64; 3]; 4]) -> f64 {
    let v = signed_volume(p[0], p[1], p[2], p[3]);
    let n = face_normals(&p);
    let area: f64 = n.iter().map(|x| 0.5 * dot(*x, *x).sqrt()).sum();
    let l_max = TET_EDGES
        .iter()
        .map(|&(i, j, _, _)| dot(sub(p[j], p[i]), sub(p[j], p[i])))
        .fold(0.0, f64::max)
        .sqrt();
    if area <= 0.0 || l_max <= 0.0 {
        return 0.0;
    }
    let r_in = 3.0 * v / area;
    2.0 * 6.0_f64.sqrt() * r_in / l_max
}

/// Smallest and largest dihedral angle over all tets, in degrees (`None` for an empty mesh).
/// Works on cosines and takes two arc cosines at the end.
pub fn dihedral_range(mesh: &TetMesh) -> Option<(f64, f64)> {
    mesh.tets
        .par_iter()
        .map(|t| cosine_extremes(t.map(|i| mesh.points[i as usize])))
        .reduce_with(widest)
        .map(cosines_to_degrees)
}

/// Largest and smallest dihedral cosine of one tet (its smallest and largest angle).
#[inline]
pub(crate) fn cosine_extremes(p: [[f64; 3]; 4]) -> (f64, f64) {
    dihedral_cosines(p)
        .iter()
        .fold(NO_COSINES, |(hi, lo), &c| (hi.max(c), lo.min(c)))
}

/// The cosine extremes of no tet (the identity of [`widest`]).
pub(crate) const NO_COSINES: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);

/// Both ranges of cosine extremes together.
pub(crate) fn widest(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0.max(b.0), a.1.min(b.1))
}

/// (smallest, largest) dihedral angle in degrees from the cosine extremes.
pub(crate) fn cosines_to_degrees((cos_max, cos_min): (f64, f64)) -> (f64, f64) {
    (cos_max.acos().to_degrees(), cos_min.acos().to_degrees())
}

/// Number of histogram bins of dihedral angles (one per degree, 0° to 180°).
pub const HISTOGRAM_BINS: usize = 180;

/// Quality summary of a whole mesh.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct QualitySummary {
    /// Number of tetrahedra.
    pub tets: usize,
    /// Smallest dihedral angle (degrees).
    pub min_dihedral: f64,
    /// Largest dihedral angle (degrees).
    pub max_dihedral: f64,
    /// Smallest radius ratio `3 r_in / r_circ`.
    pub min_radius_ratio: f64,
    /// Smallest SICN (Gmsh's `minSICN`).
    pub min_sicn: f64,
    /// Smallest gamma (Gmsh's `gamma`).
    pub min_gamma: f64,
    /// Tetrahedra whose smallest dihedral angle is below 5°, 10°, 15° and 20°.
    pub below: [usize; 4],
    /// Tetrahedra whose largest dihedral angle is above 150°, 155°, 160° and 170°.
    pub above: [usize; 4],
    /// Counts of all dihedral angles (6 per tet) per whole degree, `[0, 1)`, …, `[179, 180]`.
    pub histogram: Vec<u64>,
}

/// Angles (degrees) reported in [`QualitySummary::below`].
pub const BELOW_ANGLES: [f64; 4] = [5.0, 10.0, 15.0, 20.0];
/// Angles (degrees) reported in [`QualitySummary::above`].
pub const ABOVE_ANGLES: [f64; 4] = [150.0, 155.0, 160.0, 170.0];

impl QualitySummary {
    /// The summary of no tet, to [`QualitySummary::add`] tets to (its extremes are the
    /// identities of min and max).
    fn empty() -> Self {
        QualitySummary {
            min_dihedral: f64::INFINITY,
            max_dihedral: f64::NEG_INFINITY,
            min_radius_ratio: f64::INFINITY,
            min_sicn: f64::INFINITY,
            min_gamma: f64::INFINITY,
            histogram: vec![0; HISTOGRAM_BINS],
            ..Default::default()
        }
    }

    /// Adds the tet with corners `p` (in place: a whole mesh is summed without a summary per
    /// tet).
    fn add(mut self, p: [[f64; 3]; 4]) -> Self {
        self.tets += 1;
        self.min_radius_ratio = self.min_radius_ratio.min(radius_ratio(p));
        self.min_sicn = self.min_sicn.min(sicn(p));
        self.min_gamma = self.min_gamma.min(gamma(p));
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for a in dihedral_angles(p) {
            lo = lo.min(a);
            hi = hi.max(a);
            self.histogram[(a as usize).min(HISTOGRAM_BINS - 1)] += 1;
        }
        self.min_dihedral = self.min_dihedral.min(lo);
        self.max_dihedral = self.max_dihedral.max(hi);
        for (i, t) in BELOW_ANGLES.iter().enumerate() {
            self.below[i] += usize::from(lo < *t);
        }
        for (i, t) in ABOVE_ANGLES.iter().enumerate() {
            self.above[i] += usize::from(hi > *t);
        }
        self
    }

    fn merge(mut self, o: Self) -> Self {
        if o.tets == 0 {
            return self;
        }
        if self.tets == 0 {
            return o;
        }
        self.tets += o.tets;
        self.min_dihedral = self.min_dihedral.min(o.min_dihedral);
        self.max_dihedral = self.max_dihedral.max(o.max_dihedral);
        self.min_radius_ratio = self.min_radius_ratio.min(o.min_radius_ratio);
        self.min_sicn = self.min_sicn.min(o.min_sicn);
        self.min_gamma = self.min_gamma.min(o.min_gamma);
        for i in 0..4 {
            self.below[i] += o.below[i];
            self.above[i] += o.above[i];
        }
        for (a, b) in self.histogram.iter_mut().zip(&o.histogram) {
            *a += b;
        }
        self
    }
}

/// Quality summary of `mesh`, computed in parallel; independent of the thread count (every
/// field is a minimum, a maximum or an integer count). Each thread sums its tets into one
/// summary; the summaries are then merged.
pub fn summarize(mesh: &TetMesh) -> QualitySummary {
    let s = mesh
        .tets
        .par_iter()
        .fold(QualitySummary::empty, |s, t| {
            s.add(t.map(|i| mesh.points[i as usize]))
        })
        .reduce(QualitySummary::empty, QualitySummary::merge);
    // No tet: the summary of nothing, as before (zeros, no histogram).
    if s.tets == 0 {
        QualitySummary::default()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SICN as it was written out by hand: `nalgebra` gives the same bits.
    fn sicn_by_hand(p: [[f64; 3]; 4]) -> f64 {
        const W_INV: [[f64; 3]; 3] = [
            [1.0, -0.577_350_269_189_625_8, -0.408_248_290_463_863],
            [0.0, 1.154_700_538_379_251_7, -0.408_248_290_463_863],
            [0.0, 0.0, 1.224_744_871_391_589],
        ];
        let e = [sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0])];
        let j: [[f64; 3]; 3] = std::array::from_fn(|r| {
            std::array::from_fn(|c| (0..3).map(|k| e[k][r] * W_INV[k][c]).sum())
        });
        let det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
            - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
            + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
        let fro2: f64 = j.iter().flatten().map(|x| x * x).sum();
        let cof = |r: usize, c: usize| {
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
            j[r1][c1] * j[r2][c2] - j[r1][c2] * j[r2][c1]
        };
        let adj2: f64 = (0..9).map(|i| cof(i / 3, i % 3).powi(2)).sum();
        if det == 0.0 || adj2 == 0.0 {
            return 0.0;
        }
        3.0 * det / (fro2 * adj2).sqrt()
    }

    #[test]
    fn sicn_keeps_the_bits_of_the_cofactor_formula() {
        let mut next = crate::algebra::tests::uniform_signed();
        for _ in 0..2000 {
            let p: [[f64; 3]; 4] = std::array::from_fn(|_| [next(), next(), next()]);
            assert_eq!(sicn(p).to_bits(), sicn_by_hand(p).to_bits());
        }
        let flat = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        assert_eq!(sicn(flat), 0.0);
    }

    fn regular() -> [[f64; 3]; 4] {
        [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ]
    }

    fn orient(mut p: [[f64; 3]; 4]) -> [[f64; 3]; 4] {
        if signed_volume(p[0], p[1], p[2], p[3]) < 0.0 {
            p.swap(0, 1);
        }
        p
    }

    #[test]
    fn range_matches_per_tet_angles() {
        let mesh = TetMesh {
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
        };
        let all: Vec<f64> = mesh
            .tets
            .iter()
            .flat_map(|t| dihedral_angles(t.map(|i| mesh.points[i as usize])))
            .collect();
        let (lo, hi) = dihedral_range(&mesh).unwrap();
        let want_lo = all.iter().cloned().fold(f64::INFINITY, f64::min);
        let want_hi = all.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        assert!(
            (lo - want_lo).abs() < 1e-9 && (hi - want_hi).abs() < 1e-9,
            "{lo} {hi} vs {want_lo} {want_hi}"
        );
        assert!((lo - 54.735_610_317_245_35).abs() < 1e-9, "{lo}"); // corner tet: arctan(sqrt 2)
        assert!((hi - 90.0).abs() < 1e-9, "{hi}");
    }

    #[test]
    fn regular_tet_scores_one_everywhere() {
        let p = orient(regular());
        let want = (1.0_f64 / 3.0).acos().to_degrees();
        for a in dihedral_angles(p) {
            assert!((a - want).abs() < 1e-9, "{a}");
        }
        assert!((radius_ratio(p) - 1.0).abs() < 1e-12);
        assert!((sicn(p) - 1.0).abs() < 1e-12, "{}", sicn(p));
        assert!((gamma(p) - 1.0).abs() < 1e-12, "{}", gamma(p));
        let s = (8.0_f64 / 9.0).sqrt();
        assert!((biased_min_sine(p, 1.0) - s).abs() < 1e-12);
    }

    #[test]
    fn inverted_tets_are_negative() {
        let mut p = orient(regular());
        p.swap(0, 1);
        assert!(radius_ratio(p) < 0.0 && sicn(p) < 0.0 && gamma(p) < 0.0);
        assert!(biased_min_sine(p, 0.6) < 0.0);
    }

    #[test]
    fn kuhn_tet_is_an_orthoscheme() {
        // One tet of the 6-fold cube split along the diagonal 0–7.
        let p = orient([[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0]]);
        let mut a = dihedral_angles(p).map(|x| (x * 1e6).round() / 1e6);
        a.sort_by(f64::total_cmp);
        assert_eq!(a, [45.0, 45.0, 60.0, 90.0, 90.0, 90.0]);
        let (lo, hi) = tet_dihedral_range(p);
        assert!((lo - 45.0).abs() < 1e-9 && (hi - 90.0).abs() < 1e-9);
        // Sine of the smallest angle (45°) is the minimum; 90° has sine 1.
        assert!((biased_min_sine(p, 0.5) - 0.5_f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn biased_sine_weighs_obtuse_angles() {
        // A flat-ish "cap" tet: apex just above the centroid of a triangle has three obtuse
        // dihedral angles near 180°.
        let h = 0.05;
        let p = orient([
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 0.9, 0.0],
            [0.5, 0.3, h],
        ]);
        let (_, hi) = tet_dihedral_range(p);
        assert!(hi > 150.0);
        let s = (180.0 - hi).to_radians().sin();
        let q = biased_min_sine(p, 0.5);
        assert!(
            (q - 0.5 * s).abs() < 1e-9 || q < 0.5 * s,
            "{q} vs {}",
            0.5 * s
        );
    }

    /// The biased minimum sine from the six dihedral cosines: the sine of each angle, times
    /// the weight where it is obtuse, the smallest, with the sign of the volume.
    fn biased_sine_from_angles(p: [[f64; 3]; 4], weight: f64) -> f64 {
        let s = dihedral_cosines(p)
            .map(|c| (1.0 - c * c).max(0.0).sqrt() * if c < 0.0 { weight } else { 1.0 })
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        s.copysign(signed_volume(p[0], p[1], p[2], p[3]))
    }

    #[test]
    fn the_one_division_sine_is_the_sine_at_any_scale() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut flat, mut inverted) = (0, 0);
        for n in 0..20_000 {
            // Lengths from 1e-30 to 1e30 (the product of four squared areas leaves the normal
            // range at both ends), far from the origin, and every fifth one flat or nearly.
            let scale = 10f64.powi((n % 13) as i32 * 5 - 30);
            let mut p = [[0.0; 3]; 4];
            for c in p.iter_mut() {
                *c = [0, 1, 2].map(|_| (rand() + 3.0) * scale);
            }
            if n % 5 == 0 {
                let t = [rand(), rand()];
                let h = [0.0, 1e-9, 1e-3][n % 3] * scale;
                p[3] = [0, 1, 2]
                    .map(|i| p[0][i] + t[0] * (p[1][i] - p[0][i]) + t[1] * (p[2][i] - p[0][i]) + h);
            }
            let weight = [1.0, 0.6, 0.25][n % 3];
            let fast = biased_min_sine(p, weight);
            let by_edge = biased_min_sine_by_edge(p, weight);
            assert!(
                (fast - by_edge).abs() <= 1e-12 * by_edge.abs() + f64::MIN_POSITIVE,
                "{p:?}: {fast} against {by_edge} edge by edge"
            );
            let reference = biased_sine_from_angles(p, weight);
            if reference.abs() > 1e-3 {
                assert!(
                    (fast - reference).abs() <= 1e-9 * reference.abs(),
                    "{p:?}: {fast} against {reference} from the angles"
                );
            }
            flat += usize::from(fast.abs() < 1e-6);
            inverted += usize::from(fast < 0.0);
        }
        // Flat and inverted tets were both among them.
        assert!(
            flat > 1000 && inverted > 5000,
            "{flat} flat, {inverted} inverted"
        );
    }

    #[test]
    fn summary_counts_and_histogram() {
        let k = [[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0]];
        let mesh = TetMesh {
            points: k.to_vec(),
            values: vec![0.0; 4],
            tets: vec![[0, 1, 2, 3]; 3],
            ..Default::default()
        };
        let m = if mesh.tet_volume(0) < 0.0 {
            TetMesh {
                tets: vec![[1, 0, 2, 3]; 3],
                ..mesh
            }
        } else {
            mesh
        };
        let s = summarize(&m);
        assert_eq!(s.tets, 3);
        assert_eq!(s.histogram.iter().sum::<u64>(), 18);
        let bins = |a: usize| s.histogram[a - 1] + s.histogram[a];
        assert_eq!((bins(45), bins(60), bins(90)), (6, 3, 9));
        assert_eq!(s.below, [0, 0, 0, 0]);
        assert!((s.min_dihedral - 45.0).abs() < 1e-9);
    }

    #[test]
    fn a_mesh_summary_is_the_sum_of_its_tets_for_any_thread_count() {
        // A wavy shell: tets of every shape the clipper makes.
        let n = 16;
        let values: Vec<f64> = (0..n * n * n)
            .map(|c| {
                let [x, y, z] = [c % n, c / n % n, c / (n * n)].map(|i| i as f64 - 7.6);
                (x * x + y * y + z * z).sqrt() + 0.4 * (1.7 * x).sin() * (1.3 * y + z).cos()
            })
            .collect();
        let grid = crate::ScalarGrid::new([n, n, n], values).unwrap();
        let opts = crate::MeshOptions::new(3.1, 6.3, crate::Method::Ctd);
        let mesh = crate::mesh_interval(&grid, &opts).unwrap().mesh;
        assert!(mesh.tets.len() > 1000);
        let ranges: Vec<(f64, f64)> = mesh
            .tets
            .iter()
            .map(|t| tet_dihedral_range(t.map(|i| mesh.points[i as usize])))
            .collect();
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        let s = pool(1).install(|| summarize(&mesh));
        assert_eq!(pool(2).install(|| summarize(&mesh)), s);
        assert_eq!(s.tets, mesh.tets.len());
        assert_eq!(s.histogram.iter().sum::<u64>(), 6 * mesh.tets.len() as u64);
        for (i, t) in BELOW_ANGLES.iter().enumerate() {
            assert_eq!(s.below[i], ranges.iter().filter(|r| r.0 < *t).count());
        }
        for (i, t) in ABOVE_ANGLES.iter().enumerate() {
            assert_eq!(s.above[i], ranges.iter().filter(|r| r.1 > *t).count());
        }
        let lo = ranges.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
        assert!(
            (s.min_dihedral - lo).abs() < 1e-9,
            "{} {lo}",
            s.min_dihedral
        );
        assert!(s.below[3] > 0, "the fixture has tets below 20°");
    }
}
