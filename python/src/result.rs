//! A run's mesh as numpy arrays, in a dict the package's `__init__.py` makes a `meshio.Mesh`
//! of: points and field, tetrahedra with their region and Gmsh tags, the labelled triangles
//! (the boundary, then the interfaces between regions) with theirs, the group names, the
//! report (JSON) and the warnings. Tags and names are the `.msh` writer's
//! ([`tptd::io::msh`]), so that `tptd.write` and `meshio.read` of its `.msh` keep the groups.

use numpy::{Element, PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use tptd::io::msh::{label_tag, DOMAIN_PHYSICAL_TAG};
use tptd::mesh::{region_name, INTERVAL_LEVELS};
use tptd::pipeline::{MeshRequest, MeshRun};
use tptd::{BoundaryLabel, MeshChunk, MeshSink, TetMesh, TriSurface};

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

/// A run's mesh gathered as the arrays handed to numpy are made of: slab by slab as it is
/// meshed (a [`MeshSink`]: each element converted once, as it comes), or from a mesh held by
/// the run ([`Collect::of_mesh`]).
pub(crate) struct Collect {
    /// Levels of the run (2 for one interval).
    levels: usize,
    /// Names of the regions (several regions only).
    region_names: Vec<String>,
    points: Vec<[f64; 3]>,
    values: Vec<f64>,
    /// Tets, flat.
    tets: Vec<i64>,
    /// Region of each tet (empty for one interval).
    tet_region: Vec<i32>,
    /// Boundary triangles, flat, their labels and (several regions) the region of each.
    boundary: Vec<i64>,
    boundary_labels: Vec<BoundaryLabel>,
    boundary_region: Vec<i32>,
    /// Interface triangles between regions, flat, and their labels.
    interfaces: Vec<i64>,
    interface_labels: Vec<BoundaryLabel>,
}

impl Collect {
    /// An empty gatherer for a run of `req`.
    pub(crate) fn new(req: &MeshRequest) -> Collect {
        let levels = req.levels.as_ref().map_or(0, Vec::len).max(INTERVAL_LEVELS);
        Collect {
            levels,
            region_names: match levels > INTERVAL_LEVELS {
                true => (0..levels - 1)
                    .map(|k| region_name(&req.region_names, k))
                    .collect(),
                false => Vec::new(),
            },
            points: Vec::new(),
            values: Vec::new(),
            tets: Vec::new(),
            tet_region: Vec::new(),
            boundary: Vec::new(),
            boundary_labels: Vec::new(),
            boundary_region: Vec::new(),
            interfaces: Vec::new(),
            interface_labels: Vec::new(),
        }
    }

    /// The arrays of a mesh held by the run (which they replace, to bound the memory held
    /// at once), converted in parallel.
    fn of_mesh(mesh: TetMesh) -> Collect {
        let levels = mesh.level_count();
        let r = mesh.regions;
        Collect {
            levels,
            region_names: (0..r.count()).map(|k| r.name(k)).collect(),
            points: mesh.points,
            values: mesh.values,
            tets: flat(mesh.tets, |t| t.map(i64::from)),
            tet_region: r.tets.iter().map(|&k| i32::from(k)).collect(),
            boundary: flat(mesh.boundary, |t| t.map(i64::from)),
            boundary_labels: mesh.boundary_labels,
            boundary_region: r.boundary.iter().map(|&k| i32::from(k)).collect(),
            interfaces: flat(r.interfaces, |t| t.map(i64::from)),
            interface_labels: r.interface_labels,
        }
    }

    /// The arrays: tags and names from the labels and regions, the interfaces after the
    /// boundary.
    fn arrays(self) -> Arrays {
        let levels = self.levels;
        let tets = self.tets.len() / 4;
        let one = levels <= INTERVAL_LEVELS;
        let (tet_region, tet_tag, tet_entity) = match one {
            true => (
                vec![0; tets],
                vec![DOMAIN_PHYSICAL_TAG as i32; tets],
                vec![VOLUME_ENTITY; tets],
            ),
            false => {
                let tags: Vec<i32> = self.tet_region.par_iter().map(|k| k + 1).collect();
                (self.tet_region, tags.clone(), tags)
            }
        };
        let tag = |l: BoundaryLabel| label_tag(l, levels) as i32;
        let labels = || self.boundary_labels.iter().chain(&self.interface_labels);
        // An interface triangle on level i is a face of region i - 1 (below) and i (above).
        let below = |l: BoundaryLabel| l.level().map_or(0, |i| i as i32 - 1);
        let mut triangle_region = self.boundary_region;
        triangle_region.resize(self.boundary_labels.len(), 0);
        triangle_region.extend(self.interface_labels.iter().map(|&l| below(l)));
        let triangle_tag: Vec<i32> = labels().map(|&l| tag(l)).collect();
        let mut present = [false; tptd::mesh::NUM_LABELS];
        for &l in labels() {
            present[l.index()] = true;
        }
        let mut names: Vec<(String, i32, i32)> = BoundaryLabel::of_levels(levels)
            .filter(|l| present[l.index()])
            .map(|l| (l.name_in(levels), tag(l), 2))
            .collect();
        match one {
            true => names.push(("domain".into(), DOMAIN_PHYSICAL_TAG as i32, 3)),
            false => names.extend(
                (self.region_names.into_iter().enumerate()).map(|(k, n)| (n, k as i32 + 1, 3)),
            ),
        }
        let mut triangles = self.boundary;
        triangles.extend_from_slice(&self.interfaces);
        Arrays {
            points: flat_points(self.points),
            values: self.values,
            tets: self.tets,
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

impl MeshSink for Collect {
    fn chunk(&mut self, c: &MeshChunk) -> std::io::Result<()> {
        self.points.extend_from_slice(&c.points);
        self.values.extend_from_slice(&c.values);
        self.tets
            .extend(c.tets.as_flattened().iter().map(|&v| i64::from(v)));
        self.tet_region
            .extend(c.regions.iter().map(|&k| i32::from(k)));
        if c.boundary_regions.is_empty() {
            let rows = c.boundary.as_flattened().iter();
            self.boundary.extend(rows.map(|&v| i64::from(v)));
            self.boundary_labels.extend_from_slice(&c.boundary_labels);
            return Ok(());
        }
        let rows = c.boundary.iter().zip(&c.boundary_labels);
        for ((t, &l), &region) in rows.zip(&c.boundary_regions) {
            let t = t.map(i64::from);
            match l.is_interface(self.levels) {
                true => {
                    self.interfaces.extend_from_slice(&t);
                    self.interface_labels.push(l);
                }
                false => {
                    self.boundary.extend_from_slice(&t);
                    self.boundary_labels.push(l);
                    self.boundary_region.push(i32::from(region));
                }
            }
        }
        Ok(())
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
/// text) and `warnings`. The mesh is the run's if it held one, else what `collected`
/// gathered while it was made.
///
/// The run's input grid, which may read the caller's array in place, is dropped first (with
/// the thread attached, before the mesh's arrays are made).
pub(crate) fn mesh_dict(
    py: Python<'_>,
    run: MeshRun,
    collected: Collect,
) -> PyResult<Bound<'_, PyDict>> {
    let MeshRun {
        report, grid, mesh, ..
    } = run;
    drop(grid);
    let warnings = report.warnings.clone();
    let report = report.to_json_pretty();
    let a = py.detach(move || match mesh {
        Some(out) => Collect::of_mesh(out.mesh).arrays(),
        None => collected.arrays(),
    });
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
