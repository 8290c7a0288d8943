//! What the mesh writers (`msh`, `inp`, `vtu`) read: a [`MeshSource`], either a [`TetMesh`]
//! in memory ([`InMemory`]) or a mesh streamed to spill files (`spill.rs`). Each list is
//! visited in order, in slices, so a writer never needs the whole mesh in memory and both
//! kinds of source give the same bytes.

use std::cell::OnceCell;
use std::io;

use rustc_hash::FxHashMap;

use super::write_common::invalid;
use crate::mesh::{grow_box, EMPTY_BOX};
use crate::mesh::{BoundaryLabel, TetMesh, INTERVAL_LEVELS, NUM_LABELS};

/// A visitor of consecutive slices of one list.
pub(crate) type Visit<'a, T> = &'a mut dyn FnMut(&[T]) -> io::Result<()>;

/// Local vertex indices of the C3D4 faces S1..S4 (Abaqus / CalculiX numbering).
pub(crate) const C3D4_FACES: [[usize; 3]; 4] = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];

/// A mesh as the writers read it.
///
/// The labelled triangles are the boundary triangles and, with several regions, the
/// interface triangles on the levels between regions (labelled with those levels, oriented
/// out of the region below).
pub(crate) trait MeshSource {
    /// Number of points.
    fn num_points(&self) -> usize;
    /// Number of tets.
    fn num_tets(&self) -> usize;
    /// Number of levels the labels name: 2 for one interval ([`INTERVAL_LEVELS`]).
    fn level_count(&self) -> usize;
    /// The name of region `k` (see [`crate::mesh::region_name`]).
    fn region_name(&self, k: usize) -> String;
    /// Visits the region of each tet, in tet order (nothing for one interval).
    fn regions(&self, f: Visit<u8>) -> io::Result<()>;
    /// Tets per region (empty for one interval).
    fn region_tets(&self) -> Vec<usize>;
    /// Visits the tets with their regions, in tet order (both slices of the same length).
    fn tets_in_regions(&self, f: VisitRegions) -> io::Result<()>;
    /// Labelled triangles per label, in [`BoundaryLabel::index`] order.
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
    /// Visits the triangles labelled `label`, in mesh order.
    fn triangles(&self, label: BoundaryLabel, f: Visit<[u32; 3]>) -> io::Result<()>;
    /// Visits, for each triangle labelled `label` in mesh order, a tet it is a face of and
    /// the C3D4 face index (0..4): for an interface label the tet of the region below
    /// (`above` false) or above (`above` true); for other labels its only tet (`above` is
    /// ignored).
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] for a triangle that is not a face of such a tet.
    fn faces(&self, label: BoundaryLabel, above: bool, f: Visit<(u32, u8)>) -> io::Result<()>;

    /// Number of regions (0 for one interval).
    fn region_count(&self) -> usize {
        regions_of(self.level_count())
    }

    /// Whether `label` names a level between two regions (its triangles are interfaces).
    fn is_interface(&self, label: BoundaryLabel) -> bool {
        is_interface(label, self.level_count())
    }

    /// For each label of the run that occurs, in tag order
    /// ([`BoundaryLabel::of_levels`]): (label, triangle count).
    fn present_labels(&self) -> Vec<(BoundaryLabel, usize)> {
        let c = self.label_counts();
        BoundaryLabel::of_levels(self.level_count())
            .filter(|&l| c[l.index()] > 0)
            .map(|l| (l, c[l.index()]))
            .collect()
    }

    /// Number of labelled triangles (boundary and interfaces).
    fn num_triangles(&self) -> usize {
        self.label_counts().iter().sum()
    }
}

/// A visitor of the tets and their regions, slice by slice.
pub(crate) type VisitRegions<'a> = &'a mut dyn FnMut(&[[u32; 4]], &[u8]) -> io::Result<()>;

/// Number of regions of a run of `levels` levels: 0 for one interval.
pub(crate) fn regions_of(levels: usize) -> usize {
    if levels > INTERVAL_LEVELS {
        levels - 1
    } else {
        0
    }
}

/// Whether `label` is a level between two regions in a run of `levels` levels.
pub(crate) fn is_interface(label: BoundaryLabel, levels: usize) -> bool {
    label.is_interface(levels)
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
    /// Per boundary triangle, then per interface triangle: its faces (below, above).
    faces: OnceCell<Vec<[(u32, u8); 2]>>,
}

impl<'a> InMemory<'a> {
    pub(crate) fn new(mesh: &'a TetMesh) -> Self {
        InMemory {
            mesh,
            faces: OnceCell::new(),
        }
    }

