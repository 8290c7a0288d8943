//! VTK XML UnstructuredGrid (`.vtu`) reader, the twin of [`super::vtu`]: reads what our
//! writer writes in its three encodings, and what VTK, ParaView and meshio write (every
//! encoding of [`super::vtk_xml`]; one `<Piece>`).
//!
//! Cells: tetrahedra (`VTK_TETRA`, 10) are the mesh; quadratic tetrahedra (24) are read as
//! their four corners (the mid-edge nodes stay, unused); vertices, lines, polylines,
//! triangles, strips, polygons, pixels and quads (1–9) are skipped; any other cell type is an
//! error naming it. The point-data scalar `f`, when present, gives the nodal values. A
//! `.vtu` has no boundary groups: the mesh's `boundary` is empty.

use std::path::Path;

use super::mesh_read_common::{check_mesh, MeshFile, MeshReadError};
use super::read_common::{read_all, ReadError};
use super::vtk_xml::{parse, ArrayDesc, Parsed, Section};

/// `VTK_TETRA`.
const TETRA: u8 = 10;
/// `VTK_QUADRATIC_TETRA`.
const QUADRATIC_TETRA: u8 = 24;
/// Cell types of dimension 0 to 2 (skipped).
const LOWER: std::ops::RangeInclusive<u8> = 1..=9;

/// Reads the `.vtu` file `path` (see the module documentation).
///
/// # Errors
/// [`MeshReadError`] naming the file: unreadable, malformed, truncated, unsupported content
/// or no tetrahedra.
pub(crate) fn read_vtu(path: &Path) -> Result<MeshFile, MeshReadError> {
    let bytes = read_all(path)?;
    let p = parse(path, &bytes, "UnstructuredGrid")?;
    let src = super::vtk_xml::Source::new(path, &bytes, &p)?;
    let bad = |m: String| MeshReadError::from(ReadError::invalid(path, m));
    if p.pieces != 1 {
        return Err(bad(format!("{} <Piece>s (one is read)", p.pieces)));
    }
    let (Some(n_points), Some(n_cells)) = p.piece_counts else {
        return Err(bad("<Piece> lacks NumberOfPoints or NumberOfCells".into()));
    };
    let array = |section: Section, name: Option<&str>, what: &str| {
        find(&p, section, name).ok_or_else(|| bad(format!("no {what} array")))
    };
    let pts = src.values(array(Section::Points, None, "<Points>")?, 3 * n_points)?;
    let offsets = src.values(array(Section::Cells, Some("offsets"), "offsets")?, n_cells)?;
    let types = src.values(array(Section::Cells, Some("types"), "types")?, n_cells)?;
    let total = offsets.last().copied().unwrap_or(0.0);
    let conn = src.values(
        array(Section::Cells, Some("connectivity"), "connectivity")?,
        as_index(total).ok_or_else(|| bad(format!("bad last offset {total}")))?,
    )?;
    let mut out = MeshFile::default();
    out.mesh.tets = tets(&offsets, &types, &conn, n_points).map_err(bad)?;
    out.mesh.points = pts.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    out.mesh.values = match find(&p, Section::PointData, Some("f")) {
        Some(a) if a.components == 1 => src.values(a, n_points)?,
        _ => vec![0.0; n_points],
    };
    if out.mesh.points.iter().flatten().any(|x| !x.is_finite()) {
        return Err(bad("non-finite point coordinate".into()));
    }
    check_mesh(&out.mesh).map_err(|e| bad(e.message))?;
    Ok(out)
}

/// The first array of `section` (named `name`, when given).
fn find<'a>(p: &'a Parsed, section: Section, name: Option<&str>) -> Option<&'a ArrayDesc> {
    p.arrays
        .iter()
        .find(|a| a.section == section && name.is_none_or(|n| a.name == n))
}

/// `x` as an index, if it is a non-negative integer below 2^53.
fn as_index(x: f64) -> Option<usize> {
    (x >= 0.0 && x.fract() == 0.0 && x < 9.0e15).then_some(x as usize)
}

/// The tetrahedra of the cells (`offsets` end each cell's nodes in `conn`); shared with the
/// legacy reader [`super::vtk_read`].
pub(super) fn tets(
    offsets: &[f64],
    types: &[f64],
    conn: &[f64],
    n_points: usize,
) -> Result<Vec<[u32; 4]>, String> {
    let mut out = Vec::new();
    let mut start = 0usize;
    for (c, (&end, &ty)) in offsets.iter().zip(types).enumerate() {
        let end = as_index(end)
            .filter(|&e| e >= start && e <= conn.len())
            .ok_or_else(|| format!("cell {c}: bad offset {end}"))?;
        let ty = u8::try_from(ty as i64)
            .ok()
            .filter(|&t| f64::from(t) == ty)
            .ok_or_else(|| format!("cell {c}: bad cell type {ty}"))?;
        let nodes = &conn[start..end];
        start = end;
        let want = match ty {
            TETRA => 4,
            QUADRATIC_TETRA => 10,
            t if LOWER.contains(&t) => continue,
            t => {
                return Err(format!(
                    "cell {c}: unsupported cell type {t} (tetrahedra are read; cells of lower \
                     dimension are skipped)"
                ))
            }
        };
        if nodes.len() != want {
            return Err(format!(
                "cell {c}: a cell of type {ty} has {want} nodes, not {}",
                nodes.len()
            ));
        }
        let mut tet = [0u32; 4];
        for (t, &v) in tet.iter_mut().zip(nodes) {
            *t = as_index(v)
                .filter(|&i| i < n_points)
                .ok_or_else(|| format!("cell {c}: node {v} is not a point (0..{n_points})"))?
                as u32;
        }
        out.push(tet);
    }
    Ok(out)
}
