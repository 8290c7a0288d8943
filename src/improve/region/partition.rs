//! How the work is cut into regions: slabs along the grid's longest axis, the tets and
//! boundary faces of each region, and the bookkeeping ([`Regions`]) the splice needs.

use rayon::prelude::*;

use super::{LocalMesh, NONE};
use crate::field::Field;
use crate::improve::Ctx;
use crate::mesh::TetMesh;

/// Thickness (in voxels, along the grid's longest axis) of the slabs that split the work into
/// independent regions. Regions of slabs of the same parity are at least a slab apart, so they
/// share no tet and no vertex and are improved in parallel.
pub const SLAB: f64 = 6.0;

/// How the mesh is split into regions, in global terms (what the splice needs).
pub struct Regions {
    /// Region of each tet of the mesh (`NONE` outside every region).
    pub(super) of_tet: Vec<u32>,
    /// Per point: the region whose free vertex it is (`NONE` if frozen or outside).
    pub(super) free_in: Vec<u32>,
}

impl Regions {
    /// Whether the splice keeps mesh tet `t` where it is (it is in no region).
    pub fn keeps_tet(&self, t: usize) -> bool {
        self.of_tet[t] == NONE
    }

    /// Whether the splice keeps boundary face `tri` where it is (no corner is free).
    pub fn keeps_face(&self, tri: [u32; 3]) -> bool {
        tri.iter().all(|&v| self.free_in[v as usize] == NONE)
    }
}

/// The grid's longest axis (the first of equals), along which the work is cut into slabs.
pub fn longest_axis(field: &Field) -> usize {
    let dims = field.grid().dims;
    (0..3).max_by_key(|&a| (dims[a], 3 - a)).unwrap_or(0)
}

/// The slab of each work vertex along the grid's longest axis (`NONE` for the others).
fn slabs(mesh: &TetMesh, work: &[bool], field: &Field, offset: f64) -> Vec<u32> {
    let axis = longest_axis(field);
    (0..mesh.points.len())
        .into_par_iter()
        .map(|v| {
            if !work[v] {
                return NONE;
            }
            let u = field.to_index(mesh.points[v])[axis] + offset;
            (u / SLAB).floor().max(0.0) as u32
        })
        .collect()
}

/// Splits the stars of the work vertices in slabs of parity `phase` into regions, one per
/// slab (empty for a slab without work); `quality` is each tet's [`Ctx::quality`], and
/// `off_level` (if known) whether each point is a level vertex off its level
/// ([`crate::improve::project::off_level_points`]), so that the regions need not evaluate the field at
/// the others again. Returns the regions (region `r` at index `r`) and the global
/// bookkeeping.
pub fn extract_regions(
    mesh: &TetMesh,
    (work, off_level): (&[bool], Option<&[bool]>),
    quality: &[f64],
    ctx: &Ctx,
    phase: u32,
) -> (Vec<LocalMesh>, Regions) {
    extract(mesh, (work, off_level), quality, ctx, phase, false)
}

/// [`extract_regions`]; with `sort`, each region sorts its own points, as when regions
/// overlap (tests compare both ways).
fn extract(
    mesh: &TetMesh,
    (work, off_level): (&[bool], Option<&[bool]>),
    quality: &[f64],
    ctx: &Ctx,
    phase: u32,
    sort: bool,
) -> (Vec<LocalMesh>, Regions) {
    let slab = slabs(mesh, work, &ctx.field, ctx.round.slab_offset);
    let of_tet: Vec<u32> = mesh
        .tets
        .par_iter()
        .map(|t| {
            t.iter()
                .map(|&v| slab[v as usize])
                .filter(|&s| s != NONE && s % 2 == phase)
                .min()
                .map_or(NONE, |s| s / 2)
        })
        .collect();
    let n_regions = of_tet
        .iter()
        .filter(|&&r| r != NONE)
        .max()
        .map_or(0, |&r| r + 1);
    let mut tets_of: Vec<Vec<u32>> = vec![Vec::new(); n_regions as usize];
    let (mut owner, mut shared) = (
        vec![NONE; mesh.points.len()],
        vec![false; mesh.points.len()],
    );
    // Whether a point has tets in two regions (a tet as long as a slab is thick).
    let mut overlap = false;
    for (t, (&r, tet)) in of_tet.iter().zip(&mesh.tets).enumerate() {
        if r != NONE {
            tets_of[r as usize].push(t as u32);
        }
        for &v in tet {
            let o = &mut owner[v as usize];
            if r == NONE || (*o != NONE && *o != r) {
                shared[v as usize] = true;
                overlap |= r != NONE;
            } else {
                *o = r;
            }
        }
    }
    // Pinned points (the rim of a submesh) are frozen like shared ones.
    let pinned = |v: usize| ctx.round.pinned.is_some_and(|p| p[v]);
    let free_in: Vec<u32> = owner
        .iter()
        .zip(&shared)
        .enumerate()
        .map(|(v, (&o, &s))| if s || pinned(v) { NONE } else { o })
        .collect();
    let faces_of = faces_by_region(mesh, &free_in, n_regions as usize);
    let (points_of, local_id) = if overlap || sort {
        (vec![None; n_regions as usize], None)
    } else {
        let (p, l) = points_by_region(&owner, n_regions as usize);
        (p.into_iter().map(Some).collect(), Some(l))
    };
    let copy = Source {
        mesh,
        quality,
        free_in: &free_in,
        local_id: local_id.as_deref(),
        off_level,
    };
    let regions = tets_of
        .into_par_iter()
        .zip(faces_of)
        .zip(points_of)
        .map(|((tets, faces), points)| LocalMesh::from_tets(&copy, &tets, &faces, points, ctx))
        .collect();
    (regions, Regions { of_tet, free_in })
}

