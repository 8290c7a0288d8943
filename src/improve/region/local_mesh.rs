//! A region as the operations see it ([`LocalMesh`]): its vertices, tets, stars and
//! boundary faces in local numbering, with the qualities, memos and drift kept up to date.

use std::cell::Cell;

use rustc_hash::FxHashMap;

use super::partition::Source;
use super::{face_key, tet_edge, EdgeTets, NEW_POINT, NONE};
use crate::field::Field;
use crate::improve::constraint::{interface_bits, Constraint};
use crate::improve::face_grid::FaceGrid;
use crate::improve::Ctx;
use crate::levels::Levels;
use crate::mesh::{BoundaryLabel, TetMesh};
use crate::quality::biased_min_sine;

/// A boundary face of the region: its outward orientation and label.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoundaryFace {
    /// The face, outward-oriented.
    pub tri: [u32; 3],
    /// The surface it lies on.
    pub label: BoundaryLabel,
}

/// The working region with local vertex numbers.
#[derive(Clone)]
pub struct LocalMesh {
    /// Global id of each local vertex (sorted ascending), then [`NEW_POINT`] for each vertex
    /// added in the region (given an id when it is spliced back).
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
    /// The region of each tet (0 for one interval): operations replace tets only by tets of
    /// the same region.
    pub region: Vec<u8>,
    /// Alive tets around each vertex.
    pub star: Vec<Vec<u32>>,
    /// Quality of each tet ([`Ctx::quality`], kept up to date).
    pub q: Vec<f64>,
    /// Weight of obtuse angles in the quality.
    weight: f64,
    /// Domain-boundary faces of the region, keyed by their sorted vertex ids (change them
    /// through [`LocalMesh::insert_face`] and [`LocalMesh::remove_face`]).
    pub faces: FxHashMap<[u32; 3], BoundaryFace>,
    /// Per vertex: how many of `faces` it is a corner of.
    face_count: Vec<u32>,
    /// `faces` in buckets over index space, as their corners are now.
    pub face_grid: FaceGrid,
    /// Memo of failed attempts (see [`LocalMesh::settled_tet`]).
    memo: Memo,
    /// The tets whose quality was set below `low_bar` since the list was last compacted (with
    /// repeats, and some since removed or improved): a superset of the alive tets below it,
    /// so that finding those ([`LocalMesh::tets_below`]) takes time in their number.
    low: Vec<u32>,
    /// The quality `low` is kept for (the target; `-inf`: none is kept).
    low_bar: f64,
    /// Volume of the region's tets when it was copied out.
    pub volume: f64,
    /// With several regions (empty for one interval), per region tag: the volume of the
    /// copy's tets of that region when it was copied out, and the volume the merges and
    /// moves of level vertices have added to it since ([`LocalMesh::book_volume`]).
    pub tag_volumes: Vec<[f64; 2]>,
    /// Per vertex: the signed volume that the collapses into it and its moves have added
    /// (physical units; projections onto the level sets are corrections and do not count); for
    /// a vertex on an interface, to the region below it ([`LocalMesh::counted_region`]).
    /// The pass gives it back at the end where it can ([`crate::improve::restore`]).
    pub drift: Vec<f64>,
    /// Per vertex: found within the tolerance of its level set since it last moved (so the
    /// projections need not evaluate the field there again).
    on_level: Vec<bool>,
    /// Per vertex: the tet of its star that last stopped a collapse from it (`NONE`: none
    /// yet). The next collapse test from it looks at that tet first: the test asks whether
    /// every changed tet stays above a floor, which any order of the tets answers the same.
    collapse_hint: Vec<Cell<u32>>,
}

