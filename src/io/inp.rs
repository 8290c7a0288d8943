//! Abaqus / CalculiX `.inp` writer.
//!
//! Output (1-based ids: node `i` → `i + 1`, tet `t` → element `t + 1`):
//! * `*HEADING`;
//! * `*NODE, NSET=NALL` with all nodes;
//! * `*ELEMENT, TYPE=C3D4, ELSET=DOMAIN` with all tets. The mesh's positive orientation
//!   `(b-a)·((c-a)×(d-a)) > 0` is exactly the C3D4 convention (nodes 1-2-3 counter-clockwise
//!   seen from node 4), so node order is kept;
//! * several regions: per region that has tets, `*ELSET, ELSET=<NAME>` (its name upper-cased,
//!   `REGION1`, `REGION2`, … by default) with its element ids, ascending, 16 per line;
//! * for each label that occurs, `*NSET, NSET=<LABEL>` (the nodes of its triangles,
//!   ascending, 16 per line) and `*SURFACE, NAME=<LABEL>, TYPE=ELEMENT` with one
//!   `element, Sk` line per triangle (C3D4 faces: S1 = 1-2-3, S2 = 1-4-2, S3 = 2-4-3,
//!   S4 = 3-4-1). Labels are `ALPHA`, `BETA`, `BOX` for one interval; `LEVEL1`, `LEVEL2`, …
//!   and `BOX` for several regions, where a level between two regions (an interface) has
//!   two surfaces instead of one: `LEVEL<i>_BELOW` (the faces of the tets of the region
//!   below it) and `LEVEL<i>_ABOVE` (those of the region above).
//!
//! No material, section or step is written: a CalculiX/Abaqus deck is expected to
//! `*INCLUDE, INPUT=mesh.inp` and add those. Every numeric field is at most 20 characters
//! wide (a CalculiX limit); coordinates use the shortest round-trip form when it fits and
//! 12 fractional digits in scientific notation otherwise. The field `f` is not written.

use std::io::{self, Write};

use super::source::{InMemory, MeshSource};
use super::write_common::{check_lengths, TextOut};
use crate::mesh::{BoundaryLabel, TetMesh};

/// Maximum width of a numeric field accepted by CalculiX.
const FIELD_WIDTH: usize = 20;

/// Ids per line in `*NSET` data lines.
const IDS_PER_LINE: usize = 16;

/// Writes `mesh` as an Abaqus/CalculiX input fragment: nodes, C3D4 elements (element set
/// `DOMAIN`, and one per region), and per label that occurs a node set and element-face
/// surfaces (see the module documentation). The output is deterministic.
///
/// # Errors
/// Returns the first error of `w`, or [`io::ErrorKind::InvalidInput`] when the mesh is
/// inconsistent: `values`/`boundary_labels` of the wrong length, an out-of-range index, or a
/// boundary triangle that is not a face of any tet.
pub fn write_inp(mesh: &TetMesh, w: &mut dyn Write) -> io::Result<()> {
    check_lengths(mesh)?;
    write_inp_source(&InMemory::new(mesh), w)
}

/// [`write_inp`] from any [`MeshSource`].
pub(crate) fn write_inp_source(src: &dyn MeshSource, w: &mut dyn Write) -> io::Result<()> {
    let mut out = TextOut::new(w);
    heading(src, &mut out)?;
    nodes(src, &mut out)?;
    elements(src, &mut out)?;
    region_sets(src, &mut out)?;
    let mut in_set = vec![false; src.num_points()];
    for (label, _) in src.present_labels() {
        let upper = label.name_in(src.level_count()).to_ascii_uppercase();
        node_set(src, label, &upper, &mut in_set, &mut out)?;
        if src.is_interface(label) {
            surface(src, label, false, &format!("{upper}_BELOW"), &mut out)?;
            surface(src, label, true, &format!("{upper}_ABOVE"), &mut out)?;
        } else {
            surface(src, label, false, &upper, &mut out)?;
        }
    }
    out.finish()
}

