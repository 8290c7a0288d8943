//! The checker on meshes built to fail each check, and on small meshes that pass.

use super::*;
use crate::geom::signed_volume;
use crate::mesh::BoundaryLabel;
use crate::{mesh_interval, MeshOptions, Method};
use ProblemKind::*;

type P = [f64; 3];

/// `t` reordered to be positive (two corners swapped when negative).
fn positive(points: &[P], mut t: [u32; 4]) -> [u32; 4] {
    let [a, b, c, d] = t.map(|v| points[v as usize]);
    if signed_volume(a, b, c, d) < 0.0 {
        t.swap(2, 3);
    }
    t
}

/// A mesh of `points` and `tets` (made positive), without labelled boundary triangles.
fn mesh(points: Vec<P>, tets: &[[u32; 4]]) -> TetMesh {
    let tets = tets.iter().map(|&t| positive(&points, t)).collect();
    TetMesh {
        regions: Default::default(),
        values: vec![0.0; points.len()],
        points,
        tets,
        boundary: Vec::new(),
        boundary_labels: Vec::new(),
    }
}

fn unit_tet() -> Vec<P> {
    vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ]
}

/// Unit cubes at the integer positions `cells` (each split into the six Kuhn tets along its
/// main diagonal); corners at the same position are one point, except in the cubes
/// `moved`, which get their own points shifted by `shift`.
fn cubes(cells: &[[i32; 3]], moved: &[usize], shift: P) -> TetMesh {
    let mut points: Vec<P> = Vec::new();
    let mut ids = std::collections::HashMap::new();
    let mut tets = Vec::new();
    for (n, c) in cells.iter().enumerate() {
        let own = moved.contains(&n);
        let corner: Vec<u32> = (0..8)
            .map(|k| {
                let p = [0, 1, 2].map(|a| c[a] + ((k >> a) & 1));
                let pos = p.map(|x| x as f64);
                if own {
                    points.push([0, 1, 2].map(|a| pos[a] + shift[a]));
                    return points.len() as u32 - 1;
                }
                *ids.entry(p).or_insert_with(|| {
                    points.push(pos);
                    points.len() as u32 - 1
                })
            })
            .collect();
        for perm in [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ] {
            let (a, b) = (1 << perm[0], 1 << perm[0] | 1 << perm[1]);
            tets.push([corner[0], corner[a], corner[b], corner[7]]);
        }
    }
    mesh(points, &tets)
}

/// The four faces of a tet (unoriented).
fn faces_of(t: &[u32; 4]) -> [[u32; 3]; 4] {
    [
        [t[1], t[2], t[3]],
        [t[0], t[2], t[3]],
        [t[0], t[1], t[3]],
        [t[0], t[1], t[2]],
    ]
}

fn check(m: &TetMesh) -> CheckReport {
    check_mesh(m, &CheckOptions::default())
}

/// The kinds of `r`, for comparing with `assert_eq!`.
fn kinds(r: &CheckReport) -> Vec<ProblemKind> {
    r.kinds()
}

#[test]
fn one_tet_and_a_block_of_cubes_are_valid() {
    let r = check(&mesh(unit_tet(), &[[0, 1, 2, 3]]));
    assert!(r.valid, "{:?}", r.problems);
    assert_eq!(r.betti, Some([1, 0, 0]));
    assert_eq!(r.boundary_faces, 4);
    assert!((r.volume - 1.0 / 6.0).abs() < 1e-15);
    let w = r.winding.as_ref().unwrap();
    assert_eq!((w.samples, w.exact, w.min, w.max), (1, 1, 1.0, 1.0));
    assert!(w.max_deviation < 1e-12);

    let cells: Vec<[i32; 3]> = (0..27).map(|i| [i % 3, i / 3 % 3, i / 9]).collect();
    let r = check(&cubes(&cells, &[], [0.0; 3]));
    assert!(r.valid, "{:?}", r.problems);
    assert_eq!(r.betti, Some([1, 0, 0]));
    assert!((r.volume - 27.0).abs() < 1e-12);
    assert_eq!(r.winding.as_ref().unwrap().samples, 27 * 6);
    // A ring of 8 cubes: a solid torus.
    let ring = [
        [0, 0, 0],
        [1, 0, 0],
        [2, 0, 0],
        [2, 1, 0],
        [2, 2, 0],
        [1, 2, 0],
        [0, 2, 0],
        [0, 1, 0],
    ];
    let r = check(&cubes(&ring, &[], [0.0; 3]));
    assert!(r.valid, "{:?}", r.problems);
    assert_eq!(r.betti, Some([1, 1, 0]));
}

