//! Edge collapse: merges vertex `a` into its neighbour `b`, removing the tets around the edge.
//!
//! A collapse can change the topology; it is allowed only under the link condition
//! (Dey, Edelsbrunner et al.): the link of `a` and the link of `b` intersect exactly in the
//! link of the edge, computed in the complex closed by a virtual vertex coning the boundary,
//! so that the boundary surface stays a 2-manifold. `b` must lie on every surface `a` lies on
//! (same level, same box planes), boundary faces keep their labels, and every remaining tet
//! must stay positive and better than the worst one the collapse removes or changes.

use smallvec::SmallVec;

use super::region::{face_key, BoundaryFace, LocalMesh};
use super::Ctx;
use super::{embed, interfaces};

/// The boundary faces at a vertex ([`boundary_faces_at`]; inline up to 16).
pub type VertexFaces = SmallVec<[BoundaryFace; 16]>;

/// The qualities of the tets a collapse changes, by tet id, as its test evaluated them
/// ([`collapse_quality`]; inline up to 32).
pub type Evaluated = SmallVec<[(u32, f64); 32]>;

/// A legal and improving collapse found by [`best_collapse`].
pub struct Collapse {
    /// The vertex merged away.
    pub from: u32,
    /// The vertex it merges into.
    pub to: u32,
    /// The qualities of the changed tets afterwards ([`apply_evaluated`] keeps them).
    pub evaluated: Evaluated,
    /// The boundary faces at `from`, if the link condition gathered them.
    pub faces: Option<VertexFaces>,
}

/// The better legal and improving collapse of edge `ab` (either way: the one whose worst
/// changed tet is better afterwards); `a` into `b` on a tie. `floor(v)` is [`star_floor`] of
/// `v` (asked only for a direction that passes the cheap tests): a collapse must do better
/// than the worst tet of the star it removes. The link condition is symmetric in `a` and
/// `b`, so it is checked once.
pub fn best_collapse(
    lm: &LocalMesh,
    ctx: &Ctx,
    a: u32,
    b: u32,
    floor: impl Fn(u32) -> f64,
) -> Option<Collapse> {
    let ratio = ctx.boundary_collapse_ratio;
    let (mut at_ab, mut at_ba) = (Evaluated::new(), Evaluated::new());
    let ab = collapse_quality(lm, ctx, (a, b), || floor(a), (ratio, true), &mut at_ab);
    let ba = collapse_quality(lm, ctx, (b, a), || floor(b), (ratio, true), &mut at_ba);
    let (from, to, evaluated) = match (ab, ba) {
        (Some(x), Some(y)) if y > x => (b, a, at_ba),
        (Some(_), _) => (a, b, at_ab),
        (None, Some(_)) => (b, a, at_ba),
        (None, None) => return None,
    };
    let mut faces = None;
    link_condition_gathering(lm, from, to, &lm.edge_tets(from, to), &mut faces).then_some(
        Collapse {
            from,
            to,
            evaluated,
            faces,
        },
    )
}

/// The collapse of `a` into `b`, if legal and every remaining tet stays positive (no gain
/// needed, and no [`QualityOptions::boundary_collapse_ratio`](super::QualityOptions) limit:
/// used to remove vertices that cannot reach their level set).
pub fn evaluate_merge(lm: &LocalMesh, ctx: &Ctx, a: u32, b: u32) -> Option<f64> {
    let new = collapse_quality(
        lm,
        ctx,
        (a, b),
        || 0.0,
        (f64::INFINITY, false),
        &mut Evaluated::new(),
    )?;
    link_condition(lm, a, b, &lm.edge_tets(a, b)).then_some(new)
}

/// Whether the collapse of `a` into `b` is legal (the constraints, the link condition and
/// [`QualityOptions::boundary_collapse_ratio`](super::QualityOptions)) and leaves every tet
/// positive, whatever their quality: for operations that judge it after further moves
/// ([`super::composite`]). With `budget`, a merge of a vertex between two regions keeps
/// them within their volume budgets in the copy ([`embed::collapse_keeps_boundary`]); the
/// last resorts that bring a vertex onto its level go without.
pub fn legal_collapse(lm: &LocalMesh, ctx: &Ctx, (a, b): (u32, u32), budget: bool) -> bool {
    let ratio = ctx.boundary_collapse_ratio;
    collapse_quality(
        lm,
        ctx,
        (a, b),
        || 0.0,
        (ratio, budget),
        &mut Evaluated::new(),
    )
    .is_some()
        && link_condition(lm, a, b, &lm.edge_tets(a, b))
}

