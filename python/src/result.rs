//! A run's mesh as numpy arrays, in a dict the package's `__init__.py` makes a `meshio.Mesh`
//! of: points and field, tetrahedra with their region and Gmsh tags, the labelled triangles
//! (the boundary, then the interfaces between regions) with theirs, the group names, the
//! report (JSON) and the warnings. Tags and names are the `.msh` writer's
//! ([`tptd::io::msh`]), so that `tptd.write` and `meshio.read` of its `.msh` keep the groups.

use numpy::{Element, PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use tptd::io::msh::{label_tag, DOMAIN_PHYSICAL_TAG};
use tptd::pipeline::MeshRun;
use tptd::{BoundaryLabel, TetMesh, TriSurface};

/// Elementary tag of the one volume of a mesh of one interval (as the `.msh` writer's).
const VOLUME_ENTITY: i32 = 1;

/// The arrays of a mesh, flat, in the types they are handed to numpy in.
struct Arrays {
    points: Vec<f64>,
    values: Vec<f64>,
    tets: Vec<i64>,
    tet_region: Vec<i32>,
    tet_tag: Vec<i32>,
    tet_entity: Vec<i32>,
    triangles: Vec<i64>,
    triangle_region: Vec<i32>,
    triangle_tag: Vec<i32>,
    /// `(name, tag, dimension)` of every group: the labels that occur, then the volumes.
    names: Vec<(String, i32, i32)>,
}

impl Arrays {
    /// The arrays of `mesh` (which they replace, to bound the memory held at once).
    fn of(mesh: TetMesh) -> Arrays {
        let levels = mesh.level_count();
        let regions = &mesh.regions;
        let one = regions.is_empty();
        let tet_region: Vec<i32> = match one {
            true => vec![0; mesh.tets.len()],
            false => regions.tets.iter().map(|&k| i32::from(k)).collect(),
        };
        let (tet_tag, tet_entity) = match one {
            true => (
                vec![DOMAIN_PHYSICAL_TAG as i32; mesh.tets.len()],
                vec![VOLUME_ENTITY; mesh.tets.len()],
            ),
            false => {
                let tags: Vec<i32> = tet_region.iter().map(|k| k + 1).collect();
                (tags.clone(), tags)
            }
        };
        let tag = |l: BoundaryLabel| label_tag(l, levels) as i32;
        let boundary_region = |b: usize| regions.boundary.get(b).map_or(0, |&k| i32::from(k));
        // An interface triangle on level i is a face of region i - 1 (below) and i (above).
        let below = |l: BoundaryLabel| l.level().map_or(0, |i| i as i32 - 1);
        let mut triangle_region: Vec<i32> = (0..mesh.boundary.len()).map(boundary_region).collect();
        triangle_region.extend(regions.interface_labels.iter().map(|&l| below(l)));
        let mut triangle_tag: Vec<i32> = mesh.boundary_labels.iter().map(|&l| tag(l)).collect();
        triangle_tag.extend(regions.interface_labels.iter().map(|&l| tag(l)));
        let mut present = [false; tptd::mesh::NUM_LABELS];
        for &l in mesh.boundary_labels.iter().chain(&regions.interface_labels) {
            present[l.index()] = true;
        }
        let mut names: Vec<(String, i32, i32)> = BoundaryLabel::of_levels(levels)
            .filter(|l| present[l.index()])
            .map(|l| (l.name_in(levels), tag(l), 2))
            .collect();
        match one {
            true => names.push(("domain".into(), DOMAIN_PHYSICAL_TAG as i32, 3)),
            false => names.extend((0..regions.count()).map(|k| (regions.name(k), k as i32 + 1, 3))),
        }
        let all = mesh.boundary.len() + regions.interfaces.len();
        let mut triangles = vec![0i64; 3 * all];
        let rows = mesh
            .boundary
            .par_iter()
            .chain(regions.interfaces.par_iter());
        triangles
            .par_chunks_mut(3)
            .zip(rows)
            .for_each(|(o, t)| o.copy_from_slice(&t.map(i64::from)));
        // Each array of the mesh is freed once converted, so that the two copies of the
        // largest one only are held at once.
        let points = flat_points(mesh.points);
        let tets = flat(mesh.tets, |t| t.map(i64::from));
        Arrays {
            points,
            values: mesh.values,
            tets,
            tet_region,
            tet_tag,
            tet_entity,
            triangles,
            triangle_region,
            triangle_tag,
            names,
        }
    }
}

/// The rows of `v` converted by `f` into one flat vector, in parallel; `v` is freed.
fn flat<T, U, const N: usize>(v: Vec<[T; N]>, f: impl Fn([T; N]) -> [U; N] + Sync) -> Vec<U>
where
    T: Copy + Sync,
    U: Copy + Default + Send,
{
    let mut out = vec![U::default(); v.len() * N];
    out.par_chunks_mut(N)
        .zip(v.par_iter())
        .for_each(|(o, &row)| o.copy_from_slice(&f(row)));
    out
}

/// The points as one flat vector: the same memory, not copied.
fn flat_points(points: Vec<[f64; 3]>) -> Vec<f64> {
    bytemuck::allocation::try_cast_vec(points).unwrap_or_else(|(_, p)| flat(p, |x| x))
}

/// `v` as a numpy array (no copy) of `columns` columns.
fn array<'py, T: Element>(
    py: Python<'py>,
    v: Vec<T>,
    columns: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let rows = v.len() / columns.max(1);
    let flat = PyArray1::from_vec(py, v);
    match columns {
        1 => Ok(flat.into_any()),
        c => Ok(flat.reshape([rows, c])?.into_any()),
    }
}

