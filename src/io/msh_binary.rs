//! Binary Gmsh `.msh` 4.1: the sections, entities, blocks and tags of ASCII 4.1 (see
//! [`super::msh`]) in Gmsh's binary encoding.

use std::io::{self, Write};
use std::ops::Range;

use rayon::prelude::*;

use super::msh::{
    entity_list, node_data_head, physical_names, section_counts, Layout, TETRAHEDRON, TRIANGLE,
};
use super::source::MeshSource;
use super::write_common::{invalid, TextOut};

/// Size at which [`BinOut`] hands its buffer to the underlying writer.
const BIN_CHUNK: usize = 1 << 16;

/// Items encoded in one parallel task.
const PIECE: usize = 1 << 12;

/// Items encoded (in pieces, in parallel) before their bytes are written: a bound on the
/// memory of a list held in memory, which comes as one slice.
const WINDOW: usize = 1 << 18;

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

    /// Appends the encodings of items `0..n` (of a list the caller holds), each piece of
    /// [`PIECE`] items encoded by `encode(its range, bytes)` in parallel, [`WINDOW`] items
    /// at a time, in order.
    fn par(
        &mut self,
        n: usize,
        encode: impl Fn(Range<usize>, &mut Vec<u8>) + Sync,
    ) -> io::Result<()> {
        self.w.write_all(&self.buf)?;
        self.buf.clear();
        for start in (0..n).step_by(WINDOW) {
            let end = n.min(start + WINDOW);
            let pieces: Vec<Vec<u8>> = (start..end)
                .step_by(PIECE)
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|a| {
                    let mut b = Vec::new();
                    encode(a..end.min(a + PIECE), &mut b);
                    b
                })
                .collect();
            pieces.iter().try_for_each(|p| self.w.write_all(p))?;
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
    for first in (0..n_points).step_by(WINDOW) {
        let n = WINDOW.min(n_points - first);
        out.par(n, |r, b| r.for_each(|i| put_size(b, first + i + 1)))?;
    }
    src.points(&mut |ps| {
        out.par(ps.len(), |r, b| {
            ps[r].iter().flatten().for_each(|&x| put_float(b, x));
        })
    })?;
    out.s("\n$EndNodes\n");
    Ok(())
}

/// `$Elements`: the blocks of [`super::msh::elements_v41`]; each element is its tag and its
/// node tags.
fn elements_binary(src: &dyn MeshSource, layout: &Layout, out: &mut BinOut) -> io::Result<()> {
    let n_tets = src.num_tets();
    out.s("$Elements\n");
    out.sizes(section_counts(
        layout.blocks(),
        n_tets + src.num_triangles(),
    ));
    for v in &layout.volumes {
        out.int(3).int(v.entity).int(TETRAHEDRON).size(v.tets);
        let mut first = 0usize;
        src.tets_in_regions(&mut |ts, rs| {
            out.par(ts.len(), |r, b| {
                for i in r {
                    if v.region.is_none_or(|k| rs[i] == k) {
                        put_element(b, first + i + 1, &ts[i]);
                    }
                }
            })?;
            first += ts.len();
            Ok(())
        })?;
    }
    let mut first = n_tets;
    for &(label, count) in &layout.present {
        out.int(2).int(layout.tag(label)).int(TRIANGLE).size(count);
        src.triangles(label, &mut |ts| {
            out.par(ts.len(), |r, b| {
                r.for_each(|i| put_element(b, first + i + 1, &ts[i]));
            })?;
            first += ts.len();
            Ok(())
        })?;
    }
    out.s("\n$EndElements\n");
    Ok(())
}

/// `$NodeData`: the text head of the ASCII file, then per node its `int` tag and value.
fn node_data_binary(src: &dyn MeshSource, out: &mut BinOut) -> io::Result<()> {
    out.text(|t| node_data_head(src, t))?;
    let mut first = 0usize;
    src.values(&mut |vs| {
        out.par(vs.len(), |r, b| {
            for i in r {
                // at most i32::MAX nodes (checked before writing)
                b.extend_from_slice(&((first + i + 1) as u32).to_le_bytes());
                put_float(b, vs[i]);
            }
        })?;
        first += vs.len();
        Ok(())
    })?;
    out.s("\n$EndNodeData\n");
    Ok(())
}

/// Appends a `size_t` (8 bytes).
#[inline]
fn put_size(b: &mut Vec<u8>, v: usize) {
    b.extend_from_slice(&(v as u64).to_le_bytes());
}

#[inline]
fn put_float(b: &mut Vec<u8>, v: f64) {
    b.extend_from_slice(&v.to_le_bytes());
}

/// Appends an element: its tag and its node tags (`size_t` each).
#[inline]
fn put_element(b: &mut Vec<u8>, tag: usize, nodes: &[u32]) {
    put_size(b, tag);
    nodes.iter().for_each(|&v| put_size(b, v as usize + 1));
}
