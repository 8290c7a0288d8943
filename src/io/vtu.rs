//! VTK XML UnstructuredGrid (`.vtu`) writer, appended data in one of three encodings.
//!
//! Layout: `header_type="UInt64"`, `byte_order="LittleEndian"` (always, independent of the
//! host), every array stored in `<AppendedData>` in the order `f`, `Points`, `connectivity`,
//! `offsets`, `types` (then `region` for a mesh of several regions):
//! * `Points`: Float64 × 3;
//! * `connectivity`, `offsets`: Int32 when every id and offset fits in an `i32`, Int64
//!   otherwise;
//! * `types`: UInt8, all 10 (`VTK_TETRA`, whose node order equals the mesh's positive
//!   orientation);
//! * point data `f`: Float64, the field values (the active scalars);
//! * cell data `region` (only for a mesh of several regions): Int32, the region of each tet,
//!   counting from 0 (region `k` lies between levels `k` and `k + 1`; the `.msh` and `.inp`
//!   writers number it `k + 1` and name it). In ParaView, the Threshold filter on `region`
//!   selects one region.
//!
//! Encodings ([`VtuEncoding`]):
//! * `Base64` (default): each array is its UInt64 byte count followed by the data, base64
//!   encoded as one stream; offsets count characters. meshio, VTK and ParaView read it.
//! * `Zlib`: as VTK writes by default (`compressor="vtkZLibDataCompressor"`): each array is
//!   cut into 32 KiB blocks compressed with zlib (level 5, in parallel); the block header
//!   (`[blocks, block size, last partial block size, compressed sizes…]`, UInt64) and the
//!   compressed blocks are base64 encoded as two streams. Smallest, slowest to write.
//! * `Raw`: the byte count and the data unencoded (`encoding="raw"`). Fastest to write, but
//!   meshio refuses it: its XML parser rewrites CR LF byte pairs (meshio issue #1324).
//!
//! [`write_vtu_fields`] writes other named Float64 point and cell fields instead of `f`
//! (point fields before `Points`, cell fields after `types` and `region`), e.g. a solution
//! and its gradient.
//!
//! Only the tetrahedra are written: the labelled boundary triangles and the interfaces
//! between regions are **not** part of the `.vtu` (use the `.msh` or `.inp` writers when the
//! boundary groups or interfaces are needed; in ParaView, Extract Surface on a region
//! selected by its `region` threshold gives its boundary).

use std::borrow::Cow;
use std::io::{self, Write};

use base64::engine::general_purpose::STANDARD;
use base64::Engine as _;
use flate2::write::ZlibEncoder;
use flate2::Compression;
use rayon::prelude::*;

use super::source::{InMemory, MeshSource};
use super::spill::ByteStore;
use super::write_common::{check_lengths, invalid};
use crate::mesh::TetMesh;

/// VTK cell type of a linear tetrahedron.
const VTK_TETRA: u8 = 10;

/// Uncompressed size of a zlib block (VTK's default).
const ZLIB_BLOCK: usize = 1 << 15;

/// zlib level of the `Zlib` encoding (VTK's default).
const ZLIB_LEVEL: u32 = 5;

/// Bytes base64-encoded per parallel task (a multiple of 3, so pieces concatenate).
const B64_PIECE: usize = 3 << 14;

/// Offsets and types made at a time.
const MADE_BATCH: usize = 1 << 20;

/// Bytes gathered before they are encoded in parallel and written (a multiple of
/// [`B64_PIECE`]).
const B64_BATCH: usize = B64_PIECE << 7;

/// How the appended arrays of a `.vtu` file are stored (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum VtuEncoding {
    /// Base64 of the raw arrays: every reader takes it (default).
    #[default]
    Base64,
    /// zlib-compressed 32 KiB blocks, base64 encoded, as VTK writes by default.
    Zlib,
    /// Raw bytes: fastest, but meshio cannot read it.
    Raw,
}

