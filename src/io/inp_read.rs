//! Abaqus / CalculiX `.inp` reader, the twin of [`super::inp`].
//!
//! Reads `*NODE` (ids any positive integers; nodes get 0-based indices in file order),
//! `*ELEMENT, TYPE=C3D4` (its `ELSET=` names the region of its elements), `*ELSET, ELSET=name`
//! (element ids, or `first, last, step` with `GENERATE`: the listed elements move to the
//! region `name`, so sets written after the elements, as the writer's per-region sets, name
//! the regions), `*NSET, NSET=name` (ids, or `first, last, step` with `GENERATE`) and `*SURFACE, NAME=name, TYPE=ELEMENT`
//! (lines `element, Sk`, C3D4 faces S1 = 1-2-3, S2 = 1-4-2, S3 = 2-4-3, S4 = 3-4-1). Other
//! keywords and their data lines are skipped; `**` lines are comments; `*INCLUDE` and element
//! types other than C3D4 are errors.
//!
//! Every `*NSET` becomes a [`NodeGroup`]; a surface without a node set of the same name adds
//! the nodes of its faces as a group. Faces of the surfaces `alpha`, `beta`, `box` form the
//! mesh boundary, each oriented away from its tetrahedron.

use rustc_hash::FxHashMap;

use super::mesh_read_common::{
    check_mesh, field, label_of, normalize_groups, Lines, MeshFile, NodeGroup, ParseError,
};
use crate::mesh::BoundaryLabel;

/// Local vertex indices of the C3D4 faces S1..S4.
const C3D4_FACES: [[usize; 3]; 4] = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];

/// The keyword block being read.
#[derive(Clone, Debug, PartialEq)]
enum Block {
    Skip,
    Node,
    Element(u32),
    Nset(usize, bool),
    Elset(u32, bool),
    Surface(String),
}

#[derive(Default)]
struct State {
    node_index: FxHashMap<u64, u32>,
    elem_index: FxHashMap<u64, u32>,
    out: MeshFile,
    /// Surfaces: name and (tet, face) pairs.
    surfaces: Vec<(String, Vec<(u32, usize)>)>,
}

/// The value of `key=` in the keyword line `parts` (case-insensitive key), if present.
fn param<'a>(parts: &[&'a str], key: &str) -> Option<&'a str> {
    parts.iter().skip(1).find_map(|p| {
        let (k, v) = p.split_once('=')?;
        k.trim().eq_ignore_ascii_case(key).then(|| v.trim())
    })
}

fn has_flag(parts: &[&str], flag: &str) -> bool {
    parts
        .iter()
        .skip(1)
        .any(|p| p.trim().eq_ignore_ascii_case(flag))
}

/// Parses the text of an `.inp` file (see the module documentation).
pub(crate) fn parse_inp(text: &str) -> Result<MeshFile, ParseError> {
    let mut l = Lines::new(text);
    let mut st = State::default();
    let mut block = Block::Skip;
    while let Some(line) = l.next_line() {
        if line.starts_with("**") {
            continue;
        }
        if line.starts_with('*') {
            block = keyword(&l, &mut st, line)?;
            continue;
        }
        let f: Vec<&str> = line
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        match &block {
            Block::Skip => {}
            Block::Node => node(&l, &mut st, &f)?,
            &Block::Element(region) => element(&l, &mut st, &f, region)?,
            &Block::Nset(g, generate) => nset(&l, &mut st, &f, g, generate)?,
            &Block::Elset(r, generate) => elset(&l, &mut st, &f, r, generate)?,
            Block::Surface(_) => surface_face(&l, &mut st, &f)?,
        }
    }
    finish(st)
}

/// The index of region `set` (lower case), added when new.
fn region_index(st: &mut State, set: &str) -> u32 {
    let set = set.to_ascii_lowercase();
    let r = match st.out.regions.iter().position(|r| *r == set) {
        Some(r) => r,
        None => {
            st.out.regions.push(set);
            st.out.regions.len() - 1
        }
    };
    r as u32
}

