//! Medit ASCII `.mesh` reader (the format fTetWild, CGAL, MMG and Gmsh write).
//!
//! Free format: keywords and numbers separated by blanks and line ends; `#` starts a comment
//! line. Read: `MeshVersionFormatted`, `Dimension` (3), `Vertices` (`x y z ref`),
//! `Triangles` (`a b c ref`), `Tetrahedra` (`a b c d ref`), `End`; indices are 1-based.
//! Skipped, by their known entry sizes: `Edges`, `Quadrilaterals`, `Hexahedra`, `Prisms`,
//! `Corners`, `Ridges`, the `Required…` lists, `Normals`, `Tangents` and the `…AtVertices`
//! tables; any other keyword is an error naming it (a table of unknown size cannot be
//! skipped). Groups: each non-zero triangle reference becomes a node group named by its
//! value; the tetrahedra's references become regions (named by value) when any is non-zero.
//! The triangles are not the mesh's labelled boundary: `boundary` stays empty. Binary
//! `.meshb` files are not read.

use rustc_hash::FxHashMap;

use super::mesh_read_common::{
    check_mesh, normalize_groups, perr, MeshFile, NodeGroup, ParseError,
};

/// Entry sizes (numbers per entry) of the tables that are skipped, by lower-case keyword.
const SKIPPED: [(&str, usize); 21] = [
    ("edges", 3),
    ("quadrilaterals", 5),
    ("hexahedra", 9),
    ("prisms", 7),
    ("pyramids", 6),
    ("corners", 1),
    ("ridges", 1),
    ("requiredvertices", 1),
    ("requirededges", 1),
    ("requiredtriangles", 1),
    ("requiredquadrilaterals", 1),
    ("requiredtetrahedra", 1),
    ("requiredhexahedra", 1),
    ("normals", 3),
    ("tangents", 3),
    ("normalatvertices", 2),
    ("tangentatvertices", 2),
    ("normalattrianglevertices", 3),
    ("normalatquadrilateralvertices", 3),
    ("tangentatedgevertices", 3),
    ("ridgesedges", 1),
];

/// The tokens of the text, with their line numbers.
struct Tokens<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    cur: std::str::SplitWhitespace<'a>,
    line: usize,
    /// Tokens left in the file at most (bytes / 2): a bound for corrupt counts.
    budget: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        Tokens {
            lines: text.lines().enumerate(),
            cur: "".split_whitespace(),
            line: 0,
            budget: text.len() / 2 + 1,
        }
    }

    fn next_token(&mut self) -> Option<&'a str> {
        loop {
            if let Some(t) = self.cur.next() {
                return Some(t);
            }
            let (i, l) = self.lines.next()?;
            self.line = i + 1;
            if !l.trim_start().starts_with('#') {
                self.cur = l.split_whitespace();
            }
        }
    }

    /// The next token parsed as a `T`, or an error naming `what`.
    fn get<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, ParseError> {
        let t = self.next_token().ok_or_else(|| {
            perr(
                self.line,
                format!("unexpected end of file, expected {what}"),
            )
        })?;
        t.parse()
            .map_err(|_| perr(self.line, format!("invalid {what} {t:?}")))
    }

    /// A table's entry count, refused when `per` numbers per entry cannot fit in the file.
    fn count(&mut self, keyword: &str, per: usize) -> Result<usize, ParseError> {
        let n: usize = self.get(&format!("the number of {keyword}"))?;
        if n.saturating_mul(per) > self.budget {
            return Err(perr(
                self.line,
                format!("{n} {keyword} are more than the file holds"),
            ));
        }
        Ok(n)
    }

    /// A 1-based vertex reference as a 0-based index below `n`.
    fn vertex(&mut self, n: usize) -> Result<u32, ParseError> {
        let v: usize = self.get("vertex index")?;
        v.checked_sub(1)
            .filter(|&i| i < n)
            .map(|i| i as u32)
            .ok_or_else(|| perr(self.line, format!("vertex {v} does not exist (1..={n})")))
    }
}