/// When the neighbourhoods changed and when operations on them last failed, on one clock.
/// An operation on a tet reads only the stars of its corners and the tets that share a face
/// with it, and every change to a tet stamps its corners (a tet sharing a face with `t` has
/// three of `t`'s corners, so changing it or moving its fourth corner stamps them too); so an
/// attempt on a tet that failed after its corners' last stamps would fail again, and is
/// skipped (the same result, without the work).
#[derive(Clone, Default)]
struct Memo {
    clock: u64,
    /// Per vertex: the last change to a tet around it.
    stamp: Vec<u64>,
    /// Per tet and [`TetOp`]: when that operation on it last failed (0: never).
    tet_failed: Vec<[u64; 2]>,
    /// Per vertex: when smoothing it last failed (0: never).
    vertex_failed: Vec<u64>,
}

/// The operations on a tet whose failures are memoised separately.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TetOp {
    /// Collapsing one of its edges.
    Collapse = 0,
    /// A 2-3 flip of one of its faces or a 3-2 flip of one of its edges.
    Flip = 1,
}

impl LocalMesh {
    /// The region made of the mesh tets `tets` and the boundary faces `faces` (indices into
    /// `mesh.boundary`: those with a free vertex of this region), whose points are `points`
    /// (ascending, with [`Source::local_id`]; `None`: found here).
    pub(super) fn from_tets(
        copy: &Source,
        tets: &[u32],
        faces: &[u32],
        points: Option<Vec<u32>>,
        ctx: &Ctx,
    ) -> Self {
        let mesh = copy.mesh;
        let global = points.unwrap_or_else(|| {
            let mut all: Vec<u32> = tets.iter().flat_map(|&t| mesh.tets[t as usize]).collect();
            all.sort_unstable();
            all.dedup();
            all
        });
        let local = |g: u32| match copy.local_id {
            Some(ids) => ids[g as usize],
            None => global.binary_search(&g).map_or(NONE, |i| i as u32),
        };
        let local_tets: Vec<[u32; 4]> = tets
            .iter()
            .map(|&t| mesh.tets[t as usize].map(local))
            .collect();
        let faces: Vec<BoundaryFace> = faces
            .iter()
            .map(|&i| BoundaryFace {
                tri: mesh.boundary[i as usize].map(local),
                label: mesh.boundary_labels[i as usize],
            })
            .collect();
        let frozen: Vec<bool> = global
            .iter()
            .map(|&g| copy.free_in[g as usize] == NONE)
            .collect();
        let mut lm = LocalMesh::with_vertices(mesh, global, frozen, &ctx.field);
        lm.weight = ctx.obtuse_weight;
        lm.low_bar = ctx.target;
        lm.reserve_tets(&local_tets);
        for (t, &g) in local_tets.into_iter().zip(tets) {
            let region = mesh.regions.tets.get(g as usize).copied().unwrap_or(0);
            lm.push_tet(t, copy.quality[g as usize], region);
        }
        // Sized once (the map's order is never used: it is read in key order or summed).
        lm.faces.reserve(faces.len());
        for f in faces {
            lm.insert_face(f);
        }
        lm.classify(&ctx.field, &ctx.levels);
        if let Some(off) = copy.off_level {
            lm.seed_on_level(off, &ctx.field);
        }
        lm.volume = (0..lm.tets.len() as u32).map(|t| lm.volume_of(t)).sum();
        if ctx.levels.len() > 2 {
            lm.tag_volumes = vec![[0.0; 2]; ctx.levels.len() - 1];
            for t in 0..lm.tets.len() as u32 {
                lm.tag_volumes[lm.region[t as usize] as usize][0] += lm.volume_of(t);
            }
        }
        lm
    }

