//! A mesh streamed to disk: [`SpilledMesh`] takes the mesher's chunks as a [`MeshSink`],
//! appends each list to its own anonymous temporary file, and reads them back in slices as
//! the writers' [`MeshSource`]. Memory stays a few buffers whatever the mesh size; the files
//! hold exactly what the in-memory mesh would, so the writers produce the same bytes.
//!
//! The spill files are created in the output's folder and unlinked at once (on Unix), so they
//! vanish with the process whatever way it ends.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use bytemuck::Pod;

use super::source::{
    fill_faces, is_interface, no_tet, regions_of, triangle_faces, MeshSource, Visit, VisitRegions,
    UNSET,
};
use super::write_common::invalid;
use crate::mesh::{grow_box, MeshChunk, MeshSink, EMPTY_BOX, NUM_LABELS};
use crate::mesh::{region_name, BoundaryLabel, INTERVAL_LEVELS, LABEL_LEVELS};

/// Items read back per slice (large enough that the writers' parallel encoding of a slice
/// outweighs waking their threads).
const READ_SLICE: usize = 1 << 18;

/// One list of `T` in an anonymous temporary file.
struct SpillFile<T> {
    w: BufWriter<File>,
    /// The file's path where it could not be unlinked while open (removed on drop).
    path: Option<PathBuf>,
    len: usize,
    _t: PhantomData<T>,
}

/// Distinguishes the spill files of one process.
static NEXT: AtomicUsize = AtomicUsize::new(0);

impl<T: Pod> SpillFile<T> {
    fn create(dir: &Path) -> io::Result<Self> {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let path = dir.join(format!(".tptd-spill-{}-{n}", std::process::id()));
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)?;
        let path = if cfg!(unix) && fs::remove_file(&path).is_ok() {
            None
        } else {
            Some(path)
        };
        Ok(SpillFile {
            w: BufWriter::with_capacity(1 << 20, file),
            path,
            len: 0,
            _t: PhantomData,
        })
    }

    fn push(&mut self, items: &[T]) -> io::Result<()> {
        self.len += items.len();
        self.w.write_all(bytemuck::cast_slice(items))
    }

    fn finish(&mut self) -> io::Result<()> {
        self.w.flush()
    }

    /// Visits the items in order, [`READ_SLICE`] at a time (after [`SpillFile::finish`]).
    fn visit(&self, f: Visit<T>) -> io::Result<()> {
        let mut file = self.w.get_ref();
        file.seek(SeekFrom::Start(0))?;
        let mut buf = vec![T::zeroed(); READ_SLICE.min(self.len)];
        let mut left = self.len;
        while left > 0 {
            let n = left.min(READ_SLICE);
            file.read_exact(bytemuck::cast_slice_mut(&mut buf[..n]))?;
            f(&buf[..n])?;
            left -= n;
        }
        Ok(())
    }
}

/// `n` spill files (one per label of a run).
fn per_label<T: Pod>(dir: &Path, n: usize) -> io::Result<Vec<SpillFile<T>>> {
    (0..n).map(|_| SpillFile::create(dir)).collect()
}

/// Visits the tets and their regions in lockstep, [`READ_SLICE`] at a time (after
/// [`SpillFile::finish`]).
fn visit_pair(a: &SpillFile<[u32; 4]>, b: &SpillFile<u8>, f: VisitRegions) -> io::Result<()> {
    if a.len != b.len {
        return Err(invalid(format!(
            "{} tets but {} regions in the spilled mesh",
            a.len, b.len
        )));
    }
    let (mut fa, mut fb) = (a.w.get_ref(), b.w.get_ref());
    fa.seek(SeekFrom::Start(0))?;
    fb.seek(SeekFrom::Start(0))?;
    let mut ba = vec![[0u32; 4]; READ_SLICE.min(a.len)];
    let mut bb = vec![0u8; READ_SLICE.min(b.len)];
    let mut left = a.len;
    while left > 0 {
        let n = left.min(READ_SLICE);
        fa.read_exact(bytemuck::cast_slice_mut(&mut ba[..n]))?;
        fb.read_exact(bytemuck::cast_slice_mut(&mut bb[..n]))?;
        f(&ba[..n], &bb[..n])?;
        left -= n;
    }
    Ok(())
}