#[test]
fn two_overlapping_tets_have_winding_number_two() {
    let mut p = unit_tet();
    p.extend(unit_tet().iter().map(|q| q.map(|x| x + 0.1)));
    let r = check(&mesh(p, &[[0, 1, 2, 3], [4, 5, 6, 7]]));
    assert_eq!(kinds(&r), [BoundarySelfIntersection, WindingNumber]);
    let w = r.winding.as_ref().unwrap();
    // The first centroid lies in both tets, the second in the second only.
    assert_eq!((w.min, w.max, w.off), (1.0, 2.0, 1));
    assert!(w.max_deviation < 1e-9);
    assert_eq!(r.problems[1].examples, [vec![0]]);
}

#[test]
fn a_strip_of_cubes_bent_onto_itself_overlaps() {
    // A ring of 8 cubes whose last cube is pushed 0.3 into the first instead of joining it.
    let ring = [
        [0, 0, 0],
        [1, 0, 0],
        [2, 0, 0],
        [2, 1, 0],
        [2, 2, 0],
        [1, 2, 0],
        [0, 2, 0],
        [0, 1, 0],
    ];
    let r = check(&cubes(&ring, &[7], [0.0, -0.3, 0.0]));
    assert_eq!(
        kinds(&r),
        [BoundarySelfIntersection, BoundaryOverlap, WindingNumber]
    );
    assert_eq!(r.winding.as_ref().unwrap().max, 2.0);
    // Every tet positive and the boundary a closed manifold: the Betti numbers see two
    // solid cubes' worth of components (the moved cube has its own points), not the overlap.
    assert_eq!(r.betti, Some([2, 0, 0]));
}

/// Rotation of `p` by `angle` about the unit axis `k` (Rodrigues).
fn rotate(p: P, k: P, angle: f64) -> P {
    let (s, c) = angle.sin_cos();
    let kxp = [
        k[1] * p[2] - k[2] * p[1],
        k[2] * p[0] - k[0] * p[2],
        k[0] * p[1] - k[1] * p[0],
    ];
    let kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
    [0, 1, 2].map(|a| p[a] * c + kxp[a] * s + k[a] * kp * (1.0 - c))
}

#[test]
fn a_boundary_folded_through_a_shared_vertex_crosses_itself() {
    // The second tet is the first turned by 20° about an axis through their common corner:
    // their boundaries cross through that corner.
    let n = (1.0f64 + 4.0 + 9.0).sqrt();
    let axis = [1.0 / n, 2.0 / n, 3.0 / n];
    let mut p = unit_tet();
    p.extend(unit_tet()[1..].iter().map(|&q| rotate(q, axis, 0.35)));
    let r = check(&mesh(p, &[[0, 1, 2, 3], [0, 4, 5, 6]]));
    assert_eq!(
        kinds(&r),
        [
            NonManifoldBoundaryVertex,
            BoundarySelfIntersection,
            WindingNumber
        ]
    );
}

#[test]
fn a_coplanar_fold_over_an_edge_is_an_overlap() {
    // Two tets on either side of the plane z = 0 sharing the edge 0–1; their faces in the
    // plane overlap (a fold), though no volume does.
    let mut p = unit_tet();
    p.push([0.2, 0.6, 0.0]);
    p.push([0.3, 0.3, -1.0]);
    let r = check(&mesh(p, &[[0, 1, 2, 3], [0, 1, 4, 5]]));
    // The second tet's edge 0–4 also touches the first one's face along a segment.
    assert_eq!(
        kinds(&r),
        [
            NonManifoldBoundaryEdge,
            NonManifoldBoundaryVertex,
            BoundarySelfIntersection,
            BoundaryOverlap
        ]
    );
    assert_eq!(r.winding.as_ref().unwrap().off, 0);
}