    /// The triangles labelled `label` with their numbers among the boundary triangles
    /// followed by the interface triangles.
    fn labelled(&self, label: BoundaryLabel) -> impl Iterator<Item = (usize, &[u32; 3])> {
        let (m, r) = (self.mesh, &self.mesh.regions);
        let (tris, labels, first) = if self.is_interface(label) {
            (&r.interfaces, &r.interface_labels, m.boundary.len())
        } else {
            (&m.boundary, &m.boundary_labels, 0)
        };
        tris.iter()
            .zip(labels)
            .enumerate()
            .filter(move |&(_, (_, &l))| l == label)
            .map(move |(b, (t, _))| (first + b, t))
    }

    /// The faces of every triangle (computed once).
    fn all_faces(&self) -> &[[(u32, u8); 2]] {
        self.faces.get_or_init(|| {
            let m = self.mesh;
            let mut tris = m.boundary.clone();
            tris.extend_from_slice(&m.regions.interfaces);
            triangle_faces(&m.tets, &m.regions.tets, &tris, 0)
        })
    }
}

impl MeshSource for InMemory<'_> {
    fn num_points(&self) -> usize {
        self.mesh.points.len()
    }
    fn num_tets(&self) -> usize {
        self.mesh.tets.len()
    }
    fn level_count(&self) -> usize {
        self.mesh.level_count()
    }
    fn region_name(&self, k: usize) -> String {
        self.mesh.regions.name(k)
    }
    fn regions(&self, f: Visit<u8>) -> io::Result<()> {
        f(&self.mesh.regions.tets)
    }
    fn region_tets(&self) -> Vec<usize> {
        let mut count = vec![0; self.region_count()];
        for &k in &self.mesh.regions.tets {
            count[k as usize] += 1;
        }
        count
    }
    fn tets_in_regions(&self, f: VisitRegions) -> io::Result<()> {
        f(&self.mesh.tets, &self.mesh.regions.tets)
    }
    fn label_counts(&self) -> [usize; NUM_LABELS] {
        let mut count = [0usize; NUM_LABELS];
        let r = &self.mesh.regions;
        for &l in self.mesh.boundary_labels.iter().chain(&r.interface_labels) {
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
    fn faces(&self, label: BoundaryLabel, above: bool, f: Visit<(u32, u8)>) -> io::Result<()> {
        let faces = self.all_faces();
        let side = usize::from(above && self.is_interface(label));
        // Refused before anything is visited: a writer never sees a missing face.
        if let Some((_, t)) = self.labelled(label).find(|(b, _)| faces[*b][side] == UNSET) {
            return Err(no_tet(*t, above));
        }
        visit_iter(self.labelled(label).map(|(b, _)| faces[b][side]), f)
    }
}

fn sorted3(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// A side of a triangle without a tet.
pub(crate) const UNSET: (u32, u8) = (u32::MAX, u8::MAX);

/// The error for triangle `t` without a tet (on the side above when `above`).
pub(crate) fn no_tet(t: [u32; 3], above: bool) -> io::Error {
    let side = if above { " above it" } else { "" };
    invalid(format!(
        "triangle {t:?} is not a face of any tetrahedron{side}"
    ))
}

/// For each of `tris`, the tets of `tets` it is a face of (numbered from `first_tet`) with
/// the C3D4 face index (0..4): `[below, above]`, the tet of the lower region first (by
/// `regions`, one per tet, or empty for one interval; a triangle of one tet has it below
/// and [`UNSET`] above). A side without a tet is [`UNSET`].
pub(crate) fn triangle_faces(
    tets: &[[u32; 4]],
    regions: &[u8],
    tris: &[[u32; 3]],
    first_tet: usize,
) -> Vec<[(u32, u8); 2]> {
    let mut faces = vec![[UNSET; 2]; tris.len()];
    fill_faces(tets, regions, tris, first_tet, &mut faces);
    faces
}

/// Fills the sides of `faces` (one per triangle of `tris`) that the tets of `tets` give
/// (see [`triangle_faces`]); a tet found for a triangle that already has one goes to the
/// side of the higher region.
pub(crate) fn fill_faces(
    tets: &[[u32; 4]],
    regions: &[u8],
    tris: &[[u32; 3]],
    first_tet: usize,
    faces: &mut [[(u32, u8); 2]],
) {
    let mut index: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    index.reserve(tris.len());
    for (b, &tri) in tris.iter().enumerate() {
        index.insert(sorted3(tri), b as u32);
    }
    if index.is_empty() {
        return;
    }
    let region = |t: u32| regions.get(t as usize - first_tet).copied().unwrap_or(0);
    for (t, tet) in tets.iter().enumerate() {
        for (k, f) in C3D4_FACES.iter().enumerate() {
            let key = sorted3([tet[f[0]], tet[f[1]], tet[f[2]]]);
            if let Some(&b) = index.get(&key) {
                let new = ((first_tet + t) as u32, k as u8);
                let sides = &mut faces[b as usize];
                if sides[0] == UNSET {
                    sides[0] = new;
                } else if region(new.0) < region(sides[0].0) {
                    sides[1] = std::mem::replace(&mut sides[0], new);
                } else {
                    sides[1] = new;
                }
            }
        }
    }
}
