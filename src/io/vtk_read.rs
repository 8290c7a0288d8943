//! Legacy VTK (`.vtk`) unstructured-grid reader: ASCII or BINARY (big-endian), file versions
//! up to 4.2 (`CELLS n size` with a count before each cell's ids) and 5.1 (`CELLS` followed
//! by `OFFSETS` and `CONNECTIVITY` arrays), as VTK, ParaView and meshio write them.
//!
//! Read: `POINTS`, `CELLS`, `CELL_TYPES`, and in `POINT_DATA` a one-component `SCALARS f` or
//! `FIELD` array `f` (the nodal values). `METADATA` blocks are skipped; reading stops at the first other
//! keyword once the cells are read (point and cell data other than `f` are not needed).
//! Cells as in [`super::vtu_read`]: tetrahedra (10), quadratic tetrahedra (24) by their
//! corners, cells of lower dimension (1–9) skipped, others an error.

use super::mesh_read_common::{check_mesh, perr, MeshFile, ParseError};
use super::read_common::{decode_samples, Endian, SampleType};

/// A cursor over the file: words for ASCII data, raw big-endian bytes for BINARY.
struct Cur<'a> {
    b: &'a [u8],
    pos: usize,
    binary: bool,
}

impl<'a> Cur<'a> {
    fn err(&self, m: impl std::fmt::Display) -> ParseError {
        let line = 1 + self.b[..self.pos].iter().filter(|&&c| c == b'\n').count();
        perr(line, m.to_string())
    }

    /// The next non-blank line, trimmed (`None` at the end).
    fn line(&mut self) -> Option<&'a str> {
        while self.pos < self.b.len() {
            let rest = &self.b[self.pos..];
            let end = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
            self.pos += (end + 1).min(rest.len());
            if !rest[..end].iter().all(u8::is_ascii_whitespace) {
                // keywords and headers are text; binary data read as a line gives "?"
                return Some(std::str::from_utf8(&rest[..end]).map_or("?", str::trim));
            }
        }
        None
    }

    /// The next whitespace-separated word (ASCII data).
    fn word(&mut self) -> Option<&'a str> {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start)
            .then(|| std::str::from_utf8(&self.b[start..self.pos]).ok())
            .flatten()
    }

    /// `n` numbers of VTK type `ty` (ASCII words, or big-endian bytes right after the
    /// keyword line).
    fn numbers(&mut self, n: usize, ty: &str, what: &str) -> Result<Vec<f64>, ParseError> {
        let t = sample_type(ty).ok_or_else(|| self.err(format!("{what}: unknown type {ty:?}")))?;
        let bytes = n.saturating_mul(t.size());
        // a number takes its size in binary, at least a digit and a blank in ASCII
        let least = if self.binary {
            bytes
        } else {
            n.saturating_mul(2)
        };
        if least > self.b.len() - self.pos + 1 {
            return Err(self.err(format!("{what}: {n} values are more than the file holds")));
        }
        if self.binary {
            let v = decode_samples(&self.b[self.pos..self.pos + bytes], t, Endian::Big);
            self.pos += bytes;
            return Ok(v);
        }
        (0..n)
            .map(|_| {
                let w = self
                    .word()
                    .ok_or_else(|| self.err(format!("{what}: the file ends inside the data")))?;
                w.parse()
                    .map_err(|_| self.err(format!("{what}: invalid number {w:?}")))
            })
            .collect()
    }
}

/// The sample type of a legacy VTK data type name.
fn sample_type(ty: &str) -> Option<SampleType> {
    Some(match ty.to_ascii_lowercase().as_str() {
        "bit" | "unsigned_char" | "vtktypeuint8" => SampleType::U8,
        "char" | "vtktypeint8" => SampleType::I8,
        "unsigned_short" | "vtktypeuint16" => SampleType::U16,
        "short" | "vtktypeint16" => SampleType::I16,
        "unsigned_int" | "vtktypeuint32" => SampleType::U32,
        "int" | "vtktypeint32" => SampleType::I32,
        "unsigned_long" | "vtktypeuint64" => SampleType::U64,
        "long" | "vtkidtype" | "vtktypeint64" => SampleType::I64,
        "float" => SampleType::F32,
        "double" => SampleType::F64,
        _ => return None,
    })
}

