//! Element-quality measures.

use rayon::prelude::*;

use crate::geom::{cross, dot, sub};
use crate::mesh::TetMesh;

/// Edge (i, j) and the two other vertices (k, l): the dihedral angle at edge (i, j) is the
/// angle between the faces (i, j, k) and (i, j, l).
const EDGES: [(usize, usize, usize, usize); 6] = [
    (0, 1, 2, 3),
    (0, 2, 1, 3),
    (0, 3, 1, 2),
    (1, 2, 0, 3),
    (1, 3, 0, 2),
    (2, 3, 0, 1),
];

/// Cosines of the six dihedral angles of a tet (the angle grows as the cosine falls).
#[inline]
fn dihedral_cosines(p: [[f64; 3]; 4]) -> [f64; 6] {
    EDGES.map(|(i, j, k, l)| {
        let e = sub(p[j], p[i]);
        let n1 = cross(e, sub(p[k], p[i]));
        let n2 = cross(e, sub(p[l], p[i]));
        (dot(n1, n2) / (dot(n1, n1) * dot(n2, n2)).sqrt()).clamp(-1.0, 1.0)
    })
}

/// The six dihedral angles of a tet, in degrees.
pub fn dihedral_angles(p: [[f64; 3]; 4]) -> [f64; 6] {
    dihedral_cosines(p).map(|c| c.acos().to_degrees())
}

/// Smallest and largest dihedral angle over all tets, in degrees (`None` for an empty mesh).
/// Works on cosines and takes two arc cosines at the end.
pub fn dihedral_range(mesh: &TetMesh) -> Option<(f64, f64)> {
    mesh.tets
        .par_iter()
        .map(|t| {
            dihedral_cosines(t.map(|i| mesh.points[i as usize]))
                .iter()
                .fold((f64::NEG_INFINITY, f64::INFINITY), |(hi, lo), &c| {
                    (hi.max(c), lo.min(c))
                })
        })
        .reduce_with(|a, b| (a.0.max(b.0), a.1.min(b.1)))
        .map(|(cos_max, cos_min)| (cos_max.acos().to_degrees(), cos_min.acos().to_degrees()))
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn regular_tet_angles() {
        let p = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ];
        for a in dihedral_angles(p) {
            assert!((a - 70.528_779_365_509_3).abs() < 1e-9);
        }
    }
}