impl VtuEncoding {
    /// The encoding's name as the CLI spells it (`base64`, `zlib`, `raw`).
    pub fn name(self) -> &'static str {
        match self {
            VtuEncoding::Base64 => "base64",
            VtuEncoding::Zlib => "zlib",
            VtuEncoding::Raw => "raw",
        }
    }
}

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

/// Whether `connectivity` and `offsets` need Int64 (an id or offset exceeds `i32`).
fn is_wide(src: &dyn MeshSource) -> bool {
    src.num_points() as u64 > i32::MAX as u64
        || src.num_tets().saturating_mul(4) > i32::MAX as usize
}

/// The little-endian bytes of `v`: borrowed on a little-endian host.
fn le_f64(v: &[f64]) -> Cow<'_, [u8]> {
    if NATIVE {
        Cow::Borrowed(bytemuck::cast_slice(v))
    } else {
        Cow::Owned(v.iter().flat_map(|x| x.to_le_bytes()).collect())
    }
}

/// One array of the appended data.
#[derive(Clone, Copy)]
enum Array<'a> {
    /// A Float64 point or cell field given in memory.
    Field(&'a [f64]),
    /// The field `f` of the source.
    Values,
    /// The points, Float64 × 3.
    Points,
    /// The tets' node ids, Int32 or Int64.
    Connectivity,
    /// `4, 8, 12, …`, Int32 or Int64.
    Offsets,
    /// `VTK_TETRA` per tet, UInt8.
    Types,
    /// The region of each tet, Int32.
    Regions,
}

/// A source's arrays, and whether its ids are Int64.
struct Arrays<'a> {
    src: &'a dyn MeshSource,
    wide: bool,
}

impl Arrays<'_> {
    /// The number of bytes of `a`.
    fn byte_len(&self, a: &Array) -> u64 {
        let id = if self.wide { 8 } else { 4 };
        let (n, t) = (self.src.num_points() as u64, self.src.num_tets() as u64);
        match a {
            Array::Field(d) => 8 * d.len() as u64,
            Array::Values => 8 * n,
            Array::Points => 24 * n,
            Array::Connectivity => 4 * id * t,
            Array::Offsets => id * t,
            Array::Types => t,
            Array::Regions => 4 * t,
        }
    }

    /// Visits the little-endian bytes of `a` in order.
    fn visit(&self, a: &Array, f: &mut dyn FnMut(&[u8]) -> io::Result<()>) -> io::Result<()> {
        let t = self.src.num_tets();
        match a {
            Array::Field(d) => f(&le_f64(d)),
            Array::Values => self.src.values(&mut |v| f(&le_f64(v))),
            Array::Points => self
                .src
                .points(&mut |p| f(&le_f64(bytemuck::cast_slice(p)))),
            Array::Connectivity => self.src.tets(&mut |ts| f(&self.connectivity(ts))),
            Array::Offsets => self.offsets(t, f),
            Array::Types => {
                let block = vec![VTK_TETRA; t.min(MADE_BATCH)];
                (0..t)
                    .step_by(MADE_BATCH)
                    .try_for_each(|k| f(&block[..(t - k).min(MADE_BATCH)]))
            }
            Array::Regions => self.src.regions(&mut |rs| {
                let bytes: Vec<u8> = rs
                    .iter()
                    .flat_map(|&r| i32::from(r).to_le_bytes())
                    .collect();
                f(&bytes)
            }),
        }
    }

    /// Visits the bytes of the offsets `4, 8, …, 4 t` (Int64 or Int32: every offset fits
    /// unless the layout is wide), made in parallel, [`MADE_BATCH`] at a time.
    fn offsets(&self, t: usize, f: &mut dyn FnMut(&[u8]) -> io::Result<()>) -> io::Result<()> {
        let wide = self.wide;
        let size = if wide { 8 } else { 4 };
        let mut bytes = Vec::new();
        for k0 in (0..t).step_by(MADE_BATCH) {
            bytes.resize(size * (t - k0).min(MADE_BATCH), 0);
            bytes.par_chunks_mut(size).enumerate().for_each(|(i, b)| {
                let o = 4 * (k0 + i + 1) as u64;
                match wide {
                    true => b.copy_from_slice(&(o as i64).to_le_bytes()),
                    false => b.copy_from_slice(&(o as i32).to_le_bytes()),
                }
            });
            f(&bytes)?;
        }
        Ok(())
    }

    /// The connectivity bytes of `ts`: borrowed where memory already holds them.
    fn connectivity<'t>(&self, ts: &'t [[u32; 4]]) -> Cow<'t, [u8]> {
        let ids = ts.iter().flatten();
        match (NATIVE, self.wide) {
            (true, false) => Cow::Borrowed(bytemuck::cast_slice(ts)),
            (_, true) => Cow::Owned(ids.flat_map(|&v| i64::from(v).to_le_bytes()).collect()),
            (false, false) => Cow::Owned(ids.flat_map(|&v| (v as i32).to_le_bytes()).collect()),
        }
    }
}

