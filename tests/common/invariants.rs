//! Mesh invariants checked independently of the mesher's own analyses.

use std::collections::{HashMap, HashSet};
use tptd::union_find::UnionFind;
use tptd::{BoundaryLabel, TetMesh};

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Signed volume of (a, b, c, d), computed here (not with the crate's helper).
pub fn tet_volume(mesh: &TetMesh, t: [u32; 4]) -> f64 {
    let p = t.map(|i| mesh.points[i as usize]);
    dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0]))) / 6.0
}

pub fn total_volume(mesh: &TetMesh) -> f64 {
    mesh.tets.iter().map(|&t| tet_volume(mesh, t)).sum()
}

fn sorted3(mut f: [u32; 3]) -> [u32; 3] {
    f.sort_unstable();
    f
}

/// The four faces of a tet [a,b,c,d], each with the opposite vertex.
fn tet_faces(t: [u32; 4]) -> [([u32; 3], u32); 4] {
    let [a, b, c, d] = t;
    [
        ([b, c, d], a),
        ([a, c, d], b),
        ([a, b, d], c),
        ([a, b, c], d),
    ]
}

/// Every violated invariant, as a message (empty when the mesh is valid).
pub fn mesh_errors(mesh: &TetMesh) -> Vec<String> {
    let mut errs: Vec<String> = Vec::new();
    let np = mesh.points.len();
    macro_rules! err {
        ($($t:tt)*) => {
            if errs.len() < 50 {
                errs.push(format!($($t)*));
            }
        };
    }
    if mesh.values.len() != np {
        err!("values.len() {} != points.len() {}", mesh.values.len(), np);
    }
    if mesh.boundary.len() != mesh.boundary_labels.len() {
        err!(
            "boundary.len() {} != boundary_labels.len() {}",
            mesh.boundary.len(),
            mesh.boundary_labels.len()
        );
    }
    for (i, p) in mesh.points.iter().enumerate() {
        if !p.iter().all(|x| x.is_finite()) {
            err!("point {i} not finite: {p:?}");
        }
    }
    for (i, v) in mesh.values.iter().enumerate() {
        if !v.is_finite() {
            err!("value {i} not finite: {v}");
        }
    }
    let mut used = vec![false; np];
    let mut tetset: HashSet<[u32; 4]> = HashSet::new();
    let mut faces: HashMap<[u32; 3], Vec<(usize, u32)>> = HashMap::new();
    for (ti, &t) in mesh.tets.iter().enumerate() {
        if t.iter().any(|&i| i as usize >= np) {
            err!("tet {ti} {t:?} has an out-of-range index (points: {np})");
            continue;
        }
        let mut s = t;
        s.sort_unstable();
        if s.windows(2).any(|w| w[0] == w[1]) {
            err!("tet {ti} {t:?} repeats a vertex");
            continue;
        }
        if !tetset.insert(s) {
            err!("tet {ti} {t:?} is a duplicate");
        }
        let v = tet_volume(mesh, t);
        if v.is_nan() || v <= 0.0 {
            err!(
                "tet {ti} {t:?} has non-positive volume {v:e} (points {:?})",
                t.map(|i| mesh.points[i as usize])
            );
        }
        for &i in &t {
            used[i as usize] = true;
        }
        for (f, opp) in tet_faces(t) {
            faces.entry(sorted3(f)).or_default().push((ti, opp));
        }
    }
    if let Some(i) = used.iter().position(|&u| !u) {
        err!(
            "point {i} ({:?}) is used by no tet ({} unused)",
            mesh.points[i],
            used.iter().filter(|&&u| !u).count()
        );
    }
    for (f, ts) in &faces {
        if ts.len() > 2 {
            err!(
                "face {f:?} shared by {} tets: {:?}",
                ts.len(),
                ts.iter().map(|x| x.0).collect::<Vec<_>>()
            );
        }
    }
    // boundary triangles == faces used by exactly one tet, outward oriented
    let mut bset: HashSet<[u32; 3]> = HashSet::new();
    for (bi, &tri) in mesh.boundary.iter().enumerate() {
        let s = sorted3(tri);
        if s[0] == s[1] || s[1] == s[2] {
            err!("boundary triangle {bi} {tri:?} repeats a vertex");
            continue;
        }
        if !bset.insert(s) {
            err!("boundary triangle {bi} {tri:?} is listed twice");
        }
        match faces.get(&s) {
            None => err!("boundary triangle {bi} {tri:?} is not a face of any tet"),
            Some(ts) if ts.len() != 1 => err!(
                "boundary triangle {bi} {tri:?} is shared by {} tets (interior face)",
                ts.len()
            ),
            Some(ts) => {
                let opp = mesh.points[ts[0].1 as usize];
                let p = tri.map(|i| mesh.points[i as usize]);
                let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
                let side = dot(n, sub(opp, p[0]));
                if side.is_nan() || side >= 0.0 {
                    err!("boundary triangle {bi} {tri:?} not outward: its tet's 4th vertex is on the positive side ({side:e})");
                }
            }
        }
    }
    let mut missing = 0;
    for (f, ts) in &faces {
        if ts.len() == 1 && !bset.contains(f) {
            if missing < 5 {
                err!(
                    "face {f:?} of tet {} is used once but is not a boundary triangle",
                    ts[0].0
                );
            }
            missing += 1;
        }
    }
    if missing > 5 {
        err!("... {missing} one-sided faces missing from the boundary in total");
    }
    errs.extend(boundary_manifold_errors(mesh));
    errs
}

