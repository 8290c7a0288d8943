//! Writing regions back into the mesh: their tets, faces and points, with new points given
//! ids after the existing ones, and the points merged away dropped at the end of the pass.

use rayon::prelude::*;

use super::{BoundaryFace, LocalMesh, Regions, NEW_POINT, NONE};
use crate::mesh::{BoundaryLabel, TetMesh};

/// Writes the regions back into `mesh`: moved points, the regions' tets (after the tets
/// outside them, which keep their order; regions in order) and boundary faces; merged points
/// are dropped and the points renumbered in order.
/// `quality` (per tet) follows the tets.
/// Returns the points merged away: no tet or face uses them any more, and the caller drops
/// them ([`drop_points`]) once, at the end of the pass.
pub fn splice(
    mesh: &mut TetMesh,
    regions: Vec<LocalMesh>,
    bookkeeping: Regions,
    quality: &mut Vec<f64>,
) -> Vec<u32> {
    // Compacted in place: the tets (and their flags) outside every region keep their order.
    retain_outside(&mut mesh.tets, &bookkeeping.of_tet);
    retain_outside(quality, &bookkeeping.of_tet);
    if !mesh.regions.is_empty() {
        retain_outside(&mut mesh.regions.tets, &bookkeeping.of_tet);
    }
    let keep: Vec<bool> = mesh
        .boundary
        .iter()
        .map(|&tri| bookkeeping.keeps_face(tri))
        .collect();
    retain_flagged(&mut mesh.boundary, &keep);
    retain_flagged(&mut mesh.boundary_labels, &keep);
    // New points get ids after the existing ones, region by region.
    let mut next = mesh.points.len() as u32;
    let firsts: Vec<u32> = regions
        .iter()
        .map(|lm| {
            let first = next;
            next += lm.added_points() as u32;
            first
        })
        .collect();
    let parts: Vec<Spliced> = regions
        .into_par_iter()
        .zip(firsts)
        .map(|(lm, first)| lm.into_spliced(first))
        .collect();
    let mut removed = Vec::new();
    for part in parts {
        part.write(mesh, quality, &mut removed);
    }
    removed
}

/// A region in global ids, ready to be appended to the mesh.
struct Spliced {
    /// Its alive tets, their qualities and regions.
    tets: Vec<[u32; 4]>,
    quality: Vec<f64>,
    regions: Vec<u8>,
    /// Its boundary faces (sorted by [`face_key`](super::face_key)) and their labels.
    faces: Vec<[u32; 3]>,
    labels: Vec<BoundaryLabel>,
    /// Its free points that stay (moved or not) and the points it added: id, position, value.
    points: Vec<(u32, [f64; 3], f64)>,
    /// Its points merged away.
    removed: Vec<u32>,
}

/// Writes back regions in which vertices only moved (no tet or face was added or removed):
/// the positions and values of their free vertices, and `quality` of their tets, in place, so
/// the mesh keeps its tet order.
pub fn write_positions(
    mesh: &mut TetMesh,
    regions: &[LocalMesh],
    bookkeeping: &Regions,
    quality: &mut [f64],
) {
    // Region `r` is `regions[r]`, and its k-th tet is its k-th tet in mesh order.
    let mut next = vec![0usize; regions.len()];
    for (t, &r) in bookkeeping.of_tet.iter().enumerate() {
        if r != NONE {
            let i = r as usize;
            quality[t] = regions[i].q[next[i]];
            next[i] += 1;
        }
    }
    for lm in regions {
        for (l, &gid) in lm.global.iter().enumerate() {
            if !lm.frozen[l] && !lm.removed[l] {
                mesh.points[gid as usize] = lm.x[l];
                mesh.values[gid as usize] = lm.value[l];
            }
        }
    }
}

/// Keeps the items whose region in `of` is `NONE`, in order.
fn retain_outside<T>(items: &mut Vec<T>, of: &[u32]) {
    let mut i = 0;
    items.retain(|_| {
        i += 1;
        of[i - 1] == NONE
    });
}

/// Keeps the items whose flag in `keep` is set, in order.
pub fn retain_flagged<T>(items: &mut Vec<T>, keep: &[bool]) {
    let mut i = 0;
    items.retain(|_| {
        i += 1;
        keep[i - 1]
    });
}

