//! The interfaces between regions as the pass sees them: faces of its boundary map, labelled
//! with their level, that no operation removes.
//!
//! A mesh of several regions keeps its interface triangles apart from its boundary
//! ([`crate::mesh::Regions::interfaces`]). For the pass they join the boundary
//! ([`into_boundary`]): their vertices then get their level's constraint (they move on the
//! level set, and are merged only where every region around them keeps its topology,
//! [`keeps_regions`]), the
//! flips and edge removals leave their faces and edges alone, splits of their edges split
//! them, and the embedding guards keep them from crossing anything. Afterwards they are
//! taken out again ([`out_of_boundary`]), and the region of each boundary triangle is read
//! from its tet.

use rustc_hash::FxHashMap;
use smallvec::SmallVec;

use super::region::{face_key, LocalMesh};
use crate::mesh::TetMesh;

/// Appends the interface triangles of `mesh` (with their level labels) to its boundary.
pub(super) fn into_boundary(mesh: &mut TetMesh) {
    let regions = &mut mesh.regions;
    mesh.boundary.append(&mut regions.interfaces);
    mesh.boundary_labels.append(&mut regions.interface_labels);
    regions.boundary.clear();
}

/// Moves the boundary triangles on a level between regions back to the interfaces (both in
/// the order the pass left them) and sets the region of each boundary triangle: that of its
/// tet.
pub(super) fn out_of_boundary(mesh: &mut TetMesh) {
    let levels = mesh.regions.levels;
    let (mut boundary, mut labels) = (Vec::new(), Vec::new());
    let regions = &mut mesh.regions;
    for (&tri, &label) in mesh.boundary.iter().zip(&mesh.boundary_labels) {
        if label.is_interface(levels) {
            regions.interfaces.push(tri);
            regions.interface_labels.push(label);
        } else {
            boundary.push(tri);
            labels.push(label);
        }
    }
    mesh.boundary = boundary;
    mesh.boundary_labels = labels;
    mesh.regions.boundary = boundary_regions(mesh);
}

/// The region of the tet of each boundary triangle of `mesh` (0 where none has it: the
/// checker reports such a triangle).
fn boundary_regions(mesh: &TetMesh) -> Vec<u8> {
    let index: FxHashMap<[u32; 3], u32> = mesh
        .boundary
        .iter()
        .enumerate()
        .map(|(i, &tri)| (face_key(tri), i as u32))
        .collect();
    let mut out = vec![0u8; mesh.boundary.len()];
    for (t, tet) in mesh.tets.iter().enumerate() {
        for skip in 0..4 {
            let mut f = [0u32; 3];
            let mut n = 0;
            for (i, &v) in tet.iter().enumerate() {
                if i != skip {
                    f[n] = v;
                    n += 1;
                }
            }
            if let Some(&i) = index.get(&face_key(f)) {
                out[i as usize] = mesh.regions.tets[t];
            }
        }
    }
    out
}

/// The virtual vertex that cones a region's boundary in [`region_link`].
const OMEGA: u32 = u32::MAX - 1;

/// For a collapse of `a` into `b` (legal in the whole mesh): whether it keeps the topology of
/// every region around `a`, by the link condition in each region's complex closed by a
/// virtual vertex coning its boundary (the faces of the boundary map that are faces of the
/// region's tets: its part of the domain's boundary and its interfaces). The whole mesh's
/// condition does not imply it: a collapse along an interface could pinch one side.
pub(super) fn keeps_regions(lm: &LocalMesh, a: u32, b: u32) -> bool {
    let mut regions: SmallVec<[u8; 4]> = lm.star[a as usize]
        .iter()
        .map(|&t| lm.region[t as usize])
        .collect();
    regions.sort_unstable();
    regions.dedup();
    regions.iter().all(|&r| {
        let (la, lb) = (region_link(lm, a, r), region_link(lm, b, r));
        let lab = edge_link(lm, [a, b], r);
        let outside = |x: &u32| *x != a && *x != b;
        let common_verts: Vec<u32> = la
            .verts
            .iter()
            .filter(|x| outside(x) && lb.verts.binary_search(x).is_ok())
            .copied()
            .collect();
        let edges_ok = la
            .edges
            .iter()
            .filter(|e| e.iter().all(outside) && lb.edges.binary_search(e).is_ok())
            .all(|e| lab.edges.binary_search(e).is_ok());
        let tri_clash = la
            .tris
            .iter()
            .any(|t| t.iter().all(outside) && lb.tris.binary_search(t).is_ok());
        common_verts == lab.verts && edges_ok && !tri_clash
    })
}

/// A link as sorted lists of its vertices, edges and triangles ([`OMEGA`] for the virtual
/// vertex).
#[derive(Default)]
struct Link {
    verts: Vec<u32>,
    edges: Vec<[u32; 2]>,
    tris: Vec<[u32; 3]>,
}

impl Link {
    fn add_tri(&mut self, tri: [u32; 3]) {
        let t = face_key(tri);
        self.verts.extend_from_slice(&t);
        self.edges
            .extend([[t[0], t[1]], [t[0], t[2]], [t[1], t[2]]]);
        self.tris.push(t);
    }

    fn sorted(mut self) -> Self {
        self.verts.sort_unstable();
        self.verts.dedup();
        self.edges.sort_unstable();
        self.edges.dedup();
        self.tris.sort_unstable();
        self.tris.dedup();
        self
    }
}

/// The link of `v` in region `r`'s complex closed by [`OMEGA`]: the faces opposite `v` in
/// its tets of region `r`, and `OMEGA` joined to the edges opposite `v` in the region's
/// boundary faces at `v`.
fn region_link(lm: &LocalMesh, v: u32, r: u8) -> Link {
    let mut link = Link::default();
    for tet in region_tets(lm, v, r) {
        let others = without(tet, &[v]);
        link.add_tri([others[0], others[1], others[2]]);
        for [x, y] in [[0, 1], [0, 2], [1, 2]] {
            if lm.faces.contains_key(&face_key([v, others[x], others[y]])) {
                link.add_tri([others[x], others[y], OMEGA]);
            }
        }
    }
    link.sorted()
}

/// The link of edge `ab` in region `r`'s complex closed by [`OMEGA`]: the edges opposite it
/// in its tets of region `r`, and `OMEGA` joined to the third corner of the region's
/// boundary faces on it.
fn edge_link(lm: &LocalMesh, [a, b]: [u32; 2], r: u8) -> Link {
    let mut link = Link::default();
    for tet in region_tets(lm, a, r).filter(|t| t.contains(&b)) {
        let o = without(tet, &[a, b]);
        let (x, y) = (o[0].min(o[1]), o[0].max(o[1]));
        link.verts.extend([x, y]);
        link.edges.push([x, y]);
        for w in [x, y] {
            if lm.faces.contains_key(&face_key([a, b, w])) {
                link.verts.push(OMEGA);
                link.edges.push([w, OMEGA]);
            }
        }
    }
    link.sorted()
}

/// The tets of region `r` around `v`.
fn region_tets(lm: &LocalMesh, v: u32, r: u8) -> impl Iterator<Item = [u32; 4]> + '_ {
    lm.star[v as usize]
        .iter()
        .filter(move |&&t| lm.region[t as usize] == r)
        .map(|&t| lm.tets[t as usize])
}

/// The corners of `tet` other than `skip`, in order.
fn without(tet: [u32; 4], skip: &[u32]) -> SmallVec<[u32; 3]> {
    tet.into_iter().filter(|v| !skip.contains(v)).collect()
}