    fn with_vertices(mesh: &TetMesh, global: Vec<u32>, frozen: Vec<bool>, field: &Field) -> Self {
        let x: Vec<[f64; 3]> = global.iter().map(|&g| mesh.points[g as usize]).collect();
        let n = global.len();
        LocalMesh {
            u: x.iter().map(|&p| field.to_index(p)).collect(),
            value: global.iter().map(|&g| mesh.values[g as usize]).collect(),
            frozen,
            con: vec![Constraint::default(); n],
            removed: vec![false; n],
            star: vec![Vec::new(); n],
            x,
            global,
            tets: Vec::new(),
            alive: Vec::new(),
            region: Vec::new(),
            q: Vec::new(),
            weight: 1.0,
            faces: FxHashMap::default(),
            face_count: vec![0; n],
            face_grid: FaceGrid::default(),
            volume: 0.0,
            tag_volumes: Vec::new(),
            drift: vec![0.0; n],
            on_level: vec![false; n],
            collapse_hint: vec![Cell::new(NONE); n],
            low: Vec::new(),
            low_bar: f64::NEG_INFINITY,
            memo: Memo {
                clock: 1,
                stamp: vec![1; n],
                tet_failed: Vec::new(),
                vertex_failed: vec![0; n],
            },
        }
    }

    /// Makes room for `tets` (and the stars of their corners) at once, so that adding them
    /// reallocates nothing.
    fn reserve_tets(&mut self, tets: &[[u32; 4]]) {
        let mut size = vec![0u32; self.star.len()];
        for t in tets {
            for &v in t {
                size[v as usize] += 1;
            }
        }
        for (star, &n) in self.star.iter_mut().zip(&size) {
            star.reserve_exact(n as usize);
        }
        self.tets.reserve(tets.len());
        self.alive.reserve(tets.len());
        self.region.reserve(tets.len());
        self.q.reserve(tets.len());
        self.memo.tet_failed.reserve(tets.len());
    }

    /// Adds boundary face `f`.
    pub fn insert_face(&mut self, f: BoundaryFace) {
        for v in f.tri {
            self.face_count[v as usize] += 1;
        }
        self.face_grid
            .put(face_key(f.tri), f.tri.map(|v| self.u[v as usize]));
        if let Some(old) = self.faces.insert(face_key(f.tri), f) {
            for v in old.tri {
                self.face_count[v as usize] -= 1;
            }
        }
    }

    /// Removes the boundary face with the corners of `tri` (any order), if there is one.
    pub fn remove_face(&mut self, tri: [u32; 3]) {
        if let Some(f) = self.faces.remove(&face_key(tri)) {
            for v in f.tri {
                self.face_count[v as usize] -= 1;
            }
            self.face_grid.remove(face_key(tri));
        }
    }

    /// Whether `v` is a corner of a boundary face.
    #[inline]
    pub fn on_boundary(&self, v: u32) -> bool {
        self.face_count[v as usize] > 0
    }

    /// Alive tets containing both `a` and `b`, in the order of `a`'s star. When either is free,
    /// these are all the tets around the edge: a free vertex's whole star is in the region.
    pub fn edge_tets(&self, a: u32, b: u32) -> EdgeTets {
        self.star[a as usize]
            .iter()
            .copied()
            .filter(|&t| self.tets[t as usize].contains(&b))
            .collect()
    }

    /// [`LocalMesh::edge_tets`] of each edge `(tet[i], tet[j])`, `i < j`, of `tet` (a tet of
    /// the region), in the order `(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)`: one scan of
    /// the stars of the first three corners instead of one per edge.
    pub fn tet_edge_tets(&self, tet: [u32; 4]) -> [EdgeTets; 6] {
        let mut out: [EdgeTets; 6] = Default::default();
        for i in 0..3 {
            for &t in &self.star[tet[i] as usize] {
                let other = self.tets[t as usize];
                for j in i + 1..4 {
                    if other.contains(&tet[j]) {
                        out[tet_edge(i, j)].push(t);
                    }
                }
            }
        }
        out
    }

    /// How many domain-boundary faces `v` is a corner of.
    #[inline]
    pub fn boundary_faces_of(&self, v: u32) -> usize {
        self.face_count[v as usize] as usize
    }