#[test]
fn a_hanging_face_is_not_conforming() {
    // Tet 0 above the face (a, b, c); below it, two tets split that face at the midpoint m
    // of ab: the face is not shared.
    let p = vec![
        [0.0, 0.0, 0.0],  // a
        [2.0, 0.0, 0.0],  // b
        [0.0, 2.0, 0.0],  // c
        [0.5, 0.5, 1.0],  // d
        [1.0, 0.0, 0.0],  // m
        [0.5, 0.5, -1.0], // e
    ];
    let r = check(&mesh(p, &[[0, 1, 2, 3], [0, 4, 2, 5], [4, 1, 2, 5]]));
    // The faces below touch the one above along a (the edge am of (a, m, e) lies in it).
    assert_eq!(
        kinds(&r),
        [
            NonManifoldBoundaryEdge,
            NonManifoldBoundaryVertex,
            BoundarySelfIntersection,
            BoundaryOverlap
        ]
    );
    assert!(r.betti.is_none());
}

#[test]
fn inverted_and_degenerate_tets() {
    let m = TetMesh {
        points: unit_tet(),
        values: vec![0.0; 4],
        tets: vec![[0, 2, 1, 3]],
        ..TetMesh::default()
    };
    let r = check(&m);
    assert_eq!(kinds(&r), [InvertedTet, WindingNumber]);
    assert_eq!(r.winding.as_ref().unwrap().min, -1.0);
    assert!(r.volume < 0.0);
    // An inverted tet among others: its faces lie on the same side as its neighbours'.
    let mut m = cubes(&[[0, 0, 0], [1, 0, 0]], &[], [0.0; 3]);
    m.tets[0].swap(0, 1);
    let r = check(&m);
    assert!(
        r.has(InvertedTet) && r.has(TetsOnSameSideOfFace),
        "{:?}",
        r.kinds()
    );
    // Four coplanar points.
    let mut p = unit_tet();
    p[3] = [0.3, 0.3, 0.0];
    let r = check(&mesh(p, &[[0, 1, 2, 3]]));
    assert!(r.has(DegenerateTet), "{:?}", r.kinds());
    assert!(!r.has(InvertedTet));
}

#[test]
fn a_duplicate_tet_is_found() {
    let r = check(&mesh(unit_tet(), &[[0, 1, 2, 3], [3, 2, 1, 0]]));
    // The faces are judged without the copy; the tets' volume counts it.
    assert_eq!(kinds(&r), [DuplicateTet, VolumeMismatch]);
    assert_eq!(r.problems[0].examples, [vec![0, 1]]);
    // Among others, reported once (not at each of its faces).
    let mut m = cubes(&[[0, 0, 0], [1, 0, 0]], &[], [0.0; 3]);
    m.tets.push(m.tets[3]);
    let r = check(&m);
    assert_eq!(kinds(&r), [DuplicateTet, VolumeMismatch]);
    assert_eq!(r.problems[0].examples, [vec![3, 12]]);
    assert_eq!(r.problems[0].count, 1);
    // A face in three tets: a third tet on the face between two cubes.
    let mut m = cubes(&[[0, 0, 0], [1, 0, 0]], &[], [0.0; 3]);
    let shared = m
        .tets
        .iter()
        .flat_map(|t| t.iter())
        .copied()
        .filter(|&v| m.points[v as usize][0] == 1.0);
    let mut on_plane: Vec<u32> = shared.collect();
    on_plane.sort_unstable();
    on_plane.dedup();
    // A face the two cubes share (on the plane x = 1), and a new apex off that plane.
    let face = m
        .tets
        .iter()
        .find_map(|t| {
            faces_of(t)
                .into_iter()
                .find(|f| f.iter().all(|v| on_plane.contains(v)))
        })
        .unwrap();
    m.points.push([1.2, 0.5, 0.5]);
    let apex = m.points.len() as u32 - 1;
    let t = positive(&m.points, [face[0], face[1], face[2], apex]);
    m.tets.push(t);
    let r = check(&m);
    assert!(r.has(FaceInThreeOrMoreTets), "{:?}", r.kinds());
}