/// Parses the text of a `.mesh` file (see the module documentation).
pub(crate) fn parse_medit(text: &str) -> Result<MeshFile, ParseError> {
    let mut t = Tokens::new(text);
    let mut out = MeshFile::default();
    let mut tris: Vec<([u32; 3], i64)> = Vec::new();
    let mut refs: Vec<i64> = Vec::new();
    let mut seen_version = false;
    while let Some(word) = t.next_token() {
        let key = word.to_ascii_lowercase();
        match key.as_str() {
            "meshversionformatted" => {
                let _: i64 = t.get("the format version")?;
                seen_version = true;
            }
            _ if !seen_version => {
                return Err(perr(
                    t.line,
                    format!("not a Medit ASCII mesh: {word:?} before MeshVersionFormatted"),
                ))
            }
            "dimension" => {
                let d: usize = t.get("the dimension")?;
                if d != 3 {
                    return Err(perr(t.line, format!("dimension {d} (3 is read)")));
                }
            }
            "vertices" => vertices(&mut t, &mut out.mesh.points)?,
            "triangles" => {
                let n = t.count("triangles", 4)?;
                let np = out.mesh.points.len();
                for _ in 0..n {
                    let tri = [t.vertex(np)?, t.vertex(np)?, t.vertex(np)?];
                    tris.push((tri, t.get("triangle reference")?));
                }
            }
            "tetrahedra" => {
                let n = t.count("tetrahedra", 5)?;
                let np = out.mesh.points.len();
                for _ in 0..n {
                    let tet = [t.vertex(np)?, t.vertex(np)?, t.vertex(np)?, t.vertex(np)?];
                    out.mesh.tets.push(tet);
                    refs.push(t.get("tetrahedron reference")?);
                }
            }
            "end" => break,
            k => skip(&mut t, k, word)?,
        }
    }
    if !seen_version {
        return Err(perr(0, "empty file: no MeshVersionFormatted"));
    }
    out.node_groups = groups(&tris);
    if refs.iter().any(|&r| r != 0) {
        (out.regions, out.tet_region) = regions(&refs);
    }
    out.mesh.values = vec![0.0; out.mesh.points.len()];
    check_mesh(&out.mesh)?;
    Ok(out)
}

/// `Vertices`: `x y z ref` each (appended: a file may have several tables).
fn vertices(t: &mut Tokens, points: &mut Vec<[f64; 3]>) -> Result<(), ParseError> {
    let n = t.count("vertices", 4)?;
    if points.len() + n > u32::MAX as usize {
        return Err(perr(t.line, "too many vertices"));
    }
    for _ in 0..n {
        let p: [f64; 3] = [t.get("x")?, t.get("y")?, t.get("z")?];
        if !p.iter().all(|x| x.is_finite()) {
            return Err(perr(t.line, "non-finite coordinate"));
        }
        let _: f64 = t.get("vertex reference")?;
        points.push(p);
    }
    Ok(())
}

/// Skips the table of a known keyword `k`, or refuses an unknown one.
fn skip(t: &mut Tokens, k: &str, word: &str) -> Result<(), ParseError> {
    let Some(&(_, per)) = SKIPPED.iter().find(|(name, _)| *name == k) else {
        return Err(perr(
            t.line,
            format!("unknown keyword {word:?} (its table cannot be skipped)"),
        ));
    };
    let n = t.count(word, per)?;
    for _ in 0..n * per {
        let _: f64 = t.get(&format!("a number of {word}"))?;
    }
    Ok(())
}

/// A node group per non-zero triangle reference, in order of first use.
fn groups(tris: &[([u32; 3], i64)]) -> Vec<NodeGroup> {
    let mut out: Vec<NodeGroup> = Vec::new();
    let mut index: FxHashMap<i64, usize> = FxHashMap::default();
    for &(tri, r) in tris.iter().filter(|(_, r)| *r != 0) {
        let g = *index.entry(r).or_insert_with(|| {
            out.push(NodeGroup {
                name: r.to_string(),
                nodes: Vec::new(),
            });
            out.len() - 1
        });
        out[g].nodes.extend_from_slice(&tri);
    }
    normalize_groups(&mut out);
    out
}

/// Region names (by value, in order of first use) and each tet's region.
fn regions(refs: &[i64]) -> (Vec<String>, Vec<u32>) {
    let mut names = Vec::new();
    let mut index: FxHashMap<i64, u32> = FxHashMap::default();
    let of_tet = refs
        .iter()
        .map(|&r| {
            *index.entry(r).or_insert_with(|| {
                names.push(r.to_string());
                names.len() as u32 - 1
            })
        })
        .collect();
    (names, of_tet)
}
