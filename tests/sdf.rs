//! Closed surfaces as volumes (`tptd::sdf`, `tptd::io::read_surface`,
//! `tptd::volume_from_surface`): surfaces generated here, written as `.obj`, `.stl` and
//! `.ply`, read back, sampled as signed distances and meshed as `{d <= 0}`.

mod common;

use std::path::{Path, PathBuf};

use common::soup::{sphere, torus, write_obj, write_stl, Soup};

use tptd::check::{check_mesh, CheckOptions};
use tptd::io::read_surface;
use tptd::sdf::{surface_volume, SurfaceGridOptions, INSIDE_LEVEL};
use tptd::{mesh_interval, volume_from_surface, MeshOptions, Method, ScalarGrid, TetMesh};

/// Both soups in one.
fn join(a: Soup, b: Soup) -> Soup {
    let (mut p, mut t) = a;
    let off = p.len() as u32;
    p.extend(b.0);
    t.extend(b.1.iter().map(|x| x.map(|i| i + off)));
    (p, t)
}

/// The soup with its coordinates rounded to `f32` (what binary STL holds).
fn to_f32(s: Soup) -> Soup {
    (
        s.0.iter().map(|q| q.map(|x| f64::from(x as f32))).collect(),
        s.1,
    )
}

fn write_ascii_stl(path: &Path, (p, t): &Soup) {
    let mut s = String::from("solid test\n");
    for f in t {
        s += "facet normal 0 0 0\n outer loop\n";
        for &i in f {
            let q = p[i as usize];
            s += &format!("  vertex {} {} {}\n", q[0], q[1], q[2]);
        }
        s += " endloop\nendfacet\n";
    }
    s += "endsolid test\n";
    std::fs::write(path, s).unwrap();
}

/// PLY: ASCII, or binary little/big-endian with `double` (little) or `float` (big)
/// coordinates, an extra vertex property and a face `uchar` property to read past.
fn write_ply(path: &Path, (p, t): &Soup, format: &str) {
    let ty = if format == "binary_big_endian" {
        "float"
    } else {
        "double"
    };
    let mut b = format!(
        "ply\nformat {format} 1.0\ncomment test\nelement vertex {}\nproperty {ty} x\n\
         property {ty} y\nproperty {ty} z\nproperty uchar flag\nelement face {}\n\
         property list uchar int vertex_indices\nproperty uchar tag\nend_header\n",
        p.len(),
        t.len()
    )
    .into_bytes();
    for q in p {
        match format {
            "ascii" => b.extend(format!("{} {} {} 7\n", q[0], q[1], q[2]).bytes()),
            "binary_big_endian" => {
                q.iter().for_each(|x| b.extend((*x as f32).to_be_bytes()));
                b.push(7);
            }
            _ => {
                q.iter().for_each(|x| b.extend(x.to_le_bytes()));
                b.push(7);
            }
        }
    }
    for f in t {
        match format {
            "ascii" => b.extend(format!("3 {} {} {} 1\n", f[0], f[1], f[2]).bytes()),
            "binary_big_endian" => {
                b.push(3);
                f.iter().for_each(|i| b.extend((*i as i32).to_be_bytes()));
                b.push(1);
            }
            _ => {
                b.push(3);
                f.iter().for_each(|i| b.extend((*i as i32).to_le_bytes()));
                b.push(1);
            }
        }
    }
    std::fs::write(path, b).unwrap();
}

fn resolution(n: usize) -> SurfaceGridOptions {
    SurfaceGridOptions {
        resolution: Some(n),
        ..SurfaceGridOptions::default()
    }
}

/// `{d <= 0}` of `grid`, meshed by the default method.
fn solid(grid: &ScalarGrid) -> TetMesh {
    let opts = MeshOptions::new(f64::NEG_INFINITY, INSIDE_LEVEL, Method::Ctd);
    mesh_interval(grid, &opts).unwrap().mesh
}

/// Meshes `{d <= 0}` of `grid`, asserts the checker finds a valid embedding and returns
/// its Betti numbers.
fn checked_betti(name: &str, grid: &ScalarGrid) -> [usize; 3] {
    let mesh = solid(grid);
    let r = check_mesh(
        &mesh,
        &CheckOptions::with_grid(grid, f64::NEG_INFINITY, INSIDE_LEVEL),
    );
    assert!(r.valid, "{name}: {}", r.summary_line());
    r.betti.unwrap()
}

