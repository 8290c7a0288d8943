//! Tests of the clipper: exact volumes, closed boundaries, every class pattern of a tet.

use super::*;
use crate::geom::signed_volume;
use crate::levels::{Bounds, Levels};
use crate::samples::Samples;

struct Collect {
    vol: f64,
    tets: usize,
    area_alpha: f64,
}
impl ClipSink for Collect {
    fn tet(&mut self, p: &[ClipPoint], t: [usize; 4]) {
        let v = signed_volume(p[t[0]].pos, p[t[1]].pos, p[t[2]].pos, p[t[3]].pos);
        assert!(v > 0.0);
        self.vol += v;
        self.tets += 1;
    }
    fn triangle(&mut self, p: &[ClipPoint], t: [usize; 3], label: BoundaryLabel) {
        if label == BoundaryLabel::ALPHA {
            for &i in &t {
                assert_eq!(p[i].val, 0.25);
            }
            self.area_alpha += 1.0;
        }
    }
}

/// Volume of {alpha < x+y+z < beta} in the unit simplex-corner tet, checked against the
/// closed form for the linear field f = x + y + z on tet (0, e1, e2, e3).
#[test]
fn clip_of_linear_tet_has_exact_volume() {
    let tv = [
        ClipVertex {
            key: 1 << 3,
            pos: [0.0, 0.0, 0.0],
            val: 0.0,
            box_mask: 0,
            snap: SNAP_NONE,
        },
        ClipVertex {
            key: 2 << 3,
            pos: [1.0, 0.0, 0.0],
            val: 1.0,
            box_mask: 0,
            snap: SNAP_NONE,
        },
        ClipVertex {
            key: 3 << 3,
            pos: [0.0, 1.0, 0.0],
            val: 1.0,
            box_mask: 0,
            snap: SNAP_NONE,
        },
        ClipVertex {
            key: 4 << 3,
            pos: [0.0, 0.0, 1.0],
            val: 1.0,
            box_mask: 0,
            snap: SNAP_NONE,
        },
    ];
    // volume of {x+y+z <= s} in the corner is s^3/6
    for (a, b) in [
        (0.25, 0.75),
        (f64::NEG_INFINITY, 0.5),
        (0.25, f64::INFINITY),
        (-1.0, 2.0),
    ] {
        let mut c = Collect {
            vol: 0.0,
            tets: 0,
            area_alpha: 0.0,
        };
        clip_tet(
            &tv,
            &Levels::interval(a, b)
                .with_ties(&vec![0.0, 1.0].into())
                .region(0),
            0,
            &mut c,
        );
        let cube = |s: f64| s.clamp(0.0, 1.0).powi(3) / 6.0;
        let want = cube(b) - cube(a);
        assert!((c.vol - want).abs() < 1e-14, "{a} {b}: {} vs {want}", c.vol);
    }
}
/// Collects the emitted tets' point keys.
struct Keys(Vec<[PointKey; 4]>);
impl ClipSink for Keys {
    fn tet(&mut self, p: &[ClipPoint], t: [usize; 4]) {
        self.0.push(t.map(|i| p[i].key));
    }
    fn triangle(&mut self, _: &[ClipPoint], _: [usize; 3], _: BoundaryLabel) {}
}

/// A prism piece (two vertices inside, two below) is coned from the vertex deeper inside
/// the interval, whichever key is smaller: every tet has it as a corner.
#[test]
fn pieces_are_coned_from_their_deepest_vertex() {
    let iv = Levels::interval(0.0, 1.0)
        .with_ties(&vec![-1.0, 1.0].into())
        .region(0);
    let pos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    for (shallow, deep) in [(0.1, 0.5), (0.95, 0.6)] {
        for deep_first in [false, true] {
            // Corners 0 and 1 are inside; the deep one has the larger key unless
            // `deep_first`.
            let vals = [shallow, deep, -1.0, -1.0];
            let mut keys = [1u64 << 3, 2 << 3, 3 << 3, 4 << 3];
            if deep_first {
                keys.swap(0, 1);
            }
            let tv: [ClipVertex; 4] = std::array::from_fn(|i| ClipVertex {
                key: keys[i],
                pos: pos[i],
                val: vals[i],
                box_mask: 0,
                snap: SNAP_NONE,
            });
            let mut out = Keys(Vec::new());
            clip_tet(&tv, &iv, 0, &mut out);
            let apex = vertex_point(keys[1]);
            assert_eq!(out.0.len(), 3, "a prism makes three tets");
            assert!(
                out.0.iter().all(|t| t.contains(&apex)),
                "{shallow} {deep} {deep_first}: not coned from the deepest vertex"
            );
        }
    }
}

