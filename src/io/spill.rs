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

use super::source::{boundary_faces, MeshSource, Visit};
use crate::mesh::BoundaryLabel;
use crate::mesh::{grow_box, MeshChunk, MeshSink, EMPTY_BOX, NUM_LABELS};

/// Items read back per slice.
const READ_SLICE: usize = 1 << 16;

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

/// One spill file per boundary label, in [`BoundaryLabel::index`] order.
fn per_label<T: Pod>(dir: &Path) -> io::Result<[SpillFile<T>; NUM_LABELS]> {
    let files = (0..NUM_LABELS)
        .map(|_| SpillFile::create(dir))
        .collect::<io::Result<Vec<_>>>()?;
    match files.try_into() {
        Ok(files) => Ok(files),
        Err(_) => unreachable!("one file per label"),
    }
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
    triangles: [SpillFile<[u32; 3]>; NUM_LABELS],
    /// Per label, `[tet, C3D4 face]` of each triangle (only when asked for: `.inp`).
    faces: Option<[SpillFile<[u32; 2]>; NUM_LABELS]>,
    bbox: [f64; 6],
    label_boxes: [[f64; 6]; NUM_LABELS],
}

impl SpilledMesh {
    /// An empty spilled mesh with its files in folder `dir`; `faces`: also record the tet
    /// and face of each boundary triangle (what the `.inp` writer needs).
    ///
    /// # Errors
    /// When a file cannot be created in `dir`.
    pub fn new(dir: &Path, faces: bool) -> io::Result<Self> {
        Ok(SpilledMesh {
            points: SpillFile::create(dir)?,
            values: SpillFile::create(dir)?,
            tets: SpillFile::create(dir)?,
            triangles: per_label(dir)?,
            faces: if faces { Some(per_label(dir)?) } else { None },
            bbox: EMPTY_BOX,
            label_boxes: [EMPTY_BOX; NUM_LABELS],
        })
    }

    /// Flushes the files; call once after the last chunk, before writing.
    ///
    /// # Errors
    /// The first write error.
    pub fn finish(&mut self) -> io::Result<()> {
        self.points.finish()?;
        self.values.finish()?;
        self.tets.finish()?;
        for t in &mut self.triangles {
            t.finish()?;
        }
        for f in self.faces.iter_mut().flatten() {
            f.finish()?;
        }
        Ok(())
    }

    /// Appends the boundary triangles of `c` to their label's files.
    fn push_triangles(&mut self, c: &MeshChunk) -> io::Result<()> {
        let faces = match &self.faces {
            Some(_) => Some(boundary_faces(&c.tets, &c.boundary, c.first_tet)?),
            None => None,
        };
        for l in BoundaryLabel::ALL {
            let of_l = |b: &usize| c.boundary_labels[*b] == l;
            let idx: Vec<usize> = (0..c.boundary.len()).filter(of_l).collect();
            let tris: Vec<[u32; 3]> = idx.iter().map(|&b| c.boundary[b]).collect();
            self.triangles[l.index()].push(&tris)?;
            if let (Some(files), Some(faces)) = (&mut self.faces, &faces) {
                let tf: Vec<[u32; 2]> = idx
                    .iter()
                    .map(|&b| [faces[b].0, u32::from(faces[b].1)])
                    .collect();
                files[l.index()].push(&tf)?;
            }
        }
        Ok(())
    }
}

impl MeshSink for SpilledMesh {
    fn chunk(&mut self, c: &MeshChunk) -> io::Result<()> {
        self.points.push(&c.points)?;
        self.values.push(&c.values)?;
        self.tets.push(&c.tets)?;
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
    fn label_counts(&self) -> [usize; NUM_LABELS] {
        self.triangles.each_ref().map(|t| t.len)
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
        self.triangles[label.index()].visit(f)
    }
    fn faces(&self, label: BoundaryLabel, f: Visit<(u32, u8)>) -> io::Result<()> {
        let Some(files) = &self.faces else {
            return Err(io::Error::other(
                "the spilled mesh was made without boundary faces",
            ));
        };
        let mut buf = Vec::with_capacity(READ_SLICE);
        files[label.index()].visit(&mut |tf| {
            buf.clear();
            buf.extend(tf.iter().map(|&[t, k]| (t, k as u8)));
            f(&buf)
        })
    }
}
