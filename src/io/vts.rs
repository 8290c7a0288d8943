//! VTK XML StructuredGrid (`.vts`) reader: a curvilinear grid with point-data scalars.
//!
//! Supported as VTK and ParaView write them: `format="ascii"`, `"binary"` (base64, inline)
//! and `"appended"` data (`encoding="raw"` or `"base64"`), uncompressed or compressed with
//! `compressor="vtkZLibDataCompressor"`, `header_type` `UInt32` or `UInt64`, either
//! `byte_order`, every numeric `type`. One piece. The points (`<Points>`, 3 components) give
//! the geometry; the field is the point-data array named by `field` (default: the first
//! single-component point-data array).

use std::path::Path;

use super::read_common::{read_all, ReadError};
use super::vtk_xml::{parse, ArrayDesc, Section, Source};
use crate::grid::CurvilinearGrid;

/// Reads a `.vts` file; `field` names the point-data array (default: the first scalar one).
///
/// # Errors
/// [`ReadError`] naming the file for malformed, truncated, inconsistent or unsupported
/// content, a missing field (the message lists the ones there are) or an invalid grid.
pub fn read_vts(path: &Path, field: Option<&str>) -> Result<CurvilinearGrid, ReadError> {
    let bytes = read_all(path)?;
    let p = parse(path, &bytes, "StructuredGrid")?;
    let src = Source::new(path, &bytes, &p)?;
    let dims = p
        .dims
        .ok_or_else(|| ReadError::invalid(path, "no <StructuredGrid WholeExtent=...>"))?;
    if p.pieces > 1 {
        return Err(ReadError::unsupported(path, "more than one Piece"));
    }
    let n = dims[0]
        .checked_mul(dims[1])
        .and_then(|v| v.checked_mul(dims[2]))
        .filter(|&v| v < (1 << 40))
        .ok_or_else(|| ReadError::invalid(path, format!("dimensions {dims:?} too large")))?;
    let pts_desc = p
        .arrays
        .iter()
        .find(|a| a.section == Section::Points)
        .ok_or_else(|| ReadError::invalid(path, "no <Points> array"))?;
    let pts = src.values(pts_desc, 3 * n)?;
    let scalars: Vec<&ArrayDesc> = p
        .arrays
        .iter()
        .filter(|a| a.section == Section::PointData && a.components == 1)
        .collect();
    let chosen = match field {
        Some(f) => scalars.iter().find(|a| a.name == f),
        None => scalars.first(),
    }
    .ok_or_else(|| ReadError::invalid(path, missing_field(&p.arrays, field)))?;
    let values = src.values(chosen, n)?;
    let points = pts.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    CurvilinearGrid::new(dims, values, points).map_err(|source| ReadError::Grid {
        file: path.display().to_string(),
        source,
    })
}

/// Why no point-data scalar (named `field`) was found: the scalars there are, or, when there
/// is none, the point-data arrays there are and that none is a scalar.
fn missing_field(arrays: &[ArrayDesc], field: Option<&str>) -> String {
    let what = field.map_or("no point-data scalar".to_string(), |f| {
        format!("no point-data scalar {f:?}")
    });
    let scalars: Vec<&str> = arrays
        .iter()
        .filter(|a| a.section == Section::PointData && a.components == 1)
        .map(|a| a.name.as_str())
        .collect();
    if !scalars.is_empty() {
        return format!("{what}; the file has: {}", scalars.join(", "));
    }
    let others: Vec<String> = arrays
        .iter()
        .filter(|a| a.section == Section::PointData)
        .map(|a| format!("{:?} ({} components)", a.name, a.components))
        .collect();
    if others.is_empty() {
        format!("{what}; the file has no point-data arrays")
    } else {
        format!(
            "{what}; the file's point-data arrays are not scalar: {}",
            others.join(", ")
        )
    }
}
