//! Abaqus / CalculiX `.inp` writer.
//!
//! Output (1-based ids: node `i` → `i + 1`, tet `t` → element `t + 1`):
//! * `*HEADING`;
//! * `*NODE, NSET=NALL` with all nodes;
//! * `*ELEMENT, TYPE=C3D4, ELSET=DOMAIN` with all tets. The mesh's positive orientation
//!   `(b-a)·((c-a)×(d-a)) > 0` is exactly the C3D4 convention (nodes 1-2-3 counter-clockwise
//!   seen from node 4), so node order is kept;
//! * for each boundary label that occurs, `*NSET, NSET=ALPHA|BETA|BOX` (the nodes of its
//!   triangles, ascending, 16 per line) and `*SURFACE, NAME=ALPHA|BETA|BOX, TYPE=ELEMENT`
//!   with one `element, Sk` line per triangle (C3D4 faces: S1 = 1-2-3, S2 = 1-4-2,
//!   S3 = 2-4-3, S4 = 3-4-1).
//!
//! No material, section or step is written: a CalculiX/Abaqus deck is expected to
//! `*INCLUDE, INPUT=mesh.inp` and add those. Every numeric field is at most 20 characters
//! wide (a CalculiX limit); coordinates use the shortest round-trip form when it fits and
//! 12 fractional digits in scientific notation otherwise. The field `f` is not written.

use std::io::{self, Write};

use rustc_hash::FxHashMap;

use super::write_common::{check_lengths, invalid, present_labels, TextOut};
use crate::mesh::{BoundaryLabel, TetMesh};

/// Local vertex indices of the C3D4 faces S1..S4.
const C3D4_FACES: [[usize; 3]; 4] = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];

/// Maximum width of a numeric field accepted by CalculiX.
const FIELD_WIDTH: usize = 20;

/// Ids per line in `*NSET` data lines.
const IDS_PER_LINE: usize = 16;

/// Writes `mesh` as an Abaqus/CalculiX input fragment: nodes, C3D4 elements (element set
/// `DOMAIN`), and per boundary label that occurs a node set and an element-face surface
/// (see the module documentation). The output is deterministic.
///
/// # Errors
/// Returns the first error of `w`, or [`io::ErrorKind::InvalidInput`] when the mesh is
/// inconsistent: `values`/`boundary_labels` of the wrong length, an out-of-range index, or a
/// boundary triangle that is not a face of any tet.
pub fn write_inp(mesh: &TetMesh, w: &mut dyn Write) -> io::Result<()> {
    check_lengths(mesh)?;
    let faces = boundary_faces(mesh)?;
    let mut out = TextOut::new(w);
    heading(mesh, &mut out)?;
    nodes(mesh, &mut out)?;
    elements(mesh, &mut out)?;
    let mut in_set = vec![false; mesh.points.len()];
    for (label, _) in present_labels(mesh) {
        let upper = label.name().to_ascii_uppercase();
        node_set(mesh, label, &upper, &mut in_set, &mut out)?;
        surface(mesh, label, &upper, &faces, &mut out)?;
    }
    out.finish()
}

/// `*HEADING` and its one-line title.
fn heading(mesh: &TetMesh, out: &mut TextOut) -> io::Result<()> {
    out.s("*HEADING").nl()?;
    out.s("tptd interval-volume mesh: ")
        .int(mesh.points.len())
        .s(" nodes, ")
        .int(mesh.tets.len())
        .s(" C3D4 elements, ")
        .int(mesh.boundary.len())
        .s(" boundary faces")
        .nl()
}

/// `*NODE, NSET=NALL` with every node.
fn nodes(mesh: &TetMesh, out: &mut TextOut) -> io::Result<()> {
    out.s("*NODE, NSET=NALL").nl()?;
    for (i, p) in mesh.points.iter().enumerate() {
        out.int(i + 1);
        for &x in p {
            out.s(", ").float_width(x, FIELD_WIDTH);
        }
        out.nl()?;
    }
    Ok(())
}

