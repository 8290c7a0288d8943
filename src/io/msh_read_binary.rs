//! Gmsh binary `.msh` 4.1 reader, the twin of [`super::msh`]'s `--msh-version 4.1-binary`
//! and of what `gmsh -bin` writes: the sections, groups and elements of the ASCII reader
//! ([`super::msh_read`]), in Gmsh's binary encoding — `size_t` (8 bytes: the format line's
//! data size must be 8) counts and node and element tags, `int` entity, physical and type
//! numbers and `$NodeData` node tags, `double` coordinates and values, in the byte order
//! the `int` 1 after the format line shows. `$PhysicalNames` and the head of `$NodeData` are
//! text. Elements: tetrahedra and triangles; points and lines are skipped; any other type is
//! an error (its size is not known here). Errors name the byte offset.

use super::mesh_read_common::{perr, Lines, MeshFile, ParseError};
use super::msh_read::{finish, physical_names, State, LINE, POINT, TETRAHEDRON, TRIANGLE};

/// Whether `bytes` start a binary `.msh` file (`$MeshFormat` then a version with file type 1).
pub(crate) fn is_binary_msh(bytes: &[u8]) -> bool {
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(64)]).into_owned();
    let mut lines = head.lines().map(str::trim).filter(|l| !l.is_empty());
    lines.next() == Some("$MeshFormat")
        && lines
            .next()
            .is_some_and(|l| l.split_whitespace().nth(1) == Some("1"))
}

/// A cursor over the file's bytes.
struct Cur<'a> {
    b: &'a [u8],
    pos: usize,
    /// The file's numbers are big-endian.
    big: bool,
}

impl<'a> Cur<'a> {
    fn err(&self, m: impl std::fmt::Display) -> ParseError {
        perr(0, format!("at byte {}: {m}", self.pos))
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], ParseError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| self.err(format!("the file ends inside {what}")))?;
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn bytes<const N: usize>(&mut self, what: &str) -> Result<[u8; N], ParseError> {
        let mut a: [u8; N] = self.take(N, what)?.try_into().expect("N bytes");
        if self.big {
            a.reverse();
        }
        Ok(a)
    }

    fn size(&mut self, what: &str) -> Result<usize, ParseError> {
        let v = u64::from_le_bytes(self.bytes(what)?);
        usize::try_from(v).map_err(|_| self.err(format!("{what} {v} is too large")))
    }

    fn int(&mut self, what: &str) -> Result<i32, ParseError> {
        Ok(i32::from_le_bytes(self.bytes(what)?))
    }

    fn double(&mut self, what: &str) -> Result<f64, ParseError> {
        Ok(f64::from_le_bytes(self.bytes(what)?))
    }

    /// A count of entries of at least `per` bytes each, refused when they cannot fit.
    fn count(&mut self, per: usize, what: &str) -> Result<usize, ParseError> {
        let n = self.size(what)?;
        if n.saturating_mul(per) > self.b.len() - self.pos {
            return Err(self.err(format!("{what} {n} is more than the file holds")));
        }
        Ok(n)
    }

    /// The next non-blank text line, trimmed.
    fn line(&mut self, what: &str) -> Result<&'a str, ParseError> {
        loop {
            let rest = &self.b[self.pos..];
            if rest.is_empty() {
                return Err(self.err(format!("unexpected end of file, expected {what}")));
            }
            let end = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
            self.pos += (end + 1).min(rest.len());
            let l = std::str::from_utf8(&rest[..end])
                .map_err(|_| self.err(format!("expected {what}, found binary data")))?
                .trim();
            if !l.is_empty() {
                return Ok(l);
            }
        }
    }

    /// Text up to the line `end` (excluded), and past that line.
    fn text_until(&mut self, end: &str) -> Result<&'a str, ParseError> {
        let rest = &self.b[self.pos..];
        let at = find(rest, end.as_bytes()).ok_or_else(|| self.err(format!("no {end}")))?;
        let text = std::str::from_utf8(&rest[..at])
            .map_err(|_| self.err(format!("binary data before {end}")))?;
        self.pos += at;
        self.line(end)?;
        Ok(text)
    }
}

