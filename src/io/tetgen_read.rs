//! TetGen mesh reader: `NAME.node` and `NAME.ele`, and `NAME.face` when it exists (given
//! either of the first two).
//!
//! * `.node`: `<points> 3 <attributes> <markers>`, then `<index> <x> <y> <z> ...`; the first
//!   index (0 or 1) is the numbering base of all three files, and the indices must run on
//!   from it. Point attributes and markers are ignored.
//! * `.ele`: `<tets> <4 or 10> <attributes>`, then `<index> <n1> ... [attributes]`; of a
//!   10-node (`-o2`) tet the first four nodes, its corners, are read. With attributes, the
//!   first one is the region: regions are named by its value (`1`, `-2`, `0.5`).
//! * `.face`: `<faces> <markers>`, then `<index> <a> <b> <c> [marker] ...` (further columns,
//!   e.g. the adjacent tets of `-nn`, ignored). Each non-zero marker becomes a node group
//!   named by its value. The faces are not the mesh's labelled boundary (they carry no
//!   alpha/beta/box label, and may include inner facets): `boundary` stays empty.
//!
//! `#` starts a comment anywhere; fields are separated by blanks (or commas). Errors name
//! the file of the three where the problem is, and the line.

use std::path::{Path, PathBuf};

use rustc_hash::FxHashMap;

use super::mesh_read_common::{
    check_mesh, normalize_groups, parse_file, perr, MeshFile, MeshReadError, NodeGroup, ParseError,
};

/// The `.node`, `.ele` and (when it exists) `.face` files of the TetGen mesh `path`
/// (`NAME.node` or `NAME.ele`).
pub(crate) fn tetgen_files(path: &Path) -> Vec<PathBuf> {
    let mut out = vec![path.with_extension("node"), path.with_extension("ele")];
    let face = path.with_extension("face");
    if face.exists() {
        out.push(face);
    }
    out
}

/// Reads the TetGen mesh `path` (see the module documentation).
///
/// # Errors
/// [`MeshReadError`] naming the file and line: a missing or unreadable file, malformed or
/// inconsistent content, indices out of range, no tetrahedra.
pub(crate) fn read_tetgen(path: &Path) -> Result<MeshFile, MeshReadError> {
    let files = tetgen_files(path);
    let (points, base) = parse_file(&files[0], parse_node)?;
    let n = points.len();
    let (tets, regions) = parse_file(&files[1], |t| parse_ele(t, base, n))?;
    let mut out = MeshFile::default();
    if let Some(face) = files.get(2) {
        out.node_groups = parse_file(face, |t| parse_face(t, base, n))?;
    }
    out.mesh.values = vec![0.0; n];
    out.mesh.points = points;
    out.mesh.tets = tets;
    if let Some((names, of_tet)) = regions {
        out.regions = names;
        out.tet_region = of_tet;
    }
    check_mesh(&out.mesh).map_err(|e| MeshReadError::Invalid {
        file: files[1].display().to_string(),
        line: e.line,
        message: e.message,
    })?;
    Ok(out)
}

/// The data lines of a TetGen file: comments cut, blank lines skipped, with line numbers.
struct Rows<'a> {
    inner: std::iter::Enumerate<std::str::Lines<'a>>,
    line: usize,
}

impl<'a> Rows<'a> {
    fn new(text: &'a str) -> Self {
        Rows {
            inner: text.lines().enumerate(),
            line: 0,
        }
    }

    /// The fields of the next data line, or an error naming what was expected.
    fn next(&mut self, what: &str) -> Result<Vec<&'a str>, ParseError> {
        for (i, l) in self.inner.by_ref() {
            let l = l.split('#').next().unwrap_or("");
            let f: Vec<&str> = l
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|s| !s.is_empty())
                .collect();
            if !f.is_empty() {
                self.line = i + 1;
                return Ok(f);
            }
        }
        Err(perr(
            self.line,
            format!("unexpected end of file, expected {what}"),
        ))
    }

    /// Field `k` of `f` parsed as a `T`, or an error naming `what`.
    fn get<T: std::str::FromStr>(&self, f: &[&str], k: usize, what: &str) -> Result<T, ParseError> {
        let s = f
            .get(k)
            .ok_or_else(|| perr(self.line, format!("missing {what}")))?;
        s.parse()
            .map_err(|_| perr(self.line, format!("invalid {what} {s:?}")))
    }
}

/// The header's count, kept below a bound on what the file can hold (one entry per line
/// of at least two bytes), so a corrupt count allocates nothing.
fn count(r: &Rows, f: &[&str], text: &str, what: &str) -> Result<usize, ParseError> {
    let n: usize = r.get(f, 0, what)?;
    if n > text.len() / 2 {
        return Err(perr(
            r.line,
            format!("{what} {n} is more than the file holds"),
        ));
    }
    Ok(n)
}