/// Length of the base64 encoding of `n` bytes.
fn b64_len(n: u64) -> u64 {
    n.div_ceil(3) * 4
}

/// One array as stored in the appended data.
enum Stored<'a> {
    /// The bytes, written after their UInt64 count (raw, or base64 as one stream).
    Plain(Array<'a>, u64),
    /// The zlib block header and the compressed blocks (concatenated).
    Blocks(Vec<u64>, ByteStore),
}

impl Stored<'_> {
    /// Its size in the appended data (bytes for `Raw`, characters otherwise).
    fn stored_len(&self, encoding: VtuEncoding) -> u64 {
        match (self, encoding) {
            (Stored::Plain(_, n), VtuEncoding::Raw) => 8 + n,
            (Stored::Plain(_, n), _) => b64_len(8 + n),
            (Stored::Blocks(h, _), _) => {
                let data: u64 = h[3..].iter().sum();
                b64_len(8 * h.len() as u64) + b64_len(data)
            }
        }
    }

    /// Writes it to `w`.
    fn write(&self, arrays: &Arrays, w: &mut dyn Write, encoding: VtuEncoding) -> io::Result<()> {
        match (self, encoding) {
            (Stored::Plain(a, n), VtuEncoding::Raw) => {
                w.write_all(&n.to_le_bytes())?;
                arrays.visit(a, &mut |b| w.write_all(b))
            }
            (Stored::Plain(a, n), _) => {
                let mut out = Base64Out::new(w);
                out.put(&n.to_le_bytes())?;
                arrays.visit(a, &mut |b| out.put(b))?;
                out.finish()
            }
            (Stored::Blocks(h, blocks), _) => {
                let mut out = Base64Out::new(&mut *w);
                for x in h {
                    out.put(&x.to_le_bytes())?;
                }
                out.finish()?;
                let mut out = Base64Out::new(w);
                blocks.visit(&mut |b| out.put(b))?;
                out.finish()
            }
        }
    }
}

/// zlib blocks compressed at a time (in parallel).
const ZLIB_BATCH: usize = 64;

/// Compresses array `a` into VTK's zlib blocks (in parallel, batch by batch): the header and
/// the blocks. Blocks are cut at fixed offsets from the array's start, however its bytes
/// arrive.
fn compress(arrays: &Arrays, a: &Array) -> io::Result<Stored<'static>> {
    let n = arrays.byte_len(a);
    let mut sizes: Vec<u64> = Vec::new();
    let mut blocks = ByteStore::new();
    let mut pending: Vec<u8> = Vec::with_capacity(ZLIB_BLOCK * ZLIB_BATCH);
    let mut flush = |pending: &mut Vec<u8>| -> io::Result<()> {
        let z = pending
            .par_chunks(ZLIB_BLOCK)
            .map(|block| {
                let mut z = ZlibEncoder::new(Vec::new(), Compression::new(ZLIB_LEVEL));
                z.write_all(block)?;
                z.finish()
            })
            .collect::<io::Result<Vec<_>>>()?;
        for b in z {
            sizes.push(b.len() as u64);
            blocks.push(&b)?;
        }
        pending.clear();
        Ok(())
    };
    arrays.visit(a, &mut |mut bytes| {
        while !bytes.is_empty() {
            let take = (pending.capacity() - pending.len()).min(bytes.len());
            pending.extend_from_slice(&bytes[..take]);
            bytes = &bytes[take..];
            if pending.len() == ZLIB_BLOCK * ZLIB_BATCH {
                flush(&mut pending)?;
            }
        }
        Ok(())
    })?;
    if !pending.is_empty() {
        flush(&mut pending)?;
    }
    blocks.finish()?;
    let mut header = vec![sizes.len() as u64, ZLIB_BLOCK as u64, n % ZLIB_BLOCK as u64];
    header.extend(sizes);
    Ok(Stored::Blocks(header, blocks))
}

