//! The check after each phase of regions: the boundary surface must stay embedded.
//!
//! The operations keep every tet positive, and the guard ([`super::embed`]) keeps the new
//! boundary triangles of collapses, moves and projections clear of the region's other faces
//! (and those of collapses and moves near their level sets). A mesh whose tets are all
//! positive (locally injective) and whose boundary surface is embedded is globally
//! injective: it covers its domain once. So after the regions of a phase are improved (in
//! parallel, each blind to the others) and before they are written back, every boundary
//! triangle a region changed (new, or with a moved corner) is checked against every other
//! boundary triangle near it, the other regions' as they ended and the untouched ones of the
//! mesh, with exact predicates ([`crate::check::triangles_cross`]); in the rounds, a region's
//! volume is also checked against its start. A region that fails is put back as it was
//! copied out (its start), and the check runs again until every region passes: putting
//! regions back only returns to the boundary the phase started with, which was embedded.
//! The whole-mesh projection takes back its moves the same way
//! ([`moves_breaking_embedding`]).

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::region::{face_key, LocalMesh, Regions, NEW_POINT};
use super::Ctx;
use crate::check::triangles_cross;

type Point = [f64; 3];
use crate::mesh::TetMesh;

/// Side of the buckets (index units) the triangles are sorted into.
const BUCKET: f64 = 1.0;

/// A boundary triangle as the check sees it.
struct Face {
    /// Corners (index space).
    p: [Point; 3],
    /// Corner identities: the global point id, or one past every global id for points a
    /// region added.
    ids: [u64; 3],
    /// The region that changed it (`u32::MAX`: unchanged).
    changed_by: u32,
}

/// Buckets of triangles over index space.
struct Index {
    faces: Vec<Face>,
    buckets: FxHashMap<[i32; 3], Vec<u32>>,
}

/// Whether two faces have the same corners.
fn same_triangle(f: &Face, g: &Face) -> bool {
    let mut a = f.ids;
    let mut b = g.ids;
    a.sort_unstable();
    b.sort_unstable();
    a == b
}

fn bounds(p: &[Point; 3]) -> ([f64; 3], [f64; 3]) {
    let lo = [0, 1, 2].map(|a| p[0][a].min(p[1][a]).min(p[2][a]));
    let hi = [0, 1, 2].map(|a| p[0][a].max(p[1][a]).max(p[2][a]));
    (lo, hi)
}

fn cells(p: &[Point; 3]) -> impl Iterator<Item = [i32; 3]> {
    let (lo, hi) = bounds(p);
    let c = |x: f64| (x / BUCKET).floor().clamp(-1e6, 1e6) as i32;
    let (l, h) = (lo.map(c), hi.map(c));
    (l[2]..=h[2])
        .flat_map(move |z| (l[1]..=h[1]).flat_map(move |y| (l[0]..=h[0]).map(move |x| [x, y, z])))
}

impl Index {
    /// The faces that cross `g` (which need not be in the index; the same triangle, by its
    /// corners, does not count).
    fn crossing(&self, g: &Face) -> Vec<u32> {
        let (lo, hi) = bounds(&g.p);
        let mut seen: Vec<u32> = Vec::new();
        let mut out = Vec::new();
        for c in cells(&g.p) {
            for &j in self.buckets.get(&c).into_iter().flatten() {
                if seen.contains(&j) {
                    continue;
                }
                seen.push(j);
                let f = &self.faces[j as usize];
                let (flo, fhi) = bounds(&f.p);
                if (0..3).any(|a| flo[a] > hi[a] || fhi[a] < lo[a]) || same_triangle(f, g) {
                    continue;
                }
                if triangles_cross([&f.ids, &g.ids], [&f.p, &g.p]) {
                    out.push(j);
                }
            }
        }
        out
    }

    fn new(faces: Vec<Face>) -> Self {
        let mut buckets: FxHashMap<[i32; 3], Vec<u32>> = FxHashMap::default();
        for (i, f) in faces.iter().enumerate() {
            for c in cells(&f.p) {
                buckets.entry(c).or_default().push(i as u32);
            }
        }
        Index { faces, buckets }
    }

    /// Whether face `i` crosses another face of the index.
    fn crosses_another(&self, i: usize) -> bool {
        let f = &self.faces[i];
        let (lo, hi) = bounds(&f.p);
        let mut seen: Vec<u32> = Vec::new();
        for c in cells(&f.p) {
            let Some(list) = self.buckets.get(&c) else {
                continue;
            };
            for &j in list {
                if j as usize == i || seen.contains(&j) {
                    continue;
                }
                seen.push(j);
                let g = &self.faces[j as usize];
                let (glo, ghi) = bounds(&g.p);
                if (0..3).any(|a| glo[a] > hi[a] || ghi[a] < lo[a]) {
                    continue;
                }
                if triangles_cross([&f.ids, &g.ids], [&f.p, &g.p]) {
                    return true;
                }
            }
        }
        false
    }
}

/// The share of its volume a region may change by (the last stage gives the drift back).
/// On a thin interval, boundary faces near their level sets can still enclose a layer
/// several times thicker than the level sets do; a fat region's moves along its level sets
/// change its volume by far less.
pub const REGION_VOLUME_SHARE: f64 = 0.02;

/// Whether region `lm`'s volume is off the volume it was copied out with by more than
/// [`REGION_VOLUME_SHARE`] of it.
fn changed_volume(lm: &LocalMesh) -> bool {
    let now: f64 = (0..lm.tets.len() as u32)
        .filter(|&t| lm.alive[t as usize])
        .map(|t| lm.volume_of(t))
        .sum();
    (now - lm.volume).abs() > REGION_VOLUME_SHARE * lm.volume.abs()
}