    /// Records a change to tet `t` (created, removed, or a corner moved).
    #[inline]
    fn touch(&mut self, t: u32) {
        self.memo.clock += 1;
        for v in self.tets[t as usize] {
            self.memo.stamp[v as usize] = self.memo.clock;
        }
    }

    /// Whether operation `op` on tet `t` failed after the last change around its corners.
    pub fn settled_tet(&self, t: u32, op: TetOp) -> bool {
        let failed = self.memo.tet_failed[t as usize][op as usize];
        failed != 0
            && self.tets[t as usize]
                .iter()
                .all(|&v| self.memo.stamp[v as usize] <= failed)
    }

    /// Records that operation `op` on tet `t` changed nothing.
    pub fn tet_failed(&mut self, t: u32, op: TetOp) {
        self.memo.tet_failed[t as usize][op as usize] = self.memo.clock;
    }

    /// Whether smoothing `v` failed after the last change around it.
    pub fn settled_vertex(&self, v: u32) -> bool {
        let failed = self.memo.vertex_failed[v as usize];
        failed != 0 && self.memo.stamp[v as usize] <= failed
    }

    /// Records that smoothing `v` changed nothing.
    pub fn vertex_failed(&mut self, v: u32) {
        self.memo.vertex_failed[v as usize] = self.memo.clock;
    }

    /// Sets the constraints of the free vertices from their boundary faces and box planes,
    /// snapping box coordinates exactly onto their plane. Frozen vertices are pinned.
    fn classify(&mut self, field: &Field, levels: &Levels) {
        let mut labels = vec![0; self.global.len()];
        for f in self.faces.values() {
            for v in f.tri {
                labels[v as usize] |= f.label.bit();
            }
        }
        let dims = field.grid().dims;
        let interfaces = interface_bits(levels.len());
        for v in 0..self.global.len() {
            if self.frozen[v] {
                self.con[v].pinned = true;
                continue;
            }
            let mut c = Constraint::classify(labels[v], interfaces, &mut self.u[v], dims);
            c.region = levels.region_of(self.value[v]) as u8;
            // A level vertex must carry its level's value exactly (the clipper's cuts do).
            if c.level.is_some_and(|l| self.value[v] != levels[l as usize]) {
                c.pinned = true;
            }
            self.con[v] = c;
        }
    }

    /// Records as on their levels the free level vertices that the whole mesh found there
    /// (`off`, per point: off its level), unless [`LocalMesh::classify`] moved them onto a box
    /// plane.
    fn seed_on_level(&mut self, off: &[bool], field: &Field) {
        for v in 0..self.global.len() {
            if self.con[v].level.is_some()
                && !off[self.global[v] as usize]
                && self.u[v] == field.to_index(self.x[v])
            {
                self.on_level[v] = true;
            }
        }
    }

    /// Adds a free vertex at index point `u` carrying `value`, with constraint `con`, and
    /// returns its id; it has no tets yet.
    pub fn add_vertex(&mut self, u: [f64; 3], value: f64, con: Constraint, ctx: &Ctx) -> u32 {
        let id = self.global.len() as u32;
        self.global.push(NEW_POINT);
        self.u.push(u);
        self.x.push(ctx.field.to_physical(u));
        self.value.push(value);
        self.con.push(con);
        self.frozen.push(false);
        self.removed.push(false);
        self.star.push(Vec::new());
        self.face_count.push(0);
        self.drift.push(0.0);
        self.on_level.push(false);
        self.collapse_hint.push(Cell::new(NONE));
        self.memo.stamp.push(self.memo.clock);
        self.memo.vertex_failed.push(0);
        id
    }

    /// Appends tet `t` (local ids) of region `region` and returns its id.
    pub fn add_tet(&mut self, t: [u32; 4], region: u8) -> u32 {
        self.push_tet(t, biased_min_sine(self.corners(t), self.weight), region)
    }