impl LocalMesh {
    /// How many points the region added (they come after the copied ones).
    fn added_points(&self) -> usize {
        self.global
            .iter()
            .rev()
            .take_while(|&&g| g == NEW_POINT)
            .count()
    }

    /// This region in global ids; its added points get ids from `first` on, in order.
    fn into_spliced(self, first: u32) -> Spliced {
        let added = self.global.len() - self.added_points();
        let mut global = self.global;
        for (gid, id) in global[added..].iter_mut().zip(first..) {
            *gid = id;
        }
        let g = |v: u32| global[v as usize];
        let mut out = Spliced {
            tets: Vec::with_capacity(self.tets.len()),
            quality: Vec::with_capacity(self.tets.len()),
            regions: Vec::with_capacity(self.tets.len()),
            faces: Vec::with_capacity(self.faces.len()),
            labels: Vec::with_capacity(self.faces.len()),
            points: Vec::new(),
            removed: Vec::new(),
        };
        for (l, &gid) in global.iter().enumerate() {
            // An added point takes its id even if merged away again.
            if l >= added || (!self.removed[l] && !self.frozen[l]) {
                out.points.push((gid, self.x[l], self.value[l]));
            }
            if self.removed[l] {
                out.removed.push(gid);
            }
        }
        for (((t, &a), &q), &r) in self
            .tets
            .iter()
            .zip(&self.alive)
            .zip(&self.q)
            .zip(&self.region)
        {
            if a {
                out.tets.push(t.map(g));
                out.quality.push(q);
                out.regions.push(r);
            }
        }
        // In the order of their keys (each face's sorted corners, unique), read from the map
        // rather than sorted again at every comparison.
        let mut faces: Vec<(&[u32; 3], &BoundaryFace)> = self.faces.iter().collect();
        faces.sort_unstable_by_key(|&(key, _)| *key);
        for (_, f) in faces {
            out.faces.push(f.tri.map(g));
            out.labels.push(f.label);
        }
        out
    }
}

impl Spliced {
    /// Appends this region's tets, qualities and faces to the mesh, writes its points (added
    /// ones are appended: they come in id order) and lists its merged points in `removed`.
    fn write(self, mesh: &mut TetMesh, quality: &mut Vec<f64>, removed: &mut Vec<u32>) {
        for (gid, x, value) in self.points {
            if gid as usize == mesh.points.len() {
                mesh.points.push(x);
                mesh.values.push(value);
            } else {
                mesh.points[gid as usize] = x;
                mesh.values[gid as usize] = value;
            }
        }
        mesh.tets.extend_from_slice(&self.tets);
        quality.extend_from_slice(&self.quality);
        if !mesh.regions.is_empty() {
            mesh.regions.tets.extend_from_slice(&self.regions);
        }
        mesh.boundary.extend_from_slice(&self.faces);
        mesh.boundary_labels.extend_from_slice(&self.labels);
        removed.extend_from_slice(&self.removed);
    }
}

/// Removes the points `removed` (sorted ascending, used by no tet) and renumbers the rest.
pub fn drop_points(mesh: &mut TetMesh, removed: &[u32]) {
    if removed.is_empty() {
        return;
    }
    let n = mesh.points.len();
    let mut new_id = vec![u32::MAX; n];
    let mut next = 0u32;
    let mut r = removed.iter().peekable();
    for (v, id) in new_id.iter_mut().enumerate() {
        if r.peek() == Some(&&(v as u32)) {
            r.next();
            continue;
        }
        *id = next;
        next += 1;
    }
    let keep = |v: &usize| new_id[*v] != u32::MAX;
    mesh.points = (0..n).filter(keep).map(|v| mesh.points[v]).collect();
    mesh.values = (0..n).filter(keep).map(|v| mesh.values[v]).collect();
    mesh.tets
        .par_iter_mut()
        .for_each(|t| *t = t.map(|v| new_id[v as usize]));
    mesh.boundary
        .par_iter_mut()
        .for_each(|t| *t = t.map(|v| new_id[v as usize]));
}
