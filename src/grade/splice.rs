//! Puts the blocks into the mesh: the fine tets inside them out, the cones in, and the
//! points no tet uses any more dropped, every index renumbered in order.

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::blocks::block_face_triangles;
use super::octree::{Block, Leaves};
use crate::field::Field;
use crate::geom::signed_volume;
use crate::grid::ScalarGrid;
use crate::mesh::TetMesh;

/// No block: the tet is kept.
const KEPT: u32 = u32::MAX;

/// Index-space positions of a mesh's points (the inverse of the grid's placement, as the
/// interpolant computes it).
pub struct IndexSpace<'a> {
    field: Field<'a>,
}

/// How far from a grid vertex (in cells) a point may lie and still be taken for it: the
/// mesher places grid vertices exactly, up to the rounding of the placement.
const ON_VERTEX: f64 = 1e-6;

impl<'a> IndexSpace<'a> {
    /// `None` when the grid's placement is singular.
    pub fn new(grid: &'a ScalarGrid) -> Option<Self> {
        let field = Field::new(grid);
        field
            .inverse_matrix()
            .iter()
            .all(|x| x.is_finite())
            .then_some(IndexSpace { field })
    }

    /// The index-space position of physical point `p`.
    pub fn of(&self, p: [f64; 3]) -> [f64; 3] {
        self.field.to_index(p)
    }

    /// The grid vertex at physical point `p`, if it is one.
    pub fn vertex(&self, p: [f64; 3]) -> Option<[usize; 3]> {
        let q = self.of(p);
        q.iter()
            .all(|&x| x > -0.5 && (x - x.round()).abs() < ON_VERTEX)
            .then(|| q.map(|x| x.round() as usize))
    }
}

/// For each tet, the number of the block whose cell holds its centroid, or [`KEPT`].
fn owners(
    mesh: &TetMesh,
    leaves: &Leaves,
    index: &IndexSpace<'_>,
    number: &FxHashMap<[usize; 3], u32>,
) -> Vec<u32> {
    mesh.tets
        .par_iter()
        .map(|t| {
            let mut c = [0.0; 3];
            for &v in t {
                let p = index.of(mesh.points[v as usize]);
                (0..3).for_each(|a| c[a] += p[a] / 4.0);
            }
            let cell = c.map(|x| x.floor() as i64);
            match leaves.level_at_signed(cell) {
                Some(l) if l > 0 => {
                    let s = 1i64 << l;
                    let origin = cell.map(|x| (x & !(s - 1)) as usize);
                    number[&origin]
                }
                _ => KEPT,
            }
        })
        .collect()
}

/// The mesh point at each grid vertex (dense over the grid; `u32::MAX`: none).
struct GridVertices {
    dims: [usize; 3],
    point: Vec<u32>,
}

impl GridVertices {
    fn of(mesh: &TetMesh, index: &IndexSpace<'_>, dims: [usize; 3]) -> Self {
        let at: Vec<Option<usize>> = mesh
            .points
            .par_iter()
            .map(|&p| {
                let g = index.vertex(p)?;
                (g[0] < dims[0] && g[1] < dims[1] && g[2] < dims[2])
                    .then(|| g[0] + dims[0] * (g[1] + dims[1] * g[2]))
            })
            .collect();
        let mut point = vec![u32::MAX; dims[0] * dims[1] * dims[2]];
        for (v, g) in at.into_iter().enumerate() {
            if let Some(g) = g {
                point[g] = v as u32;
            }
        }
        GridVertices { dims, point }
    }

    fn get(&self, g: &[usize; 3]) -> Option<&u32> {
        let d = self.dims;
        let p = self.point.get(g[0] + d[0] * (g[1] + d[1] * g[2]))?;
        (*p != u32::MAX).then_some(p)
    }
}

/// What [`splice`] did.
pub struct Spliced {
    /// Fine tets taken out.
    pub removed: usize,
    /// Block tets put in.
    pub added: usize,
    /// Volume of the tets taken out and of those put in (equal up to rounding).
    pub volumes: (f64, f64),
}

/// Replaces the fine tets inside `blocks` with the blocks' cones. `None` (mesh unchanged)
/// when a block's vertex is not a point of the mesh, which the mesher's interior cells rule
/// out.
pub fn splice(
    mesh: &mut TetMesh,
    leaves: &Leaves,
    blocks: &[Block],
    index: &IndexSpace<'_>,
) -> Option<Spliced> {
    let number: FxHashMap<[usize; 3], u32> = blocks
        .iter()
        .enumerate()
        .map(|(i, b)| (b.origin, i as u32))
        .collect();
    let owner = owners(mesh, leaves, index, &number);
    // The removed tets of each block, in tet order.
    let mut of_block: Vec<Vec<u32>> = vec![Vec::new(); blocks.len()];
    for (t, &o) in owner.iter().enumerate() {
        if o != KEPT {
            of_block[o as usize].push(t as u32);
        }
    }
    let vertex = GridVertices::of(mesh, index, leaves.dims.map(|d| d + 1));
    let cones: Option<Vec<Vec<[u32; 4]>>> = blocks
        .par_iter()
        .zip(&of_block)
        .map(|(&b, tets)| block_cones(mesh, leaves, b, tets, (&vertex, index)))
        .collect();
    let cones = cones?;
    let volume = |t: &[u32; 4]| {
        let p = t.map(|v| mesh.points[v as usize]);
        signed_volume(p[0], p[1], p[2], p[3])
    };
    let removed_volume: f64 = of_block
        .iter()
        .flatten()
        .map(|&t| volume(&mesh.tets[t as usize]))
        .sum();
    let added_volume: f64 = cones.iter().flatten().map(volume).sum();
    let region_of_block: Vec<Option<u8>> = of_block
        .iter()
        .map(|tets| {
            let t = *tets.first()? as usize;
            mesh.regions.tets.get(t).copied()
        })
        .collect();
    let removed = owner.iter().filter(|&&o| o != KEPT).count();
    let added = cones.iter().map(Vec::len).sum();
    rebuild(mesh, &owner, &cones, &region_of_block);
    Some(Spliced {
        removed,
        added,
        volumes: (removed_volume, added_volume),
    })
}

