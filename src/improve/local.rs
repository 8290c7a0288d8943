//! The part of a mesh the quality pass works on: the stars of the vertices that need work,
//! copied out with their own numbering, tet stars and boundary faces, and spliced back.
//!
//! A vertex of the region is *frozen* when some tet outside the region uses it: its star is
//! incomplete, so it neither moves nor is merged; every vertex that needs work has its whole
//! star in the region and is free.

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::constraint::Constraint;
use super::field::Field;
use super::Ctx;
use crate::improve::quality::biased_min_sine;
use crate::mesh::{BoundaryLabel, TetMesh};

/// A boundary face of the region: its outward orientation and label.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoundaryFace {
    /// The face, outward-oriented.
    pub tri: [u32; 3],
    /// The surface it lies on.
    pub label: BoundaryLabel,
}

/// The working region with local vertex numbers.
pub struct LocalMesh {
    /// Global id of each local vertex (sorted ascending).
    pub global: Vec<u32>,
    /// Index-space position of each vertex.
    pub u: Vec<[f64; 3]>,
    /// Physical position of each vertex.
    pub x: Vec<[f64; 3]>,
    /// Field value carried by each vertex.
    pub value: Vec<f64>,
    /// Allowed motion of each vertex.
    pub con: Vec<Constraint>,
    /// Vertex used by a tet outside the region.
    pub frozen: Vec<bool>,
    /// Vertex merged away by a collapse.
    pub removed: Vec<bool>,
    /// Tets over local vertex ids, positively oriented; dead ones have `alive == false`.
    pub tets: Vec<[u32; 4]>,
    /// Whether each tet is still part of the mesh.
    pub alive: Vec<bool>,
    /// Alive tets around each vertex.
    pub star: Vec<Vec<u32>>,
    /// Quality of each tet ([`Ctx::quality`], kept up to date).
    pub q: Vec<f64>,
    /// Weight of obtuse angles in the quality.
    weight: f64,
    /// Domain-boundary faces of the region, keyed by their sorted vertex ids.
    pub faces: FxHashMap<[u32; 3], BoundaryFace>,
}

