//! Gmsh ASCII `.msh` reader (formats 4.1 and 2.2), the twin of [`super::msh`]; binary 4.1 is
//! read by [`super::msh_read_binary`] into the same [`State`].
//!
//! Reads `$MeshFormat`, `$PhysicalNames`, `$Entities` (4.1), `$Nodes`, `$Elements` and a
//! one-component `$NodeData` named `f`; other sections are skipped. Elements: 4-node
//! tetrahedra (type 4) and 3-node triangles (type 2); points and lines (types 15, 1) are
//! ignored, any other type is an error. Node tags may be any positive integers; nodes get
//! 0-based indices in file order. Groups:
//! * every physical group of dimension 2 becomes a [`NodeGroup`] (the nodes of its
//!   triangles), named by `$PhysicalNames` or, without a name, by its tag in decimal;
//!   triangles of the groups `alpha`, `beta`, `box` form the mesh boundary;
//! * every physical group of dimension 3 becomes a region; a tet without one is in the
//!   region `unassigned`.

use rustc_hash::FxHashMap;

use super::mesh_read_common::{
    check_mesh, field, label_of, normalize_groups, perr, Lines, MeshFile, NodeGroup, ParseError,
};

/// Gmsh element types this reader knows.
pub(super) const LINE: u32 = 1;
pub(super) const TRIANGLE: u32 = 2;
pub(super) const TETRAHEDRON: u32 = 4;
pub(super) const POINT: u32 = 15;

/// Everything read so far.
#[derive(Default)]
pub(super) struct State {
    /// Major version: 2 or 4.
    pub(super) version: u32,
    /// Physical names by (dimension, tag).
    pub(super) names: FxHashMap<(u32, i64), String>,
    /// Physical tags of the 4.1 entities, by (dimension, entity tag).
    pub(super) entity_phys: FxHashMap<(u32, i64), Vec<i64>>,
    /// Node tag → index.
    pub(super) index: FxHashMap<u64, u32>,
    pub(super) points: Vec<[f64; 3]>,
    pub(super) values: Option<Vec<f64>>,
    pub(super) tets: Vec<[u32; 4]>,
    /// Physical tag of each tet (0 = none).
    pub(super) tet_phys: Vec<i64>,
    /// Triangles with the physical tag of a group they belong to (one entry per group).
    pub(super) tris: Vec<([u32; 3], i64)>,
}

/// Parses the text of a `.msh` file (see the module documentation).
pub(crate) fn parse_msh(text: &str) -> Result<MeshFile, ParseError> {
    let mut l = Lines::new(text);
    let mut st = State::default();
    while let Some(line) = l.next_line() {
        match line {
            "$MeshFormat" => st.version = mesh_format(&mut l)?,
            _ if st.version == 0 => return Err(l.err("not a Gmsh file: no $MeshFormat first")),
            "$PhysicalNames" => physical_names(&mut l, &mut st)?,
            "$Entities" if st.version == 4 => entities(&mut l, &mut st)?,
            "$Nodes" if st.version == 4 => nodes_v41(&mut l, &mut st)?,
            "$Nodes" => nodes_v22(&mut l, &mut st)?,
            "$Elements" if st.version == 4 => elements_v41(&mut l, &mut st)?,
            "$Elements" => elements_v22(&mut l, &mut st)?,
            "$NodeData" => node_data(&mut l, &mut st)?,
            s if s.starts_with('$') && !s.starts_with("$End") => {
                skip_section(&mut l, s)?;
                continue;
            }
            s => return Err(l.err(format!("unexpected line {s:?}"))),
        }
        let end = l.expect("an $End line")?;
        if !end.starts_with("$End") {
            return Err(l.err(format!("expected the end of the section, found {end:?}")));
        }
    }
    finish(st)
}

fn mesh_format(l: &mut Lines) -> Result<u32, ParseError> {
    let line = l.expect("the format version")?;
    let f: Vec<&str> = line.split_whitespace().collect();
    if f.len() < 3 {
        return Err(l.err("malformed $MeshFormat line"));
    }
    if f[1] != "0" {
        return Err(
            l.err("binary .msh other than 4.1 is not read (convert: gmsh FILE -0 -format msh41)")
        );
    }
    match f[0] {
        "4.1" => Ok(4),
        "2.2" | "2.1" | "2" => Ok(2),
        v => Err(l.err(format!(
            "unsupported .msh version {v} (4.1 and 2.2 are read)"
        ))),
    }
}

fn skip_section(l: &mut Lines, name: &str) -> Result<(), ParseError> {
    let end = format!("$End{}", &name[1..]);
    loop {
        let line = l.expect(&end)?;
        if line == end {
            return Ok(());
        }
    }
}

fn count(l: &mut Lines, what: &str) -> Result<usize, ParseError> {
    let line = l.expect(what)?;
    field(line.split_whitespace().next().unwrap_or(""), l.line, what)
}

/// The whitespace-separated fields of the next line.
fn fields<'a>(l: &mut Lines<'a>, what: &str) -> Result<Vec<&'a str>, ParseError> {
    Ok(l.expect(what)?.split_whitespace().collect())
}

