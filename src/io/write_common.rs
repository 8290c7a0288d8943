//! Helpers shared by the mesh writers (`msh`, `inp`, `vtu`, `obj`, `ply`, `stl`): the mesh and
//! surface consistency checks, triangle normals, the
//! invalid-input error, the boundary labels that occur, and the buffered text formatter.

use std::io::{self, Write};

use crate::mesh::{TetMesh, TriSurface, LABEL_LEVELS};

/// Checks that `values` and `boundary_labels` have the lengths of `points` and `boundary` and
/// that every tet and triangle refers to an existing node.
pub(crate) fn check_lengths(mesh: &TetMesh) -> io::Result<()> {
    if mesh.values.len() != mesh.points.len() {
        return Err(invalid(format!(
            "mesh has {} points but {} values",
            mesh.points.len(),
            mesh.values.len()
        )));
    }
    if mesh.boundary_labels.len() != mesh.boundary.len() {
        return Err(invalid(format!(
            "mesh has {} boundary triangles but {} labels",
            mesh.boundary.len(),
            mesh.boundary_labels.len()
        )));
    }
    let n = mesh.points.len();
    let bad = mesh
        .tets
        .iter()
        .flatten()
        .chain(mesh.boundary.iter().flatten())
        .chain(mesh.regions.interfaces.iter().flatten())
        .any(|&i| i as usize >= n);
    if bad {
        return Err(invalid(format!(
            "mesh refers to a node index >= the {n} points"
        )));
    }
    check_regions(mesh)
}

/// Checks that the regions (if any) fit the mesh: one per tet, each below the count, one
/// label per interface triangle, and every label one of the run's.
fn check_regions(mesh: &TetMesh) -> io::Result<()> {
    let r = &mesh.regions;
    let levels = mesh.level_count();
    if levels > LABEL_LEVELS {
        return Err(invalid(format!(
            "mesh has {levels} levels, at most {LABEL_LEVELS}"
        )));
    }
    if !r.is_empty() && r.tets.len() != mesh.tets.len() {
        return Err(invalid(format!(
            "mesh has {} tets but {} regions",
            mesh.tets.len(),
            r.tets.len()
        )));
    }
    if r.tets.iter().any(|&k| k as usize >= r.count()) {
        return Err(invalid(format!("a region >= the {} regions", r.count())));
    }
    if r.interface_labels.len() != r.interfaces.len() {
        return Err(invalid(format!(
            "mesh has {} interface triangles but {} labels",
            r.interfaces.len(),
            r.interface_labels.len()
        )));
    }
    let mut labels = mesh.boundary_labels.iter().chain(&r.interface_labels);
    if let Some(l) = labels.find(|l| l.level().is_some_and(|i| i >= levels)) {
        return Err(invalid(format!(
            "label {l:?} outside the run of {levels} levels"
        )));
    }
    Ok(())
}

/// An [`io::ErrorKind::InvalidInput`] error with `msg`.
pub(crate) fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Threshold at which [`TextOut`] hands its buffer to the underlying writer.
const CHUNK: usize = 1 << 16;

/// Fast formatter for the text writers: integers via `itoa`, floats via `ryu` (shortest
/// representation that round-trips), collected in a local buffer that is passed to the
/// (possibly dynamically dispatched) writer in 64 KiB chunks.
pub(crate) struct TextOut<'a> {
    w: &'a mut dyn Write,
    buf: Vec<u8>,
    int: itoa::Buffer,
    float: ryu::Buffer,
}

impl<'a> TextOut<'a> {
    pub(crate) fn new(w: &'a mut dyn Write) -> Self {
        TextOut {
            w,
            buf: Vec::with_capacity(CHUNK + 4096),
            int: itoa::Buffer::new(),
            float: ryu::Buffer::new(),
        }
    }

    /// Appends a string.
    #[inline]
    pub(crate) fn s(&mut self, s: &str) -> &mut Self {
        self.buf.extend_from_slice(s.as_bytes());
        self
    }

    /// Appends an integer in decimal.
    #[inline]
    pub(crate) fn int<I: itoa::Integer>(&mut self, v: I) -> &mut Self {
        self.buf.extend_from_slice(self.int.format(v).as_bytes());
        self
    }

    /// Appends a float in the shortest form that parses back to the same `f64`
    /// (`NaN`/`inf`/`-inf` for non-finite values).
    #[inline]
    pub(crate) fn float(&mut self, v: f64) -> &mut Self {
        self.buf.extend_from_slice(self.float.format(v).as_bytes());
        self
    }

    /// Appends a point's three coordinates, space-separated ([`TextOut::float`] each).
    #[inline]
    pub(crate) fn vec3(&mut self, p: [f64; 3]) -> &mut Self {
        self.float(p[0]).s(" ").float(p[1]).s(" ").float(p[2])
    }

    /// Appends a float in at most `width` (>= 16) characters: the shortest round-trip form when
    /// it fits, otherwise scientific notation with `width - 8` fractional digits.
    #[inline]
    pub(crate) fn float_width(&mut self, v: f64, width: usize) -> &mut Self {
        let short = self.float.format(v);
        if short.len() <= width {
            self.buf.extend_from_slice(short.as_bytes());
        } else {
            use std::io::Write as _;
            let _ = write!(self.buf, "{:.*e}", width - 8, v);
        }
        self
    }

    /// Ends a line and passes the buffer on when it is full.
    #[inline]
    pub(crate) fn nl(&mut self) -> io::Result<()> {
        self.buf.push(b'\n');
        if self.buf.len() >= CHUNK {
            self.w.write_all(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }

    /// Writes whatever is buffered and flushes the underlying writer.
    pub(crate) fn finish(mut self) -> io::Result<()> {
        self.w.write_all(&self.buf)?;
        self.buf.clear();
        self.w.flush()
    }
}

/// Checks that a surface's `values` and `labels` have the lengths of `points` and
/// `triangles` and that every triangle refers to an existing point.
pub(crate) fn check_surface(s: &TriSurface) -> io::Result<()> {
    if s.values.len() != s.points.len() || s.labels.len() != s.triangles.len() {
        return Err(invalid(format!(
            "surface has {} points, {} values, {} triangles, {} labels",
            s.points.len(),
            s.values.len(),
            s.triangles.len(),
            s.labels.len()
        )));
    }
    let n = s.points.len();
    if s.triangles.iter().flatten().any(|&i| i as usize >= n) {
        return Err(invalid(format!(
            "surface refers to a point index >= the {n} points"
        )));
    }
    Ok(())
}

/// The unit normal of triangle `t` of `s` (right-hand rule; zero for a degenerate one).
pub(crate) fn unit_normal(s: &TriSurface, t: [u32; 3]) -> [f64; 3] {
    let [a, b, c] = t.map(|i| s.points[i as usize]);
    let n = crate::geom::cross(crate::geom::sub(b, a), crate::geom::sub(c, a));
    let len = crate::geom::dot(n, n).sqrt();
    if len > 0.0 {
        n.map(|x| x / len)
    } else {
        [0.0; 3]
    }
}