/// `.node`: the points and the numbering base (the first point's index: 0 or 1).
fn parse_node(text: &str) -> Result<(Vec<[f64; 3]>, usize), ParseError> {
    let mut r = Rows::new(text);
    let h = r.next("the .node header")?;
    let n = count(&r, &h, text, "number of points")?;
    if n == 0 {
        return Err(perr(
            r.line,
            "no points (points in a .poly file are not read)",
        ));
    }
    let dim: usize = r.get(&h, 1, "dimension")?;
    if dim != 3 {
        return Err(perr(r.line, format!("dimension {dim} (3 is read)")));
    }
    let mut points = Vec::with_capacity(n);
    let mut base = 0;
    for i in 0..n {
        let f = r.next("a point")?;
        let idx: usize = r.get(&f, 0, "point index")?;
        if i == 0 {
            if idx > 1 {
                return Err(perr(r.line, format!("first point index {idx} (0 or 1)")));
            }
            base = idx;
        } else if idx != base + i {
            return Err(perr(
                r.line,
                format!("point index {idx}, expected {}", base + i),
            ));
        }
        let p: [f64; 3] = [r.get(&f, 1, "x")?, r.get(&f, 2, "y")?, r.get(&f, 3, "z")?];
        if !p.iter().all(|x| x.is_finite()) {
            return Err(perr(r.line, "non-finite coordinate"));
        }
        points.push(p);
    }
    if u32::try_from(points.len()).is_err() {
        return Err(perr(0, "too many points"));
    }
    Ok((points, base))
}

/// The regions of the tets' first attributes: names in order of first use, and the index of
/// each tet's.
type Regions = (Vec<String>, Vec<u32>);

/// The node `s` of a line: a 0-based index below `n` in the numbering from `base`.
fn node(r: &Rows, f: &[&str], k: usize, base: usize, n: usize) -> Result<u32, ParseError> {
    let v: usize = r.get(f, k, "node index")?;
    v.checked_sub(base)
        .filter(|&i| i < n)
        .map(|i| i as u32)
        .ok_or_else(|| {
            perr(
                r.line,
                format!("node {v} is not a point ({base}..{})", base + n),
            )
        })
}

/// `.ele`: the tets (corners) and, with attributes, their regions.
fn parse_ele(
    text: &str,
    base: usize,
    n: usize,
) -> Result<(Vec<[u32; 4]>, Option<Regions>), ParseError> {
    let mut r = Rows::new(text);
    let h = r.next("the .ele header")?;
    let m = count(&r, &h, text, "number of tetrahedra")?;
    let per: usize = r.get(&h, 1, "nodes per tetrahedron")?;
    if per != 4 && per != 10 {
        return Err(perr(
            r.line,
            format!("{per} nodes per tetrahedron (4 or 10)"),
        ));
    }
    let attrs: usize = if h.len() > 2 {
        r.get(&h, 2, "number of attributes")?
    } else {
        0
    };
    let mut tets = Vec::with_capacity(m);
    let mut names: Vec<String> = Vec::new();
    let mut index: FxHashMap<String, u32> = FxHashMap::default();
    let mut of_tet = Vec::new();
    for _ in 0..m {
        let f = r.next("a tetrahedron")?;
        let mut t = [0u32; 4];
        for (k, v) in t.iter_mut().enumerate() {
            *v = node(&r, &f, 1 + k, base, n)?;
        }
        if f.len() < 1 + per + attrs {
            return Err(perr(
                r.line,
                format!("a tetrahedron needs {} fields", 1 + per + attrs),
            ));
        }
        tets.push(t);
        if attrs > 0 {
            let a: f64 = r.get(&f, 1 + per, "region attribute")?;
            let name = region_name(a);
            let next = names.len() as u32;
            let i = *index.entry(name.clone()).or_insert_with(|| {
                names.push(name);
                next
            });
            of_tet.push(i);
        }
    }
    Ok((tets, (attrs > 0).then_some((names, of_tet))))
}

/// A region attribute as a name: integers without a decimal point.
fn region_name(a: f64) -> String {
    if a.fract() == 0.0 && a.abs() < 1e15 {
        format!("{}", a as i64)
    } else {
        format!("{a}")
    }
}

/// `.face`: a node group per non-zero marker.
fn parse_face(text: &str, base: usize, n: usize) -> Result<Vec<NodeGroup>, ParseError> {
    let mut r = Rows::new(text);
    let h = r.next("the .face header")?;
    let m = count(&r, &h, text, "number of faces")?;
    let markers: usize = if h.len() > 1 {
        r.get(&h, 1, "marker flag")?
    } else {
        0
    };
    let mut groups: Vec<NodeGroup> = Vec::new();
    let mut index: FxHashMap<i64, usize> = FxHashMap::default();
    for _ in 0..m {
        let f = r.next("a face")?;
        let mut tri = [0u32; 3];
        for (k, v) in tri.iter_mut().enumerate() {
            *v = node(&r, &f, 1 + k, base, n)?;
        }
        let marker: i64 = if markers > 0 {
            r.get(&f, 4, "boundary marker")?
        } else {
            0
        };
        if marker == 0 {
            continue;
        }
        let g = *index.entry(marker).or_insert_with(|| {
            groups.push(NodeGroup {
                name: marker.to_string(),
                nodes: Vec::new(),
            });
            groups.len() - 1
        });
        groups[g].nodes.extend_from_slice(&tri);
    }
    normalize_groups(&mut groups);
    Ok(groups)
}