fn keyword(l: &Lines, st: &mut State, line: &str) -> Result<Block, ParseError> {
    let parts: Vec<&str> = line.split(',').collect();
    let name = parts[0].trim().to_ascii_uppercase();
    Ok(match name.as_str() {
        "*NODE" => Block::Node,
        "*ELEMENT" => {
            let ty = param(&parts, "TYPE").unwrap_or("");
            if !ty.eq_ignore_ascii_case("C3D4") {
                return Err(l.err(format!("unsupported element type {ty:?} (only C3D4)")));
            }
            let set = param(&parts, "ELSET").unwrap_or("unassigned");
            Block::Element(region_index(st, set))
        }
        "*ELSET" => {
            let set = param(&parts, "ELSET").ok_or_else(|| l.err("*ELSET without ELSET="))?;
            Block::Elset(region_index(st, set), has_flag(&parts, "GENERATE"))
        }
        "*NSET" => {
            let set = param(&parts, "NSET").ok_or_else(|| l.err("*NSET without NSET="))?;
            st.out.node_groups.push(NodeGroup {
                name: set.to_ascii_lowercase(),
                nodes: Vec::new(),
            });
            Block::Nset(st.out.node_groups.len() - 1, has_flag(&parts, "GENERATE"))
        }
        "*SURFACE" => {
            let set = param(&parts, "NAME").ok_or_else(|| l.err("*SURFACE without NAME="))?;
            let ty = param(&parts, "TYPE").unwrap_or("ELEMENT");
            if !ty.eq_ignore_ascii_case("ELEMENT") {
                return Err(l.err(format!("unsupported surface type {ty:?}")));
            }
            st.surfaces.push((set.to_ascii_lowercase(), Vec::new()));
            Block::Surface(set.to_string())
        }
        "*INCLUDE" => return Err(l.err("*INCLUDE is not supported")),
        _ => Block::Skip,
    })
}

fn node(l: &Lines, st: &mut State, f: &[&str]) -> Result<(), ParseError> {
    if f.len() < 4 {
        return Err(l.err("a node line needs an id and three coordinates"));
    }
    let id: u64 = field(f[0], l.line, "node id")?;
    let mut p = [0.0f64; 3];
    for k in 0..3 {
        p[k] = field(f[k + 1], l.line, "coordinate")?;
    }
    if !p.iter().all(|x| x.is_finite()) {
        return Err(l.err("non-finite coordinate"));
    }
    let i = st.out.mesh.points.len() as u32;
    if st.node_index.insert(id, i).is_some() {
        return Err(l.err(format!("node {id} defined twice")));
    }
    st.out.mesh.points.push(p);
    Ok(())
}

fn node_ref(l: &Lines, st: &State, s: &str) -> Result<u32, ParseError> {
    let id: u64 = field(s, l.line, "node id")?;
    st.node_index
        .get(&id)
        .copied()
        .ok_or_else(|| l.err(format!("undefined node {id}")))
}

fn element(l: &Lines, st: &mut State, f: &[&str], region: u32) -> Result<(), ParseError> {
    if f.len() != 5 {
        return Err(l.err("a C3D4 line needs an id and four nodes"));
    }
    let id: u64 = field(f[0], l.line, "element id")?;
    let mut tet = [0u32; 4];
    for k in 0..4 {
        tet[k] = node_ref(l, st, f[k + 1])?;
    }
    let t = st.out.mesh.tets.len() as u32;
    if st.elem_index.insert(id, t).is_some() {
        return Err(l.err(format!("element {id} defined twice")));
    }
    st.out.mesh.tets.push(tet);
    st.out.tet_region.push(region);
    Ok(())
}

fn nset(l: &Lines, st: &mut State, f: &[&str], g: usize, generate: bool) -> Result<(), ParseError> {
    if generate {
        let a: u64 = field(f.first().copied().unwrap_or(""), l.line, "first id")?;
        let b: u64 = field(f.get(1).copied().unwrap_or(""), l.line, "last id")?;
        let s: u64 = field(f.get(2).copied().unwrap_or("1"), l.line, "step")?;
        if s == 0 || b < a {
            return Err(l.err("invalid GENERATE range"));
        }
        for id in (a..=b).step_by(s as usize) {
            let i = node_ref(l, st, &id.to_string())?;
            st.out.node_groups[g].nodes.push(i);
        }
        return Ok(());
    }
    for s in f {
        let i = node_ref(l, st, s)?;
        st.out.node_groups[g].nodes.push(i);
    }
    Ok(())
}