fn file(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

#[test]
fn closed_torus_obj_meshes_as_a_solid_torus() {
    let dir = tempfile::tempdir().unwrap();
    let path = file(&dir, "torus.obj");
    write_obj(&path, &torus(1.0, 0.4, 64, 32));
    let (grid, facts) = volume_from_surface(&path, &resolution(56)).unwrap();
    assert!(
        facts.is_watertight() && facts.warnings().is_empty(),
        "{facts:?}"
    );
    assert_eq!(facts.triangles, 64 * 32 * 2);
    assert_eq!(checked_betti("torus", &grid), [1, 1, 0]);
}

#[test]
fn two_spheres_closer_than_a_voxel_stay_apart_when_resolved() {
    // gap 0.06: under one voxel at the default resolution (4.06 / 64 = 0.063), two at 140
    let gap = 0.06;
    let x = 1.0 + gap / 2.0;
    let s = join(
        sphere([-x, 0.0, 0.0], 1.0, 4),
        sphere([x, 0.0, 0.0], 1.0, 4),
    );
    let dir = tempfile::tempdir().unwrap();
    let path = file(&dir, "two.stl");
    write_stl(&path, &s);
    let default = volume_from_surface(&path, &SurfaceGridOptions::default()).unwrap();
    assert!(default.0.spacing[0] > gap, "{:?}", default.0.spacing);
    let (grid, facts) = volume_from_surface(&path, &resolution(140)).unwrap();
    assert!(facts.is_watertight(), "{facts:?}");
    assert!(grid.spacing[0] * 2.0 <= gap, "{:?}", grid.spacing);
    let mesh = solid(&grid);
    assert_eq!(tptd::topology::betti(&mesh), [2, 0, 0]);
}

#[test]
fn sphere_with_a_hole_keeps_its_inside_and_reports_the_hole() {
    let (p, t) = sphere([0.0; 3], 1.0, 4);
    let cut = |f: &[u32; 3]| f.iter().all(|&i| p[i as usize][2] > 0.985);
    let kept: Vec<[u32; 3]> = t.iter().filter(|f| !cut(f)).copied().collect();
    let removed = t.len() - kept.len();
    assert!(removed > 0 && removed <= 20, "{removed}");
    let (grid, facts) = surface_volume(&p, &kept, &resolution(40)).unwrap();
    assert_eq!((facts.holes, facts.closed), (1, false), "{facts:?}");
    // the rim lies inside the circle z = 0.985 of circumference 2π √(1 − 0.985²) ≈ 1.08,
    // around the pole, along edges of about 0.1
    assert!(
        facts.largest_hole > 0.3 && facts.largest_hole < 1.5,
        "{} ({removed} triangles removed)",
        facts.largest_hole
    );
    assert!(
        facts.warnings()[0].contains("1 hole"),
        "{:?}",
        facts.warnings()
    );
    let at = |q: [f64; 3]| {
        let idx = [0, 1, 2].map(|a| ((q[a] - grid.origin[a]) / grid.spacing[a]).round() as usize);
        grid.value(idx[0], idx[1], idx[2])
    };
    assert!(at([0.0, 0.0, 0.0]) < -0.9);
    assert!(
        at([0.0, 0.0, 0.8]) < 0.0,
        "under the hole: {}",
        at([0.0, 0.0, 0.8])
    );
    assert!(at([0.0, 0.0, 1.1]) > 0.0);
    assert!(at([1.1, 0.0, 0.0]) > 0.0);
    assert_eq!(checked_betti("holed sphere", &grid), [1, 0, 0]);
}

#[test]
fn overlapping_spheres_in_one_file_are_one_solid() {
    let s = join(
        sphere([-0.5, 0.0, 0.0], 1.0, 3),
        sphere([0.5, 0.0, 0.0], 1.0, 3),
    );
    let dir = tempfile::tempdir().unwrap();
    let path = file(&dir, "overlap.ply");
    write_ply(&path, &s, "binary_little_endian");
    let (grid, facts) = volume_from_surface(&path, &resolution(48)).unwrap();
    assert!(facts.closed, "{facts:?}");
    assert_eq!(checked_betti("overlap", &grid), [1, 0, 0]);
}

#[test]
fn unit_sphere_distance_within_the_chordal_error() {
    let (p, t) = sphere([0.0; 3], 1.0, 5);
    // the deepest point of a triangle below the sphere: 1 − its plane's distance
    let sag = t
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| p[i as usize]);
            let (u, v) = (
                [0, 1, 2].map(|k| b[k] - a[k]),
                [0, 1, 2].map(|k| c[k] - a[k]),
            );
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            1.0 - (n[0] * a[0] + n[1] * a[1] + n[2] * a[2]).abs() / len
        })
        .fold(0.0, f64::max);
    assert!(sag > 0.0 && sag < 2e-3, "{sag}");
    let (grid, _) = surface_volume(&p, &t, &resolution(40)).unwrap();
    let mut worst: f64 = 0.0;
    for k in 0..grid.dims[2] {
        for j in 0..grid.dims[1] {
            for i in 0..grid.dims[0] {
                let q = grid.to_physical([i as f64, j as f64, k as f64]);
                let exact = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt() - 1.0;
                worst = worst.max((grid.value(i, j, k) - exact).abs());
            }
        }
    }
    assert!(worst <= sag + 1e-12, "worst {worst}, sag {sag}");
}