/// A count field of a keyword line.
fn count(c: &Cur, f: &[&str], k: usize) -> Result<usize, ParseError> {
    f.get(k)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| c.err(format!("{}: missing or bad count", f[0])))
}

/// What the keywords gave.
#[derive(Default)]
struct Parts {
    points: Vec<f64>,
    /// Offsets (one more than the cells, from 0) and connectivity.
    cells: Option<(Vec<usize>, Vec<f64>)>,
    types: Vec<f64>,
    values: Option<Vec<f64>>,
}

/// Parses the bytes of a `.vtk` file (see the module documentation).
pub(crate) fn parse_vtk(bytes: &[u8]) -> Result<MeshFile, ParseError> {
    let mut c = Cur {
        b: bytes,
        pos: 0,
        binary: false,
    };
    let head = c.line().unwrap_or("");
    if !head
        .to_ascii_lowercase()
        .starts_with("# vtk datafile version")
    {
        return Err(perr(
            1,
            "not a legacy VTK file (no \"# vtk DataFile Version\")",
        ));
    }
    c.line(); // title
    c.binary = match c.line().map(str::to_ascii_uppercase).as_deref() {
        Some("ASCII") => false,
        Some("BINARY") => true,
        _ => return Err(c.err("expected ASCII or BINARY")),
    };
    let dataset = c.line().unwrap_or("").to_ascii_uppercase();
    if dataset.split_whitespace().nth(1) != Some("UNSTRUCTURED_GRID") {
        return Err(c.err(format!(
            "{dataset:?}: only DATASET UNSTRUCTURED_GRID holds tetrahedra"
        )));
    }
    let p = keywords(&mut c)?;
    let Some((offsets, conn)) = p.cells else {
        return Err(c.err("no CELLS"));
    };
    let n = p.points.len() / 3;
    if p.types.len() + 1 != offsets.len() {
        return Err(c.err("CELL_TYPES and CELLS count different cells"));
    }
    let mut out = MeshFile::default();
    out.mesh.tets = super::vtu_read::tets(
        &offsets[1..].iter().map(|&o| o as f64).collect::<Vec<_>>(),
        &p.types,
        &conn,
        n,
    )
    .map_err(|m| perr(0, m))?;
    out.mesh.points = p
        .points
        .chunks_exact(3)
        .map(|q| [q[0], q[1], q[2]])
        .collect();
    if out.mesh.points.iter().flatten().any(|x| !x.is_finite()) {
        return Err(perr(0, "non-finite point coordinate"));
    }
    out.mesh.values = p.values.unwrap_or_else(|| vec![0.0; n]);
    check_mesh(&out.mesh)?;
    Ok(out)
}

/// Reads the keywords after `DATASET`.
fn keywords(c: &mut Cur) -> Result<Parts, ParseError> {
    let mut p = Parts::default();
    while let Some(line) = c.line() {
        let f: Vec<&str> = line.split_whitespace().collect();
        match f[0].to_ascii_uppercase().as_str() {
            "POINTS" => {
                let n = count(c, &f, 1)?;
                p.points = c.numbers(n.saturating_mul(3), f.get(2).unwrap_or(&"?"), "POINTS")?;
            }
            "CELLS" => p.cells = Some(cells(c, &f)?),
            "CELL_TYPES" => {
                let n = count(c, &f, 1)?;
                p.types = c.numbers(n, "int", "CELL_TYPES")?;
            }
            "METADATA" => skip_metadata(c),
            "POINT_DATA" if p.cells.is_some() => {
                p.values = scalars_f(c, count(c, &f, 1)?)?;
                break;
            }
            _ if p.cells.is_some() && !p.types.is_empty() => break,
            k => return Err(c.err(format!("unsupported keyword {k:?} before the cells"))),
        }
    }
    Ok(p)
}