/// An `*ELSET` data line: its elements move to region `r`.
fn elset(l: &Lines, st: &mut State, f: &[&str], r: u32, generate: bool) -> Result<(), ParseError> {
    let ids: Vec<u64> = match generate {
        true => {
            let a: u64 = field(f.first().copied().unwrap_or(""), l.line, "first id")?;
            let b: u64 = field(f.get(1).copied().unwrap_or(""), l.line, "last id")?;
            let s: u64 = field(f.get(2).copied().unwrap_or("1"), l.line, "step")?;
            if s == 0 || b < a {
                return Err(l.err("invalid GENERATE range"));
            }
            (a..=b).step_by(s as usize).collect()
        }
        false => (f.iter())
            .map(|s| field(s, l.line, "element id (sets of sets are not read)"))
            .collect::<Result<_, _>>()?,
    };
    for id in ids {
        let t = *st
            .elem_index
            .get(&id)
            .ok_or_else(|| l.err(format!("undefined element {id}")))?;
        st.out.tet_region[t as usize] = r;
    }
    Ok(())
}

fn surface_face(l: &Lines, st: &mut State, f: &[&str]) -> Result<(), ParseError> {
    if f.len() != 2 {
        return Err(l.err("a surface line needs an element id and a face S1..S4"));
    }
    let id: u64 = field(f[0], l.line, "element id")?;
    let t = *st
        .elem_index
        .get(&id)
        .ok_or_else(|| l.err(format!("undefined element {id}")))?;
    let face = match f[1].to_ascii_uppercase().as_str() {
        "S1" => 0,
        "S2" => 1,
        "S3" => 2,
        "S4" => 3,
        s => return Err(l.err(format!("invalid face {s:?} (S1..S4)"))),
    };
    if let Some(s) = st.surfaces.last_mut() {
        s.1.push((t, face));
    }
    Ok(())
}

/// Face `face` of tet `t`, oriented so that the opposite node lies behind it.
fn outward_face(st: &State, t: u32, face: usize) -> [u32; 3] {
    let mesh = &st.out.mesh;
    let tet = mesh.tets[t as usize];
    let [a, b, c] = C3D4_FACES[face].map(|k| tet[k]);
    let opposite = tet[6 - C3D4_FACES[face].iter().sum::<usize>()];
    let p = |i: u32| mesh.points[i as usize];
    let vol = crate::geom::signed_volume(p(a), p(b), p(c), p(opposite));
    if vol > 0.0 {
        [a, c, b]
    } else {
        [a, b, c]
    }
}

fn finish(mut st: State) -> Result<MeshFile, ParseError> {
    let surfaces = std::mem::take(&mut st.surfaces);
    for (name, faces) in &surfaces {
        let tris: Vec<[u32; 3]> = faces
            .iter()
            .map(|&(t, k)| outward_face(&st, t, k))
            .collect();
        if let Some(label) = label_of(name) {
            st.out.mesh.boundary.extend_from_slice(&tris);
            st.out
                .mesh
                .boundary_labels
                .extend(std::iter::repeat_n(label, tris.len()));
        }
        if st.out.group(name).is_none() {
            let nodes = tris.iter().flatten().copied().collect();
            st.out.node_groups.push(NodeGroup {
                name: name.clone(),
                nodes,
            });
        }
    }
    sort_boundary(&mut st.out.mesh);
    normalize_groups(&mut st.out.node_groups);
    st.out.mesh.values = vec![0.0; st.out.mesh.points.len()];
    check_mesh(&st.out.mesh)?;
    Ok(st.out)
}

/// Orders the boundary triangles by label (stable), as the writers group them.
fn sort_boundary(mesh: &mut crate::mesh::TetMesh) {
    let mut order: Vec<usize> = (0..mesh.boundary.len()).collect();
    order.sort_by_key(|&b| mesh.boundary_labels[b]);
    mesh.boundary = order.iter().map(|&b| mesh.boundary[b]).collect();
    mesh.boundary_labels = order
        .iter()
        .map(|&b| mesh.boundary_labels[b])
        .collect::<Vec<BoundaryLabel>>();
}
