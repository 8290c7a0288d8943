//! Element-quality measures.

use rayon::prelude::*;

use crate::mesh::{cross, dot, sub, TetMesh};

/// The six dihedral angles of a tet, in degrees.
pub fn dihedral_angles(p: [[f64; 3]; 4]) -> [f64; 6] {
    // Edge (i, j) is opposite edge (k, l); the dihedral angle at edge (i, j) is between the
    // faces (i, j, k) and (i, j, l).
    const E: [(usize, usize, usize, usize); 6] = [
        (0, 1, 2, 3),
        (0, 2, 1, 3),
        (0, 3, 1, 2),
        (1, 2, 0, 3),
        (1, 3, 0, 2),
        (2, 3, 0, 1),
    ];
    E.map(|(i, j, k, l)| {
        let e = sub(p[j], p[i]);
        let n1 = cross(e, sub(p[k], p[i]));
        let n2 = cross(e, sub(p[l], p[i]));
        let c = dot(n1, n2) / (dot(n1, n1).sqrt() * dot(n2, n2).sqrt());
        c.clamp(-1.0, 1.0).acos().to_degrees()
    })
}

/// Smallest and largest dihedral angle over all tets, in degrees (`None` for an empty mesh).
pub fn dihedral_range(mesh: &TetMesh) -> Option<(f64, f64)> {
    mesh.tets
        .par_iter()
        .map(|t| {
            let a = dihedral_angles(t.map(|i| mesh.points[i as usize]));
            a.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                    (lo.min(x), hi.max(x))
                })
        })
        .reduce_with(|a, b| (a.0.min(b.0), a.1.max(b.1)))
}

#[cfg(test)]
mod tests {
    use super::*;

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