/// `*HEADING` and its one-line title.
fn heading(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    let present = src.present_labels();
    let count = |interface: bool| -> usize {
        let of_kind = present
            .iter()
            .filter(|(l, _)| src.is_interface(*l) == interface);
        of_kind.map(|&(_, n)| n).sum()
    };
    out.s("*HEADING").nl()?;
    out.s("tptd interval-volume mesh: ")
        .int(src.num_points())
        .s(" nodes, ")
        .int(src.num_tets())
        .s(" C3D4 elements, ");
    if src.region_count() > 0 {
        out.s("in ").int(src.region_count()).s(" regions, ");
    }
    out.int(count(false)).s(" boundary faces");
    if src.region_count() > 0 {
        out.s(", ").int(count(true)).s(" interface faces");
    }
    out.nl()
}

/// Data lines of ids, [`IDS_PER_LINE`] per line.
struct IdLines {
    on_line: usize,
}

impl IdLines {
    fn new() -> Self {
        IdLines { on_line: 0 }
    }

    fn push(&mut self, out: &mut TextOut, id: usize) -> io::Result<()> {
        if self.on_line == IDS_PER_LINE {
            out.nl()?;
            self.on_line = 0;
        }
        if self.on_line > 0 {
            out.s(", ");
        }
        out.int(id);
        self.on_line += 1;
        Ok(())
    }

    fn end(self, out: &mut TextOut) -> io::Result<()> {
        if self.on_line > 0 {
            out.nl()?;
        }
        Ok(())
    }
}

/// Per region that has tets, `*ELSET, ELSET=<NAME>` with the ids of its elements.
fn region_sets(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    for (k, n) in src.region_tets().into_iter().enumerate() {
        if n == 0 {
            continue;
        }
        let name = src.region_name(k).to_ascii_uppercase();
        out.s("*ELSET, ELSET=").s(&name).nl()?;
        let mut lines = IdLines::new();
        let mut t = 0usize;
        src.regions(&mut |rs| {
            for &r in rs {
                t += 1;
                if r as usize == k {
                    lines.push(out, t)?;
                }
            }
            Ok(())
        })?;
        lines.end(out)?;
    }
    Ok(())
}

/// `*NODE, NSET=NALL` with every node.
fn nodes(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    out.s("*NODE, NSET=NALL").nl()?;
    let mut i = 0usize;
    src.points(&mut |ps| {
        for p in ps {
            i += 1;
            out.int(i);
            for &x in p {
                out.s(", ").float_width(x, FIELD_WIDTH);
            }
            out.nl()?;
        }
        Ok(())
    })
}

/// `*ELEMENT, TYPE=C3D4, ELSET=DOMAIN` with every tet.
fn elements(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    out.s("*ELEMENT, TYPE=C3D4, ELSET=DOMAIN").nl()?;
    let mut t = 0usize;
    src.tets(&mut |ts| {
        for tet in ts {
            t += 1;
            out.int(t);
            for &v in tet {
                out.s(", ").int(v + 1);
            }
            out.nl()?;
        }
        Ok(())
    })
}

/// `*NSET, NSET={upper}`: the nodes of the triangles labelled `label`, ascending,
/// [`IDS_PER_LINE`] per line. `in_set` is scratch space of one flag per node.
fn node_set(
    src: &dyn MeshSource,
    label: BoundaryLabel,
    upper: &str,
    in_set: &mut [bool],
    out: &mut TextOut,
) -> io::Result<()> {
    in_set.iter_mut().for_each(|b| *b = false);
    src.triangles(label, &mut |ts| {
        for &v in ts.iter().flatten() {
            in_set[v as usize] = true;
        }
        Ok(())
    })?;
    out.s("*NSET, NSET=").s(upper).nl()?;
    let mut lines = IdLines::new();
    for (i, _) in in_set.iter().enumerate().filter(|(_, &b)| b) {
        lines.push(out, i + 1)?;
    }
    lines.end(out)
}

/// `*SURFACE, NAME={name}, TYPE=ELEMENT`: one `element, Sk` line per triangle labelled
/// `label` (for an interface, the faces of the tets above it when `above`, else below).
fn surface(
    src: &dyn MeshSource,
    label: BoundaryLabel,
    above: bool,
    name: &str,
    out: &mut TextOut,
) -> io::Result<()> {
    out.s("*SURFACE, NAME=").s(name).s(", TYPE=ELEMENT").nl()?;
    src.faces(label, above, &mut |fs| {
        for &(tet, face) in fs {
            out.int(tet as usize + 1).s(", S").int(face + 1).nl()?;
        }
        Ok(())
    })
}