/// The points of each region in ascending order (`owner`: the region of each point, which
/// is one at most), and each point's place in its region's list.
fn points_by_region(owner: &[u32], n_regions: usize) -> (Vec<Vec<u32>>, Vec<u32>) {
    let mut points_of: Vec<Vec<u32>> = vec![Vec::new(); n_regions];
    let local_id = owner
        .iter()
        .enumerate()
        .map(|(v, &r)| {
            if r == NONE {
                return NONE;
            }
            let list = &mut points_of[r as usize];
            list.push(v as u32);
            list.len() as u32 - 1
        })
        .collect();
    (points_of, local_id)
}

/// Indices of the boundary faces of each region, in mesh order: a face with a free vertex
/// lies in a tet of that vertex's region (all free vertices of a face are in one region).
fn faces_by_region(mesh: &TetMesh, free_in: &[u32], n_regions: usize) -> Vec<Vec<u32>> {
    let mut faces_of: Vec<Vec<u32>> = vec![Vec::new(); n_regions];
    for (i, tri) in mesh.boundary.iter().enumerate() {
        if let Some(r) = tri
            .iter()
            .map(|&v| free_in[v as usize])
            .find(|&r| r != NONE)
        {
            faces_of[r as usize].push(i as u32);
        }
    }
    faces_of
}

/// What the regions of one phase are copied from.
pub(super) struct Source<'a> {
    pub(super) mesh: &'a TetMesh,
    /// Per tet: its quality.
    pub(super) quality: &'a [f64],
    /// Per point: the region whose free vertex it is (`NONE` if frozen or outside).
    pub(super) free_in: &'a [u32],
    /// Per point: whether it is a level vertex off its level (`None`: not known).
    pub(super) off_level: Option<&'a [bool]>,
    /// Per point: its local id in the one region that uses it ([`points_by_region`]); `None`
    /// when the regions sort their own points.
    pub(super) local_id: Option<&'a [u32]>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::{wavy_torus, wavy_torus_mesh};
    use crate::improve::quality_cache::tet_qualities;
    use crate::improve::region::face_key;
    use crate::mesh::BoundaryLabel;

    fn faces_sorted(lm: &LocalMesh) -> Vec<([u32; 3], BoundaryLabel)> {
        let mut f: Vec<_> = lm.faces.values().map(|f| (f.tri, f.label)).collect();
        f.sort_unstable_by_key(|x| face_key(x.0));
        f
    }

    /// The regions found from the points' owners (one ascending scan) equal those whose
    /// points are sorted per region (the path taken when regions overlap).
    #[test]
    fn owner_scan_and_sorting_give_the_same_regions() {
        let grid = wavy_torus();
        let (mesh, ctx) = wavy_torus_mesh(&grid);
        let quality = tet_qualities(&mesh, &ctx);
        let mesh_tets: std::collections::HashSet<[u32; 4]> = mesh.tets.iter().copied().collect();
        // Every third point needs work: regions with frozen points and holes.
        let work: Vec<bool> = (0..mesh.points.len()).map(|v| v % 3 == 0).collect();
        for phase in 0..2 {
            let (fast, _) = extract(&mesh, (&work, None), &quality, &ctx, phase, false);
            let (sorted, _) = extract(&mesh, (&work, None), &quality, &ctx, phase, true);
            assert_eq!(fast.len(), sorted.len());
            assert!(fast.iter().map(|lm| lm.tets.len()).sum::<usize>() > 100);
            for (a, b) in fast.iter().zip(&sorted) {
                assert_eq!(a.global, b.global);
                assert_eq!(a.tets, b.tets);
                assert_eq!(a.q, b.q);
                assert_eq!(a.frozen, b.frozen);
                assert_eq!(faces_sorted(a), faces_sorted(b));
                // Local ids name the mesh's tets.
                for t in &a.tets {
                    assert!(mesh_tets.contains(&t.map(|v| a.global[v as usize])));
                }
            }
        }
    }
}
