//! Gmsh ASCII `.msh` writer (formats 4.1 and 2.2).
//!
//! Numbering and tags, identical in both versions:
//! * node `i` of the mesh gets tag `i + 1`; tet `t` gets element tag `t + 1`; the boundary
//!   triangles follow, grouped by label in the order alpha, beta, box (mesh order within a
//!   label), with tags `#T + 1, …`;
//! * physical groups: surfaces `alpha` = 1, `beta` = 2, `box` = 3 (dimension 2, only the
//!   labels that occur) and volume `domain` = 4 (dimension 3); the elementary entity of a
//!   surface has the same tag as its physical group, the volume entity has tag 1;
//! * the field is written as `$NodeData` named `f` (time 0, step 0, one component).
//!
//! Coordinates and values use the shortest decimal form that parses back to the same `f64`.

use std::io::{self, Write};

use super::write_common::{check_lengths, present_labels, TextOut};
use crate::mesh::{BoundaryLabel, TetMesh};

/// Which `.msh` format version [`write_msh`] produces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MshVersion {
    /// Gmsh 4.1 ASCII (`$Entities`, entity-blocked `$Nodes`/`$Elements`); the default.
    #[default]
    V41,
    /// Legacy Gmsh 2.2 ASCII, read by most third-party tools.
    V22,
}

/// Physical tag of the volume group `domain`.
pub const DOMAIN_PHYSICAL_TAG: u32 = 4;

/// Physical (and elementary surface) tag of the boundary group of `label`: 1, 2, 3 for
/// alpha, beta, box.
pub fn label_tag(label: BoundaryLabel) -> u32 {
    label as u32 + 1
}

/// Gmsh element type of a 3-node triangle.
const TRIANGLE: u32 = 2;
/// Gmsh element type of a 4-node tetrahedron.
const TETRAHEDRON: u32 = 4;
/// Elementary tag of the single volume entity.
const VOLUME_ENTITY: u32 = 1;

/// Writes `mesh` as a Gmsh ASCII mesh of the given version: nodes, tetrahedra (volume
/// physical group `domain`), the labelled boundary triangles (surface physical groups
/// `alpha`, `beta`, `box`, only those that occur) and the nodal field `f` (see the module
/// documentation for numbering and tags). The output is deterministic.
///
/// # Errors
/// Returns the first error of `w`, or [`io::ErrorKind::InvalidInput`] when the mesh is
/// inconsistent (`values` or `boundary_labels` of the wrong length).
pub fn write_msh(mesh: &TetMesh, w: &mut dyn Write, version: MshVersion) -> io::Result<()> {
    check_lengths(mesh)?;
    let mut out = TextOut::new(w);
    let present = present_labels(mesh);
    match version {
        MshVersion::V41 => write_v41(mesh, &present, &mut out)?,
        MshVersion::V22 => write_v22(mesh, &present, &mut out)?,
    }
    out.finish()
}

fn header(out: &mut TextOut, version: &str, present: &[(BoundaryLabel, usize)]) -> io::Result<()> {
    out.s("$MeshFormat").nl()?;
    out.s(version).s(" 0 8").nl()?;
    out.s("$EndMeshFormat").nl()?;
    out.s("$PhysicalNames").nl()?;
    out.int(present.len() + 1).nl()?;
    for &(label, _) in present {
        out.s("2 ")
            .int(label_tag(label))
            .s(" \"")
            .s(label.name())
            .s("\"")
            .nl()?;
    }
    out.s("3 ").int(DOMAIN_PHYSICAL_TAG).s(" \"domain\"").nl()?;
    out.s("$EndPhysicalNames").nl()
}

fn node_data(mesh: &TetMesh, out: &mut TextOut) -> io::Result<()> {
    out.s("$NodeData").nl()?;
    out.s("1").nl()?;
    out.s("\"f\"").nl()?;
    out.s("1").nl()?;
    out.s("0").nl()?;
    out.s("3").nl()?;
    out.s("0").nl()?;
    out.s("1").nl()?;
    out.int(mesh.points.len()).nl()?;
    for (i, &v) in mesh.values.iter().enumerate() {
        out.int(i + 1).s(" ").float(v).nl()?;
    }
    out.s("$EndNodeData").nl()
}

fn point<'o, 'w>(out: &'o mut TextOut<'w>, p: [f64; 3]) -> &'o mut TextOut<'w> {
    out.vec3(p)
}

/// Axis-aligned bounding box of the given node indices (zeros if there are none).
fn bbox(mesh: &TetMesh, nodes: impl Iterator<Item = u32>) -> [f64; 6] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for i in nodes {
        let p = mesh.points[i as usize];
        for k in 0..3 {
            b[k] = b[k].min(p[k]);
            b[k + 3] = b[k + 3].max(p[k]);
        }
    }
    if b[0] > b[3] {
        [0.0; 6]
    } else {
        b
    }
}

fn write_v41(
    mesh: &TetMesh,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    header(out, "4.1", present)?;
    entities_v41(mesh, present, out)?;
    nodes_v41(mesh, out)?;
    elements_v41(mesh, present, out)?;
    node_data(mesh, out)
}