#[test]
fn edge_index_inverts_edges() {
    let hand = [[9, 0, 1, 2], [0, 9, 3, 4], [1, 3, 9, 5], [2, 4, 5, 9]];
    for i in 0..4 {
        for j in 0..4 {
            if i != j {
                assert_eq!(edge_index(i, j), hand[i][j]);
                assert_eq!(EDGES[edge_index(i, j)], (i.min(j), i.max(j)));
            }
        }
    }
}

/// Every output tet and boundary triangle of one clip, as point keys.
#[derive(Default)]
struct Record {
    tets: Vec<[ClipPoint; 4]>,
    tris: Vec<([ClipPoint; 3], BoundaryLabel)>,
}
impl ClipSink for Record {
    fn tet(&mut self, p: &[ClipPoint], t: [usize; 4]) {
        self.tets.push(t.map(|i| p[i]));
    }
    fn triangle(&mut self, p: &[ClipPoint], t: [usize; 3], label: BoundaryLabel) {
        self.tris.push((t.map(|i| p[i]), label));
    }
}

/// Volume of `{f < s}` in the tet `pos` with linear `f` given by its vertex values,
/// computed without the clipper: the cubic closed forms when one or three vertices are
/// below `s`, an explicit three-tet split of the wedge when two are.
fn sublevel_volume(pos: &[[f64; 3]; 4], val: &[f64; 4], s: f64) -> f64 {
    let vol = signed_volume(pos[0], pos[1], pos[2], pos[3]);
    let mut o = [0usize, 1, 2, 3];
    o.sort_by(|&a, &b| val[a].total_cmp(&val[b]));
    let f = o.map(|i| val[i]);
    let p = o.map(|i| pos[i]);
    let below = f.iter().filter(|&&x| x < s).count();
    let at = |i: usize, j: usize| {
        let t = (s - f[i]) / (f[j] - f[i]);
        [0, 1, 2].map(|r| p[i][r] + t * (p[j][r] - p[i][r]))
    };
    match below {
        0 => 0.0,
        1 => vol * (s - f[0]).powi(3) / ((f[1] - f[0]) * (f[2] - f[0]) * (f[3] - f[0])),
        2 => {
            // prism (p0, c02, c03) – (p1, c12, c13), lateral edges p0p1, c02c12, c03c13
            let (a, b) = ([p[0], at(0, 2), at(0, 3)], [p[1], at(1, 2), at(1, 3)]);
            [
                [a[0], a[1], a[2], b[2]],
                [a[0], a[1], b[1], b[2]],
                [a[0], b[0], b[1], b[2]],
            ]
            .iter()
            .map(|t| signed_volume(t[0], t[1], t[2], t[3]).abs())
            .sum()
        }
        3 => vol * (1.0 - (f[3] - s).powi(3) / ((f[3] - f[0]) * (f[3] - f[1]) * (f[3] - f[2]))),
        _ => vol,
    }
}

/// Sorted key triple of a triangle.
fn tri_key(t: [PointKey; 3]) -> [PointKey; 3] {
    let mut k = t;
    k.sort();
    k
}