/// The boundary is a closed, oriented 2-manifold: every directed edge once, its reverse once;
/// the link of every boundary vertex is one cycle.
pub fn boundary_manifold_errors(mesh: &TetMesh) -> Vec<String> {
    let mut errs = Vec::new();
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for &[a, b, c] in &mesh.boundary {
        for e in [(a, b), (b, c), (c, a)] {
            *directed.entry(e).or_default() += 1;
        }
    }
    for (&(u, v), &n) in &directed {
        let back = directed.get(&(v, u)).copied().unwrap_or(0);
        if (n != 1 || back != 1) && errs.len() < 10 {
            errs.push(format!(
                "boundary edge ({u},{v}) used {n} times in this direction and {back} reversed"
            ));
        }
    }
    // vertex links
    let mut link: HashMap<u32, Vec<(u32, u32)>> = HashMap::new();
    for &[a, b, c] in &mesh.boundary {
        link.entry(a).or_default().push((b, c));
        link.entry(b).or_default().push((c, a));
        link.entry(c).or_default().push((a, b));
    }
    for (v, edges) in &link {
        let mut next: HashMap<u32, u32> = HashMap::new();
        let mut ok = true;
        for &(x, y) in edges {
            if next.insert(x, y).is_some() {
                ok = false;
            }
        }
        if ok {
            // walk one cycle from the first edge; it must cover all edges
            let start = edges[0].0;
            let mut cur = start;
            let mut steps = 0;
            loop {
                match next.get(&cur) {
                    Some(&n) => cur = n,
                    None => {
                        ok = false;
                        break;
                    }
                }
                steps += 1;
                if cur == start || steps > edges.len() {
                    break;
                }
            }
            ok = ok && cur == start && steps == edges.len();
        }
        if !ok && errs.len() < 20 {
            errs.push(format!(
                "link of boundary vertex {v} ({:?}) is not a single cycle: {edges:?}",
                mesh.points[*v as usize]
            ));
        }
    }
    errs
}

/// Panics with all violated invariants.
pub fn check_mesh(mesh: &TetMesh) {
    let errs = mesh_errors(mesh);
    assert!(
        errs.is_empty(),
        "invalid mesh ({} tets, {} points):\n  {}",
        mesh.tets.len(),
        mesh.points.len(),
        errs.join("\n  ")
    );
}

/// Label consistency: alpha triangles have node values ≈ alpha, beta ones ≈ beta, box ones lie
/// on one face of the grid box [0, extent].
pub fn label_errors(mesh: &TetMesh, alpha: f64, beta: f64, extent: [f64; 3]) -> Vec<String> {
    let mut errs = Vec::new();
    let vmax = mesh.values.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    for (bi, (&tri, &lab)) in mesh.boundary.iter().zip(&mesh.boundary_labels).enumerate() {
        let bad = match lab {
            BoundaryLabel::Level(l) => {
                let lvl = if l == 0 { alpha } else { beta };
                let tol = 1e-9 * vmax.max(lvl.abs());
                !lvl.is_finite()
                    || tri
                        .iter()
                        .any(|&i| (mesh.values[i as usize] - lvl).abs() > tol)
            }
            BoundaryLabel::Box => {
                let p = tri.map(|i| mesh.points[i as usize]);
                !(0..3).any(|a| {
                    let tol = 1e-9 * extent[a].max(1.0);
                    p.iter().all(|q| q[a].abs() <= tol)
                        || p.iter().all(|q| (q[a] - extent[a]).abs() <= tol)
                })
            }
        };
        if bad && errs.len() < 10 {
            errs.push(format!(
                "boundary triangle {bi} labelled {lab:?} but values {:?} points {:?}",
                tri.map(|i| mesh.values[i as usize]),
                tri.map(|i| mesh.points[i as usize])
            ));
        }
    }
    errs
}

pub fn check_labels(mesh: &TetMesh, alpha: f64, beta: f64, extent: [f64; 3]) {
    let errs = label_errors(mesh, alpha, beta, extent);
    assert!(
        errs.is_empty(),
        "inconsistent labels:\n  {}",
        errs.join("\n  ")
    );
}

