//! What the mesh writers (`msh`, `inp`, `vtu`) read: a [`MeshSource`], either a [`TetMesh`]
//! in memory ([`InMemory`]) or a mesh streamed to spill files (`spill.rs`). Each list is
//! visited in order, in slices, so a writer never needs the whole mesh in memory and both
//! kinds of source give the same bytes.

use std::cell::OnceCell;
use std::io;

use rustc_hash::FxHashMap;

use super::write_common::invalid;
use crate::mesh::{grow_box, EMPTY_BOX};
use crate::mesh::{BoundaryLabel, TetMesh, NUM_LABELS};

/// A visitor of consecutive slices of one list.
pub(crate) type Visit<'a, T> = &'a mut dyn FnMut(&[T]) -> io::Result<()>;

/// Local vertex indices of the C3D4 faces S1..S4 (Abaqus / CalculiX numbering).
pub(crate) const C3D4_FACES: [[usize; 3]; 4] = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];

/// A mesh as the writers read it.
pub(crate) trait MeshSource {
    /// Number of points.
    fn num_points(&self) -> usize;
    /// Number of tets.
    fn num_tets(&self) -> usize;
    /// Boundary triangles per label, in [`BoundaryLabel::ALL`] order.
    fn label_counts(&self) -> [usize; NUM_LABELS];
    /// Bounding box `[min xyz, max xyz]` of all points (`None`) or of the vertices of the
    /// triangles labelled `label`; [`EMPTY_BOX`] when there are none.
    fn bbox(&self, label: Option<BoundaryLabel>) -> [f64; 6];
    /// Visits the points in order.
    fn points(&self, f: Visit<[f64; 3]>) -> io::Result<()>;
    /// Visits the field values in point order.
    fn values(&self, f: Visit<f64>) -> io::Result<()>;
    /// Visits the tets in order.
    fn tets(&self, f: Visit<[u32; 4]>) -> io::Result<()>;
    /// Visits the boundary triangles labelled `label`, in mesh order.
    fn triangles(&self, label: BoundaryLabel, f: Visit<[u32; 3]>) -> io::Result<()>;
    /// Visits, for each triangle labelled `label` in mesh order, the tet it is a face of and
    /// the C3D4 face index (0..4).
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] for a triangle that is not a face of any tet.
    fn faces(&self, label: BoundaryLabel, f: Visit<(u32, u8)>) -> io::Result<()>;

    /// For each label that occurs, in [`BoundaryLabel::ALL`] order: (label, triangle count).
    fn present_labels(&self) -> Vec<(BoundaryLabel, usize)> {
        let c = self.label_counts();
        BoundaryLabel::ALL
            .into_iter()
            .filter(|&l| c[l.index()] > 0)
            .map(|l| (l, c[l.index()]))
            .collect()
    }

    /// Number of boundary triangles.
    fn num_boundary(&self) -> usize {
        self.label_counts().iter().sum()
    }
}

/// Slices visited at a time when a list has to be filtered or built.
pub(crate) const SLICE: usize = 1 << 16;

/// Visits the items of `it` in slices of [`SLICE`].
pub(crate) fn visit_iter<T: Copy>(
    it: impl Iterator<Item = T>,
    f: &mut dyn FnMut(&[T]) -> io::Result<()>,
) -> io::Result<()> {
    let mut buf = Vec::with_capacity(SLICE);
    for x in it {
        buf.push(x);
        if buf.len() == SLICE {
            f(&buf)?;
            buf.clear();
        }
    }
    if !buf.is_empty() {
        f(&buf)?;
    }
    Ok(())
}

/// A [`TetMesh`] in memory as a [`MeshSource`] (its lists are visited as one slice each).
pub(crate) struct InMemory<'a> {
    mesh: &'a TetMesh,
    faces: OnceCell<Vec<(u32, u8)>>,
}

impl<'a> InMemory<'a> {
    pub(crate) fn new(mesh: &'a TetMesh) -> Self {
        InMemory {
            mesh,
            faces: OnceCell::new(),
        }
    }

    fn labelled(&self, label: BoundaryLabel) -> impl Iterator<Item = (usize, &[u32; 3])> {
        self.mesh
            .boundary
            .iter()
            .zip(&self.mesh.boundary_labels)
            .enumerate()
            .filter(move |&(_, (_, &l))| l == label)
            .map(|(b, (t, _))| (b, t))
    }
}

impl MeshSource for InMemory<'_> {
    fn num_points(&self) -> usize {
        self.mesh.points.len()
    }
    fn num_tets(&self) -> usize {
        self.mesh.tets.len()
    }
    fn label_counts(&self) -> [usize; NUM_LABELS] {
        let mut count = [0usize; NUM_LABELS];
        for &l in &self.mesh.boundary_labels {
            count[l.index()] += 1;
        }
        count
    }
    fn bbox(&self, label: Option<BoundaryLabel>) -> [f64; 6] {
        let mut b = EMPTY_BOX;
        match label {
            None => self.mesh.points.iter().for_each(|&p| grow_box(&mut b, p)),
            Some(l) => {
                for (_, t) in self.labelled(l) {
                    t.iter()
                        .for_each(|&i| grow_box(&mut b, self.mesh.points[i as usize]));
                }
            }
        }
        b
    }
    fn points(&self, f: Visit<[f64; 3]>) -> io::Result<()> {
        f(&self.mesh.points)
    }
    fn values(&self, f: Visit<f64>) -> io::Result<()> {
        f(&self.mesh.values)
    }
    fn tets(&self, f: Visit<[u32; 4]>) -> io::Result<()> {
        f(&self.mesh.tets)
    }
    fn triangles(&self, label: BoundaryLabel, f: Visit<[u32; 3]>) -> io::Result<()> {
        visit_iter(self.labelled(label).map(|(_, &t)| t), f)
    }
    fn faces(&self, label: BoundaryLabel, f: Visit<(u32, u8)>) -> io::Result<()> {
        let faces = match self.faces.get() {
            Some(x) => x,
            None => {
                let x = boundary_faces(&self.mesh.tets, &self.mesh.boundary, 0)?;
                self.faces.get_or_init(|| x)
            }
        };
        visit_iter(self.labelled(label).map(|(b, _)| faces[b]), f)
    }
}

fn sorted3(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// For each of `boundary`, the tet of `tets` it is a face of (numbered from `first_tet`) and
/// the C3D4 face index (0..4).
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] for a triangle that is not a face of any tet.
pub(crate) fn boundary_faces(
    tets: &[[u32; 4]],
    boundary: &[[u32; 3]],
    first_tet: usize,
) -> io::Result<Vec<(u32, u8)>> {
    const UNSET: (u32, u8) = (u32::MAX, u8::MAX);
    let mut index: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    index.reserve(boundary.len());
    for (b, &tri) in boundary.iter().enumerate() {
        index.insert(sorted3(tri), b as u32);
    }
    let mut faces = vec![UNSET; boundary.len()];
    if !index.is_empty() {
        for (t, tet) in tets.iter().enumerate() {
            for (k, f) in C3D4_FACES.iter().enumerate() {
                let key = sorted3([tet[f[0]], tet[f[1]], tet[f[2]]]);
                if let Some(&b) = index.get(&key) {
                    faces[b as usize] = ((first_tet + t) as u32, k as u8);
                }
            }
        }
    }
    if let Some(b) = faces.iter().position(|&f| f == UNSET) {
        return Err(invalid(format!(
            "boundary triangle {b} {:?} is not a face of any tetrahedron",
            boundary[b]
        )));
    }
    Ok(faces)
}