/// A base64 stream: bytes put in any pieces encode as one stream. They are gathered into
/// batches of [`B64_BATCH`] bytes, each encoded in parallel pieces of [`B64_PIECE`] (large
/// batches: the threads' work outweighs waking them) while the batch before is written.
struct Base64Out<'a> {
    w: &'a mut dyn Write,
    pending: Vec<u8>,
    /// The encoding of the last batch, not written yet.
    encoded: Vec<u8>,
    next: Vec<u8>,
}

impl<'a> Base64Out<'a> {
    fn new(w: &'a mut dyn Write) -> Self {
        Base64Out {
            w,
            pending: Vec::new(),
            encoded: Vec::new(),
            next: Vec::new(),
        }
    }

    /// Appends `data` to the stream.
    fn put(&mut self, mut data: &[u8]) -> io::Result<()> {
        while !data.is_empty() {
            let take = (B64_BATCH - self.pending.len()).min(data.len());
            self.pending.extend_from_slice(&data[..take]);
            data = &data[take..];
            if self.pending.len() == B64_BATCH {
                self.encode_pending()?;
            }
        }
        Ok(())
    }

    /// Encodes the whole triples of the pending bytes (in parallel pieces, on the other
    /// threads) while this one writes the last batch's encoding.
    fn encode_pending(&mut self) -> io::Result<()> {
        let whole = self.pending.len() / 3 * 3;
        let (pending, next) = (&self.pending[..whole], &mut self.next);
        let (w, encoded) = (&mut *self.w, &self.encoded);
        let written = rayon::in_place_scope(|s| {
            s.spawn(move |_| encode(pending, next));
            write_in_pieces(w, encoded)
        });
        written?;
        std::mem::swap(&mut self.encoded, &mut self.next);
        self.pending.drain(..whole);
        Ok(())
    }

    /// Ends the stream (with `=` padding when needed).
    fn finish(mut self) -> io::Result<()> {
        self.encode_pending()?;
        write_in_pieces(self.w, &self.encoded)?;
        self.w.write_all(STANDARD.encode(&self.pending).as_bytes())
    }
}

/// The base64 encoding of `bytes` (whole triples) into `out`, in parallel pieces.
fn encode(bytes: &[u8], out: &mut Vec<u8>) {
    out.resize(bytes.len() / 3 * 4, 0);
    let pieces = out.par_chunks_mut(B64_PIECE / 3 * 4);
    pieces
        .zip(bytes.par_chunks(B64_PIECE))
        .for_each(|(o, piece)| {
            // `o` has exactly the length of the piece's encoding (whole triples)
            let _ = STANDARD.encode_slice(piece, o);
        });
}

/// Writes `bytes` a mebibyte at a time (the system copies huge writes much more slowly).
fn write_in_pieces(w: &mut dyn Write, bytes: &[u8]) -> io::Result<()> {
    bytes.chunks(1 << 20).try_for_each(|c| w.write_all(c))
}

