//! VTK XML UnstructuredGrid (`.vtu`) writer, binary appended data.
//!
//! Layout: `header_type="UInt64"`, `byte_order="LittleEndian"` (always, independent of the
//! host), every array stored raw in `<AppendedData encoding="raw">` as a UInt64 byte count
//! followed by the data, in the order `f`, `Points`, `connectivity`, `offsets`, `types`.
//! * `Points`: Float64 × 3;
//! * `connectivity`, `offsets`: Int32 when every id and offset fits in an `i32`, Int64
//!   otherwise;
//! * `types`: UInt8, all 10 (`VTK_TETRA`, whose node order equals the mesh's positive
//!   orientation);
//! * point data `f`: Float64, the field values (the active scalars).
//!
//! [`write_vtu_fields`] writes other named Float64 point and cell fields instead of `f`
//! (point fields before `Points`, cell fields after `types`), e.g. a solution and its
//! gradient.
//!
//! Only the tetrahedra are written: the labelled boundary triangles are **not** part of the
//! `.vtu` (use the `.msh` or `.inp` writers when the boundary groups are needed).

use std::io::{self, Write};

use super::write_common::{check_lengths, invalid};
use crate::mesh::TetMesh;

/// VTK cell type of a linear tetrahedron.
const VTK_TETRA: u8 = 10;

/// Bytes converted per `write_all` call for the binary arrays.
const CHUNK: usize = 1 << 16;

/// A named Float64 array written as point or cell data by [`write_vtu_fields`].
#[derive(Clone, Copy, Debug)]
pub struct VtuField<'a> {
    /// The array name shown in ParaView.
    pub name: &'a str,
    /// Components per point or cell (1 for a scalar, 3 for a vector).
    pub components: usize,
    /// `components` values per point or cell, interleaved.
    pub data: &'a [f64],
}

/// Sizes of the appended arrays, in file order, and the integer type of the cell arrays.
struct Layout {
    /// Whether `connectivity` and `offsets` need Int64 (an id or offset exceeds `i32`).
    wide: bool,
    /// Byte sizes of the point fields, `Points`, `connectivity`, `offsets`, `types` and the
    /// cell fields, in file order.
    sizes: Vec<u64>,
}

impl Layout {
    fn new(mesh: &TetMesh, point: &[VtuField], cell: &[VtuField]) -> Self {
        let n_points = mesh.points.len() as u64;
        let n_tets = mesh.tets.len();
        let wide = n_points > i32::MAX as u64 || n_tets.saturating_mul(4) > i32::MAX as usize;
        let int_size = if wide { 8 } else { 4 };
        let n_tets = n_tets as u64;
        let mut sizes: Vec<u64> = point.iter().map(|f| 8 * f.data.len() as u64).collect();
        sizes.extend([
            24 * n_points,
            int_size * 4 * n_tets,
            int_size * n_tets,
            n_tets,
        ]);
        sizes.extend(cell.iter().map(|f| 8 * f.data.len() as u64));
        Layout { wide, sizes }
    }

    /// VTK name of the integer type of `connectivity` and `offsets`.
    fn int_type(&self) -> &'static str {
        if self.wide {
            "Int64"
        } else {
            "Int32"
        }
    }

    /// Offsets of the arrays in the appended data (each preceded by its UInt64 byte count).
    fn offsets(&self) -> Vec<u64> {
        let mut offsets = vec![0u64; self.sizes.len()];
        for k in 1..offsets.len() {
            offsets[k] = offsets[k - 1] + 8 + self.sizes[k - 1];
        }
        offsets
    }
}

/// One `<DataArray>` line of a Float64 field stored at `offset`.
fn field_line(f: &VtuField, offset: u64) -> String {
    format!(
        "        <DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{offset}\"/>\n",
        f.name, f.components
    )
}

