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
//! Only the tetrahedra are written: the labelled boundary triangles are **not** part of the
//! `.vtu` (use the `.msh` or `.inp` writers when the boundary groups are needed).

use std::io::{self, Write};

use super::msh::check_lengths;
use crate::mesh::TetMesh;

/// VTK cell type of a linear tetrahedron.
const VTK_TETRA: u8 = 10;

/// Bytes converted per `write_all` call for the binary arrays.
const CHUNK: usize = 1 << 16;

/// The UInt64 byte count that precedes each appended array.
fn header_bytes(size: u64) -> [u8; 8] {
    size.to_le_bytes()
}

/// Hands the pending bytes of `buf` to `w`.
fn flush(buf: &mut Vec<u8>, w: &mut dyn Write) -> io::Result<()> {
    w.write_all(buf)?;
    buf.clear();
    Ok(())
}

/// Writes the tetrahedra and the nodal field `f` of `mesh` as a VTK XML UnstructuredGrid
/// with raw appended binary data (see the module documentation; boundary triangles are not
/// written). The output is deterministic and independent of the host's byte order.
///
/// # Errors
/// Returns the first error of `w`, or [`io::ErrorKind::InvalidInput`] when the mesh is
/// inconsistent (`values` or `boundary_labels` of the wrong length, an out-of-range index).
pub fn write_vtu(mesh: &TetMesh, w: &mut dyn Write) -> io::Result<()> {
    check_lengths(mesh)?;
    let n_points = mesh.points.len();
    let n_tets = mesh.tets.len();
    let wide = n_points > i32::MAX as usize || n_tets.saturating_mul(4) > i32::MAX as usize;
    let (int_type, int_size) = if wide {
        ("Int64", 8u64)
    } else {
        ("Int32", 4u64)
    };

    let sizes = [
        8 * n_points as u64,
        24 * n_points as u64,
        int_size * 4 * n_tets as u64,
        int_size * n_tets as u64,
        n_tets as u64,
    ];
    let mut offsets = [0u64; 5];
    for k in 1..5 {
        offsets[k] = offsets[k - 1] + 8 + sizes[k - 1];
    }

    let header = format!(
        concat!(
            "<?xml version=\"1.0\"?>\n",
            "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
            "  <UnstructuredGrid>\n",
            "    <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">\n",
            "      <PointData Scalars=\"f\">\n",
            "        <DataArray type=\"Float64\" Name=\"f\" NumberOfComponents=\"1\" format=\"appended\" offset=\"{o0}\"/>\n",
            "      </PointData>\n",
            "      <Points>\n",
            "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{o1}\"/>\n",
            "      </Points>\n",
            "      <Cells>\n",
            "        <DataArray type=\"{it}\" Name=\"connectivity\" format=\"appended\" offset=\"{o2}\"/>\n",
            "        <DataArray type=\"{it}\" Name=\"offsets\" format=\"appended\" offset=\"{o3}\"/>\n",
            "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{o4}\"/>\n",
            "      </Cells>\n",
            "    </Piece>\n",
            "  </UnstructuredGrid>\n",
            "  <AppendedData encoding=\"raw\">\n",
            "   _"
        ),
        np = n_points,
        nc = n_tets,
        it = int_type,
        o0 = offsets[0],
        o1 = offsets[1],
        o2 = offsets[2],
        o3 = offsets[3],
        o4 = offsets[4],
    );
    w.write_all(header.as_bytes())?;

    let mut buf: Vec<u8> = Vec::with_capacity(CHUNK + 64);
    let put = |buf: &mut Vec<u8>, bytes: &[u8], w: &mut dyn Write| -> io::Result<()> {
        buf.extend_from_slice(bytes);
        if buf.len() >= CHUNK {
            w.write_all(buf)?;
            buf.clear();
        }
        Ok(())
    };

    // On a little-endian host the in-memory f64 and u32 arrays already are the file's bytes
    // (ids fit in Int32 unless `wide`): write them as they are.
    let native = cfg!(target_endian = "little");
    w.write_all(&header_bytes(sizes[0]))?;
    if native {
        w.write_all(bytemuck::cast_slice(&mesh.values))?;
    } else {
        for &v in &mesh.values {
            put(&mut buf, &v.to_le_bytes(), w)?;
        }
    }
    flush(&mut buf, w)?;
    w.write_all(&header_bytes(sizes[1]))?;
    if native {
        w.write_all(bytemuck::cast_slice(&mesh.points))?;
    } else {
        for p in &mesh.points {
            for &x in p {
                put(&mut buf, &x.to_le_bytes(), w)?;
            }
        }
    }
    flush(&mut buf, w)?;
    w.write_all(&header_bytes(sizes[2]))?;
    if native && !wide {
        w.write_all(bytemuck::cast_slice(&mesh.tets))?;
    } else {
        for &v in mesh.tets.iter().flatten() {
            if wide {
                put(&mut buf, &i64::from(v).to_le_bytes(), w)?;
            } else {
                put(&mut buf, &(v as i32).to_le_bytes(), w)?;
            }
        }
    }
    put(&mut buf, &sizes[3].to_le_bytes(), w)?;
    for t in 1..=n_tets as u64 {
        if wide {
            put(&mut buf, &(4 * t as i64).to_le_bytes(), w)?;
        } else {
            put(&mut buf, &(4 * t as i32).to_le_bytes(), w)?;
        }
    }
    put(&mut buf, &sizes[4].to_le_bytes(), w)?;
    for _ in 0..n_tets {
        put(&mut buf, &[VTK_TETRA], w)?;
    }
    buf.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
    w.write_all(&buf)?;
    w.flush()
}