/// Betti numbers of the mesh, computed from its simplices: b0 = components of tets through
/// shared faces; χ = V − E + F − T; b2 = components of the boundary surface − b0 (valid for a
/// compact 3-manifold in R³); b1 = b0 + b2 − χ.
pub fn mesh_betti(mesh: &TetMesh) -> [usize; 3] {
    let nt = mesh.tets.len();
    if nt == 0 {
        return [0, 0, 0];
    }
    let mut dsu = UnionFind::new(nt);
    let mut faces: HashMap<[u32; 3], usize> = HashMap::new();
    let mut edges: HashSet<[u32; 2]> = HashSet::new();
    let mut verts: HashSet<u32> = HashSet::new();
    for (ti, &t) in mesh.tets.iter().enumerate() {
        for (f, _) in tet_faces(t) {
            let s = sorted3(f);
            if let Some(&o) = faces.get(&s) {
                dsu.union(ti as u32, o as u32);
            } else {
                faces.insert(s, ti);
            }
        }
        for i in 0..4 {
            verts.insert(t[i]);
            for j in i + 1..4 {
                edges.insert([t[i].min(t[j]), t[i].max(t[j])]);
            }
        }
    }
    let b0 = (0..nt as u32).filter(|&t| dsu.find(t) == t).count();
    let chi = verts.len() as i64 - edges.len() as i64 + faces.len() as i64 - nt as i64;
    let nb = mesh.boundary.len();
    let mut bd = UnionFind::new(nb);
    let mut by_edge: HashMap<[u32; 2], usize> = HashMap::new();
    for (bi, &[a, b, c]) in mesh.boundary.iter().enumerate() {
        for (u, v) in [(a, b), (b, c), (c, a)] {
            let e = [u.min(v), u.max(v)];
            if let Some(&o) = by_edge.get(&e) {
                bd.union(bi as u32, o as u32);
            } else {
                by_edge.insert(e, bi);
            }
        }
    }
    let bcomps = (0..nb as u32).filter(|&t| bd.find(t) == t).count();
    let b2 = bcomps as i64 - b0 as i64;
    let b1 = b0 as i64 + b2 - chi;
    // a negative value (impossible for a valid mesh) is reported as usize::MAX
    let f = |v: i64| if v < 0 { usize::MAX } else { v as usize };
    [b0, f(b1), f(b2)]
}

/// Per-cell mesh volume: every tet must lie in one closed grid cell; returns the volume per
/// cell (x fastest) or an error for a tet straddling cells.
pub fn per_cell_volumes(mesh: &TetMesh, cell_dims: [usize; 3]) -> Result<Vec<f64>, String> {
    let mut vols = vec![0.0; cell_dims[0] * cell_dims[1] * cell_dims[2]];
    for (ti, &t) in mesh.tets.iter().enumerate() {
        let p = t.map(|i| mesh.points[i as usize]);
        let mut cell = [0usize; 3];
        for a in 0..3 {
            let c = (p[0][a] + p[1][a] + p[2][a] + p[3][a]) / 4.0;
            let ci = (c.floor().max(0.0) as usize).min(cell_dims[a] - 1);
            let (lo, hi) = (ci as f64 - 1e-9, ci as f64 + 1.0 + 1e-9);
            if p.iter().any(|q| q[a] < lo || q[a] > hi) {
                return Err(format!(
                    "tet {ti} {t:?} straddles cells along axis {a}: {p:?}"
                ));
            }
            cell[a] = ci;
        }
        vols[cell[0] + cell_dims[0] * (cell[1] + cell_dims[1] * cell[2])] += tet_volume(mesh, t);
    }
    Ok(vols)
}

/// Outward faces of a positive tet `[a, b, c, d]`.
fn outward_faces(t: [u32; 4]) -> [[u32; 3]; 4] {
    [
        [t[1], t[2], t[3]],
        [t[0], t[3], t[2]],
        [t[0], t[1], t[3]],
        [t[0], t[2], t[1]],
    ]
}

/// The tets of region `k` as a mesh of their own: points renumbered, the faces that belong
/// to one of its tets as its boundary (labelled box: only the complex is judged here).
pub fn region_submesh(mesh: &TetMesh, k: u8) -> TetMesh {
    let regions = &mesh.regions.tets;
    let mut new_id: HashMap<u32, u32> = HashMap::new();
    let mut out = TetMesh::default();
    let mut count: HashMap<[u32; 3], ([u32; 3], usize)> = HashMap::new();
    for (t, _) in mesh.tets.iter().zip(regions).filter(|(_, &r)| r == k) {
        let t = t.map(|p| {
            *new_id.entry(p).or_insert_with(|| {
                out.points.push(mesh.points[p as usize]);
                out.values.push(mesh.values[p as usize]);
                (out.points.len() - 1) as u32
            })
        });
        out.tets.push(t);
        for f in outward_faces(t) {
            count.entry(sorted3(f)).or_insert((f, 0)).1 += 1;
        }
    }
    let mut faces: Vec<[u32; 3]> = (count.values())
        .filter(|(_, n)| *n == 1)
        .map(|(f, _)| *f)
        .collect();
    faces.sort_unstable();
    out.boundary_labels = vec![BoundaryLabel::Box; faces.len()];
    out.boundary = faces;
    out
}