#[test]
fn the_same_surface_in_every_format_gives_the_same_grid() {
    let s = to_f32(join(
        torus(1.0, 0.3, 24, 12),
        sphere([0.0, 0.0, 0.9], 0.35, 2),
    ));
    let dir = tempfile::tempdir().unwrap();
    let mut paths = vec![
        file(&dir, "s.obj"),
        file(&dir, "s.stl"),
        file(&dir, "a.stl"),
    ];
    write_obj(&paths[0], &s);
    write_stl(&paths[1], &s);
    write_ascii_stl(&paths[2], &s);
    for f in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let path = file(&dir, &format!("{f}.PLY"));
        write_ply(&path, &s, f);
        paths.push(path);
    }
    let soups: Vec<_> = paths.iter().map(|p| read_surface(p).unwrap()).collect();
    for (p, soup) in paths.iter().zip(&soups) {
        assert_eq!(soup, &soups[0], "{}", p.display());
    }
    let first = volume_from_surface(&paths[0], &resolution(32)).unwrap().0;
    for p in &paths[1..] {
        let g = volume_from_surface(p, &resolution(32)).unwrap().0;
        assert_eq!(g, first, "{}", p.display());
    }
    // the same for any thread count
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let single = one.install(|| volume_from_surface(&paths[1], &resolution(32)).unwrap().0);
    assert_eq!(single, first);
}

#[test]
fn bad_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let tet = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty.obj", vec![], "empty"),
        ("empty.stl", vec![], "empty"),
        ("empty.ply", vec![], "empty"),
        ("range.obj", format!("{tet}f 1 2 3\nf 1 2 9\n").into_bytes(), "out of bounds"),
        ("nan.obj", format!("{tet}v nan 0 0\nf 1 2 5\n").into_bytes(), "not finite"),
        ("lines.obj", format!("{tet}l 1 2\n").into_bytes(), "no triangles"),
        ("notply.ply", b"solid x\n".to_vec(), "ply"),
        (
            "range.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
              end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"
                .to_vec(),
            "point 4",
        ),
        (
            "short.ply",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
              property float y\nproperty float z\nend_header\n\x00\x00"
                .to_vec(),
            "truncated",
        ),
        ("nan.stl", b"solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex NaN 1 0\nendloop\nendfacet\nendsolid\n".to_vec(), "not finite"),
        ("cut.stl", b"solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\n".to_vec(), "truncated"),
        ("surface.off", b"OFF\n".to_vec(), "unknown surface format"),
    ];
    for (name, bytes, want) in &cases {
        let path = file(&dir, name);
        std::fs::write(&path, bytes).unwrap();
        let e = read_surface(&path).unwrap_err().to_string();
        assert!(e.starts_with(&path.display().to_string()), "{name}: {e}");
        assert!(e.contains(want) && !e.contains('\n'), "{name}: {e}");
    }
    // a binary STL cut short
    let path = file(&dir, "truncated.stl");
    write_stl(&path, &sphere([0.0; 3], 1.0, 1));
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 30]).unwrap();
    let e = read_surface(&path).unwrap_err().to_string();
    assert!(e.contains("truncated"), "{e}");
    assert!(read_surface(&file(&dir, "missing.stl")).is_err());
    // read, but not a solid: every triangle flat
    let path = file(&dir, "flat.obj");
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let e = volume_from_surface(&path, &SurfaceGridOptions::default()).unwrap_err();
    assert!(
        e.to_string().starts_with(&path.display().to_string()),
        "{e}"
    );
    let both = SurfaceGridOptions {
        resolution: Some(10),
        voxel_size: Some(0.1),
        ..SurfaceGridOptions::default()
    };
    let (p, t) = sphere([0.0; 3], 1.0, 1);
    assert!(surface_volume(&p, &t, &both).is_err());
    let tiny = SurfaceGridOptions {
        voxel_size: Some(1e-12),
        ..SurfaceGridOptions::default()
    };
    assert!(surface_volume(&p, &t, &tiny).is_err());
}

/// A UV sphere of `nu × nv` quads (about `2 nu nv` triangles), outward.
fn uv_sphere(nu: usize, nv: usize) -> Soup {
    let (tau, pi) = (std::f64::consts::TAU, std::f64::consts::PI);
    let mut p = vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    for j in 1..nv {
        let v = pi * j as f64 / nv as f64;
        for i in 0..nu {
            let u = tau * i as f64 / nu as f64;
            p.push([v.sin() * u.cos(), v.sin() * u.sin(), v.cos()]);
        }
    }
    let id = |i: usize, j: usize| (2 + (j - 1) * nu + i % nu) as u32;
    let mut t = Vec::new();
    for i in 0..nu {
        t.push([0, id(i, 1), id(i + 1, 1)]);
        t.push([1, id(i + 1, nv - 1), id(i, nv - 1)]);
        for j in 1..nv - 1 {
            let (a, b, c, d) = (id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    (p, t)
}

/// How long the grids of a 20k-triangle surface take (`cargo test --release --test sdf
/// -- --ignored --nocapture`).
#[test]
#[ignore]
fn timing_128_and_256() {
    let (p, t) = uv_sphere(100, 100);
    println!("{} triangles", t.len());
    for n in [128, 256] {
        let start = std::time::Instant::now();
        let (grid, _) = surface_volume(&p, &t, &resolution(n)).unwrap();
        println!(
            "resolution {n}: {:?} points in {:.2} s on {} threads",
            grid.dims,
            start.elapsed().as_secs_f64(),
            rayon::current_num_threads()
        );
    }
}