/// The worst quality in the star of `v` (at least 0): what a collapse of `v` must beat.
pub fn star_floor(lm: &LocalMesh, v: u32) -> f64 {
    lm.star[v as usize]
        .iter()
        .map(|&t| lm.q[t as usize])
        .fold(f64::INFINITY, f64::min)
        .max(0.0)
}

/// Whether `a` may merge into `b` whatever the tets' signs afterwards: both free, the
/// constraints allow it, `ab` is an edge and the link condition holds (for a merge whose
/// inverted tets are then untangled, [`super::project::merge_and_untangle`]).
pub fn topological_merge(lm: &LocalMesh, ctx: &Ctx, a: u32, b: u32) -> bool {
    let edge = lm.edge_tets(a, b);
    lm.is_free(a)
        && lm.is_free(b)
        && lm.con[a as usize].may_merge_into(&lm.con[b as usize])
        && !edge.is_empty()
        && link_condition(lm, a, b, &edge)
        && embed::collapse_keeps_boundary(lm, ctx, (a, b), false)
}

/// For a collapse of `a` into `b` along an edge of the mesh that the constraints allow and
/// that leaves every changed tet above `floor()` (asked after the cheap tests), along an
/// edge shorter than `ratio` times the mean edge at `a` if `a` is a level vertex
/// ([`short_edge`]): the smallest quality of the changed tets after, with the quality of each
/// changed tet evaluated in `evaluated`. Stops at the first changed tet that fails.
fn collapse_quality(
    lm: &LocalMesh,
    ctx: &Ctx,
    (a, b): (u32, u32),
    floor: impl FnOnce() -> f64,
    (ratio, budget): (f64, bool),
    evaluated: &mut Evaluated,
) -> Option<f64> {
    if !lm.is_free(a) || !lm.is_free(b) {
        return None;
    }
    if !lm.con[a as usize].may_merge_into(&lm.con[b as usize]) {
        return None;
    }
    // The quality first: most attempts fail there. The tet that stopped the last collapse
    // from `a` goes first; the order does not change the answer (any tet at or below the
    // floor stops it, and the smallest quality is the same). Whether `ab` is an edge at all
    // is seen on the way (it is, for an edge of a tet): a collapse along a non-edge fails
    // either way.
    let floor = floor();
    let mut new = f64::INFINITY;
    let xb = lm.x[b as usize];
    let around_edge = |t: u32| lm.tets[t as usize].contains(&b);
    let hint = lm.collapse_hint(a).filter(|&t| !around_edge(t));
    let mut stops = |t: u32| {
        let q = ctx.quality(lm.corners_with(t, a, xb));
        evaluated.push((t, q));
        new = new.min(q);
        let stop = new <= floor;
        if stop {
            lm.set_collapse_hint(a, t);
        }
        stop
    };
    if hint.is_some_and(&mut stops) {
        return None;
    }
    let mut edge = false;
    for &t in &lm.star[a as usize] {
        if around_edge(t) {
            edge = true;
        } else if Some(t) != hint && stops(t) {
            return None;
        }
    }
    if !edge {
        return None;
    }
    if lm.con[a as usize].level.is_some() && !short_edge(lm, a, b, ratio) {
        return None;
    }
    // The star sizes first: the level test evaluates the field.
    if lm.star[a as usize].len() + lm.star[b as usize].len() > HUB_TETS && lm.off_its_level(b, ctx)
    {
        // A vertex with many tets around it can hardly be moved onto its level later.
        return None;
    }
    // Last, the boundary faces `a` leaves to `b` must stay near their level sets.
    if !embed::collapse_keeps_boundary(lm, ctx, (a, b), budget) {
        return None;
    }
    Some(new)
}