/// The identity of region `r`'s vertex `v` ([`Face::ids`]).
fn vertex_id(lm: &LocalMesh, r: usize, v: u32, n_points: usize) -> u64 {
    match lm.global[v as usize] {
        NEW_POINT => n_points as u64 + ((r as u64) << 32) + v as u64,
        g => g as u64,
    }
}

/// Whether face `tri` of region `lm` changed since `start` (a new face, or a moved corner).
fn changed(lm: &LocalMesh, start: &LocalMesh, tri: [u32; 3]) -> bool {
    !start.faces.contains_key(&face_key(tri))
        || tri
            .iter()
            .any(|&v| start.u.get(v as usize) != Some(&lm.u[v as usize]))
}

/// The boundary as the regions leave it: the mesh's faces outside every region, then each
/// region's faces, the changed ones marked.
fn boundary(
    mesh: &TetMesh,
    ctx: &Ctx,
    regions: &[LocalMesh],
    starts: &[LocalMesh],
    bookkeeping: &Regions,
) -> Vec<Face> {
    let n = mesh.points.len();
    let mut faces: Vec<Face> = mesh
        .boundary
        .iter()
        .filter(|tri| bookkeeping.keeps_face(**tri))
        .map(|tri| Face {
            p: tri.map(|v| ctx.field.to_index(mesh.points[v as usize])),
            ids: tri.map(|v| v as u64),
            changed_by: u32::MAX,
        })
        .collect();
    for (r, (lm, start)) in regions.iter().zip(starts).enumerate() {
        let mut own: Vec<_> = lm.faces.values().collect();
        own.sort_unstable_by_key(|f| face_key(f.tri));
        faces.extend(own.into_iter().map(|f| Face {
            p: f.tri.map(|v| lm.u[v as usize]),
            ids: f.tri.map(|v| vertex_id(lm, r, v, n)),
            changed_by: if changed(lm, start, f.tri) {
                r as u32
            } else {
                u32::MAX
            },
        }));
    }
    faces
}

/// Puts back as it started every region whose changed boundary faces cross another boundary
/// face, until none does, and first (with `check_volume`: not in the
/// last stage, whose restoration changes volumes on purpose) every region whose volume
/// changed by more than [`REGION_VOLUME_SHARE`]. `starts[r]` is region `r` as copied out.
/// Returns how many regions were put back.
pub fn keep_embedded(
    mesh: &TetMesh,
    ctx: &Ctx,
    regions: &mut [LocalMesh],
    starts: Vec<LocalMesh>,
    bookkeeping: &Regions,
    check_volume: bool,
) -> usize {
    let mut undone = vec![false; regions.len()];
    let swelled: Vec<bool> = regions
        .iter()
        .map(|lm| check_volume && changed_volume(lm))
        .collect();
    for (r, &bad) in swelled.iter().enumerate() {
        if bad {
            regions[r] = starts[r].clone();
            undone[r] = true;
        }
    }
    loop {
        let index = Index::new(boundary(mesh, ctx, regions, &starts, bookkeeping));
        let mut fails: Vec<u32> = (0..index.faces.len())
            .into_par_iter()
            .filter_map(|i| {
                let f = &index.faces[i];
                if f.changed_by == u32::MAX {
                    return None;
                }
                index.crosses_another(i).then_some(f.changed_by)
            })
            .collect();
        fails.sort_unstable();
        fails.dedup();
        if fails.is_empty() {
            break;
        }
        for r in fails {
            regions[r as usize] = starts[r as usize].clone();
            undone[r as usize] = true;
        }
    }
    undone.iter().filter(|&&u| u).count()
}

/// The moved corners (flagged in `moved`) of the boundary faces of `mesh` that, with every
/// point at `position` (physical), cross another boundary face, among the pairs with a face
/// that has a corner flagged in `changed`: the moves of the whole-mesh projection to take
/// back. Pairs of faces with no corner in `changed` are not looked at: the first call passes
/// every move; after moves are taken back, only the faces around those changed.
pub fn moves_breaking_embedding(
    mesh: &TetMesh,
    ctx: &Ctx,
    position: &[[f64; 3]],
    (moved, changed): (&[bool], &[bool]),
) -> Vec<u32> {
    let face = |tri: &[u32; 3]| Face {
        p: tri.map(|v| ctx.field.to_index(position[v as usize])),
        ids: tri.map(|v| v as u64),
        changed_by: 0,
    };
    // The changed faces in buckets, and every face looked up in them (in parallel).
    let near: Vec<u32> = (0..mesh.boundary.len() as u32)
        .into_par_iter()
        .filter(|&i| {
            mesh.boundary[i as usize]
                .iter()
                .any(|&v| changed[v as usize])
        })
        .collect();
    let index = Index::new(
        near.iter()
            .map(|&i| face(&mesh.boundary[i as usize]))
            .collect(),
    );
    let mut back: Vec<u32> = mesh
        .boundary
        .par_iter()
        .flat_map_iter(|tri| {
            let g = face(tri);
            let crossed = index.crossing(&g);
            let own = (!crossed.is_empty()).then_some(*tri);
            let others = crossed
                .into_iter()
                .map(|j| mesh.boundary[near[j as usize] as usize]);
            own.into_iter().chain(others).flatten()
        })
        .filter(|&v| moved[v as usize])
        .collect();
    back.sort_unstable();
    back.dedup();
    back
}