/// The dict of a run's mesh: `points`, `f`, `tetra`, `tetra_region`, `tetra_tag`,
/// `tetra_entity`, `triangle`, `triangle_region`, `triangle_tag`, `names`, `report` (JSON
/// text) and `warnings`.
///
/// The run's input grid, which may read the caller's array in place, is dropped first (with
/// the thread attached, before the mesh's arrays are made).
pub(crate) fn mesh_dict(py: Python<'_>, run: MeshRun) -> PyResult<Bound<'_, PyDict>> {
    let MeshRun {
        report, grid, mesh, ..
    } = run;
    drop(grid);
    let warnings = report.warnings.clone();
    let report = report.to_json_pretty();
    let Some(out) = mesh else {
        return Err(PyValueError::new_err(
            "the run wrote its mesh instead of holding it",
        ));
    };
    let a = py.detach(move || Arrays::of(out.mesh));
    let d = PyDict::new(py);
    d.set_item("points", array(py, a.points, 3)?)?;
    d.set_item("f", array(py, a.values, 1)?)?;
    d.set_item("tetra", array(py, a.tets, 4)?)?;
    d.set_item("tetra_region", array(py, a.tet_region, 1)?)?;
    d.set_item("tetra_tag", array(py, a.tet_tag, 1)?)?;
    d.set_item("tetra_entity", array(py, a.tet_entity, 1)?)?;
    d.set_item("triangle", array(py, a.triangles, 3)?)?;
    d.set_item("triangle_region", array(py, a.triangle_region, 1)?)?;
    d.set_item("triangle_tag", array(py, a.triangle_tag, 1)?)?;
    d.set_item("names", a.names)?;
    d.set_item("report", report)?;
    d.set_item("warnings", warnings)?;
    Ok(d)
}

/// The dict of a level surface: `points`, `f` and `triangle`, and the run's `warnings`.
pub(crate) fn surface_dict(
    py: Python<'_>,
    s: TriSurface,
    warnings: Vec<String>,
) -> PyResult<Bound<'_, PyDict>> {
    let (points, triangles) = py.detach(move || {
        let points = flat(s.points, |p| p);
        (points, flat(s.triangles, |t| t.map(i64::from)))
    });
    let d = PyDict::new(py);
    d.set_item("points", array(py, points, 3)?)?;
    d.set_item("f", array(py, s.values, 1)?)?;
    d.set_item("triangle", array(py, triangles, 3)?)?;
    d.set_item("warnings", warnings)?;
    Ok(d)
}