/// A level vertex still off its level set takes no collapse that would give it a star of
/// about this many tets (the two stars' sizes summed): it must still be moved onto its level,
/// and a hub is hard to move without inverting a tet (on the MNI T1 at `[101.5, 151.5]` with
/// `--boundary-collapse-ratio 3`, such a vertex with 66 tets stayed 0.7 voxel off its level).
/// A smaller limit (40) or none left more tets below 5° on the noisy 256³ field.
const HUB_TETS: usize = 56;

/// Whether edge `ab` is short against the other edges at `a`: boundary collapses are kept to
/// such edges, since merging two boundary vertices further apart shrinks a convex boundary
/// (the surface is inscribed in the level set).
fn short_edge(lm: &LocalMesh, a: u32, b: u32, ratio: f64) -> bool {
    if ratio.is_infinite() {
        return true;
    }
    let xa = lm.x[a as usize];
    let len = |w: u32| {
        let d = crate::geom::sub(lm.x[w as usize], xa);
        crate::geom::dot(d, d).sqrt()
    };
    let (mut sum, mut n) = (0.0, 0);
    for &t in &lm.star[a as usize] {
        for w in lm.tets[t as usize] {
            if w != a {
                sum += len(w);
                n += 1;
            }
        }
    }
    n > 0 && len(b) < ratio * sum / n as f64
}

/// Applies the collapse `c`, keeping the qualities its test evaluated.
pub fn apply_evaluated(lm: &mut LocalMesh, c: Collapse) {
    merge(lm, c.from, c.to, &c.evaluated, c.faces);
}

/// Merges `a` into `b` (legality and gain checked by the caller).
pub fn apply_collapse(lm: &mut LocalMesh, a: u32, b: u32) {
    merge(lm, a, b, &[], None);
}

/// Merges `a` into `b`; a changed tet listed in `known` takes the quality given there (the
/// collapse test's, evaluated at the same corners), the others are evaluated. `faces`: the
/// boundary faces at `a`, if known.
fn merge(lm: &mut LocalMesh, a: u32, b: u32, known: &[(u32, f64)], faces: Option<VertexFaces>) {
    // Only a level vertex's star changes the domain: the tets left still fill an interior
    // vertex's star.
    let level = lm.con[a as usize].level.is_some();
    let counted = lm.counted_region(a);
    let budget = lm.budget_region(a);
    let mut added = if level { -lm.counted_volume(a) } else { 0.0 };
    let shared = lm.edge_tets(a, b);
    let faces = faces.unwrap_or_else(|| boundary_faces_at(lm, a));
    for f in &faces {
        lm.remove_face(f.tri);
    }
    for f in faces {
        if !f.tri.contains(&b) {
            let tri = f.tri.map(|v| if v == a { b } else { v });
            lm.insert_face(BoundaryFace { tri, ..f });
        }
    }
    for t in shared {
        lm.kill_tet(t);
    }
    let star = std::mem::take(&mut lm.star[a as usize]);
    for t in star {
        let tet = &mut lm.tets[t as usize];
        for w in tet.iter_mut() {
            if *w == a {
                *w = b;
            }
        }
        lm.star[b as usize].push(t);
        match known.iter().find(|k| k.0 == t) {
            Some(&(_, q)) => lm.set_quality(t, q),
            None => lm.update_quality(t),
        }
        if level && counted.is_none_or(|r| lm.region[t as usize] == r) {
            added += lm.volume_of(t);
        }
    }
    lm.drift[b as usize] += std::mem::take(&mut lm.drift[a as usize]) + added;
    lm.book_volume(budget, added);
    lm.removed[a as usize] = true;
}