    /// Appends tet `t` (local ids) of region `region` whose quality (already evaluated) is
    /// `q` and returns its id.
    pub fn push_tet(&mut self, t: [u32; 4], q: f64, region: u8) -> u32 {
        let id = self.tets.len() as u32;
        self.tets.push(t);
        self.alive.push(true);
        self.region.push(region);
        self.q.push(q);
        self.note_low(id);
        self.memo.tet_failed.push([0; 2]);
        for v in t {
            self.star[v as usize].push(id);
        }
        self.touch(id);
        id
    }

    /// Removes tet `id` from the mesh and from its vertices' stars.
    pub fn kill_tet(&mut self, id: u32) {
        self.touch(id);
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

    /// Corner positions of tet `t` with vertex `v` (if a corner) at physical point `x`.
    #[inline]
    pub fn corners_with(&self, t: u32, v: u32, x: [f64; 3]) -> [[f64; 3]; 4] {
        let tet = self.tets[t as usize];
        let mut p = self.corners(tet);
        for (i, &w) in tet.iter().enumerate() {
            if w == v {
                p[i] = x;
            }
        }
        p
    }

    /// Whether every tet of the star of `v` would have quality above `floor` with `v` at
    /// index point `u` (stops at the first that does not).
    pub fn star_above_at(&self, v: u32, u: [f64; 3], ctx: &Ctx, floor: f64) -> bool {
        let x = ctx.field.to_physical(u);
        self.star[v as usize]
            .iter()
            .all(|&t| ctx.quality(self.corners_with(t, v, x)) > floor)
    }

    /// Puts `v` at index point `u` and updates its physical position, its value (a level
    /// vertex carries its level exactly, other vertices the trilinear value) and the quality
    /// of its star.
    pub fn set_position(&mut self, v: u32, u: [f64; 3], ctx: &Ctx) {
        self.place(v, u, ctx);
        self.update_star_quality(v);
    }

    /// As [`LocalMesh::set_position`], with the star's new qualities (in star order) known
    /// from [`StarCorners::qualities_above`](super::StarCorners::qualities_above).
    pub fn set_position_with(&mut self, v: u32, u: [f64; 3], ctx: &Ctx, q: &[f64]) {
        self.place(v, u, ctx);
        for (i, &qt) in q.iter().enumerate() {
            let t = self.star[v as usize][i];
            self.touch(t);
            self.q[t as usize] = qt;
            self.note_low(t);
        }
    }

    fn place(&mut self, v: u32, u: [f64; 3], ctx: &Ctx) {
        let i = v as usize;
        self.u[i] = u;
        self.on_level[i] = false;
        self.x[i] = ctx.field.to_physical(u);
        self.value[i] = match self.con[i].level {
            Some(l) => ctx.levels[l as usize],
            None => ctx.field.value(u),
        };
        if self.on_boundary(v) {
            for f in crate::improve::collapse::boundary_faces_at(self, v) {
                let p = f.tri.map(|w| self.u[w as usize]);
                self.face_grid.put(face_key(f.tri), p);
            }
        }
    }

    /// Recomputes the quality of the tets around `v` (after `v` moved).
    pub fn update_star_quality(&mut self, v: u32) {
        for i in 0..self.star[v as usize].len() {
            let t = self.star[v as usize][i];
            self.touch(t);
            self.q[t as usize] = biased_min_sine(self.corners(self.tets[t as usize]), self.weight);
            self.note_low(t);
        }
    }

    /// Sets the quality of tet `t` to `q`, evaluated at its corners as they are now.
    pub fn set_quality(&mut self, t: u32, q: f64) {
        self.touch(t);
        self.q[t as usize] = q;
        self.note_low(t);
    }

    /// Recomputes the quality of tet `t` (after its corners changed).
    pub fn update_quality(&mut self, t: u32) {
        self.touch(t);
        self.q[t as usize] = biased_min_sine(self.corners(self.tets[t as usize]), self.weight);
        self.note_low(t);
    }

    /// Adds tet `t` to [`LocalMesh::low`] if its quality is below the bar kept.
    #[inline]
    fn note_low(&mut self, t: u32) {
        if self.q[t as usize] < self.low_bar {
            self.low.push(t);
        }
    }

    /// The alive tets with quality below `bar`, ascending. At the bar the list of low tets is
    /// kept for, from that list (compacted to them); at another, by a scan of all tets.
    pub fn tets_below(&mut self, bar: f64) -> Vec<u32> {
        let below = |lm: &Self, t: u32| lm.alive[t as usize] && lm.q[t as usize] < bar;
        if bar != self.low_bar {
            return (0..self.tets.len() as u32)
                .filter(|&t| below(self, t))
                .collect();
        }
        let mut low = std::mem::take(&mut self.low);
        low.retain(|&t| below(self, t));
        low.sort_unstable();
        low.dedup();
        self.low = low;
        self.low.clone()
    }

    /// Signed volume of tet `t`.
    pub fn volume_of(&self, t: u32) -> f64 {
        let p = self.corners(self.tets[t as usize]);
        crate::geom::signed_volume(p[0], p[1], p[2], p[3])
    }

    /// Summed signed volume of the tets around `v`.
    /// For a vertex on an interface, the region below it: the region whose volume its drift
    /// counts (the one above changes by the opposite). `None` for the others, whose drift
    /// counts their whole star (the domain's volume).
    #[inline]
    pub fn counted_region(&self, v: u32) -> Option<u8> {
        let c = self.con[v as usize];
        c.level.filter(|_| c.interface).map(|l| l - 1)
    }

    /// The volume of the tets around `v` that its drift counts
    /// ([`LocalMesh::counted_region`]).
    pub fn counted_volume(&self, v: u32) -> f64 {
        let region = self.counted_region(v);
        self.star[v as usize]
            .iter()
            .filter(|&&t| region.is_none_or(|r| self.region[t as usize] == r))
            .map(|&t| self.volume_of(t))
            .sum()
    }

    /// With several regions, for a level vertex `v`: the region whose volume budget its
    /// merges and moves draw on (below an interface, [`LocalMesh::counted_region`]; the
    /// region its star lies in on the domain's boundary) and whether the region above an
    /// interface draws the opposite. `None` for one interval and for vertices off the levels.
    pub fn budget_region(&self, v: u32) -> Option<(u8, bool)> {
        if self.tag_volumes.is_empty() {
            return None;
        }
        if let Some(r) = self.counted_region(v) {
            return Some((r, true));
        }
        self.con[v as usize].level?;
        let t = *self.star[v as usize].first()?;
        Some((self.region[t as usize], false))
    }

    /// Books `added`, the volume a merge into or a move of a level vertex added to its
    /// budget's region `to` ([`LocalMesh::budget_region`]), and its opposite on the region
    /// above an interface.
    pub fn book_volume(&mut self, to: Option<(u8, bool)>, added: f64) {
        if let Some((r, interface)) = to {
            self.tag_volumes[r as usize][1] += added;
            if interface {
                self.tag_volumes[r as usize + 1][1] -= added;
            }
        }
    }

    /// Whether adding `added` to region tag `r` of the copy keeps the volume its interface
    /// vertices' merges and moves added within `share` of the region's volume in the copy, or
    /// brings it nearer.
    pub fn within_budget(&self, r: usize, added: f64, share: f64) -> bool {
        let [start, booked] = self.tag_volumes[r];
        (booked + added).abs() <= (share * start.abs()).max(booked.abs())
    }

    /// Whether `v` may be moved or merged.
    #[inline]
    pub fn is_free(&self, v: u32) -> bool {
        !self.frozen[v as usize] && !self.removed[v as usize]
    }

    /// Whether `v` is known to lie within the tolerance of its level set: it was found there
    /// ([`LocalMesh::found_on_level`]) and has not moved since.
    #[inline]
    pub fn known_on_level(&self, v: u32) -> bool {
        self.on_level[v as usize]
    }

    /// Records that `v` lies within the tolerance of its level set where it is.
    #[inline]
    pub fn found_on_level(&mut self, v: u32) {
        self.on_level[v as usize] = true;
    }

    /// The tet that last stopped a collapse from `v`, if it is still alive and around `v`.
    #[inline]
    pub fn collapse_hint(&self, v: u32) -> Option<u32> {
        let t = self.collapse_hint[v as usize].get();
        (t != NONE && self.alive[t as usize] && self.tets[t as usize].contains(&v)).then_some(t)
    }

    /// Records that tet `t` stopped a collapse from `v`.
    #[inline]
    pub fn set_collapse_hint(&self, v: u32, t: u32) {
        self.collapse_hint[v as usize].set(t);
    }

    /// Whether `v` is a level vertex farther than the tolerance from its level set.
    pub fn off_its_level(&self, v: u32, ctx: &Ctx) -> bool {
        self.con[v as usize].level.is_some_and(|l| {
            !self.on_level[v as usize]
                && (ctx.field.value(self.u[v as usize]) - ctx.levels[l as usize]).abs() > ctx.tol
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::wavy_torus;

    #[test]
    fn the_low_list_finds_the_tets_below_the_target_as_a_scan_does() {
        let grid = wavy_torus();
        let (ctx, mut regions) = crate::improve::fixtures::wavy_torus_regions(&grid, &[0]);
        let lm = regions.iter_mut().max_by_key(|lm| lm.tets.len()).unwrap();
        let scan = |lm: &LocalMesh, bar: f64| -> Vec<u32> {
            (0..lm.tets.len() as u32)
                .filter(|&t| lm.alive[t as usize] && lm.q[t as usize] < bar)
                .collect()
        };
        let start = scan(lm, ctx.target);
        assert!(!start.is_empty());
        assert_eq!(lm.tets_below(ctx.target), start);
        // Qualities raised and lowered, tets removed and added, and moves, in a fixed order.
        let mut seed = 11u64;
        let mut next = |n: usize| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as usize % n
        };
        for round in 0..50 {
            for _ in 0..40 {
                let t = next(lm.tets.len()) as u32;
                if lm.alive[t as usize] {
                    lm.set_quality(t, if next(2) == 0 { 0.01 } else { 0.9 });
                }
            }
            let t = next(lm.tets.len()) as u32;
            if lm.alive[t as usize] && round % 3 == 0 {
                let tet = lm.tets[t as usize];
                lm.kill_tet(t);
                lm.push_tet(tet, 0.02, 0);
            }
            let v = next(lm.u.len()) as u32;
            if lm.is_free(v) && !lm.star[v as usize].is_empty() {
                lm.update_star_quality(v);
            }
            let bar = ctx.target;
            assert_eq!(lm.tets_below(bar), scan(lm, bar), "round {round}");
            assert_eq!(lm.tets_below(0.5), scan(lm, 0.5), "round {round}");
        }
        assert!(lm.low.len() > start.len() / 2);
    }

    #[test]
    fn tet_edge_tets_lists_each_edge_as_edge_tets_does() {
        let grid = wavy_torus();
        let (_, regions) = crate::improve::fixtures::wavy_torus_regions(&grid, &[0, 1]);
        let mut edges = 0;
        for lm in &regions {
            for &tet in &lm.tets {
                let all = lm.tet_edge_tets(tet);
                let pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
                for ((i, j), e) in pairs.into_iter().zip(&all) {
                    assert_eq!(e, &lm.edge_tets(tet[i], tet[j]), "{tet:?} {i} {j}");
                    assert!(!e.is_empty());
                    edges += 1;
                }
            }
        }
        assert!(edges > 10_000, "{edges}");
    }
}