/// Sorted copy of a triangle, the key of [`LocalMesh::faces`].
#[inline]
pub fn face_key(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// What the splice needs to know about the region in global terms.
pub struct Region {
    /// Tets of the mesh that belong to the region.
    in_region: Vec<bool>,
    /// Local id of every global vertex in the region (`u32::MAX` outside).
    local_of: Vec<u32>,
}

impl LocalMesh {
    /// Copies out the stars of the vertices flagged in `work` (one flag per mesh point).
    pub fn extract(mesh: &TetMesh, work: &[bool], ctx: &Ctx) -> (Self, Region) {
        let (field, levels) = (&ctx.field, ctx.levels);
        let in_region: Vec<bool> = mesh
            .tets
            .par_iter()
            .map(|t| t.iter().any(|&v| work[v as usize]))
            .collect();
        let n = mesh.points.len();
        let (used, outside) = vertex_marks(mesh, &in_region, n);
        let mut local_of = vec![u32::MAX; n];
        let mut global = Vec::new();
        for (v, &u) in used.iter().enumerate() {
            if u {
                local_of[v] = global.len() as u32;
                global.push(v as u32);
            }
        }
        let mut lm = LocalMesh::with_vertices(mesh, global, &outside, field);
        lm.weight = ctx.obtuse_weight;
        for (t, tet) in mesh.tets.iter().enumerate() {
            if in_region[t] {
                lm.add_tet(tet.map(|v| local_of[v as usize]));
            }
        }
        lm.collect_faces(mesh, &local_of);
        lm.classify(field, levels);
        (
            lm,
            Region {
                in_region,
                local_of,
            },
        )
    }

    fn with_vertices(mesh: &TetMesh, global: Vec<u32>, outside: &[bool], field: &Field) -> Self {
        let x: Vec<[f64; 3]> = global.iter().map(|&g| mesh.points[g as usize]).collect();
        let n = global.len();
        LocalMesh {
            u: x.iter().map(|&p| field.to_index(p)).collect(),
            value: global.iter().map(|&g| mesh.values[g as usize]).collect(),
            frozen: global.iter().map(|&g| outside[g as usize]).collect(),
            con: vec![Constraint::default(); n],
            removed: vec![false; n],
            star: vec![Vec::new(); n],
            x,
            global,
            tets: Vec::new(),
            alive: Vec::new(),
            q: Vec::new(),
            weight: 1.0,
            faces: FxHashMap::default(),
        }
    }

    /// The boundary faces with at least one free vertex (the others stay in the mesh as
    /// they are: no operation touches them).
    fn collect_faces(&mut self, mesh: &TetMesh, local_of: &[u32]) {
        for (t, tri) in mesh.boundary.iter().enumerate() {
            let l = tri.map(|v| local_of[v as usize]);
            if l.iter().any(|&v| v != u32::MAX && !self.frozen[v as usize]) {
                let label = mesh.boundary_labels[t];
                self.faces
                    .insert(face_key(l), BoundaryFace { tri: l, label });
            }
        }
    }

    /// Sets the constraints of the free vertices from their boundary faces and box planes,
    /// snapping box coordinates exactly onto their plane. Frozen vertices are pinned.
    fn classify(&mut self, field: &Field, levels: [f64; 2]) {
        let mut labels = vec![0u8; self.global.len()];
        for f in self.faces.values() {
            for v in f.tri {
                labels[v as usize] |= 1 << (f.label as u8);
            }
        }
        let dims = field.grid().dims;
        for v in 0..self.global.len() {
            if self.frozen[v] {
                self.con[v].pinned = true;
                continue;
            }
            let mut c = Constraint::classify(labels[v], &mut self.u[v], dims);
            // A level vertex must carry its level's value exactly (the clipper's cuts do).
            if c.level.is_some_and(|l| self.value[v] != levels[l as usize]) {
                c.pinned = true;
            }
            self.con[v] = c;
        }
    }

    /// Appends tet `t` (local ids) and returns its id.
    pub fn add_tet(&mut self, t: [u32; 4]) -> u32 {
        let id = self.tets.len() as u32;
        self.tets.push(t);
        self.alive.push(true);
        self.q.push(biased_min_sine(self.corners(t), self.weight));
        for v in t {
            self.star[v as usize].push(id);
        }
        id
    }

    /// Removes tet `id` from the mesh and from its vertices' stars.
    pub fn kill_tet(&mut self, id: u32) {
        self.alive[id as usize] = false;
        for v in self.tets[id as usize] {
            let s = &mut self.star[v as usize];
            if let Some(i) = s.iter().position(|&t| t == id) {
                s.swap_remove(i);
            }
        }
    }

    /// Corner positions of tet `t`.
    #[inline]
    pub fn corners(&self, t: [u32; 4]) -> [[f64; 3]; 4] {
        t.map(|v| self.x[v as usize])
    }

    /// Recomputes the quality of the tets around `v` (after `v` moved).
    pub fn update_star_quality(&mut self, v: u32) {
        for i in 0..self.star[v as usize].len() {
            let t = self.star[v as usize][i] as usize;
            self.q[t] = biased_min_sine(self.corners(self.tets[t]), self.weight);
        }
    }

    /// Recomputes the quality of tet `t` (after its corners changed).
    pub fn update_quality(&mut self, t: u32) {
        let t = t as usize;
        self.q[t] = biased_min_sine(self.corners(self.tets[t]), self.weight);
    }

    /// Whether `v` may be moved or merged.
    #[inline]
    pub fn is_free(&self, v: u32) -> bool {
        !self.frozen[v as usize] && !self.removed[v as usize]
    }

    /// Writes the region back into `mesh`: moved points, the region's tets (after the tets
    /// outside it, which keep their order) and boundary faces; merged points are dropped and
    /// the points renumbered in order.
    pub fn splice(self, mesh: &mut TetMesh, region: Region) {
        for (l, &g) in self.global.iter().enumerate() {
            if !self.frozen[l] {
                mesh.points[g as usize] = self.x[l];
                mesh.values[g as usize] = self.value[l];
            }
        }
        let to_global = |t: &[u32]| {
            t.iter()
                .map(|&v| self.global[v as usize])
                .collect::<Vec<_>>()
        };
        let mut tets: Vec<[u32; 4]> = mesh
            .tets
            .iter()
            .zip(&region.in_region)
            .filter(|(_, &r)| !r)
            .map(|(t, _)| *t)
            .collect();
        for (t, &a) in self.tets.iter().zip(&self.alive) {
            if a {
                let g = to_global(t);
                tets.push([g[0], g[1], g[2], g[3]]);
            }
        }
        let keep_face = |tri: &[u32; 3]| {
            !tri.iter().any(|&v| {
                let l = region.local_of[v as usize];
                l != u32::MAX && !self.frozen[l as usize]
            })
        };
        let mut boundary = Vec::with_capacity(mesh.boundary.len());
        let mut labels = Vec::with_capacity(mesh.boundary.len());
        for (tri, &label) in mesh.boundary.iter().zip(&mesh.boundary_labels) {
            if keep_face(tri) {
                boundary.push(*tri);
                labels.push(label);
            }
        }
        let mut local_faces: Vec<&BoundaryFace> = self.faces.values().collect();
        local_faces.sort_unstable_by_key(|f| face_key(f.tri));
        for f in local_faces {
            let g = to_global(&f.tri);
            boundary.push([g[0], g[1], g[2]]);
            labels.push(f.label);
        }
        mesh.tets = tets;
        mesh.boundary = boundary;
        mesh.boundary_labels = labels;
        let removed: Vec<u32> = (0..self.global.len())
            .filter(|&l| self.removed[l])
            .map(|l| self.global[l])
            .collect();
        drop_points(mesh, &removed);
    }
}

/// Per point: used by a region tet; used by a tet outside the region.
fn vertex_marks(mesh: &TetMesh, in_region: &[bool], n: usize) -> (Vec<bool>, Vec<bool>) {
    let mut used = vec![false; n];
    let mut outside = vec![false; n];
    for (t, &r) in mesh.tets.iter().zip(in_region) {
        let m = if r { &mut used } else { &mut outside };
        for &v in t {
            m[v as usize] = true;
        }
    }
    (used, outside)
}

/// Removes the points `removed` (sorted ascending, used by no tet) and renumbers the rest.
fn drop_points(mesh: &mut TetMesh, removed: &[u32]) {
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