#[test]
fn non_manifold_boundaries() {
    // Two tets sharing only an edge.
    let mut p = unit_tet();
    p.push([-1.0, -1.0, 0.5]);
    p.push([-1.0, 0.0, -1.0]);
    let r = check(&mesh(p, &[[0, 1, 2, 3], [0, 3, 4, 5]]));
    assert_eq!(
        kinds(&r),
        [NonManifoldBoundaryEdge, NonManifoldBoundaryVertex]
    );
    assert!(r.betti.is_none());
    // Two cubes sharing only a corner.
    let r = check(&cubes(&[[0, 0, 0], [1, 1, 1]], &[], [0.0; 3]));
    assert_eq!(kinds(&r), [NonManifoldBoundaryVertex]);
    assert_eq!(r.problems[0].examples, [vec![7]]);
}

#[test]
fn labelled_boundary_must_be_the_faces_of_one_tet() {
    let outward = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];
    let labelled = |tris: Vec<[u32; 3]>| {
        let mut m = mesh(unit_tet(), &[[0, 1, 2, 3]]);
        m.boundary_labels = vec![BoundaryLabel::Box; tris.len()];
        m.boundary = tris;
        m
    };
    let r = check(&labelled(outward.to_vec()));
    assert!(r.valid, "{:?}", r.problems);
    let r = check(&labelled(outward[..3].to_vec()));
    assert_eq!(kinds(&r), [BoundaryFaceUnlisted, VolumeMismatch]);
    let mut inward = outward.to_vec();
    inward[1] = [0, 2, 3];
    let r = check(&labelled(inward));
    assert_eq!(kinds(&r), [BoundaryTriangleInward, VolumeMismatch]);
    assert_eq!(r.problems[0].examples, [vec![1]]);
    let mut extra = outward.to_vec();
    extra.push([0, 2, 1]);
    let r = check(&labelled(extra));
    assert_eq!(kinds(&r), [ListedFaceNotBoundary, VolumeMismatch]);
    let mut m = labelled(outward.to_vec());
    m.boundary_labels.pop();
    assert_eq!(kinds(&check(&m)), [LabelCount]);
    let mut m = labelled(outward.to_vec());
    m.tets[0][3] = 9;
    assert_eq!(kinds(&check(&m)), [BadIndex]);
    let mut m = labelled(outward.to_vec());
    m.points[1][0] = f64::NAN;
    assert_eq!(kinds(&check(&m)), [NonFinitePoint]);
}

/// A 6³ grid of `f = x + 0.3 y` on a spacing of (2, 1, 1) from `(10, 0, 0)` and its mesh of
/// `[alpha, beta]`.
fn ramp(alpha: f64, beta: f64) -> (ScalarGrid, TetMesh) {
    let n = 6;
    let values: Vec<f64> = (0..n * n * n)
        .map(|i| (i % n) as f64 + 0.3 * (i / n % n) as f64)
        .collect();
    let grid = ScalarGrid::with_geometry(
        [n; 3],
        [2.0, 1.0, 1.0],
        [10.0, 0.0, 0.0],
        crate::grid::IDENTITY,
        values,
    )
    .unwrap();
    let m = mesh_interval(&grid, &MeshOptions::new(alpha, beta, Method::Ctd))
        .unwrap()
        .mesh;
    (grid, m)
}