/// The cone of block `b` from its centre over its faces: those bordering other blocks
/// ([`block_face_triangles`]) and those bordering fine cells (the faces of its fine `tets`
/// on its boundary with a fine cell across).
fn block_cones(
    mesh: &TetMesh,
    leaves: &Leaves,
    b: Block,
    tets: &[u32],
    (vertex, index): (&GridVertices, &IndexSpace<'_>),
) -> Option<Vec<[u32; 4]>> {
    let h = b.side() / 2;
    let centre = *vertex.get(&b.origin.map(|x| x + h))?;
    let mut tris: Vec<[u32; 3]> = Vec::new();
    for t in block_face_triangles(leaves, b) {
        tris.push([
            *vertex.get(&t[0])?,
            *vertex.get(&t[1])?,
            *vertex.get(&t[2])?,
        ]);
    }
    if b.level == 1 {
        for &t in tets {
            fine_faces(mesh, leaves, b, mesh.tets[t as usize], index, &mut tris);
        }
    }
    let mut out = Vec::with_capacity(tris.len());
    for [a, bb, c] in tris {
        let p = |v: u32| mesh.points[v as usize];
        let t = if signed_volume(p(centre), p(a), p(bb), p(c)) > 0.0 {
            [centre, a, bb, c]
        } else {
            [centre, bb, a, c]
        };
        out.push(t);
    }
    Some(out)
}

/// The faces of the fine tet `t` of block `b` that lie on the block's boundary with a fine
/// cell across.
fn fine_faces(
    mesh: &TetMesh,
    leaves: &Leaves,
    b: Block,
    t: [u32; 4],
    index: &IndexSpace<'_>,
    out: &mut Vec<[u32; 3]>,
) {
    let q = t.map(|v| index.of(mesh.points[v as usize]));
    let s = b.side() as f64;
    for skip in 0..4 {
        let f: Vec<usize> = (0..4).filter(|&i| i != skip).collect();
        for axis in 0..3 {
            for high in [false, true] {
                let plane = b.origin[axis] as f64 + if high { s } else { 0.0 };
                if f.iter().all(|&i| (q[i][axis] - plane).abs() < ON_VERTEX) {
                    let mut across = b.origin.map(|x| x as i64);
                    across[axis] = if high { plane as i64 } else { plane as i64 - 1 };
                    // the cell across this face, next to the face's centroid
                    for a in (0..3).filter(|&a| a != axis) {
                        let m = f.iter().map(|&i| q[i][a]).sum::<f64>() / 3.0;
                        across[a] = m.floor() as i64;
                    }
                    if leaves.level_at_signed(across) == Some(0) {
                        out.push([t[f[0]], t[f[1]], t[f[2]]]);
                    }
                }
            }
        }
    }
}

/// The mesh with the owned tets replaced by `cones` (after the kept tets, block by block),
/// its points renumbered in order without the unused ones.
fn rebuild(mesh: &mut TetMesh, owner: &[u32], cones: &[Vec<[u32; 4]>], region: &[Option<u8>]) {
    let has_regions = !mesh.regions.tets.is_empty();
    let mut tets = Vec::with_capacity(owner.len());
    let mut regions = Vec::new();
    for (t, &o) in owner.iter().enumerate() {
        if o == KEPT {
            tets.push(mesh.tets[t]);
            if has_regions {
                regions.push(mesh.regions.tets[t]);
            }
        }
    }
    for (b, c) in cones.iter().enumerate() {
        tets.extend_from_slice(c);
        if has_regions {
            regions.extend(std::iter::repeat_n(region[b].unwrap_or(0), c.len()));
        }
    }
    let mut new_id = vec![u32::MAX; mesh.points.len()];
    for t in &tets {
        for &v in t {
            new_id[v as usize] = 0;
        }
    }
    let mut next = 0u32;
    let mut points = Vec::new();
    let mut values = Vec::new();
    for (v, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = next;
            next += 1;
            points.push(mesh.points[v]);
            values.push(mesh.values[v]);
        }
    }
    let map = |v: &mut u32| *v = new_id[*v as usize];
    tets.iter_mut().for_each(|t| t.iter_mut().for_each(map));
    mesh.boundary
        .iter_mut()
        .for_each(|t| t.iter_mut().for_each(map));
    mesh.regions
        .interfaces
        .iter_mut()
        .for_each(|t| t.iter_mut().for_each(map));
    mesh.tets = tets;
    mesh.points = points;
    mesh.values = values;
    if has_regions {
        mesh.regions.tets = regions;
    }
}