/// Boundary faces with `v` as a corner.
pub fn boundary_faces_at(lm: &LocalMesh, v: u32) -> VertexFaces {
    let mut out = VertexFaces::new();
    if !lm.on_boundary(v) {
        return out;
    }
    let all = lm.boundary_faces_of(v);
    for &t in &lm.star[v as usize] {
        let tet = lm.tets[t as usize];
        // A face at `v` (the face opposite a corner other than `v`) is on the boundary only if
        // its corners are: with one corner off the boundary only the face opposite it may be,
        // with two or more none.
        let mut off = (0..4).filter(|&i| tet[i] != v && !lm.on_boundary(tet[i]));
        let only = match (off.next(), off.next()) {
            (None, _) => None,
            (Some(k), None) => Some(k),
            _ => continue,
        };
        for skip in (0..4).filter(|&s| tet[s] != v && only.is_none_or(|k| k == s)) {
            if let Some(f) = lm.faces.get(&face_key(face_without(tet, skip))) {
                if !out.contains(f) {
                    out.push(*f);
                    if out.len() == all {
                        return out;
                    }
                }
            }
        }
    }
    out
}

/// The face of `tet` opposite corner `skip` (unoriented).
#[inline]
fn face_without(tet: [u32; 4], skip: usize) -> [u32; 3] {
    let mut f = [0; 3];
    let mut n = 0;
    for (i, &v) in tet.iter().enumerate() {
        if i != skip {
            f[n] = v;
            n += 1;
        }
    }
    f
}

/// A 256-bit filter of the corners of the tets around a vertex: a vertex whose bit is clear
/// is not one of them; one whose bit is set is looked for in the star ([`StarFilter::has`]).
struct StarFilter([u64; 4]);

impl StarFilter {
    fn of(lm: &LocalMesh, v: u32) -> Self {
        let mut bits = [0u64; 4];
        for &t in &lm.star[v as usize] {
            for w in lm.tets[t as usize] {
                let h = Self::slot(w);
                bits[h >> 6] |= 1 << (h & 63);
            }
        }
        StarFilter(bits)
    }

    /// The bit of `w` (the top byte of a multiplicative hash).
    #[inline]
    fn slot(w: u32) -> usize {
        (w.wrapping_mul(0x9E37_79B1) >> 24) as usize
    }

    /// Whether `w` is a corner of a tet around `v` (the vertex the filter was made for).
    #[inline]
    fn has(&self, lm: &LocalMesh, v: u32, w: u32) -> bool {
        let h = Self::slot(w);
        self.0[h >> 6] & (1 << (h & 63)) != 0
            && lm.star[v as usize]
                .iter()
                .any(|&t| lm.tets[t as usize].contains(&w))
    }
}

/// Whether some tet around `v` has all of `ws` as corners.
fn star_has(lm: &LocalMesh, v: u32, ws: &[u32]) -> bool {
    lm.star[v as usize]
        .iter()
        .any(|&t| ws.iter().all(|w| lm.tets[t as usize].contains(w)))
}

/// The link condition for collapsing the edge `ab`, whose tets are `shared`: the links of `a`
/// and `b` meet exactly in the link of `ab` (its *ring*: the edges opposite `ab` in `shared`).
///
/// Vertices first: the common vertices must be the ring's. Then a common edge or triangle
/// has all its corners on the ring, so only faces of the star of `a` over ring vertices are
/// looked up in the star of `b`: an edge `vw` of both links must lie in a tet of `shared`,
/// and no triangle may be in both links (the two tets would become one).
fn link_condition(lm: &LocalMesh, a: u32, b: u32, shared: &[u32]) -> bool {
    link_condition_gathering(lm, a, b, shared, &mut None)
}

/// [`link_condition`], leaving in `faces` the boundary faces at `a` when its boundary part
/// gathered them.
fn link_condition_gathering(
    lm: &LocalMesh,
    a: u32,
    b: u32,
    shared: &[u32],
    faces: &mut Option<VertexFaces>,
) -> bool {
    let mut ring: SmallVec<[u32; 16]> = shared
        .iter()
        .flat_map(|&t| lm.tets[t as usize])
        .filter(|&w| w != a && w != b)
        .collect();
    ring.sort_unstable();
    ring.dedup();
    if shares_off_ring(lm, [a, b], &ring) {
        return false;
    }
    let on_ring = |w: u32| ring.binary_search(&w).is_ok();
    for &t in &lm.star[a as usize] {
        let tet = lm.tets[t as usize];
        if tet.contains(&b) {
            continue;
        }
        let tri = face_without(tet, tet.iter().position(|&w| w == a).unwrap_or(0));
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            let e = [tri[i], tri[j]];
            if on_ring(e[0]) && on_ring(e[1]) && !edge_allowed(lm, a, b, shared, e) {
                return false;
            }
        }
        if tri.iter().all(|&w| on_ring(w)) && star_has(lm, b, &tri) {
            return false;
        }
    }
    boundary_link_condition(lm, a, b, &ring, faces)
        && (!lm.con[a as usize].interface || interfaces::keeps_regions(lm, a, b))
}