/// Checks one clip: positive pieces, the closed-form volume, and a closed boundary (each
/// tet face shared by two pieces or emitted as a boundary triangle lying on its level or
/// on its tet face, and every boundary edge used twice).
fn check_clip(tv: &[ClipVertex; 4], iv: &Bounds, case: &str) {
    let mut rec = Record::default();
    // each tet face f is on box plane f, so every boundary triangle is emitted
    clip_tet(tv, iv, 0b1111, &mut rec);
    if let Some(out) = snapped_face_corner(tv, iv) {
        check_snapped_face(tv, out, &rec, case);
        return;
    }
    let pos = tv.map(|v| v.pos);
    let eff = tv.map(|v| placed(&v, iv));
    let want = sublevel_volume(&pos, &eff, iv.get(1)) - sublevel_volume(&pos, &eff, iv.get(0));
    let (got, faces) = pieces(&rec, case);
    let scale = signed_volume(pos[0], pos[1], pos[2], pos[3]);
    assert!(
        (got - want).abs() <= 1e-9 * scale,
        "{case}: volume {got} vs {want}"
    );
    let mut boundary: std::collections::HashMap<[PointKey; 3], BoundaryLabel> = Default::default();
    let mut edges: std::collections::HashMap<[PointKey; 2], usize> = Default::default();
    for (t, label) in &rec.tris {
        check_on_boundary(tv, iv, t, *label, case);
        let k = t.map(|p| p.key);
        assert!(
            boundary.insert(tri_key(k), *label).is_none(),
            "{case}: twice"
        );
        for e in 0..3 {
            let (a, b) = (k[e], k[(e + 1) % 3]);
            *edges.entry([a.min(b), a.max(b)]).or_default() += 1;
        }
    }
    for (tri, n) in &faces {
        match n {
            1 => assert!(boundary.contains_key(tri), "{case}: open face {tri:?}"),
            2 => assert!(
                !boundary.contains_key(tri),
                "{case}: inner face on boundary"
            ),
            _ => panic!("{case}: face used {n} times"),
        }
    }
    let once = faces.values().filter(|&&n| n == 1).count();
    assert_eq!(
        once,
        boundary.len(),
        "{case}: boundary triangle without a tet"
    );
    assert!(
        edges.values().all(|&n| n == 2),
        "{case}: boundary not closed"
    );
}

/// If three corners are snapped to one level and the fourth lies beyond it (the piece
/// is their face, with no volume): the fourth.
fn snapped_face_corner(tv: &[ClipVertex; 4], iv: &Bounds) -> Option<usize> {
    [(SNAP_ALPHA, BELOW), (SNAP_BETA, ABOVE)]
        .into_iter()
        .find_map(|(snap, side)| {
            let snapped = tv.iter().filter(|v| v.snap == snap).count();
            let out = (0..4).find(|&i| tv[i].snap != snap)?;
            let beyond = classify(tv[out].val, iv) == side;
            (snapped == 3 && tv[out].snap == SNAP_NONE && beyond).then_some(out)
        })
}

/// The flat piece of three snapped corners: no tet, and their face as one boundary
/// triangle of their level whose normal points at the outside corner `out` (the domain
/// is the tet across the face).
fn check_snapped_face(tv: &[ClipVertex; 4], out: usize, rec: &Record, case: &str) {
    assert!(rec.tets.is_empty(), "{case}: a flat piece made tets");
    let [(t, label)] = rec.tris.as_slice() else {
        panic!("{case}: {} triangles instead of one", rec.tris.len());
    };
    let want = match tv[(out + 1) % 4].snap {
        SNAP_ALPHA => BoundaryLabel::ALPHA,
        _ => BoundaryLabel::BETA,
    };
    assert_eq!(*label, want, "{case}");
    let corners = (0..4)
        .filter(|&i| i != out)
        .map(|i| vertex_point(tv[i].key));
    let mut keys: Vec<PointKey> = corners.collect();
    keys.sort_unstable();
    assert_eq!(tri_key(t.map(|p| p.key)).to_vec(), keys, "{case}");
    let normal = cross(sub(t[1].pos, t[0].pos), sub(t[2].pos, t[0].pos));
    assert!(
        dot(normal, sub(tv[out].pos, t[0].pos)) > 0.0,
        "{case}: the face points away from the outside corner"
    );
}

