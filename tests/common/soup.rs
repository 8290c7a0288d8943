//! Closed triangle surfaces for the surface-input tests: a subdivided octahedron sphere, a
//! torus, and their OBJ and binary STL files.

use std::collections::HashMap;
use std::path::Path;

/// Points and outward triangles.
pub type Soup = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// A sphere: an octahedron subdivided `levels` times, projected, outward, points shared.
pub fn sphere(centre: [f64; 3], r: f64, levels: usize) -> Soup {
    let mut p: Vec<[f64; 3]> = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let mut t: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::new();
        for tri in &t {
            let mut m = [0u32; 3];
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                m[e] = *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let q = [0, 1, 2].map(|k| p[a as usize][k] + p[b as usize][k]);
                    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
                    p.push(q.map(|x| x / n));
                    (p.len() - 1) as u32
                });
            }
            next.extend([
                [tri[0], m[0], m[2]],
                [m[0], tri[1], m[1]],
                [m[2], m[1], tri[2]],
                m,
            ]);
        }
        t = next;
    }
    let p = p
        .iter()
        .map(|q| [0, 1, 2].map(|k| centre[k] + r * q[k]))
        .collect();
    (p, t)
}

/// A torus around the z axis (radii `big`, `small`), `nu × nv` quads, outward.
pub fn torus(big: f64, small: f64, nu: usize, nv: usize) -> Soup {
    let tau = std::f64::consts::TAU;
    let mut p = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (u, v) = (tau * i as f64 / nu as f64, tau * j as f64 / nv as f64);
            let rho = big + small * v.cos();
            p.push([rho * u.cos(), rho * u.sin(), small * v.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut t = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    (p, t)
}

pub fn write_obj(path: &Path, (p, t): &Soup) {
    let mut s = String::from("# test surface\n");
    for q in p {
        s += &format!("v {} {} {}\n", q[0], q[1], q[2]);
    }
    s += "g all\n";
    for f in t {
        s += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    std::fs::write(path, s).unwrap();
}

pub fn write_stl(path: &Path, (p, t): &Soup) {
    let mut b = vec![0u8; 80];
    b.extend((t.len() as u32).to_le_bytes());
    for f in t {
        b.extend([0u8; 12]);
        for &i in f {
            for x in p[i as usize] {
                b.extend((x as f32).to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    std::fs::write(path, b).unwrap();
}