impl<T> Drop for SpillFile<T> {
    fn drop(&mut self) {
        if let Some(p) = &self.path {
            let _ = fs::remove_file(p);
        }
    }
}

/// Bytes kept in memory by a [`ByteStore`] before it moves them to a file.
const STORE_IN_MEMORY: usize = 64 << 20;

/// Bytes appended in pieces and read back in order: in memory while small, then in an
/// anonymous temporary file (in the system's temporary folder), e.g. a `.vtu` array's zlib
/// blocks, whose sizes must be written before them.
pub(crate) struct ByteStore {
    mem: Vec<u8>,
    file: Option<SpillFile<u8>>,
}

impl ByteStore {
    pub(crate) fn new() -> Self {
        ByteStore {
            mem: Vec::new(),
            file: None,
        }
    }

    /// Appends `data`.
    pub(crate) fn push(&mut self, data: &[u8]) -> io::Result<()> {
        if let Some(f) = &mut self.file {
            return f.push(data);
        }
        if self.mem.len() + data.len() <= STORE_IN_MEMORY {
            self.mem.extend_from_slice(data);
            return Ok(());
        }
        let mut f = SpillFile::create(&std::env::temp_dir())?;
        f.push(&self.mem)?;
        f.push(data)?;
        self.mem = Vec::new();
        self.file = Some(f);
        Ok(())
    }

    /// Ends the appending.
    pub(crate) fn finish(&mut self) -> io::Result<()> {
        self.file.as_mut().map_or(Ok(()), SpillFile::finish)
    }

    /// Visits the bytes in order (after [`ByteStore::finish`]).
    pub(crate) fn visit(&self, f: Visit<u8>) -> io::Result<()> {
        match &self.file {
            Some(file) => file.visit(f),
            None => f(&self.mem),
        }
    }
}

/// A mesh spilled to temporary files, chunk by chunk (see the module documentation).
pub struct SpilledMesh {
    points: SpillFile<[f64; 3]>,
    values: SpillFile<f64>,
    tets: SpillFile<[u32; 4]>,
    /// With several regions, the region of each tet.
    regions: Option<SpillFile<u8>>,
    /// Tets per region.
    region_tets: Vec<usize>,
    /// Levels of the run (2 for one interval).
    levels: usize,
    /// The regions' names (missing ones: [`region_name`]).
    names: Vec<String>,
    /// Per label of the run (by [`BoundaryLabel::code`]), its triangles.
    triangles: Vec<SpillFile<[u32; 3]>>,
    /// The tet and face of each triangle (only when asked for: `.inp`).
    faces: Option<Faces>,
    bbox: [f64; 6],
    label_boxes: [[f64; 6]; NUM_LABELS],
}

/// Per label of the run (by [`BoundaryLabel::code`]), `[tet, C3D4 face]` of each triangle:
/// of its tet below (or only tet), and for interface labels of its tet above.
struct Faces {
    below: Vec<SpillFile<[u32; 2]>>,
    above: Vec<Option<SpillFile<[u32; 2]>>>,
    /// The previous chunk's first tet number and tets (with several regions): an interface
    /// on the plane between two slabs may have its tet above in the neighbouring chunk.
    prev: (usize, Vec<[u32; 4]>),
    /// Per label, the previous chunk's interface triangles whose tet above is in none of
    /// the chunks seen yet, with their faces above so far (written once the next chunk
    /// gives them).
    waiting: Vec<Waiting>,
}

/// Interface triangles and their faces above, some still [`UNSET`].
type Waiting = (Vec<[u32; 3]>, Vec<(u32, u8)>);