/// The first position of `pat` in `b`.
fn find(b: &[u8], pat: &[u8]) -> Option<usize> {
    b.windows(pat.len()).position(|w| w == pat)
}

/// Parses a binary `.msh` 4.1 file (see the module documentation).
pub(crate) fn parse_msh_binary(bytes: &[u8]) -> Result<MeshFile, ParseError> {
    let mut c = Cur {
        b: bytes,
        pos: 0,
        big: false,
    };
    header(&mut c)?;
    let mut st = State {
        version: 4,
        ..State::default()
    };
    while c.b[c.pos..].iter().any(|b| !b.is_ascii_whitespace()) {
        let name = c.line("a section")?;
        match name {
            "$PhysicalNames" => {
                let text = c.text_until("$EndPhysicalNames")?;
                physical_names(&mut Lines::new(text), &mut st)
                    .map_err(|e| c.err(format!("$PhysicalNames: {}", e.message)))?;
                continue;
            }
            "$Entities" => entities(&mut c, &mut st)?,
            "$Nodes" => nodes(&mut c, &mut st)?,
            "$Elements" => elements(&mut c, &mut st)?,
            "$NodeData" => node_data(&mut c, &mut st)?,
            s if s.starts_with('$') && !s.starts_with("$End") => {
                let end = format!("\n$End{}", &s[1..]);
                let at = find(&c.b[c.pos..], end.as_bytes())
                    .ok_or_else(|| c.err(format!("no $End{}", &s[1..])))?;
                c.pos += at;
            }
            s => return Err(c.err(format!("unexpected {s:?}"))),
        }
        let end = c.line("an $End line")?;
        if !end.starts_with("$End") {
            return Err(c.err(format!("expected the end of the section, found {end:?}")));
        }
    }
    finish(st)
}

/// `$MeshFormat`: version 4.1, file type 1, data size 8, the `int` 1 (byte order).
fn header(c: &mut Cur) -> Result<(), ParseError> {
    c.line("$MeshFormat")?;
    let f: Vec<&str> = c.line("the format line")?.split_whitespace().collect();
    if f.first() != Some(&"4.1") {
        return Err(c.err(format!(
            "binary .msh version {} is not read (4.1 is)",
            f.first().unwrap_or(&"?")
        )));
    }
    if f.get(2) != Some(&"8") {
        return Err(c.err("data size other than 8 is not read"));
    }
    let one = c.take(4, "the byte-order int")?;
    c.big = match one {
        [1, 0, 0, 0] => false,
        [0, 0, 0, 1] => true,
        _ => return Err(c.err("the int after the format line is not 1")),
    };
    if c.line("$EndMeshFormat")? != "$EndMeshFormat" {
        return Err(c.err("expected $EndMeshFormat"));
    }
    Ok(())
}

/// `$Entities`: the physical tags of every entity.
fn entities(c: &mut Cur, st: &mut State) -> Result<(), ParseError> {
    let mut counts = [0usize; 4];
    for n in &mut counts {
        *n = c.count(4, "entity count")?;
    }
    for (dim, n) in counts.into_iter().enumerate() {
        for _ in 0..n {
            let tag = c.int("an entity tag")?;
            let coords = if dim == 0 { 3 } else { 6 };
            c.take(8 * coords, "an entity's box")?;
            let np = c.count(4, "physical tag count")?;
            let phys = (0..np)
                .map(|_| c.int("a physical tag").map(i64::from))
                .collect::<Result<Vec<_>, _>>()?;
            if dim > 0 {
                let nb = c.count(4, "bounding entity count")?;
                c.take(4 * nb, "bounding entities")?;
            }
            st.entity_phys.insert((dim as u32, i64::from(tag)), phys);
        }
    }
    Ok(())
}