pub(super) fn physical_names(l: &mut Lines, st: &mut State) -> Result<(), ParseError> {
    let n = count(l, "the number of physical names")?;
    for _ in 0..n {
        let line = l.expect("a physical name")?;
        let mut it = line.splitn(3, char::is_whitespace);
        let dim: u32 = field(it.next().unwrap_or(""), l.line, "dimension")?;
        let tag: i64 = field(it.next().unwrap_or(""), l.line, "physical tag")?;
        let name = it.next().unwrap_or("").trim().trim_matches('"');
        st.names.insert((dim, tag), name.to_ascii_lowercase());
    }
    Ok(())
}

fn entities(l: &mut Lines, st: &mut State) -> Result<(), ParseError> {
    let f = fields(l, "the entity counts")?;
    if f.len() < 4 {
        return Err(l.err("malformed $Entities counts"));
    }
    for dim in 0..4u32 {
        let n: usize = field(f[dim as usize], l.line, "entity count")?;
        for _ in 0..n {
            let e = fields(l, "an entity")?;
            let first = if dim == 0 { 4 } else { 7 };
            let tag: i64 = field(e.first().copied().unwrap_or(""), l.line, "entity tag")?;
            let np: usize = field(e.get(first).copied().unwrap_or(""), l.line, "count")?;
            let phys = (0..np)
                .map(|k| field(e.get(first + 1 + k).copied().unwrap_or(""), l.line, "tag"))
                .collect::<Result<Vec<i64>, _>>()?;
            st.entity_phys.insert((dim, tag), phys);
        }
    }
    Ok(())
}

fn add_node(l: &Lines, st: &mut State, tag: u64, p: [f64; 3]) -> Result<(), ParseError> {
    if !p.iter().all(|x| x.is_finite()) {
        return Err(l.err("non-finite coordinate"));
    }
    let i = st.points.len() as u32;
    if st.index.insert(tag, i).is_some() {
        return Err(l.err(format!("node {tag} defined twice")));
    }
    st.points.push(p);
    Ok(())
}

fn coords(f: &[&str], line: usize) -> Result<[f64; 3], ParseError> {
    if f.len() < 3 {
        return Err(perr(line, "a node needs three coordinates"));
    }
    Ok([
        field(f[0], line, "coordinate")?,
        field(f[1], line, "coordinate")?,
        field(f[2], line, "coordinate")?,
    ])
}

fn nodes_v22(l: &mut Lines, st: &mut State) -> Result<(), ParseError> {
    let n = count(l, "the number of nodes")?;
    for _ in 0..n {
        let f = fields(l, "a node")?;
        let tag: u64 = field(f[0], l.line, "node tag")?;
        let p = coords(&f[1..], l.line)?;
        add_node(l, st, tag, p)?;
    }
    Ok(())
}

fn nodes_v41(l: &mut Lines, st: &mut State) -> Result<(), ParseError> {
    let f = fields(l, "the node counts")?;
    let blocks: usize = field(f[0], l.line, "block count")?;
    for _ in 0..blocks {
        let b = fields(l, "a node block header")?;
        if b.len() < 4 {
            return Err(l.err("malformed node block header"));
        }
        let parametric: u32 = field(b[2], l.line, "parametric flag")?;
        if parametric != 0 {
            return Err(l.err("parametric nodes are not supported"));
        }
        let n: usize = field(b[3], l.line, "node count")?;
        let mut tags = Vec::with_capacity(n.min(1 << 20));
        for _ in 0..n {
            let line = l.expect("a node tag")?;
            tags.push(field::<u64>(line, l.line, "node tag")?);
        }
        for tag in tags {
            let f = fields(l, "node coordinates")?;
            let p = coords(&f, l.line)?;
            add_node(l, st, tag, p)?;
        }
    }
    Ok(())
}

/// Node indices of the element whose node tags are `f`.
fn element_nodes<const N: usize>(
    l: &Lines,
    st: &State,
    f: &[&str],
) -> Result<[u32; N], ParseError> {
    if f.len() < N {
        return Err(l.err(format!("element needs {N} nodes")));
    }
    let mut out = [0u32; N];
    for k in 0..N {
        let tag: u64 = field(f[k], l.line, "node tag")?;
        out[k] = *st
            .index
            .get(&tag)
            .ok_or_else(|| l.err(format!("element refers to undefined node {tag}")))?;
    }
    Ok(out)
}

/// Stores one element of `kind` with nodes `f` in the groups `phys`.
fn add_element(
    l: &Lines,
    st: &mut State,
    kind: u32,
    f: &[&str],
    phys: &[i64],
) -> Result<(), ParseError> {
    match kind {
        TETRAHEDRON => {
            let tet = element_nodes::<4>(l, st, f)?;
            st.tets.push(tet);
            st.tet_phys.push(phys.first().copied().unwrap_or(0));
        }
        TRIANGLE => {
            let tri = element_nodes::<3>(l, st, f)?;
            for &p in phys {
                st.tris.push((tri, p));
            }
        }
        LINE | POINT => {}
        t => {
            return Err(l.err(format!(
                "unsupported element type {t} (only 4-node tetrahedra and triangles)"
            )))
        }
    }
    Ok(())
}