/// Total volume of the pieces (each checked positive) and how often each face occurs.
fn pieces(rec: &Record, case: &str) -> (f64, std::collections::HashMap<[PointKey; 3], usize>) {
    let mut got = 0.0;
    let mut faces: std::collections::HashMap<[PointKey; 3], usize> = Default::default();
    for t in &rec.tets {
        let v = signed_volume(t[0].pos, t[1].pos, t[2].pos, t[3].pos);
        assert!(v > 0.0, "{case}: piece volume {v}");
        got += v;
        for skip in 0..4 {
            let k = [0, 1, 2, 3].map(|i| t[i].key);
            let tri = [k[(skip + 1) % 4], k[(skip + 2) % 4], k[(skip + 3) % 4]];
            *faces.entry(tri_key(tri)).or_default() += 1;
        }
    }
    (got, faces)
}

/// A boundary triangle lies on its level, or (box) within one face of the tet.
fn check_on_boundary(
    tv: &[ClipVertex; 4],
    iv: &Bounds,
    t: &[ClipPoint; 3],
    label: BoundaryLabel,
    case: &str,
) {
    match label {
        BoundaryLabel::ALPHA => assert!(t.iter().all(|p| p.val == iv.get(0)), "{case}"),
        BoundaryLabel::BETA => assert!(t.iter().all(|p| p.val == iv.get(1)), "{case}"),
        _ => {
            let on = |f: usize| {
                let [a, b, c] = TET_FACES[f].map(|i| tv[i].key);
                t.iter().all(|p| {
                    let (x, rest) = crate::keys::split(p.key);
                    let y = rest.map_or(x, |r| r.0);
                    [x, y].iter().all(|k| [a, b, c].contains(k))
                })
            };
            assert!((0..4).any(on), "{case}: box triangle off the tet faces");
        }
    }
}

fn rng(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
}

/// Every class pattern of the four vertices (below, equal to alpha, inside, equal to
/// beta, above), for a two-sided interval and both one-sided ones, on random tets with
/// random key orders.
#[test]
fn clip_every_class_pattern() {
    let mut seed = 7u64;
    let (inf, alpha, beta) = (f64::INFINITY, -0.5, 1.5);
    for (a, b) in [(alpha, beta), (alpha, inf), (-inf, beta)] {
        // 0 below, 1 = alpha, 2 inside, 3 = beta, 4 above, 5 snapped to alpha, 6 snapped
        // to beta; skip classes a bound rules out
        let classes: Vec<usize> = (0..7)
            .filter(|&c| a.is_finite() || !matches!(c, 0 | 1 | 5))
            .filter(|&c| b.is_finite() || !matches!(c, 3 | 4 | 6))
            .collect();
        let n = classes.len();
        for pattern in 0..n.pow(4) {
            let cls: [usize; 4] = std::array::from_fn(|i| classes[pattern / n.pow(i as u32) % n]);
            if !snaps_possible(&cls) {
                continue;
            }
            for _ in 0..4 {
                let tv = random_tet(&mut seed, cls, alpha, beta);
                let vals: Vec<f64> = tv.iter().map(|v| v.val).collect();
                let iv = Levels::interval(a, b).with_ties(&vals.into()).region(0);
                check_clip(&tv, &iv, &format!("({a}, {b}) classes {cls:?}"));
            }
        }
    }
}

/// A positively oriented random tet with vertex values of the given classes and shuffled
/// keys.
/// Whether `warp` can make these classes: at most three corners snapped to one level
/// (`warp`'s `Link::on_edge_ok`: a fourth would be a tet with four corners on it).
fn snaps_possible(cls: &[usize; 4]) -> bool {
    let count = |c: usize| cls.iter().filter(|&&x| x == c).count();
    count(5) <= 3 && count(6) <= 3
}

