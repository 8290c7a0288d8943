//! Meshes from Python as the library's [`TetMesh`]: the arrays `tptd/__init__.py` takes out
//! of a `meshio.Mesh` (points, field, tetrahedra with their regions, labelled triangles) in
//! the mesh of a run ([`MeshArrays::into_mesh`]) that the library's writers and checker
//! read. The arrays are copied with the GIL held; the work that follows releases it.

use numpy::{Element, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tptd::mesh::{BoundaryLabel, Regions, INTERVAL_LEVELS, LABEL_LEVELS};
use tptd::TetMesh;

/// The arrays of a mesh, as `tptd/__init__.py` passes them (every key present).
///
/// `triangle_label` is each triangle's label code ([`BoundaryLabel::code`] in a run of
/// `levels` levels: the level index, `levels` for the box; `-1`: not labelled, left out).
/// `levels` is 0 for a mesh of one interval; with more, `tetra_region` and
/// `triangle_region` give the regions and `region_names` their names.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct MeshArrays<'py> {
    points: PyReadonlyArrayDyn<'py, f64>,
    f: Option<PyReadonlyArrayDyn<'py, f64>>,
    tetra: PyReadonlyArrayDyn<'py, i64>,
    tetra_region: Option<PyReadonlyArrayDyn<'py, i64>>,
    triangle: PyReadonlyArrayDyn<'py, i64>,
    triangle_label: PyReadonlyArrayDyn<'py, i64>,
    triangle_region: Option<PyReadonlyArrayDyn<'py, i64>>,
    levels: usize,
    region_names: Vec<String>,
}

/// `mesh: {what}` as a `ValueError`.
fn bad(what: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("mesh: {what}"))
}

/// The rows of the `(n, N)` array `a`, named `name` in messages.
fn rows<T: Element + Copy + Default, const N: usize>(
    a: &PyReadonlyArrayDyn<'_, T>,
    name: &str,
) -> PyResult<Vec<[T; N]>> {
    let shape = a.shape();
    if shape.len() != 2 || shape[1] != N {
        return Err(bad(format_args!(
            "{name} must be an (n, {N}) array, got shape {shape:?}"
        )));
    }
    let view = a.as_array();
    let flat: Vec<T> = view.iter().copied().collect();
    Ok(flat
        .chunks_exact(N)
        .map(|c| std::array::from_fn(|i| c[i]))
        .collect())
}

/// The values of the 1-D array `a` of `n` values, named `name` in messages.
fn column<T: Element + Copy>(
    a: &PyReadonlyArrayDyn<'_, T>,
    n: usize,
    name: &str,
) -> PyResult<Vec<T>> {
    if a.shape() != [n] {
        return Err(bad(format_args!(
            "{name} must have {n} values, got shape {:?}",
            a.shape()
        )));
    }
    Ok(a.as_array().iter().copied().collect())
}

/// Node indices as the mesh's `u32` (the library checks them against the points).
fn indices<const N: usize>(a: &PyReadonlyArrayDyn<'_, i64>, name: &str) -> PyResult<Vec<[u32; N]>> {
    let rows = rows::<i64, N>(a, name)?;
    let index = |i: i64| u32::try_from(i).map_err(|_| bad(format_args!("{name}: node {i}")));
    rows.into_iter()
        .map(|r| {
            let mut out = [0u32; N];
            for (o, &i) in out.iter_mut().zip(&r) {
                *o = index(i)?;
            }
            Ok(out)
        })
        .collect()
}

/// A region number (0 to 255), named `name` in messages.
fn region(k: i64, name: &str) -> PyResult<u8> {
    u8::try_from(k).map_err(|_| bad(format_args!("{name}: region {k}")))
}

impl MeshArrays<'_> {
    /// The mesh: the labelled triangles split into the boundary and (with several regions)
    /// the interfaces on the levels between regions.
    ///
    /// # Errors
    /// `ValueError` for arrays of the wrong shape, a negative index, or a label or region
    /// outside the run's.
    pub(crate) fn into_mesh(self) -> PyResult<TetMesh> {
        if self.levels > LABEL_LEVELS {
            return Err(bad(format_args!(
                "{} levels, at most {LABEL_LEVELS}",
                self.levels
            )));
        }
        let points = rows::<f64, 3>(&self.points, "points")?;
        let n = points.len();
        let values = match &self.f {
            Some(f) => column(f, n, "point_data f")?,
            None => vec![0.0; n],
        };
        let tets = indices::<4>(&self.tetra, "tetra")?;
        let mut mesh = TetMesh {
            points,
            values,
            tets,
            ..TetMesh::default()
        };
        self.add_triangles(&mut mesh)?;
        Ok(mesh)
    }

    /// Adds the labelled triangles and the regions to `mesh`.
    fn add_triangles(&self, mesh: &mut TetMesh) -> PyResult<()> {
        let levels = self.levels.max(INTERVAL_LEVELS);
        let several = self.levels > INTERVAL_LEVELS;
        let tris = indices::<3>(&self.triangle, "triangle")?;
        let codes = column(&self.triangle_label, tris.len(), "triangle labels")?;
        let tri_regions = match (&self.triangle_region, several) {
            (Some(r), true) => column(r, tris.len(), "triangle regions")?,
            _ => vec![0; tris.len()],
        };
        let mut r = Regions::default();
        if several {
            r.levels = self.levels;
            r.names = self.region_names.clone();
            let Some(tet_regions) = &self.tetra_region else {
                return Err(bad("several levels need the region of each tetra"));
            };
            let tet_regions = column(tet_regions, mesh.tets.len(), "tetra regions")?;
            r.tets = tet_regions
                .into_iter()
                .map(|k| region(k, "tetra"))
                .collect::<PyResult<_>>()?;
        }
        for ((&tri, &code), &k) in tris.iter().zip(&codes).zip(&tri_regions) {
            let Ok(code) = usize::try_from(code) else {
                continue;
            };
            if code > levels {
                return Err(bad(format_args!(
                    "triangle label {code} of {levels} levels"
                )));
            }
            let label = BoundaryLabel::from_code(code, levels);
            if several && label.is_interface(levels) {
                r.interfaces.push(tri);
                r.interface_labels.push(label);
            } else {
                mesh.boundary.push(tri);
                mesh.boundary_labels.push(label);
                if several {
                    r.boundary.push(region(k, "triangle")?);
                }
            }
        }
        mesh.regions = r;
        Ok(())
    }
}