impl Faces {
    fn new(dir: &Path, levels: usize) -> io::Result<Self> {
        let above = BoundaryLabel::of_levels(levels)
            .map(|l| {
                is_interface(l, levels)
                    .then(|| SpillFile::create(dir))
                    .transpose()
            })
            .collect::<io::Result<_>>()?;
        Ok(Faces {
            below: per_label(dir, levels + 1)?,
            above,
            prev: (0, Vec::new()),
            waiting: vec![(Vec::new(), Vec::new()); levels + 1],
        })
    }

    /// Records the faces of chunk `c`'s triangles, label by label (`idx[j]`: the triangles
    /// of label `j`).
    fn push(&mut self, c: &MeshChunk, idx: &[Vec<usize>]) -> io::Result<()> {
        let sides = triangle_faces(&c.tets, &c.regions, &c.boundary, c.first_tet);
        for j in 0..idx.len() {
            self.flush_waiting(j, c)?;
            let below: Vec<[u32; 2]> = idx[j].iter().map(|&b| pair(sides[b][0])).collect();
            if let Some(&b) = idx[j].iter().find(|&&b| sides[b][0] == UNSET) {
                return Err(no_tet(c.boundary[b], false));
            }
            self.below[j].push(&below)?;
            if self.above[j].is_some() {
                let tris: Vec<[u32; 3]> = idx[j].iter().map(|&b| c.boundary[b]).collect();
                let above = idx[j].iter().map(|&b| sides[b][1]).collect();
                self.push_above(j, tris, above)?;
            }
        }
        if !c.regions.is_empty() {
            self.prev = (c.first_tet, c.tets.clone());
        }
        Ok(())
    }

    /// Fills the missing faces above of `tris` from `tets` (numbered from `first_tet`).
    fn fill_above(tets: &[[u32; 4]], first_tet: usize, tris: &[[u32; 3]], above: &mut [(u32, u8)]) {
        let missing: Vec<usize> = (0..tris.len()).filter(|&i| above[i] == UNSET).collect();
        if missing.is_empty() {
            return;
        }
        let m_tris: Vec<[u32; 3]> = missing.iter().map(|&i| tris[i]).collect();
        let mut found = vec![[UNSET; 2]; m_tris.len()];
        fill_faces(tets, &[], &m_tris, first_tet, &mut found);
        for (&i, f) in missing.iter().zip(found) {
            above[i] = f[0];
        }
    }

    /// Writes the faces above of label `j`'s interface triangles, or keeps them waiting for
    /// the next chunk when some are in neither this chunk nor the previous one.
    fn push_above(
        &mut self,
        j: usize,
        tris: Vec<[u32; 3]>,
        mut above: Vec<(u32, u8)>,
    ) -> io::Result<()> {
        Self::fill_above(&self.prev.1, self.prev.0, &tris, &mut above);
        if above.contains(&UNSET) {
            self.waiting[j] = (tris, above);
            return Ok(());
        }
        self.write_above(j, &tris, above)
    }

    /// Completes label `j`'s waiting faces with the tets of chunk `c` and writes them.
    fn flush_waiting(&mut self, j: usize, c: &MeshChunk) -> io::Result<()> {
        let (tris, mut above) = std::mem::take(&mut self.waiting[j]);
        if tris.is_empty() {
            return Ok(());
        }
        Self::fill_above(&c.tets, c.first_tet, &tris, &mut above);
        self.write_above(j, &tris, above)
    }

    /// Writes complete faces above of label `j`.
    fn write_above(
        &mut self,
        j: usize,
        tris: &[[u32; 3]],
        above: Vec<(u32, u8)>,
    ) -> io::Result<()> {
        if let Some(i) = above.iter().position(|&f| f == UNSET) {
            return Err(no_tet(tris[i], true));
        }
        let file = self.above[j].as_mut().expect("an interface label");
        file.push(&above.into_iter().map(pair).collect::<Vec<_>>())
    }