fn random_tet(seed: &mut u64, cls: [usize; 4], alpha: f64, beta: f64) -> [ClipVertex; 4] {
    let mut pos: [[f64; 3]; 4] = std::array::from_fn(|_| [0; 3].map(|_| rng(seed) * 2.0));
    while signed_volume(pos[0], pos[1], pos[2], pos[3]).abs() < 0.05 {
        pos = std::array::from_fn(|_| [0; 3].map(|_| rng(seed) * 2.0));
    }
    if signed_volume(pos[0], pos[1], pos[2], pos[3]) < 0.0 {
        pos.swap(2, 3);
    }
    let mut keys = [1u64, 2, 3, 4].map(|k| (k << 3) | (rng(seed) * 8.0) as u64);
    for i in (1..4).rev() {
        keys.swap(i, (rng(seed) * (i + 1) as f64) as usize);
    }
    std::array::from_fn(|i| ClipVertex {
        key: keys[i] + ((i as u64) << 8),
        pos: pos[i],
        val: match cls[i] {
            0 => alpha - 0.1 - rng(seed),
            1 => alpha,
            2 => alpha + (0.05 + 0.9 * rng(seed)) * (beta - alpha),
            3 | 6 => beta,
            5 => alpha,
            _ => beta + 0.1 + rng(seed),
        },
        box_mask: 0b1111 & !(1 << i),
        snap: match cls[i] {
            5 => SNAP_ALPHA,
            6 => SNAP_BETA,
            _ => SNAP_NONE,
        },
    })
}

/// Collects a region's tets (volume) and its boundary triangles by label, as point keys.
#[derive(Default)]
struct Region {
    vol: f64,
    tris: Vec<(BoundaryLabel, [PointKey; 3])>,
}
impl ClipSink for Region {
    fn tet(&mut self, p: &[ClipPoint], t: [usize; 4]) {
        let v = signed_volume(p[t[0]].pos, p[t[1]].pos, p[t[2]].pos, p[t[3]].pos);
        assert!(v > 0.0);
        self.vol += v;
    }
    fn triangle(&mut self, p: &[ClipPoint], t: [usize; 3], label: BoundaryLabel) {
        self.tris.push((label, t.map(|i| p[i].key)));
    }
}

/// A triangle's keys rotated to start at the smallest (orientation kept).
fn canonical(t: [PointKey; 3]) -> [PointKey; 3] {
    let r = (0..3).min_by_key(|&i| t[i]).unwrap();
    [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
}

/// Three levels, two regions: each tet clipped to each region's levels. The two sides of
/// the level between the regions are the same triangles (same keys, opposite orientation,
/// both labelled with the middle level's index), also where a corner equals that level
/// (it belongs to the region below); the regions' volumes add up to the clip of the union
/// when no corner is tied.
#[test]
fn two_regions_meet_in_the_same_triangles() {
    let pos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.1, 0.0],
        [0.2, 1.0, 0.1],
        [0.1, 0.3, 1.0],
    ];
    let choices = [0.2, 0.9, 1.5, 1.7, 2.1, 2.8, 1.5, 0.6];
    let data = Samples::from(choices.to_vec());
    let run = Levels::new(&[0.5, 1.5, 2.5]).unwrap().with_ties(&data);
    let union = Levels::interval(0.5, 2.5).with_ties(&data).region(0);
    let mut seed = 12345u64;
    for _ in 0..2000 {
        let vals: [f64; 4] = std::array::from_fn(|_| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            choices[(seed >> 33) as usize % choices.len()]
        });
        let tv: [ClipVertex; 4] = std::array::from_fn(|i| ClipVertex {
            key: ((i as u64 + 1) * 7 % 5) << 5,
            pos: pos[i],
            val: vals[i],
            box_mask: 0,
            snap: SNAP_NONE,
        });
        let mut r: [Region; 2] = Default::default();
        for (k, sink) in r.iter_mut().enumerate() {
            clip_tet(&tv, &run.region(k), 0, sink);
        }
        let side = |reg: &Region, level: u8, flip: bool| {
            let mut v: Vec<[PointKey; 3]> = (reg.tris.iter())
                .filter(|(l, _)| *l == BoundaryLabel::Level(level))
                .map(|&(_, [a, b, c])| canonical(if flip { [a, c, b] } else { [a, b, c] }))
                .collect();
            v.sort_unstable();
            v
        };
        assert_eq!(side(&r[0], 1, false), side(&r[1], 1, true), "{vals:?}");
        assert!(side(&r[0], 2, false).is_empty() && side(&r[1], 0, false).is_empty());
        if !vals.contains(&1.5) {
            let mut u = Region::default();
            clip_tet(&tv, &union, 0, &mut u);
            let sum = r[0].vol + r[1].vol;
            assert!((sum - u.vol).abs() <= 1e-13, "{vals:?}: {sum} vs {}", u.vol);
        }
    }
}