/// `$Entities`: one surface per boundary label that occurs, then the volume entity.
fn entities_v41(
    mesh: &TetMesh,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    out.s("$Entities").nl()?;
    out.s("0 0 ").int(present.len()).s(" 1").nl()?;
    for &(label, _) in present {
        let nodes = triangles_labelled(mesh, label).flat_map(|t| t.iter().copied());
        out.int(label_tag(label));
        bbox_fields(out, bbox(mesh, nodes));
        // one physical tag; no bounding curves
        out.s(" 1 ").int(label_tag(label)).s(" 0").nl()?;
    }
    out.int(VOLUME_ENTITY);
    bbox_fields(out, bbox(mesh, 0..mesh.points.len() as u32));
    out.s(" 1 ")
        .int(DOMAIN_PHYSICAL_TAG)
        .s(" ")
        .int(present.len());
    for &(label, _) in present {
        out.s(" ").int(label_tag(label));
    }
    out.nl()?;
    out.s("$EndEntities").nl()
}

/// Appends the six numbers of a bounding box, each preceded by a space.
fn bbox_fields(out: &mut TextOut, b: [f64; 6]) {
    for x in b {
        out.s(" ").float(x);
    }
}

/// `$Nodes`: all nodes in one block classified on the volume entity.
fn nodes_v41(mesh: &TetMesh, out: &mut TextOut) -> io::Result<()> {
    let n_points = mesh.points.len();
    out.s("$Nodes").nl()?;
    let max_tag = n_points; // 0 when empty, matching gmsh's own output for empty meshes
    let min_tag = usize::from(n_points > 0);
    out.int(1)
        .s(" ")
        .int(n_points)
        .s(" ")
        .int(min_tag)
        .s(" ")
        .int(max_tag)
        .nl()?;
    out.s("3 ").int(VOLUME_ENTITY).s(" 0 ").int(n_points).nl()?;
    for i in 1..=n_points {
        out.int(i).nl()?;
    }
    for &p in &mesh.points {
        point(out, p).nl()?;
    }
    out.s("$EndNodes").nl()
}

/// `$Elements`: the tets in one block on the volume entity, then one triangle block per
/// boundary label that occurs.
fn elements_v41(
    mesh: &TetMesh,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    let n_tets = mesh.tets.len();
    let n_elems = n_tets + mesh.boundary.len();
    out.s("$Elements").nl()?;
    out.int(present.len() + 1)
        .s(" ")
        .int(n_elems)
        .s(" ")
        .int(usize::from(n_elems > 0))
        .s(" ")
        .int(n_elems)
        .nl()?;
    element_block(out, VOLUME_ENTITY, 3, TETRAHEDRON, n_tets)?;
    for (t, tet) in mesh.tets.iter().enumerate() {
        element_nodes(out.int(t + 1), tet)?;
    }
    let mut tag = n_tets;
    for &(label, count) in present {
        element_block(out, label_tag(label), 2, TRIANGLE, count)?;
        for tri in triangles_labelled(mesh, label) {
            tag += 1;
            element_nodes(out.int(tag), tri)?;
        }
    }
    out.s("$EndElements").nl()
}

/// The header line of an element block: entity dimension, entity tag, element type, count.
fn element_block(
    out: &mut TextOut,
    entity: u32,
    dim: u32,
    element_type: u32,
    count: usize,
) -> io::Result<()> {
    out.int(dim)
        .s(" ")
        .int(entity)
        .s(" ")
        .int(element_type)
        .s(" ")
        .int(count)
        .nl()
}

/// Appends the 1-based node tags of an element, each preceded by a space, and ends the line.
fn element_nodes(out: &mut TextOut, nodes: &[u32]) -> io::Result<()> {
    for &v in nodes {
        out.s(" ").int(v + 1);
    }
    out.nl()
}

fn write_v22(
    mesh: &TetMesh,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    header(out, "2.2", present)?;
    out.s("$Nodes").nl()?;
    out.int(mesh.points.len()).nl()?;
    for (i, &p) in mesh.points.iter().enumerate() {
        out.int(i + 1).s(" ");
        point(out, p).nl()?;
    }
    out.s("$EndNodes").nl()?;
    elements_v22(mesh, present, out)?;
    node_data(mesh, out)
}

/// `$Elements` (2.2): the tets, then the boundary triangles grouped by label; each element
/// carries two tags, physical and elementary.
fn elements_v22(
    mesh: &TetMesh,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    out.s("$Elements").nl()?;
    let n_tets = mesh.tets.len();
    out.int(n_tets + mesh.boundary.len()).nl()?;
    for (t, tet) in mesh.tets.iter().enumerate() {
        out.int(t + 1)
            .s(" 4 2 ")
            .int(DOMAIN_PHYSICAL_TAG)
            .s(" ")
            .int(VOLUME_ENTITY);
        element_nodes(out, tet)?;
    }
    let mut tag = n_tets;
    for &(label, _) in present {
        let lt = label_tag(label);
        for tri in triangles_labelled(mesh, label) {
            tag += 1;
            out.int(tag).s(" 2 2 ").int(lt).s(" ").int(lt);
            element_nodes(out, tri)?;
        }
    }
    out.s("$EndElements").nl()
}

/// The boundary triangles of `mesh` that carry `label`, in mesh order.
fn triangles_labelled(mesh: &TetMesh, label: BoundaryLabel) -> impl Iterator<Item = &[u32; 3]> {
    mesh.boundary
        .iter()
        .zip(&mesh.boundary_labels)
        .filter(move |&(_, &l)| l == label)
        .map(|(tri, _)| tri)
}