fn elements_v22(l: &mut Lines, st: &mut State) -> Result<(), ParseError> {
    let n = count(l, "the number of elements")?;
    for _ in 0..n {
        let f = fields(l, "an element")?;
        if f.len() < 3 {
            return Err(l.err("malformed element"));
        }
        let kind: u32 = field(f[1], l.line, "element type")?;
        let ntags: usize = field(f[2], l.line, "tag count")?;
        if f.len() < 3 + ntags {
            return Err(l.err("malformed element"));
        }
        let phys: Vec<i64> = match ntags {
            0 => Vec::new(),
            _ => vec![field(f[3], l.line, "physical tag")?],
        };
        let phys: Vec<i64> = phys.into_iter().filter(|&p| p != 0).collect();
        add_element(l, st, kind, &f[3 + ntags..], &phys)?;
    }
    Ok(())
}

fn elements_v41(l: &mut Lines, st: &mut State) -> Result<(), ParseError> {
    let f = fields(l, "the element counts")?;
    let blocks: usize = field(f[0], l.line, "block count")?;
    for _ in 0..blocks {
        let b = fields(l, "an element block header")?;
        if b.len() < 4 {
            return Err(l.err("malformed element block header"));
        }
        let dim: u32 = field(b[0], l.line, "entity dimension")?;
        let entity: i64 = field(b[1], l.line, "entity tag")?;
        let kind: u32 = field(b[2], l.line, "element type")?;
        let n: usize = field(b[3], l.line, "element count")?;
        let phys = st
            .entity_phys
            .get(&(dim, entity))
            .cloned()
            .unwrap_or_default();
        for _ in 0..n {
            let f = fields(l, "an element")?;
            add_element(l, st, kind, f.get(1..).unwrap_or(&[]), &phys)?;
        }
    }
    Ok(())
}

/// `$NodeData`: kept only when named `f` with one component.
fn node_data(l: &mut Lines, st: &mut State) -> Result<(), ParseError> {
    let mut tags = [Vec::new(), Vec::new(), Vec::new()];
    for t in &mut tags {
        let n = count(l, "a tag count")?;
        for _ in 0..n {
            t.push(l.expect("a tag")?.trim_matches('"').to_string());
        }
    }
    let name = tags[0].first().map(String::as_str).unwrap_or("");
    let comps = tags[2].get(1).map(String::as_str).unwrap_or("1");
    let n: usize = field(
        tags[2].get(2).map(String::as_str).unwrap_or("0"),
        l.line,
        "count",
    )?;
    let keep = name == "f" && comps == "1";
    let mut values = vec![0.0; st.points.len()];
    for _ in 0..n {
        let f = fields(l, "a node value")?;
        if !keep {
            continue;
        }
        let tag: u64 = field(f[0], l.line, "node tag")?;
        let v: f64 = field(f.get(1).copied().unwrap_or(""), l.line, "value")?;
        let i = *st
            .index
            .get(&tag)
            .ok_or_else(|| l.err(format!("value for undefined node {tag}")))?;
        values[i as usize] = v;
    }
    if keep {
        st.values = Some(values);
    }
    Ok(())
}

/// The name of the physical group (`dim`, `tag`).
fn name_of(st: &State, dim: u32, tag: i64) -> String {
    st.names
        .get(&(dim, tag))
        .cloned()
        .unwrap_or_else(|| tag.to_string())
}

pub(super) fn finish(st: State) -> Result<MeshFile, ParseError> {
    let mut out = MeshFile::default();
    let mut group_of: FxHashMap<i64, usize> = FxHashMap::default();
    for &(tri, p) in &st.tris {
        let name = name_of(&st, 2, p);
        if let Some(label) = label_of(&name) {
            out.mesh.boundary.push(tri);
            out.mesh.boundary_labels.push(label);
        }
        let g = *group_of.entry(p).or_insert_with(|| {
            out.node_groups.push(NodeGroup {
                name,
                nodes: Vec::new(),
            });
            out.node_groups.len() - 1
        });
        out.node_groups[g].nodes.extend_from_slice(&tri);
    }
    normalize_groups(&mut out.node_groups);
    if st.tet_phys.iter().any(|&p| p != 0) {
        let mut region_of: FxHashMap<i64, u32> = FxHashMap::default();
        for &p in &st.tet_phys {
            let r = *region_of.entry(p).or_insert_with(|| {
                let name = if p == 0 {
                    "unassigned".into()
                } else {
                    name_of(&st, 3, p)
                };
                out.regions.push(name);
                out.regions.len() as u32 - 1
            });
            out.tet_region.push(r);
        }
    }
    out.mesh.values = st.values.unwrap_or_else(|| vec![0.0; st.points.len()]);
    out.mesh.points = st.points;
    out.mesh.tets = st.tets;
    check_mesh(&out.mesh)?;
    Ok(out)
}
