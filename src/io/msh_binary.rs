//! Binary Gmsh `.msh` 4.1: the sections, entities, blocks and tags of ASCII 4.1 (see
//! [`super::msh`]) in Gmsh's binary encoding.

use std::io::{self, Write};

use super::msh::{
    entity_list, node_data_head, physical_names, section_counts, volume_tets, Layout, TETRAHEDRON,
    TRIANGLE,
};
use super::source::MeshSource;
use super::write_common::{invalid, TextOut};

/// Size at which [`BinOut`] hands its buffer to the underlying writer.
const BIN_CHUNK: usize = 1 << 16;

/// Buffered output of binary `.msh`: little-endian numbers and the text between them.
struct BinOut<'a> {
    w: &'a mut dyn Write,
    buf: Vec<u8>,
}

impl<'a> BinOut<'a> {
    fn new(w: &'a mut dyn Write) -> Self {
        BinOut {
            w,
            buf: Vec::with_capacity(BIN_CHUNK + 4096),
        }
    }

    /// Appends text formatted by `f` (the writers' [`TextOut`]).
    fn text(&mut self, f: impl FnOnce(&mut TextOut) -> io::Result<()>) -> io::Result<()> {
        let mut t = TextOut::new(&mut self.buf);
        f(&mut t)?;
        t.finish()?;
        self.spill()
    }

    fn s(&mut self, s: &str) -> &mut Self {
        self.buf.extend_from_slice(s.as_bytes());
        self
    }

    /// Appends a `size_t` (8 bytes).
    #[inline]
    fn size(&mut self, v: usize) -> &mut Self {
        self.buf.extend_from_slice(&(v as u64).to_le_bytes());
        self
    }

    fn sizes(&mut self, v: [usize; 4]) -> &mut Self {
        for x in v {
            self.size(x);
        }
        self
    }

    /// Appends an `int` (4 bytes); `v` is at most `i32::MAX`.
    #[inline]
    fn int(&mut self, v: u32) -> &mut Self {
        debug_assert!(i32::try_from(v).is_ok());
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    #[inline]
    fn float(&mut self, v: f64) -> &mut Self {
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// Passes the buffer on when it is full.
    #[inline]
    fn spill(&mut self) -> io::Result<()> {
        if self.buf.len() >= BIN_CHUNK {
            self.w.write_all(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }

    fn finish(self) -> io::Result<()> {
        self.w.write_all(&self.buf)?;
        self.w.flush()
    }
}

pub(super) fn write_v41_binary(
    src: &dyn MeshSource,
    layout: &Layout,
    w: &mut dyn Write,
) -> io::Result<()> {
    if i32::try_from(src.num_points()).is_err() {
        return Err(invalid(format!(
            "{} nodes are too many for binary .msh 4.1 ($NodeData numbers nodes by 4-byte int)",
            src.num_points()
        )));
    }
    let mut out = BinOut::new(w);
    out.text(|t| {
        t.s("$MeshFormat").nl()?;
        t.s("4.1 1 8").nl()
    })?;
    out.int(1).s("\n$EndMeshFormat\n");
    out.text(|t| physical_names(t, layout))?;
    entities_binary(src, layout, &mut out);
    nodes_binary(src, layout, &mut out)?;
    elements_binary(src, layout, &mut out)?;
    node_data_binary(src, &mut out)?;
    out.finish()
}

/// `$Entities` of [`entity_list`]: counts, then per entity its tag, bounding box, physical
/// tag and bounding entities.
fn entities_binary(src: &dyn MeshSource, layout: &Layout, out: &mut BinOut) {
    out.s("$Entities\n");
    out.size(0).size(0).size(layout.present.len());
    out.size(layout.volumes.len());
    for e in entity_list(src, layout) {
        out.int(e.tag);
        for x in e.bbox {
            out.float(x);
        }
        out.size(1).int(e.physical).size(e.bounding.len());
        for b in e.bounding {
            out.int(b);
        }
    }
    out.s("\n$EndEntities\n");
}

/// `$Nodes`: one block on the first volume entity, the tags `1..=n`, then the coordinates.
fn nodes_binary(src: &dyn MeshSource, layout: &Layout, out: &mut BinOut) -> io::Result<()> {
    let n_points = src.num_points();
    out.s("$Nodes\n");
    out.sizes(section_counts(1, n_points));
    out.int(3).int(layout.node_entity()).int(0).size(n_points);
    for i in 1..=n_points {
        out.size(i).spill()?;
    }
    src.points(&mut |ps| {
        for p in ps {
            out.float(p[0]).float(p[1]).float(p[2]).spill()?;
        }
        Ok(())
    })?;
    out.s("\n$EndNodes\n");
    Ok(())
}

/// `$Elements`: the blocks of [`elements_v41`]; each element is its tag and its node tags.
fn elements_binary(src: &dyn MeshSource, layout: &Layout, out: &mut BinOut) -> io::Result<()> {
    let n_tets = src.num_tets();
    out.s("$Elements\n");
    out.sizes(section_counts(
        layout.blocks(),
        n_tets + src.num_triangles(),
    ));
    let element = |out: &mut BinOut, tag: usize, nodes: &[u32]| {
        out.size(tag);
        for &v in nodes {
            out.size(v as usize + 1);
        }
        out.spill()
    };
    for v in &layout.volumes {
        out.int(3).int(v.entity).int(TETRAHEDRON).size(v.tets);
        volume_tets(src, v, &mut |tag, t| element(out, tag, t))?;
    }
    let mut tag = n_tets;
    for &(label, count) in &layout.present {
        out.int(2).int(layout.tag(label)).int(TRIANGLE).size(count);
        src.triangles(label, &mut |ts| {
            ts.iter().try_for_each(|t| {
                tag += 1;
                element(out, tag, t)
            })
        })?;
    }
    out.s("\n$EndElements\n");
    Ok(())
}

/// `$NodeData`: the text head of the ASCII file, then per node its `int` tag and value.
fn node_data_binary(src: &dyn MeshSource, out: &mut BinOut) -> io::Result<()> {
    out.text(|t| node_data_head(src, t))?;
    let mut tag = 0u32;
    src.values(&mut |vs| {
        for &v in vs {
            tag += 1;
            out.int(tag).float(v).spill()?;
        }
        Ok(())
    })?;
    out.s("\n$EndNodeData\n");
    Ok(())
}