/// The points of alpha triangles, and the alpha triangles.
fn alpha_points(m: &TetMesh) -> Vec<u32> {
    let mut v: Vec<u32> = m
        .boundary
        .iter()
        .zip(&m.boundary_labels)
        .filter(|(_, &l)| l == BoundaryLabel::ALPHA)
        .flat_map(|(t, _)| *t)
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
fn a_triangle_off_its_level_by_more_than_the_bound() {
    let (grid, m) = ramp(1.65, 3.15);
    let opts = CheckOptions::with_grid(&grid, 1.65, 3.15);
    let r = check_mesh(&m, &opts);
    assert!(r.valid, "{:?}", r.problems);
    let l = r.level.as_ref().unwrap();
    assert!(l.max_distance < 1e-9 && l.points > 0, "{l:?}");
    // An alpha point moved out of the domain (towards lower x) by 0.3 and 0.8 voxels along x
    // (index units; 0.6 and 1.6 physical units).
    let v = alpha_points(&m)[0] as usize;
    for (shift, off) in [(0.3, false), (0.8, true)] {
        let mut moved = m.clone();
        moved.points[v][0] -= 2.0 * shift;
        let r = check_mesh(&moved, &opts);
        let l = r.level.as_ref().unwrap();
        if off {
            assert_eq!(kinds(&r), [OffLevel]);
            assert!(l.beyond > 0);
            // How far, found by the search out to four times the bound.
            let d = 0.8 / (1.0f64 + 0.09).sqrt();
            assert!((l.max_beyond - d).abs() < 1e-6, "{l:?} vs {d}");
        } else {
            assert!(r.valid, "{:?}", r.problems);
            // The level set x + 0.3 y = 1.65 is a plane: the distance of the moved corner.
            let d = 0.3 / (1.0f64 + 0.09).sqrt();
            assert!((l.max_distance - d).abs() < 1e-6, "{l:?} vs {d}");
        }
    }
    // A tighter bound catches the smaller shift too.
    let mut moved = m.clone();
    moved.points[v][0] -= 0.6;
    let tight = CheckOptions {
        level_distance_bound: 0.2,
        ..opts
    };
    assert_eq!(kinds(&check_mesh(&moved, &tight)), [OffLevel]);
    // The wrong level.
    let r = check_mesh(&m, &CheckOptions::with_grid(&grid, 2.9, 3.15));
    assert_eq!(kinds(&r), [OffLevel]);
}

#[test]
fn box_triangles_lie_on_the_box_and_labelled_points_in_it() {
    let (grid, m) = ramp(1.65, 3.15);
    let opts = CheckOptions::with_grid(&grid, 1.65, 3.15);
    let mut relabelled = m.clone();
    let t = relabelled
        .boundary_labels
        .iter()
        .position(|&l| l == BoundaryLabel::ALPHA)
        .unwrap();
    relabelled.boundary_labels[t] = BoundaryLabel::Box;
    let r = check_mesh(&relabelled, &opts);
    assert_eq!(kinds(&r), [BoxTriangleOffBox]);
    assert_eq!(r.problems[0].examples, [vec![t]]);
    assert_eq!(r.level.as_ref().unwrap().box_off, 1);
    // A mesh of the whole box has an alpha-free boundary on the box.
    let (_, whole) = ramp(-1.0, 100.0);
    let r = check_mesh(&whole, &CheckOptions::with_grid(&grid, -1.0, 100.0));
    assert!(r.valid, "{:?}", r.problems);
    // The grid shifted by half its width: every alpha point lies outside it.
    let mut far = grid.clone();
    far.origin[1] += 100.0;
    let r = check_mesh(&m, &CheckOptions::with_grid(&far, 1.65, 3.15));
    assert!(
        r.has(OutsideGrid) && r.has(BoxTriangleOffBox),
        "{:?}",
        r.kinds()
    );
    assert!(r.level.as_ref().unwrap().outside > 0);
}

#[test]
fn the_report_does_not_depend_on_the_thread_count() {
    let (grid, m) = ramp(1.65, 3.15);
    let opts = CheckOptions {
        winding_samples: 50,
        ..CheckOptions::with_grid(&grid, 1.65, 3.15)
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| check_mesh(&m, &opts))
    };
    let one = run(1);
    assert!(one.valid, "{:?}", one.problems);
    assert_eq!(
        one.winding.as_ref().unwrap().samples,
        m.tets.len().div_ceil(m.tets.len().div_ceil(50))
    );
    assert_eq!(one, run(3));
    let json = serde_json::to_string(&one).unwrap();
    assert!(json.contains("\"valid\":true"), "{json}");
    // Problems serialise with their kind's name.
    let mut bad = m.clone();
    bad.tets.push(bad.tets[0]);
    let json = serde_json::to_string(&check(&bad)).unwrap();
    assert!(json.contains("\"kind\":\"duplicate_tet\""), "{json}");
}