/// The XML part of the file, up to and including the `_` that starts the appended data.
fn xml_header(mesh: &TetMesh, layout: &Layout, point: &[VtuField], cell: &[VtuField]) -> String {
    let o = layout.offsets();
    let np = point.len();
    let mut x = String::from(concat!(
        "<?xml version=\"1.0\"?>\n",
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
        "  <UnstructuredGrid>\n",
    ));
    x += &format!(
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        mesh.points.len(),
        mesh.tets.len()
    );
    if let Some(first) = point.first() {
        x += &format!("      <PointData Scalars=\"{}\">\n", first.name);
        for (f, &off) in point.iter().zip(&o) {
            x += &field_line(f, off);
        }
        x += "      </PointData>\n";
    }
    if !cell.is_empty() {
        x += "      <CellData>\n";
        for (f, &off) in cell.iter().zip(&o[np + 4..]) {
            x += &field_line(f, off);
        }
        x += "      </CellData>\n";
    }
    let it = layout.int_type();
    x += &format!(
        concat!(
            "      <Points>\n",
            "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{}\"/>\n",
            "      </Points>\n",
            "      <Cells>\n",
            "        <DataArray type=\"{it}\" Name=\"connectivity\" format=\"appended\" offset=\"{}\"/>\n",
            "        <DataArray type=\"{it}\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>\n",
            "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{}\"/>\n",
            "      </Cells>\n",
            "    </Piece>\n",
            "  </UnstructuredGrid>\n",
            "  <AppendedData encoding=\"raw\">\n",
            "   _"
        ),
        o[np],
        o[np + 1],
        o[np + 2],
        o[np + 3],
        it = it,
    );
    x
}

/// The binary appended data: small pieces are collected in a buffer that is handed to the
/// writer in [`CHUNK`]-sized pieces; large native arrays go to the writer directly.
struct Appended<'a> {
    w: &'a mut dyn Write,
    buf: Vec<u8>,
}

impl Appended<'_> {
    /// Appends `bytes`, passing the buffer on when it is full.
    fn put(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.buf.extend_from_slice(bytes);
        if self.buf.len() >= CHUNK {
            self.flush()?;
        }
        Ok(())
    }

    /// Hands the pending bytes to the writer.
    fn flush(&mut self) -> io::Result<()> {
        self.w.write_all(&self.buf)?;
        self.buf.clear();
        Ok(())
    }

    /// Writes `bytes` after whatever is pending, bypassing the buffer.
    fn put_direct(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.flush()?;
        self.w.write_all(bytes)
    }

    /// The UInt64 byte count that precedes each appended array.
    fn array_size(&mut self, size: u64) -> io::Result<()> {
        self.put(&size.to_le_bytes())
    }

    /// A Float64 array (a field).
    fn values(&mut self, data: &[f64], size: u64) -> io::Result<()> {
        self.array_size(size)?;
        if NATIVE {
            return self.put_direct(bytemuck::cast_slice(data));
        }
        for &v in data {
            self.put(&v.to_le_bytes())?;
        }
        Ok(())
    }

    /// The node coordinates as Float64 × 3.
    fn points(&mut self, mesh: &TetMesh, size: u64) -> io::Result<()> {
        self.array_size(size)?;
        if NATIVE {
            return self.put_direct(bytemuck::cast_slice(&mesh.points));
        }
        for &x in mesh.points.iter().flatten() {
            self.put(&x.to_le_bytes())?;
        }
        Ok(())
    }

    /// The tets' node ids as Int32, or Int64 when `wide`.
    fn connectivity(&mut self, mesh: &TetMesh, size: u64, wide: bool) -> io::Result<()> {
        self.array_size(size)?;
        if NATIVE && !wide {
            return self.put_direct(bytemuck::cast_slice(&mesh.tets));
        }
        for &v in mesh.tets.iter().flatten() {
            if wide {
                self.put(&i64::from(v).to_le_bytes())?;
            } else {
                self.put(&(v as i32).to_le_bytes())?;
            }
        }
        Ok(())
    }

    /// The end offset `4 t` of every tet `t` (1-based) in `connectivity`.
    fn offsets(&mut self, n_tets: usize, size: u64, wide: bool) -> io::Result<()> {
        self.array_size(size)?;
        for t in 1..=n_tets as u64 {
            if wide {
                self.put(&(4 * t as i64).to_le_bytes())?;
            } else {
                self.put(&(4 * t as i32).to_le_bytes())?;
            }
        }
        Ok(())
    }

    /// The cell types, all [`VTK_TETRA`].
    fn types(&mut self, n_tets: usize, size: u64) -> io::Result<()> {
        self.array_size(size)?;
        for _ in 0..n_tets {
            self.put(&[VTK_TETRA])?;
        }
        Ok(())
    }
}