    fn finish(&mut self) -> io::Result<()> {
        for j in 0..self.waiting.len() {
            let (tris, above) = std::mem::take(&mut self.waiting[j]);
            if !tris.is_empty() {
                self.write_above(j, &tris, above)?;
            }
        }
        self.below.iter_mut().try_for_each(SpillFile::finish)?;
        self.above
            .iter_mut()
            .flatten()
            .try_for_each(SpillFile::finish)
    }
}

/// A face as stored: `[tet, C3D4 face]`.
fn pair((t, k): (u32, u8)) -> [u32; 2] {
    [t, u32::from(k)]
}

impl SpilledMesh {
    /// An empty spilled mesh with its files in folder `dir`; `faces`: also record the tets
    /// and faces of the triangles (what the `.inp` writer needs); `levels`: the run's levels
    /// (2 for one interval), `names`: its regions' names (missing ones default, see
    /// [`region_name`]).
    ///
    /// # Errors
    /// When a file cannot be created in `dir`, or for more levels than a run can have.
    pub fn new(dir: &Path, faces: bool, levels: usize, names: Vec<String>) -> io::Result<Self> {
        let levels = levels.max(INTERVAL_LEVELS);
        if levels > LABEL_LEVELS {
            return Err(invalid(format!(
                "{levels} levels, at most {LABEL_LEVELS} are supported"
            )));
        }
        let regions = regions_of(levels);
        Ok(SpilledMesh {
            points: SpillFile::create(dir)?,
            values: SpillFile::create(dir)?,
            tets: SpillFile::create(dir)?,
            regions: (regions > 0).then(|| SpillFile::create(dir)).transpose()?,
            region_tets: vec![0; regions],
            levels,
            names,
            triangles: per_label(dir, levels + 1)?,
            faces: faces.then(|| Faces::new(dir, levels)).transpose()?,
            bbox: EMPTY_BOX,
            label_boxes: [EMPTY_BOX; NUM_LABELS],
        })
    }

    /// Flushes the files; call once after the last chunk, before writing.
    ///
    /// # Errors
    /// The first write error; [`io::ErrorKind::InvalidInput`] when the chunks gave a region
    /// for some tets only, or an interface triangle with no tet above it.
    pub fn finish(&mut self) -> io::Result<()> {
        self.points.finish()?;
        self.values.finish()?;
        self.tets.finish()?;
        if let Some(r) = &mut self.regions {
            r.finish()?;
            if r.len != self.tets.len {
                return Err(invalid(format!(
                    "{} tets but {} regions in the streamed mesh",
                    self.tets.len, r.len
                )));
            }
        }
        self.triangles.iter_mut().try_for_each(SpillFile::finish)?;
        self.faces.as_mut().map_or(Ok(()), Faces::finish)
    }

    /// The slot of `label` in the per-label files, `None` when the run has no such label.
    fn slot(&self, label: BoundaryLabel) -> Option<usize> {
        let j = label.code(self.levels);
        (label.level().is_none_or(|i| i < self.levels)).then_some(j)
    }

    /// Appends the triangles of `c` to their label's files.
    fn push_triangles(&mut self, c: &MeshChunk) -> io::Result<()> {
        let idx: Vec<Vec<usize>> = BoundaryLabel::of_levels(self.levels)
            .map(|l| {
                (0..c.boundary.len())
                    .filter(|&b| c.boundary_labels[b] == l)
                    .collect()
            })
            .collect();
        for (file, idx) in self.triangles.iter_mut().zip(&idx) {
            let tris: Vec<[u32; 3]> = idx.iter().map(|&b| c.boundary[b]).collect();
            file.push(&tris)?;
        }
        let counted: usize = idx.iter().map(Vec::len).sum();
        if counted != c.boundary.len() {
            return Err(invalid(format!(
                "a triangle labelled outside the run of {} levels",
                self.levels
            )));
        }
        match &mut self.faces {
            Some(f) => f.push(c, &idx),
            None => Ok(()),
        }
    }
}