/// Skips a `METADATA` block: its lines up to a blank one.
fn skip_metadata(c: &mut Cur) {
    while c.pos < c.b.len() {
        let rest = &c.b[c.pos..];
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        c.pos += (end + 1).min(rest.len());
        if rest[..end].iter().all(u8::is_ascii_whitespace) {
            return;
        }
    }
}

/// `CELLS`: version ≤ 4.2 (`CELLS n size`, each cell a count and ids) or 5.1 (`CELLS
/// offsets connectivity`, then the `OFFSETS` and `CONNECTIVITY` arrays).
fn cells(c: &mut Cur, f: &[&str]) -> Result<(Vec<usize>, Vec<f64>), ParseError> {
    let (n, size) = (count(c, f, 1)?, count(c, f, 2)?);
    let next = {
        let save = c.pos;
        let l = c.line().unwrap_or("").to_ascii_uppercase();
        c.pos = save;
        l
    };
    if next.starts_with("OFFSETS") {
        let ty = c
            .line()
            .and_then(|l| l.split_whitespace().nth(1))
            .unwrap_or("?");
        let offsets = c.numbers(n, ty, "OFFSETS")?;
        let ty = c
            .line()
            .and_then(|l| l.split_whitespace().nth(1))
            .unwrap_or("?");
        let conn = c.numbers(size, ty, "CONNECTIVITY")?;
        let offsets = offsets.iter().map(|&o| o.max(0.0) as usize).collect();
        return Ok((offsets, conn));
    }
    let all = c.numbers(size, "int", "CELLS")?;
    let (mut offsets, mut conn) = (vec![0usize], Vec::with_capacity(size));
    let mut i = 0;
    for _ in 0..n {
        let k = all.get(i).copied().unwrap_or(-1.0);
        if k < 0.0 || i + 1 + k as usize > all.len() {
            return Err(c.err("CELLS: a cell runs past the list"));
        }
        conn.extend_from_slice(&all[i + 1..i + 1 + k as usize]);
        i += 1 + k as usize;
        offsets.push(conn.len());
    }
    Ok((offsets, conn))
}

/// In `POINT_DATA n`: the values of a one-component `SCALARS f` (VTK) or `FIELD` array `f`
/// (meshio), if it comes first (`SCALARS`) or among the field's arrays (`FIELD`).
fn scalars_f(c: &mut Cur, n: usize) -> Result<Option<Vec<f64>>, ParseError> {
    let Some(line) = c.line() else {
        return Ok(None);
    };
    let f: Vec<&str> = line.split_whitespace().collect();
    if f[0].eq_ignore_ascii_case("FIELD") {
        return field_f(c, n, count(c, &f, 2)?);
    }
    let comps = f.get(3).and_then(|s| s.parse::<usize>().ok()).unwrap_or(1);
    if !f[0].eq_ignore_ascii_case("SCALARS") || f.get(1) != Some(&"f") || comps != 1 {
        return Ok(None);
    }
    let ty = f.get(2).copied().unwrap_or("?");
    let save = c.pos;
    if !c
        .line()
        .is_some_and(|l| l.to_ascii_uppercase().starts_with("LOOKUP_TABLE"))
    {
        c.pos = save;
    }
    c.numbers(n, ty, "SCALARS f").map(Some)
}

/// The `arrays` arrays of a `FIELD`: `name components tuples type` and the data each; the
/// one-component array `f` of `n` tuples, if any.
fn field_f(c: &mut Cur, n: usize, arrays: usize) -> Result<Option<Vec<f64>>, ParseError> {
    for _ in 0..arrays {
        let Some(line) = c.line() else {
            return Ok(None);
        };
        let f: Vec<&str> = line.split_whitespace().collect();
        let (comps, tuples) = (count(c, &f, 1)?, count(c, &f, 2)?);
        let ty = f.get(3).copied().unwrap_or("?");
        let v = c.numbers(comps.saturating_mul(tuples), ty, "FIELD array")?;
        if f[0] == "f" && comps == 1 && tuples == n {
            return Ok(Some(v));
        }
    }
    Ok(None)
}