/// The XML part of the file, up to and including the `_` that starts the appended data;
/// `o` are the offsets of the arrays in the appended data, in file order.
fn xml_header(
    src: &dyn MeshSource,
    wide: bool,
    o: &[u64],
    encoding: VtuEncoding,
    point: &[VtuField],
    cell: &[VtuField],
    regions: bool,
) -> String {
    let compressor = match encoding {
        VtuEncoding::Zlib => " compressor=\"vtkZLibDataCompressor\"",
        _ => "",
    };
    let np = point.len();
    let mut h = format!(
        concat!(
            "<?xml version=\"1.0\"?>\n",
            "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"{compressor}>\n",
            "  <UnstructuredGrid>\n",
            "    <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">\n",
        ),
        compressor = compressor,
        np = src.num_points(),
        nc = src.num_tets(),
    );
    if let Some(first) = point.first() {
        h += &format!("      <PointData Scalars=\"{}\">\n", first.name);
        h += &data_arrays(point, &o[..np]);
        h += "      </PointData>\n";
    }
    h += &geometry_arrays(wide, &o[np..np + 4]);
    let mut o = &o[np + 4..];
    if regions || !cell.is_empty() {
        h += "      <CellData>\n";
        if regions {
            h += &format!(
                "        <DataArray type=\"Int32\" Name=\"region\" format=\"appended\" offset=\"{}\"/>\n",
                o[0]
            );
            o = &o[1..];
        }
        h += &data_arrays(cell, o);
        h += "      </CellData>\n";
    }
    h += &appended_data_start(encoding);
    h
}

/// The `Points` and `Cells` elements: the points, connectivity, offsets and types arrays at
/// offsets `o` (connectivity and offsets `Int64` if `wide`, else `Int32`).
fn geometry_arrays(wide: bool, o: &[u64]) -> String {
    let it = if wide { "Int64" } else { "Int32" };
    format!(
        concat!(
            "      <Points>\n",
            "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{o1}\"/>\n",
            "      </Points>\n",
            "      <Cells>\n",
            "        <DataArray type=\"{it}\" Name=\"connectivity\" format=\"appended\" offset=\"{o2}\"/>\n",
            "        <DataArray type=\"{it}\" Name=\"offsets\" format=\"appended\" offset=\"{o3}\"/>\n",
            "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{o4}\"/>\n",
            "      </Cells>\n",
        ),
        it = it,
        o1 = o[0],
        o2 = o[1],
        o3 = o[2],
        o4 = o[3],
    )
}

/// Closes the piece and opens the `AppendedData` of `encoding`, up to and including its `_`.
fn appended_data_start(encoding: VtuEncoding) -> String {
    let data_encoding = match encoding {
        VtuEncoding::Raw => "raw",
        _ => "base64",
    };
    format!(
        concat!(
            "    </Piece>\n",
            "  </UnstructuredGrid>\n",
            "  <AppendedData encoding=\"{enc}\">\n",
            "   _"
        ),
        enc = data_encoding
    )
}

/// The `DataArray` lines of `fields` at offsets `o`.
fn data_arrays(fields: &[VtuField], o: &[u64]) -> String {
    fields
        .iter()
        .zip(o)
        .map(|(f, o)| {
            format!(
                "        <DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{o}\"/>\n",
                f.name, f.components
            )
        })
        .collect()
}

/// On a little-endian host the in-memory f64 and u32 arrays already are the file's bytes
/// (ids fit in Int32 unless the layout is wide): they are written as they are.
const NATIVE: bool = cfg!(target_endian = "little");

/// Writes `mesh` as `.vtu` in the default encoding ([`VtuEncoding::Base64`]); see
/// [`write_vtu_with`].
///
/// # Errors
/// As [`write_vtu_with`].
pub fn write_vtu(mesh: &TetMesh, w: &mut dyn Write) -> io::Result<()> {
    write_vtu_with(mesh, w, VtuEncoding::default())
}

/// Writes the tetrahedra and the nodal field `f` of `mesh` as a VTK XML UnstructuredGrid
/// with appended data in `encoding` (see the module documentation; boundary triangles are
/// not written). The output is deterministic, independent of the thread count and of the
/// host's byte order.
///
/// # Errors
/// Returns the first error of `w`, or [`io::ErrorKind::InvalidInput`] when the mesh is
/// inconsistent (`values` or `boundary_labels` of the wrong length, an out-of-range index).
pub fn write_vtu_with(mesh: &TetMesh, w: &mut dyn Write, encoding: VtuEncoding) -> io::Result<()> {
    check_lengths(mesh)?;
    write_vtu_source(&InMemory::new(mesh), w, encoding)
}

