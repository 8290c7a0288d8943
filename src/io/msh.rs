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

use super::source::{InMemory, MeshSource};
use super::write_common::{check_lengths, TextOut};
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
    write_msh_source(&InMemory::new(mesh), w, version)
}

/// [`write_msh`] from any [`MeshSource`].
pub(crate) fn write_msh_source(
    src: &dyn MeshSource,
    w: &mut dyn Write,
    version: MshVersion,
) -> io::Result<()> {
    let mut out = TextOut::new(w);
    let present = src.present_labels();
    match version {
        MshVersion::V41 => write_v41(src, &present, &mut out)?,
        MshVersion::V22 => write_v22(src, &present, &mut out)?,
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

fn node_data(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    out.s("$NodeData").nl()?;
    out.s("1").nl()?;
    out.s("\"f\"").nl()?;
    out.s("1").nl()?;
    out.s("0").nl()?;
    out.s("3").nl()?;
    out.s("0").nl()?;
    out.s("1").nl()?;
    out.int(src.num_points()).nl()?;
    let mut i = 0usize;
    src.values(&mut |vs| {
        for &v in vs {
            i += 1;
            out.int(i).s(" ").float(v).nl()?;
        }
        Ok(())
    })?;
    out.s("$EndNodeData").nl()
}

fn point<'o, 'w>(out: &'o mut TextOut<'w>, p: [f64; 3]) -> &'o mut TextOut<'w> {
    out.vec3(p)
}

/// The bounding box of [`MeshSource::bbox`], zeros if there are no points.
fn bbox(src: &dyn MeshSource, label: Option<BoundaryLabel>) -> [f64; 6] {
    let b = src.bbox(label);
    if b[0] > b[3] {
        [0.0; 6]
    } else {
        b
    }
}

fn write_v41(
    src: &dyn MeshSource,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    header(out, "4.1", present)?;
    entities_v41(src, present, out)?;
    nodes_v41(src, out)?;
    elements_v41(src, present, out)?;
    node_data(src, out)
}

/// `$Entities`: one surface per boundary label that occurs, then the volume entity.
fn entities_v41(
    src: &dyn MeshSource,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    out.s("$Entities").nl()?;
    out.s("0 0 ").int(present.len()).s(" 1").nl()?;
    for &(label, _) in present {
        out.int(label_tag(label));
        bbox_fields(out, bbox(src, Some(label)));
        // one physical tag; no bounding curves
        out.s(" 1 ").int(label_tag(label)).s(" 0").nl()?;
    }
    out.int(VOLUME_ENTITY);
    bbox_fields(out, bbox(src, None));
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
fn nodes_v41(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    let n_points = src.num_points();
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
    src.points(&mut |ps| {
        for &p in ps {
            point(out, p).nl()?;
        }
        Ok(())
    })?;
    out.s("$EndNodes").nl()
}

/// `$Elements`: the tets in one block on the volume entity, then one triangle block per
/// boundary label that occurs.
fn elements_v41(
    src: &dyn MeshSource,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    let n_tets = src.num_tets();
    let n_elems = n_tets + src.num_boundary();
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
    let mut tag = 0usize;
    src.tets(&mut |ts| {
        for tet in ts {
            tag += 1;
            element_nodes(out.int(tag), tet)?;
        }
        Ok(())
    })?;
    for &(label, count) in present {
        element_block(out, label_tag(label), 2, TRIANGLE, count)?;
        src.triangles(label, &mut |ts| {
            for tri in ts {
                tag += 1;
                element_nodes(out.int(tag), tri)?;
            }
            Ok(())
        })?;
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
    src: &dyn MeshSource,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    header(out, "2.2", present)?;
    out.s("$Nodes").nl()?;
    out.int(src.num_points()).nl()?;
    let mut i = 0usize;
    src.points(&mut |ps| {
        for &p in ps {
            i += 1;
            out.int(i).s(" ");
            point(out, p).nl()?;
        }
        Ok(())
    })?;
    out.s("$EndNodes").nl()?;
    elements_v22(src, present, out)?;
    node_data(src, out)
}

/// `$Elements` (2.2): the tets, then the boundary triangles grouped by label; each element
/// carries two tags, physical and elementary.
fn elements_v22(
    src: &dyn MeshSource,
    present: &[(BoundaryLabel, usize)],
    out: &mut TextOut,
) -> io::Result<()> {
    out.s("$Elements").nl()?;
    out.int(src.num_tets() + src.num_boundary()).nl()?;
    let mut tag = 0usize;
    src.tets(&mut |ts| {
        for tet in ts {
            tag += 1;
            out.int(tag)
                .s(" 4 2 ")
                .int(DOMAIN_PHYSICAL_TAG)
                .s(" ")
                .int(VOLUME_ENTITY);
            element_nodes(out, tet)?;
        }
        Ok(())
    })?;
    for &(label, _) in present {
        let lt = label_tag(label);
        src.triangles(label, &mut |ts| {
            for tri in ts {
                tag += 1;
                out.int(tag).s(" 2 2 ").int(lt).s(" ").int(lt);
                element_nodes(out, tri)?;
            }
            Ok(())
        })?;
    }
    out.s("$EndElements").nl()
}