/// `$Nodes`: blocks of tags then coordinates.
fn nodes(c: &mut Cur, st: &mut State) -> Result<(), ParseError> {
    let blocks = c.count(20, "node block count")?;
    c.take(24, "the node counts")?;
    for _ in 0..blocks {
        c.take(8, "a node block header")?;
        if c.int("the parametric flag")? != 0 {
            return Err(c.err("parametric nodes are not supported"));
        }
        let n = c.count(32, "node count")?;
        let tags = (0..n)
            .map(|_| c.size("a node tag").map(|t| t as u64))
            .collect::<Result<Vec<_>, _>>()?;
        for tag in tags {
            let p = [c.double("x")?, c.double("y")?, c.double("z")?];
            if !p.iter().all(|x| x.is_finite()) {
                return Err(c.err("non-finite coordinate"));
            }
            let i = u32::try_from(st.points.len()).map_err(|_| c.err("too many nodes"))?;
            if st.index.insert(tag, i).is_some() {
                return Err(c.err(format!("node {tag} defined twice")));
            }
            st.points.push(p);
        }
    }
    Ok(())
}

/// The node index of node tag `tag`.
fn node(c: &Cur, st: &State, tag: usize) -> Result<u32, ParseError> {
    st.index
        .get(&(tag as u64))
        .copied()
        .ok_or_else(|| c.err(format!("element refers to undefined node {tag}")))
}

/// `$Elements`: blocks of tetrahedra and triangles (points and lines skipped).
fn elements(c: &mut Cur, st: &mut State) -> Result<(), ParseError> {
    let blocks = c.count(20, "element block count")?;
    c.take(24, "the element counts")?;
    for _ in 0..blocks {
        let dim = c.int("an entity dimension")?;
        let entity = c.int("an entity tag")?;
        let kind = c.int("an element type")?;
        let per = match kind as u32 {
            TETRAHEDRON => 4,
            TRIANGLE => 3,
            LINE => 2,
            POINT => 1,
            t => {
                return Err(c.err(format!(
                    "unsupported element type {t} (only 4-node tetrahedra and triangles)"
                )))
            }
        };
        let n = c.count(8 * (per + 1), "element count")?;
        let phys = st
            .entity_phys
            .get(&(dim as u32, i64::from(entity)))
            .cloned()
            .unwrap_or_default();
        for _ in 0..n {
            c.size("an element tag")?;
            let mut v = [0u32; 4];
            for x in v.iter_mut().take(per) {
                let tag = c.size("a node tag")?;
                *x = node(c, st, tag)?;
            }
            match per {
                4 => {
                    st.tets.push(v);
                    st.tet_phys.push(phys.first().copied().unwrap_or(0));
                }
                3 => st
                    .tris
                    .extend(phys.iter().map(|&p| ([v[0], v[1], v[2]], p))),
                _ => {}
            }
        }
    }
    Ok(())
}

/// `$NodeData`: the text head (string, real and integer tags), then `int` node tags and
/// values; kept when named `f` with one component.
fn node_data(c: &mut Cur, st: &mut State) -> Result<(), ParseError> {
    let mut tags: [Vec<&str>; 3] = Default::default();
    for t in &mut tags {
        let n: usize = c
            .line("a tag count")?
            .parse()
            .map_err(|_| c.err("bad $NodeData tag count"))?;
        for _ in 0..n {
            t.push(c.line("a tag")?.trim_matches('"'));
        }
    }
    let comps: usize = tags[2].get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    if comps == 0 {
        return Err(c.err("$NodeData with 0 components"));
    }
    let n: usize = tags[2]
        .get(2)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| c.err("$NodeData without a value count"))?;
    if n.saturating_mul(4 + 8 * comps) > c.b.len() - c.pos {
        return Err(c.err("$NodeData holds more values than the file"));
    }
    let keep = tags[0].first() == Some(&"f") && comps == 1;
    let mut values = vec![0.0; st.points.len()];
    for _ in 0..n {
        let tag = c.int("a node tag")?;
        let v = c.double("a value")?;
        c.take(8 * (comps - 1), "values")?;
        if keep {
            let i = usize::try_from(tag).map_err(|_| c.err("bad node tag"))?;
            let i = node(c, st, i)?;
            values[i as usize] = v;
        }
    }
    if keep {
        st.values = Some(values);
    }
    Ok(())
}