/// Whether a corner of the tets around `b` (other than `a` and `b`) is one of the tets
/// around `a` too but not on the sorted `ring`: the links of `a` and `b` then share a vertex
/// that the link of `ab` lacks. (Every ring vertex is in both links: the ring is made of
/// corners of tets around `ab`.)
fn shares_off_ring(lm: &LocalMesh, [a, b]: [u32; 2], ring: &[u32]) -> bool {
    let around_a = StarFilter::of(lm, a);
    lm.star[b as usize]
        .iter()
        .flat_map(|&t| lm.tets[t as usize])
        .any(|w| w != a && w != b && ring.binary_search(&w).is_err() && around_a.has(lm, a, w))
}

/// For an edge `vw` (no end `a` or `b`) of the link of `a`: it is also in the link of `b`
/// only if it is in the link of `ab` (some tet of `shared` has both ends).
fn edge_allowed(lm: &LocalMesh, a: u32, b: u32, shared: &[u32], e: [u32; 2]) -> bool {
    if e.contains(&a) || e.contains(&b) {
        return true;
    }
    let in_shared = shared
        .iter()
        .any(|&t| e.iter().all(|w| lm.tets[t as usize].contains(w)));
    in_shared || !star_has(lm, b, &e)
}

/// The part of the link condition that involves the virtual vertex coning the boundary, once
/// the links of `a` and `b` are known to share no vertex off the sorted `ring`
/// ([`shares_off_ring`]).
///
/// The virtual vertex is in both links when `a` and `b` are on the boundary, and then must be
/// in the link of `ab`: `ab` is a boundary edge. Its edge to `v` is in the link of `a` when
/// `av` is a boundary edge: with `bv` one too, `abv` must be a boundary face. Its triangle
/// with `vw` is in the link of `a` when `avw` is a boundary face, and never in the link of
/// `ab`: `bvw` must not be one. A vertex `v` of both of these is in both links, so on the
/// ring, and only the boundary faces at `a` are gathered; those at `b` are looked up.
fn boundary_link_condition(
    lm: &LocalMesh,
    a: u32,
    b: u32,
    ring: &[u32],
    faces: &mut Option<VertexFaces>,
) -> bool {
    if !lm.on_boundary(a) || !lm.on_boundary(b) {
        return true;
    }
    let fa = faces.insert(boundary_faces_at(lm, a));
    let opposite = |f: &BoundaryFace| {
        let i = f.tri.iter().position(|&w| w == a).unwrap_or(0);
        [f.tri[(i + 1) % 3], f.tri[(i + 2) % 3]]
    };
    // The third corners of the boundary faces at `ab`.
    let closing: SmallVec<[u32; 4]> = fa
        .iter()
        .map(opposite)
        .filter(|o| o.contains(&b))
        .map(|o| if o[0] == b { o[1] } else { o[0] })
        .collect();
    if closing.is_empty() {
        // Both ends on the boundary but the edge is not: collapsing would pinch the boundary.
        return false;
    }
    let on_ring = |w: u32| ring.binary_search(&w).is_ok();
    for o in fa.iter().map(opposite).filter(|o| !o.contains(&b)) {
        let open = |v: u32| on_ring(v) && !closing.contains(&v) && boundary_edge(lm, b, v);
        if open(o[0]) || open(o[1]) {
            return false;
        }
        if on_ring(o[0]) && on_ring(o[1]) && lm.faces.contains_key(&face_key([b, o[0], o[1]])) {
            return false;
        }
    }
    true
}