/// `*ELEMENT, TYPE=C3D4, ELSET=DOMAIN` with every tet.
fn elements(mesh: &TetMesh, out: &mut TextOut) -> io::Result<()> {
    out.s("*ELEMENT, TYPE=C3D4, ELSET=DOMAIN").nl()?;
    for (t, tet) in mesh.tets.iter().enumerate() {
        out.int(t + 1);
        for &v in tet {
            out.s(", ").int(v + 1);
        }
        out.nl()?;
    }
    Ok(())
}

/// `*NSET, NSET={upper}`: the nodes of the triangles labelled `label`, ascending,
/// [`IDS_PER_LINE`] per line. `in_set` is scratch space of one flag per node.
fn node_set(
    mesh: &TetMesh,
    label: BoundaryLabel,
    upper: &str,
    in_set: &mut [bool],
    out: &mut TextOut,
) -> io::Result<()> {
    in_set.iter_mut().for_each(|b| *b = false);
    for (tri, _) in labelled(mesh, label) {
        for &v in tri {
            in_set[v as usize] = true;
        }
    }
    out.s("*NSET, NSET=").s(upper).nl()?;
    let mut on_line = 0;
    for (i, _) in in_set.iter().enumerate().filter(|(_, &b)| b) {
        if on_line == IDS_PER_LINE {
            out.nl()?;
            on_line = 0;
        }
        if on_line > 0 {
            out.s(", ");
        }
        out.int(i + 1);
        on_line += 1;
    }
    if on_line > 0 {
        out.nl()?;
    }
    Ok(())
}

/// `*SURFACE, NAME={upper}, TYPE=ELEMENT`: one `element, Sk` line per triangle labelled
/// `label`, with `faces` from [`boundary_faces`].
fn surface(
    mesh: &TetMesh,
    label: BoundaryLabel,
    upper: &str,
    faces: &[(u32, u8)],
    out: &mut TextOut,
) -> io::Result<()> {
    out.s("*SURFACE, NAME=").s(upper).s(", TYPE=ELEMENT").nl()?;
    for (b, _) in mesh
        .boundary_labels
        .iter()
        .enumerate()
        .filter(|&(_, &l)| l == label)
    {
        let (tet, face) = faces[b];
        out.int(tet as usize + 1).s(", S").int(face + 1).nl()?;
    }
    Ok(())
}

fn labelled(
    mesh: &TetMesh,
    label: BoundaryLabel,
) -> impl Iterator<Item = (&[u32; 3], &BoundaryLabel)> {
    mesh.boundary
        .iter()
        .zip(&mesh.boundary_labels)
        .filter(move |&(_, &l)| l == label)
}

fn sorted3(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// For each boundary triangle, the tet it is a face of and the C3D4 face index (0..4).
fn boundary_faces(mesh: &TetMesh) -> io::Result<Vec<(u32, u8)>> {
    const UNSET: (u32, u8) = (u32::MAX, u8::MAX);
    let mut index: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    index.reserve(mesh.boundary.len());
    for (b, &tri) in mesh.boundary.iter().enumerate() {
        index.insert(sorted3(tri), b as u32);
    }
    let mut faces = vec![UNSET; mesh.boundary.len()];
    if !index.is_empty() {
        for (t, tet) in mesh.tets.iter().enumerate() {
            for (k, f) in C3D4_FACES.iter().enumerate() {
                let key = sorted3([tet[f[0]], tet[f[1]], tet[f[2]]]);
                if let Some(&b) = index.get(&key) {
                    faces[b as usize] = (t as u32, k as u8);
                }
            }
        }
    }
    if let Some(b) = faces.iter().position(|&f| f == UNSET) {
        return Err(invalid(format!(
            "boundary triangle {b} {:?} is not a face of any tetrahedron",
            mesh.boundary[b]
        )));
    }
    Ok(faces)
}