/// On a little-endian host the in-memory f64 and u32 arrays already are the file's bytes
/// (ids fit in Int32 unless the layout is wide): they are written as they are.
const NATIVE: bool = cfg!(target_endian = "little");

/// Writes the tetrahedra and the nodal field `f` of `mesh` as a VTK XML UnstructuredGrid
/// with raw appended binary data (see the module documentation; boundary triangles are not
/// written). The output is deterministic and independent of the host's byte order.
///
/// # Errors
/// Returns the first error of `w`, or [`io::ErrorKind::InvalidInput`] when the mesh is
/// inconsistent (`values` or `boundary_labels` of the wrong length, an out-of-range index).
pub fn write_vtu(mesh: &TetMesh, w: &mut dyn Write) -> io::Result<()> {
    let f = VtuField {
        name: "f",
        components: 1,
        data: &mesh.values,
    };
    write_vtu_fields(mesh, &[f], &[], w)
}

/// Writes the tetrahedra of `mesh` with the given point and cell fields (instead of `f`) as
/// a VTK XML UnstructuredGrid, like [`write_vtu`]: point fields first, then `Points`, the
/// cell arrays and the cell fields in the appended data; the first point field is the
/// active scalar.
///
/// # Errors
/// As [`write_vtu`], and [`io::ErrorKind::InvalidInput`] when a field does not have
/// `components` values per point (cell).
pub fn write_vtu_fields(
    mesh: &TetMesh,
    point: &[VtuField],
    cell: &[VtuField],
    w: &mut dyn Write,
) -> io::Result<()> {
    check_lengths(mesh)?;
    check_fields(point, mesh.points.len())?;
    check_fields(cell, mesh.tets.len())?;
    let layout = Layout::new(mesh, point, cell);
    let np = point.len();
    let n_tets = mesh.tets.len();
    w.write_all(xml_header(mesh, &layout, point, cell).as_bytes())?;
    let mut out = Appended {
        w,
        buf: Vec::with_capacity(CHUNK + 64),
    };
    let s = &layout.sizes;
    for (f, &size) in point.iter().zip(s) {
        out.values(f.data, size)?;
    }
    out.points(mesh, s[np])?;
    out.connectivity(mesh, s[np + 1], layout.wide)?;
    out.offsets(n_tets, s[np + 2], layout.wide)?;
    out.types(n_tets, s[np + 3])?;
    for (f, &size) in cell.iter().zip(&s[np + 4..]) {
        out.values(f.data, size)?;
    }
    out.put(b"\n  </AppendedData>\n</VTKFile>\n")?;
    out.flush()?;
    out.w.flush()
}

/// Checks that every field has `components` values for each of `n` points or cells.
fn check_fields(fields: &[VtuField], n: usize) -> io::Result<()> {
    for f in fields {
        if f.components == 0 || f.data.len() != n * f.components {
            return Err(invalid(format!(
                "field {} has {} values, expected {} x {n}",
                f.name,
                f.data.len(),
                f.components
            )));
        }
    }
    Ok(())
}