/// Whether `bv` is an edge of a boundary face (`b` free, so its whole star is in the region).
fn boundary_edge(lm: &LocalMesh, b: u32, v: u32) -> bool {
    if !lm.on_boundary(v) {
        return false;
    }
    lm.star[b as usize].iter().any(|&t| {
        let tet = lm.tets[t as usize];
        tet.contains(&v)
            && (0..4)
                .filter(|&s| tet[s] != b && tet[s] != v)
                .any(|s| lm.faces.contains_key(&face_key(face_without(tet, s))))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::{wavy_torus, wavy_torus_regions};

    /// The link of `v`, as sorted lists of its vertices, edges and triangles (from the tets of
    /// its star; the virtual boundary vertex is handled separately).
    struct Link {
        verts: Vec<u32>,
        edges: Vec<[u32; 2]>,
        tris: Vec<[u32; 3]>,
    }

    fn link_of(lm: &LocalMesh, v: u32) -> Link {
        let n = lm.star[v as usize].len();
        let mut l = Link {
            verts: Vec::with_capacity(3 * n),
            edges: Vec::with_capacity(3 * n),
            tris: Vec::with_capacity(n),
        };
        for &t in &lm.star[v as usize] {
            let tet = lm.tets[t as usize];
            let i = tet.iter().position(|&w| w == v).unwrap_or(0);
            let tri = face_key(face_without(tet, i));
            l.verts.extend_from_slice(&tri);
            l.edges
                .extend_from_slice(&[[tri[0], tri[1]], [tri[0], tri[2]], [tri[1], tri[2]]]);
            l.tris.push(tri);
        }
        l.verts.sort_unstable();
        l.verts.dedup();
        l.edges.sort_unstable();
        l.edges.dedup();
        l.tris.sort_unstable();
        l
    }

    /// The link condition as set operations on whole links (the first implementation).
    fn reference_link_condition(lm: &LocalMesh, a: u32, b: u32, shared: &[u32]) -> bool {
        let (la, lb) = (link_of(lm, a), link_of(lm, b));
        let mut edge_verts: Vec<u32> = Vec::new();
        let mut edge_edges: Vec<[u32; 2]> = Vec::new();
        for &t in shared {
            let mut o: Vec<u32> = lm.tets[t as usize]
                .into_iter()
                .filter(|&w| w != a && w != b)
                .collect();
            o.sort_unstable();
            edge_verts.extend_from_slice(&o);
            edge_edges.push([o[0], o[1]]);
        }
        edge_verts.sort_unstable();
        edge_verts.dedup();
        let outside = |x: &u32| *x != a && *x != b;
        let common_verts: Vec<u32> = la
            .verts
            .iter()
            .filter(|x| outside(x) && lb.verts.binary_search(x).is_ok())
            .copied()
            .collect();
        if common_verts != edge_verts {
            return false;
        }
        let edge_ok = la
            .edges
            .iter()
            .filter(|e| outside(&e[0]) && outside(&e[1]) && lb.edges.binary_search(e).is_ok())
            .all(|e| edge_edges.contains(e));
        let tri_clash = la
            .tris
            .iter()
            .any(|t| t.iter().all(outside) && lb.tris.binary_search(t).is_ok());
        edge_ok && !tri_clash && reference_boundary_link_condition(lm, a, b)
    }

    /// The part of the link condition that involves the virtual vertex coning the boundary,
    /// from the boundary faces at both ends (the first implementation).
    fn reference_boundary_link_condition(lm: &LocalMesh, a: u32, b: u32) -> bool {
        if !lm.on_boundary(a) || !lm.on_boundary(b) {
            return true;
        }
        let (fa, fb) = (boundary_faces_at(lm, a), boundary_faces_at(lm, b));
        if fa.is_empty() || fb.is_empty() {
            return true;
        }
        let on_edge = |f: &BoundaryFace| f.tri.contains(&a) && f.tri.contains(&b);
        let ab_faces: SmallVec<[[u32; 3]; 4]> = fa
            .iter()
            .filter(|f| on_edge(f))
            .map(|f| face_key(f.tri))
            .collect();
        if ab_faces.is_empty() {
            // Both ends on the boundary but the edge is not: collapsing would pinch the boundary.
            return false;
        }
        let others = |faces: &[BoundaryFace], v: u32| {
            let mut verts: SmallVec<[u32; 32]> = SmallVec::new();
            let mut edges: SmallVec<[[u32; 2]; 16]> = SmallVec::new();
            for f in faces {
                let i = f.tri.iter().position(|&w| w == v).unwrap_or(0);
                let o = [f.tri[(i + 1) % 3], f.tri[(i + 2) % 3]];
                verts.extend_from_slice(&o);
                edges.push([o[0].min(o[1]), o[0].max(o[1])]);
            }
            verts.sort_unstable();
            verts.dedup();
            edges.sort_unstable();
            (verts, edges)
        };
        let (va, ea) = others(&fa, a);
        let (vb, eb) = others(&fb, b);
        let outside = |x: &u32| *x != a && *x != b;
        // Boundary edges av and bv: abv must be a boundary face.
        let verts_ok = va
            .iter()
            .filter(|v| outside(v) && vb.binary_search(v).is_ok())
            .all(|&v| ab_faces.contains(&face_key([a, b, v])));
        // Boundary faces avw and bvw both present: the virtual tets would clash.
        let faces_ok = !ea
            .iter()
            .any(|e| outside(&e[0]) && outside(&e[1]) && eb.binary_search(e).is_ok());
        verts_ok && faces_ok
    }

    #[test]
    fn link_condition_matches_the_set_definition() {
        let grid = wavy_torus();
        let (_, mut regions) = wavy_torus_regions(&grid, &[0]);
        let (mut legal, mut illegal, mut applied) = (0, 0, 0);
        for lm in &mut regions {
            for t in 0..lm.tets.len() {
                for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                    let tet = lm.tets[t];
                    if !lm.alive[t] || !lm.is_free(tet[i]) || !lm.is_free(tet[j]) {
                        continue;
                    }
                    let (a, b) = (tet[i], tet[j]);
                    let shared = lm.edge_tets(a, b);
                    let fast = link_condition(lm, a, b, &shared);
                    assert_eq!(fast, reference_link_condition(lm, a, b, &shared), "{a} {b}");
                    if !fast {
                        illegal += 1;
                        continue;
                    }
                    legal += 1;
                    // Change the mesh now and then (keeping it valid), so that later edges
                    // meet the configurations collapses make.
                    if legal % 5 == 0 && lm.con[a as usize].may_merge_into(&lm.con[b as usize]) {
                        apply_collapse(lm, a, b);
                        applied += 1;
                    }
                }
            }
        }
        assert!(
            legal > 1000 && illegal > 100 && applied > 100,
            "{legal} {illegal} {applied}"
        );
    }

    #[test]
    fn the_star_filter_finds_exactly_the_corners_around_a_vertex() {
        let grid = wavy_torus();
        let (_, regions) = wavy_torus_regions(&grid, &[0]);
        let lm = regions.iter().max_by_key(|lm| lm.tets.len()).unwrap();
        let (mut found, mut passed_filter) = (0, 0);
        for v in (0..lm.u.len() as u32).step_by(3) {
            let filter = StarFilter::of(lm, v);
            for w in 0..lm.u.len() as u32 {
                let around = lm.star[v as usize]
                    .iter()
                    .any(|&t| lm.tets[t as usize].contains(&w));
                assert_eq!(filter.has(lm, v, w), around, "{v} {w}");
                found += usize::from(around);
                let h = StarFilter::slot(w);
                passed_filter += usize::from(filter.0[h >> 6] & (1 << (h & 63)) != 0);
            }
        }
        // The filter alone lets through more than the star holds (so the look-up is tested).
        assert!(
            found > 1000 && passed_filter > found,
            "{found} {passed_filter}"
        );
    }

    #[test]
    fn no_edge_of_a_lone_tet_may_collapse() {
        // All four faces of a lone tet are boundary faces. The links of two corners share
        // only the other two corners and their edge, as the link of the edge does; but both
        // links hold the virtual vertex's triangle over that edge (two boundary faces), which
        // the link of the edge cannot. Only the boundary part of the condition sees it.
        let grid =
            crate::ScalarGrid::new([4, 4, 4], (0..64u8).map(f64::from).collect::<Vec<f64>>())
                .unwrap();
        let mesh = crate::mesh::TetMesh {
            regions: Default::default(),
            points: vec![
                [1.0, 1.0, 1.0],
                [2.0, 1.0, 1.0],
                [1.0, 2.0, 1.0],
                [1.0, 1.0, 2.0],
            ],
            values: vec![21.0, 22.0, 25.0, 37.0],
            tets: vec![[0, 1, 2, 3]],
            boundary: vec![[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]],
            boundary_labels: vec![crate::mesh::BoundaryLabel::ALPHA; 4],
        };
        let opts = crate::improve::QualityOptions::default();
        let ctx = crate::improve::ctx::context(
            &grid,
            &crate::Levels::interval(20.0, 40.0),
            &opts,
            std::time::Instant::now(),
        );
        let quality = crate::improve::quality_cache::tet_qualities(&mesh, &ctx);
        let (regions, _) =
            crate::improve::region::extract_regions(&mesh, (&[true; 4], None), &quality, &ctx, 0);
        let lm = regions.iter().find(|lm| !lm.tets.is_empty()).unwrap();
        for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            assert!(lm.is_free(a) && lm.is_free(b));
            let shared = lm.edge_tets(a, b);
            assert!(!link_condition(lm, a, b, &shared), "{a} {b}");
            assert!(!reference_link_condition(lm, a, b, &shared), "{a} {b}");
            let ring: Vec<u32> = (0..4).filter(|&w| w != a && w != b).collect();
            assert!(!shares_off_ring(lm, [a, b], &ring));
        }
    }

    #[test]
    fn a_vertex_off_its_level_takes_no_collapse_that_makes_it_a_hub() {
        // Before projection the level vertices of the warped mesh sit at linear cut points,
        // off the trilinear level set (except the snapped grid vertices). Collapse neighbours
        // into such vertices while it is allowed, until their stars reach the limit.
        let grid = wavy_torus();
        let (ctx, mut regions) = wavy_torus_regions(&grid, &[0]);
        let (mut applied, mut refused) = (0, 0);
        for lm in &mut regions {
            for b in 0..lm.u.len() as u32 {
                if !lm.is_free(b) || !lm.off_its_level(b, &ctx) || refused >= 20 {
                    continue;
                }
                while let Some(a) = positive_merge_into(lm, &ctx, b) {
                    let mut evaluated = Evaluated::new();
                    let q = collapse_quality(
                        lm,
                        &ctx,
                        (a, b),
                        || 0.0,
                        (f64::INFINITY, true),
                        &mut evaluated,
                    );
                    if lm.star[a as usize].len() + lm.star[b as usize].len() > HUB_TETS {
                        assert!(q.is_none(), "{a} into {b}");
                        refused += 1;
                        break;
                    }
                    if q.is_none() && !embed::collapse_keeps_boundary(lm, &ctx, (a, b), true) {
                        // The embedding guard refuses it (its faces would leave the level
                        // set: `b` is off its level).
                        break;
                    }
                    assert!(q.is_some(), "{a} into {b}");
                    apply_collapse(lm, a, b);
                    applied += 1;
                }
            }
        }
        assert!(refused >= 20 && applied > 100, "{refused} {applied}");
    }

    /// A free neighbour of `b` that may merge into it under the link condition with every
    /// remaining tet positive.
    fn positive_merge_into(lm: &LocalMesh, ctx: &Ctx, b: u32) -> Option<u32> {
        let mut nbrs: Vec<u32> = lm.star[b as usize]
            .iter()
            .flat_map(|&t| lm.tets[t as usize])
            .filter(|&a| a != b && lm.is_free(a))
            .collect();
        nbrs.sort_unstable();
        nbrs.dedup();
        nbrs.into_iter().find(|&a| {
            let xb = lm.x[b as usize];
            lm.con[a as usize].may_merge_into(&lm.con[b as usize])
                && link_condition(lm, a, b, &lm.edge_tets(a, b))
                && lm.star[a as usize]
                    .iter()
                    .filter(|&&t| !lm.tets[t as usize].contains(&b))
                    .all(|&t| ctx.quality(lm.corners_with(t, a, xb)) > 0.0)
        })
    }
}