/// [`write_vtu_with`] from any [`MeshSource`].
pub(crate) fn write_vtu_source(
    src: &dyn MeshSource,
    w: &mut dyn Write,
    encoding: VtuEncoding,
) -> io::Result<()> {
    write_arrays(
        src,
        &[("f", 1, Array::Values)],
        Vec::new(),
        &[],
        w,
        encoding,
    )
}

/// Writes the tetrahedra of `mesh` with the given point and cell fields (instead of `f`) in
/// the default encoding; see [`write_vtu_fields_with`].
///
/// # Errors
/// As [`write_vtu_fields_with`].
pub fn write_vtu_fields(
    mesh: &TetMesh,
    point: &[VtuField],
    cell: &[VtuField],
    w: &mut dyn Write,
) -> io::Result<()> {
    write_vtu_fields_with(mesh, point, cell, w, VtuEncoding::default())
}

/// Writes the tetrahedra of `mesh` with the given point and cell fields (instead of `f`) as
/// a VTK XML UnstructuredGrid, like [`write_vtu_with`]: point fields first, then `Points`,
/// the cell arrays and the cell fields in the appended data; the first point field is the
/// active scalar.
///
/// # Errors
/// As [`write_vtu_with`], and [`io::ErrorKind::InvalidInput`] when a field does not have
/// `components` values per point (cell).
pub fn write_vtu_fields_with(
    mesh: &TetMesh,
    point: &[VtuField],
    cell: &[VtuField],
    w: &mut dyn Write,
    encoding: VtuEncoding,
) -> io::Result<()> {
    check_lengths(mesh)?;
    check_fields(point, mesh.points.len())?;
    check_fields(cell, mesh.tets.len())?;
    let p: Vec<_> = point
        .iter()
        .map(|f| (f.name, f.components, Array::Field(f.data)))
        .collect();
    let c = cell.iter().map(|f| Array::Field(f.data)).collect();
    write_arrays(&InMemory::new(mesh), &p, c, cell, w, encoding)
}

/// Writes the `.vtu`: point arrays (name, components, data), then `Points`, the cell
/// arrays, `region` (several regions) and `cell` arrays (`cell_fields` names them).
fn write_arrays(
    src: &dyn MeshSource,
    point: &[(&str, usize, Array)],
    cell: Vec<Array>,
    cell_fields: &[VtuField],
    w: &mut dyn Write,
    encoding: VtuEncoding,
) -> io::Result<()> {
    let arrays = Arrays {
        src,
        wide: is_wide(src),
    };
    let mut all: Vec<Array> = point.iter().map(|(_, _, a)| *a).collect();
    all.extend([
        Array::Points,
        Array::Connectivity,
        Array::Offsets,
        Array::Types,
    ]);
    let regions = src.region_count() > 0;
    if regions {
        all.push(Array::Regions);
    }
    all.extend(cell);
    let stored = all
        .into_iter()
        .map(|a| match encoding {
            VtuEncoding::Zlib => compress(&arrays, &a),
            _ => {
                let n = arrays.byte_len(&a);
                Ok(Stored::Plain(a, n))
            }
        })
        .collect::<io::Result<Vec<_>>>()?;
    let mut offsets = vec![0u64; stored.len()];
    for k in 1..stored.len() {
        offsets[k] = offsets[k - 1] + stored[k - 1].stored_len(encoding);
    }
    let names: Vec<VtuField> = point
        .iter()
        .map(|&(name, components, _)| VtuField {
            name,
            components,
            data: &[],
        })
        .collect();
    let header = xml_header(
        src,
        arrays.wide,
        &offsets,
        encoding,
        &names,
        cell_fields,
        regions,
    );
    w.write_all(header.as_bytes())?;
    for a in &stored {
        a.write(&arrays, w, encoding)?;
    }
    w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")?;
    w.flush()
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