impl MeshSink for SpilledMesh {
    fn chunk(&mut self, c: &MeshChunk) -> io::Result<()> {
        self.points.push(&c.points)?;
        self.values.push(&c.values)?;
        self.tets.push(&c.tets)?;
        if let Some(r) = &mut self.regions {
            r.push(&c.regions)?;
            for &k in &c.regions {
                let count = self.region_tets.get_mut(k as usize);
                *count.ok_or_else(|| invalid(format!("region {k} out of range")))? += 1;
            }
        }
        self.push_triangles(c)?;
        c.points.iter().for_each(|&p| grow_box(&mut self.bbox, p));
        for (b, cb) in self.label_boxes.iter_mut().zip(&c.label_boxes) {
            for k in 0..3 {
                b[k] = b[k].min(cb[k]);
                b[k + 3] = b[k + 3].max(cb[k + 3]);
            }
        }
        Ok(())
    }
}

impl MeshSource for SpilledMesh {
    fn num_points(&self) -> usize {
        self.points.len
    }
    fn num_tets(&self) -> usize {
        self.tets.len
    }
    fn level_count(&self) -> usize {
        self.levels
    }
    fn region_name(&self, k: usize) -> String {
        region_name(&self.names, k)
    }
    fn regions(&self, f: Visit<u8>) -> io::Result<()> {
        self.regions.as_ref().map_or(Ok(()), |r| r.visit(f))
    }
    fn region_tets(&self) -> Vec<usize> {
        self.region_tets.clone()
    }
    fn tets_in_regions(&self, f: VisitRegions) -> io::Result<()> {
        match &self.regions {
            Some(r) => visit_pair(&self.tets, r, f),
            None => self.tets.visit(&mut |ts| f(ts, &[])),
        }
    }
    fn label_counts(&self) -> [usize; NUM_LABELS] {
        let mut count = [0; NUM_LABELS];
        for (l, t) in BoundaryLabel::of_levels(self.levels).zip(&self.triangles) {
            count[l.index()] = t.len;
        }
        count
    }
    fn bbox(&self, label: Option<BoundaryLabel>) -> [f64; 6] {
        match label {
            None => self.bbox,
            Some(l) => self.label_boxes[l.index()],
        }
    }
    fn points(&self, f: Visit<[f64; 3]>) -> io::Result<()> {
        self.points.visit(f)
    }
    fn values(&self, f: Visit<f64>) -> io::Result<()> {
        self.values.visit(f)
    }
    fn tets(&self, f: Visit<[u32; 4]>) -> io::Result<()> {
        self.tets.visit(f)
    }
    fn triangles(&self, label: BoundaryLabel, f: Visit<[u32; 3]>) -> io::Result<()> {
        match self.slot(label) {
            Some(j) => self.triangles[j].visit(f),
            None => Ok(()),
        }
    }
    fn faces(&self, label: BoundaryLabel, above: bool, f: Visit<(u32, u8)>) -> io::Result<()> {
        let Some(faces) = &self.faces else {
            return Err(io::Error::other(
                "the spilled mesh was made without boundary faces",
            ));
        };
        let Some(j) = self.slot(label) else {
            return Ok(());
        };
        let file = match (above, &faces.above[j]) {
            (true, Some(a)) => a,
            _ => &faces.below[j],
        };
        let mut buf = Vec::with_capacity(READ_SLICE);
        file.visit(&mut |tf| {
            buf.clear();
            buf.extend(tf.iter().map(|&[t, k]| (t, k as u8)));
            f(&buf)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::inp::write_inp_source;
    use crate::io::source::InMemory;
    use crate::mesh::{Regions, TetMesh};

    const LOW: BoundaryLabel = BoundaryLabel::Level(0);
    const MID: BoundaryLabel = BoundaryLabel::Level(1);
    const TOP: BoundaryLabel = BoundaryLabel::Level(2);

    /// Two tets on a shared face: tet 0 in region 0, tet 1 in region 1, the face between
    /// them an interface on level 1 (three levels).
    fn two_regions() -> TetMesh {
        TetMesh {
            points: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.5],
            ],
            values: vec![0.0, 1.0, 1.0, 1.0, 2.0],
            tets: vec![[0, 1, 2, 3], [1, 2, 3, 4]],
            boundary: vec![[0, 2, 1], [1, 2, 4]],
            boundary_labels: vec![LOW, TOP],
            regions: Regions {
                levels: 3,
                tets: vec![0, 1],
                boundary: vec![0, 1],
                interfaces: vec![[1, 2, 3]],
                interface_labels: vec![MID],
                names: Vec::new(),
            },
        }
    }

    /// The chunk of `mesh`'s tet `t` (points all in the first chunk, the one of tet `first`),
    /// with the triangles of its region (the interface with the region below it).
    fn chunk_of(mesh: &TetMesh, t: usize, first: usize) -> MeshChunk {
        let mut c = MeshChunk {
            first_tet: t,
            tets: vec![mesh.tets[t]],
            label_boxes: [EMPTY_BOX; NUM_LABELS],
            regions: vec![mesh.regions.tets[t]],
            ..MeshChunk::default()
        };
        if t == first {
            c.points = mesh.points.clone();
            c.values = mesh.values.clone();
        }
        let r = &mesh.regions;
        c.boundary.push(mesh.boundary[t]);
        c.boundary_labels.push(mesh.boundary_labels[t]);
        c.boundary_regions.push(r.boundary[t]);
        if r.tets[t] == 0 {
            c.boundary.push(r.interfaces[0]);
            c.boundary_labels.push(MID);
            c.boundary_regions.push(0);
        }
        c
    }

    /// The `.inp` of `mesh` streamed in one chunk per tet, in the order `order`.
    fn streamed_inp(mesh: &TetMesh, order: [usize; 2]) -> Vec<u8> {
        let dir = tempfile::tempdir().unwrap();
        let mut spill = SpilledMesh::new(dir.path(), true, 3, Vec::new()).unwrap();
        let mut chunks: Vec<MeshChunk> =
            order.iter().map(|&t| chunk_of(mesh, t, order[0])).collect();
        // Chunks number their tets in the order they come.
        for (i, c) in chunks.iter_mut().enumerate() {
            c.first_tet = i;
        }
        chunks.iter().try_for_each(|c| spill.chunk(c)).unwrap();
        spill.finish().unwrap();
        let mut out = Vec::new();
        write_inp_source(&spill, &mut out).unwrap();
        out
    }

    /// An interface whose tet above comes in the next chunk, or came in the previous one,
    /// has the faces of both sides, as in memory.
    #[test]
    fn interfaces_find_their_tet_above_in_a_neighbouring_chunk() {
        let mesh = two_regions();
        let mut want = Vec::new();
        write_inp_source(&InMemory::new(&mesh), &mut want).unwrap();
        let text = String::from_utf8(want.clone()).unwrap();
        assert!(
            text.contains("LEVEL2_BELOW, TYPE=ELEMENT\n1, S3\n"),
            "{text}"
        );
        assert!(
            text.contains("LEVEL2_ABOVE, TYPE=ELEMENT\n2, S1\n"),
            "{text}"
        );
        assert_eq!(streamed_inp(&mesh, [0, 1]), want);
        let mut swapped = mesh.clone();
        swapped.tets.swap(0, 1);
        swapped.regions.tets.swap(0, 1);
        swapped.boundary.swap(0, 1);
        swapped.boundary_labels.swap(0, 1);
        swapped.regions.boundary.swap(0, 1);
        let mut want = Vec::new();
        write_inp_source(&InMemory::new(&swapped), &mut want).unwrap();
        assert_eq!(streamed_inp(&swapped, [0, 1]), want);
    }
}
