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

use super::atomic::TextOut;
use crate::mesh::{BoundaryLabel, TetMesh};

/// Which `.msh` format version [`write_msh`] produces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MshVersion {
    /// Gmsh 4.1 ASCII (`$Entities`, entity-blocked `$Nodes`/`$Elements`).
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
        .any(|&i| i as usize >= n);
    if bad {
        return Err(invalid(format!(
            "mesh refers to a node index >= the {n} points"
        )));
    }
    Ok(())
}

pub(crate) fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// For each label in [`BoundaryLabel::ALL`] order that occurs: (label, triangle count).
pub(crate) fn present_labels(mesh: &TetMesh) -> Vec<(BoundaryLabel, usize)> {
    let mut count = [0usize; 3];
    for &l in &mesh.boundary_labels {
        count[l as usize] += 1;
    }
    BoundaryLabel::ALL
        .into_iter()
        .filter(|&l| count[l as usize] > 0)
        .map(|l| (l, count[l as usize]))
        .collect()
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
    out.float(p[0]).s(" ").float(p[1]).s(" ").float(p[2])
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
    let n_points = mesh.points.len();
    let n_tets = mesh.tets.len();

    out.s("$Entities").nl()?;
    out.s("0 0 ").int(present.len()).s(" 1").nl()?;
    for &(label, _) in present {
        let nodes = mesh
            .boundary
            .iter()
            .zip(&mesh.boundary_labels)
            .filter(|&(_, &l)| l == label)
            .flat_map(|(t, _)| t.iter().copied());
        let b = bbox(mesh, nodes);
        out.int(label_tag(label));
        for x in b {
            out.s(" ").float(x);
        }
        // one physical tag; no bounding curves
        out.s(" 1 ").int(label_tag(label)).s(" 0").nl()?;
    }
    let b = bbox(mesh, 0..n_points as u32);
    out.int(VOLUME_ENTITY);
    for x in b {
        out.s(" ").float(x);
    }
    out.s(" 1 ")
        .int(DOMAIN_PHYSICAL_TAG)
        .s(" ")
        .int(present.len());
    for &(label, _) in present {
        out.s(" ").int(label_tag(label));
    }
    out.nl()?;
    out.s("$EndEntities").nl()?;

    // All nodes in one block classified on the volume entity.
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
    out.s("$EndNodes").nl()?;

    out.s("$Elements").nl()?;
    let n_elems = n_tets + mesh.boundary.len();
    out.int(present.len() + 1)
        .s(" ")
        .int(n_elems)
        .s(" ")
        .int(usize::from(n_elems > 0))
        .s(" ")
        .int(n_elems)
        .nl()?;
    out.s("3 ")
        .int(VOLUME_ENTITY)
        .s(" ")
        .int(TETRAHEDRON)
        .s(" ")
        .int(n_tets)
        .nl()?;
    for (t, tet) in mesh.tets.iter().enumerate() {
        out.int(t + 1);
        for &v in tet {
            out.s(" ").int(v + 1);
        }
        out.nl()?;
    }
    let mut tag = n_tets;
    for &(label, count) in present {
        out.s("2 ")
            .int(label_tag(label))
            .s(" ")
            .int(TRIANGLE)
            .s(" ")
            .int(count)
            .nl()?;
        for tri in triangles_labelled(mesh, label) {
            tag += 1;
            out.int(tag);
            for &v in tri {
                out.s(" ").int(v + 1);
            }
            out.nl()?;
        }
    }
    out.s("$EndElements").nl()?;
    node_data(mesh, out)
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

    out.s("$Elements").nl()?;
    let n_tets = mesh.tets.len();
    out.int(n_tets + mesh.boundary.len()).nl()?;
    for (t, tet) in mesh.tets.iter().enumerate() {
        // type, 2 tags: physical, elementary
        out.int(t + 1)
            .s(" 4 2 ")
            .int(DOMAIN_PHYSICAL_TAG)
            .s(" ")
            .int(VOLUME_ENTITY);
        for &v in tet {
            out.s(" ").int(v + 1);
        }
        out.nl()?;
    }
    let mut tag = n_tets;
    for &(label, _) in present {
        let lt = label_tag(label);
        for tri in triangles_labelled(mesh, label) {
            tag += 1;
            out.int(tag).s(" 2 2 ").int(lt).s(" ").int(lt);
            for &v in tri {
                out.s(" ").int(v + 1);
            }
            out.nl()?;
        }
    }
    out.s("$EndElements").nl()?;
    node_data(mesh, out)
}

/// The boundary triangles of `mesh` that carry `label`, in mesh order.
fn triangles_labelled(mesh: &TetMesh, label: BoundaryLabel) -> impl Iterator<Item = &[u32; 3]> {
    mesh.boundary
        .iter()
        .zip(&mesh.boundary_labels)
        .filter(move |&(_, &l)| l == label)
        .map(|(tri, _)| tri)
}
