//! What every closed-surface reader shares: the [`TriSoup`] they return and [`finish`], which
//! checks the points and triangles a reader decoded (finite coordinates, indices in range, at
//! least one triangle) and welds points with identical coordinates.
//!
//! Errors are [`ReadError`]s: one line naming the file.

use std::path::Path;

use rustc_hash::FxHashMap;

use super::read_common::ReadError;

/// A triangle surface as read from a file: points and triangles indexing them, nothing else
/// (no normals, colours or groups).
///
/// Points with bit-identical coordinates are welded into one (`-0.0` counts as `0.0`), so
/// triangles that meet in a file without shared vertices (STL, or separate OBJ groups) share
/// their edges; every point is used by a triangle, numbered in order of first use.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriSoup {
    /// Point coordinates, all finite.
    pub points: Vec<[f64; 3]>,
    /// Triangles as indices into `points`, in file order (polygons fan-triangulated).
    pub triangles: Vec<[u32; 3]>,
}

/// Refuses an empty file before it is parsed.
pub(crate) fn check_not_empty(path: &Path, bytes: &[u8]) -> Result<(), ReadError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ReadError::invalid(path, "the file is empty"));
    }
    Ok(())
}

/// The soup of `points` and `triangles` as decoded from `path`: every index in range, every
/// coordinate of a used point finite, at least one triangle; identical points welded and
/// unused ones dropped.
///
/// # Errors
/// [`ReadError::Invalid`] naming the first offending triangle or point.
pub(crate) fn finish(
    path: &Path,
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<TriSoup, ReadError> {
    if triangles.is_empty() {
        let what = if points.is_empty() {
            "no points and no triangles"
        } else {
            "no triangles"
        };
        return Err(ReadError::invalid(path, format!("the surface has {what}")));
    }
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(&i) = tri.iter().find(|&&i| i as usize >= points.len()) {
            return Err(index_out_of_range(path, t, i, points.len()));
        }
    }
    let mut ids: FxHashMap<[u64; 3], u32> = FxHashMap::default();
    let mut new_of = vec![u32::MAX; points.len()];
    let mut out = TriSoup::default();
    for tri in triangles {
        let mut welded = [0u32; 3];
        for (c, &i) in tri.iter().enumerate() {
            let i = i as usize;
            if new_of[i] == u32::MAX {
                let p = points[i];
                if let Some(a) = (0..3).find(|&a| !p[a].is_finite()) {
                    let msg = format!(
                        "point {} has a coordinate that is not finite ({})",
                        i + 1,
                        p[a]
                    );
                    return Err(ReadError::invalid(path, msg));
                }
                let key = p.map(|x| (x + 0.0).to_bits());
                let next = out.points.len() as u32;
                new_of[i] = *ids.entry(key).or_insert_with(|| {
                    out.points.push(p.map(|x| x + 0.0));
                    next
                });
            }
            welded[c] = new_of[i];
        }
        out.triangles.push(welded);
    }
    Ok(out)
}

/// The error for triangle `t` (0-based) naming point `i` (0-based) of `n`.
pub(crate) fn index_out_of_range(path: &Path, t: usize, i: u32, n: usize) -> ReadError {
    ReadError::invalid(
        path,
        format!(
            "triangle {} uses point {} but the file has {n} point{}",
            t + 1,
            u64::from(i) + 1,
            if n == 1 { "" } else { "s" }
        ),
    )
}

/// Fan-triangulates the polygon `poly` (point indices) into `out`: `(v0, vi, vi+1)`.
/// Polygons of fewer than three points add nothing.
pub(crate) fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    for i in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[i], poly[i + 1]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welds_identical_points_and_drops_unused() {
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [9.0, 9.0, 9.0],
            [0.0, 1.0, 0.0],
            [-0.0, 0.0, 0.0],
        ];
        let s = finish(Path::new("x.stl"), &p, &[[0, 1, 3], [4, 3, 1]]).unwrap();
        assert_eq!(s.points.len(), 3);
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 1]]);
    }

    #[test]
    fn refuses_bad_content() {
        let path = Path::new("bad.ply");
        let e = finish(path, &[[0.0; 3]], &[[0, 0, 1]])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("bad.ply: ") && e.contains("point 2"), "{e}");
        let e = finish(path, &[[f64::NAN, 0.0, 0.0]], &[[0, 0, 0]]).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
        assert!(finish(path, &[], &[]).is_err());
        let mut t = Vec::new();
        fan(&[4, 5, 6, 7], &mut t);
        assert_eq!(t, vec![[4, 5, 6], [4, 6, 7]]);
    }
}
