//! Single-cell configurations covering the Marching Cubes 33 family (Chernyaev's cases),
//! as 8 corner values (our corner order: corner c at offset (c&1, (c>>1)&1, (c>>2)&1)) and an
//! isovalue.
//!
//! Sources:
//! * `cgal_*`: the inner-ambiguity cases of CGAL's `Isosurfacing_3/test/Isosurfacing_3/
//!   test_tmc_topology.cpp`. CGAL stores `values(x, y, z) = center_values[4x + 2y + z]`
//!   (x most significant); ours is `c = x + 2y + 4z`, so
//!   `ours[c] = cgal[4*(c&1) + 2*((c>>1)&1) + ((c>>2)&1)]` (a reflection swapping x and z,
//!   which preserves topology anyway).
//! * the others (`SEARCHED`) are generated into `mc33_table.rs` by the seeded random search of
//!   `tests/gen_mc33.rs` (`cargo test --release --test gen_mc33 -- --ignored
//!   generate_mc33_table`; do not edit that file by hand): cells with values in [-1, 1],
//!   bucketed by [`bucket`] (MC sign class under the 24 rotations + complement, number of
//!   ambiguous faces resolved "joined" for the minority sign, number of body saddles in the
//!   cell and their side) and by the reference Betti numbers of {f > iso} and {f < iso},
//!   rounded to 4 decimals, one cell each, labelled by [`mc33_label`] with the MC33 subcase
//!   that the face tests and the Betti numbers identify. Labels are documentation only: every
//!   test recomputes the truth with `reference.rs`, and `mc33_labels_are_consistent` checks
//!   the sign class and tunnel claims of each label against the values.
//!
//! Note: for case 13 with three "joined" faces, the three faces always share a corner (a
//! random search of 2·10⁷ tetrahedral-pattern cells found no "band" triple). Around a corner of
//! the minority sign this gives the single 12-vertex disk ({f>iso} and {f<iso} both balls):
//! labelled 13.4 here (CGAL's `MC_13_12_VTS_*`; the search of `tests/gen_mc33.rs` finds one);
//! around a corner of the other sign it gives 13.5.1 (two balls each side) or 13.5.2 (tunnel).

#![allow(clippy::approx_constant, clippy::excessive_precision)]

use super::mc33_table::SEARCHED;
use super::reference::{body_saddles, face_saddle, face_saddles, Field, CELL_FACES};

#[derive(Clone, Debug)]
pub struct Config {
    pub name: &'static str,
    /// MC33 label ("7.4.2", ...), or "" when only the class is known.
    pub case: &'static str,
    pub values: [f64; 8],
    pub iso: f64,
}

/// An interval cutting a cell twice (alpha and beta both inside the cell's range).
#[derive(Clone, Debug)]
pub struct TwoLevel {
    pub name: String,
    pub values: [f64; 8],
    pub alpha: f64,
    pub beta: f64,
}

fn from_cgal(v: [f64; 8]) -> [f64; 8] {
    std::array::from_fn(|c| v[4 * (c & 1) + 2 * ((c >> 1) & 1) + ((c >> 2) & 1)])
}

pub fn configs() -> Vec<Config> {
    let mut v: Vec<Config> = SEARCHED
        .iter()
        .map(|&(name, case, values, iso)| Config {
            name,
            case,
            values,
            iso,
        })
        .collect();
    // CGAL test_tmc_topology.cpp inner-ambiguity cases (CGAL corner order converted)
    let cgal: [(&'static str, [f64; 8], f64); 13] = [
        (
            "cgal_contour_6_vts",
            [
                -0.960492426392903,
                0.793207329559554,
                0.916735525189067,
                -0.422761282626275,
                -0.934993247757551,
                -0.850129305868777,
                -0.0367116785741896,
                -0.656740699156587,
            ],
            0.0387,
        ),
        (
            "cgal_contour_7_vts_a",
            [
                10.2967816247556,
                9.45145192686147,
                9.54753711271687,
                10.6482067822841,
                9.81494966341055,
                9.31168538578250,
                9.80950580411527,
                10.7451536262220,
            ],
            9.8588,
        ),
        (
            "cgal_contour_7_vts_b",
            [
                9.9998593195995547,
                9.9993381282115549,
                9.9979160205452544,
                9.9986053863704142,
                9.9999374908631235,
                9.999424800002032,
                9.9983922749132219,
                9.999579324965488,
            ],
            9.9994608191478135,
        ),
        (
            "cgal_contour_8_vts_a",
            [
                0.454797708726920,
                0.801330575352402,
                0.649991492712356,
                -0.973974554763863,
                -0.134171007607162,
                -0.0844698148589140,
                -0.826313795402046,
                0.433391503783462,
            ],
            0.0097,
        ),
        (
            "cgal_contour_8_vts_b",
            [
                9.9985934885536665,
                9.9998695572230147,
                9.9999045831713928,
                9.999316745478131,
                9.9986117521866866,
                9.9998754368055813,
                9.9999031760062458,
                9.9992041920402936,
            ],
            9.99946,
        ),
        (
            "cgal_contour_9_vts_a",
            [
                -15.6504952739285,
                2.90290077342601,
                24.5454566157887,
                -24.5274127623786,
                21.6741877710053,
                -4.49696327433901,
                -19.7891575872492,
                -15.5588482753161,
            ],
            -1.8061,
        ),
        (
            "cgal_mc_4_tunnel",
            [
                -7.70146936482581,
                -3.21868369245987,
                -5.44023748418735,
                15.6051950593180,
                12.7611835388515,
                -4.46952393442309,
                -11.7240576326183,
                -9.23038948829007,
            ],
            -1.7660,
        ),
        (
            "cgal_mc_7_tunnel",
            [
                -3.42744283804455,
                0.621278122151001,
                4.48110777981235,
                -1.95551129669134,
                2.30448107596369,
                -1.04182240925489,
                -3.51087814405650,
                -6.44976786808517,
            ],
            -0.6,
        ),
        (
            "cgal_mc_10_tunnel",
            [-0.1, -6.11, 2.0, 10.2, 10.8, 1.8, -8.2, -0.18],
            1.10918,
        ),
        (
            "cgal_mc_12_tunnel",
            [
                -3.37811990337124,
                0.473258332744286,
                2.54344310345736,
                7.87658724379480,
                4.38700713005133,
                -1.49950251870885,
                -4.21025867362045,
                -1.00233824192217,
            ],
            0.0708,
        ),
        (
            "cgal_mc_13_tunnel",
            [
                2.74742516087490,
                -3.39187542578189,
                -12.5297639669456,
                0.431517989649243,
                -6.92460546400188,
                2.52228314017858,
                14.6950568276448,
                -10.0732624062474,
            ],
            -1.3064,
        ),
        (
            "cgal_mc_13_12_vts_a",
            [
                0.546912886195662,
                -0.421103532406922,
                -0.643375084081520,
                0.855507421818445,
                -0.260686312588506,
                0.206413666735986,
                0.237274227130530,
                -0.183297728364877,
            ],
            0.0293,
        ),
        (
            "cgal_mc_13_simple",
            [
                0.520482995461163,
                -0.839814387388296,
                -0.467491517013617,
                0.937814095887345,
                -0.825777099007084,
                0.506695544835103,
                0.345318915961394,
                -0.861107217966913,
            ],
            0.0293,
        ),
    ];
    let labels = [
        "", "", "", "", "", "", "4.1.2", "7.4.2", "10.1.2", "12.1.2", "13.5.2", "13.4", "13.2",
    ];
    for ((name, vals, iso), case) in cgal.into_iter().zip(labels) {
        v.push(Config {
            name,
            case,
            values: from_cgal(vals),
            iso,
        });
    }
    v.push(Config {
        name: "cgal_mc_13_12_vts_b",
        case: "13.4",
        values: from_cgal([1069.0, 843.0, 950.0, 1133.0, 958.0, 1029.0, 1198.0, 946.0]),
        iso: 1007.4,
    });
    v
}

/// Two-level cells: for every configuration whose cell has two body saddles and six face
/// saddles, thin intervals around the body saddles (both levels cut the cell). The levels are
/// placed at fractions of the gaps between consecutive critical values, so they stay away from
/// them.
pub fn two_level_cells() -> Vec<TwoLevel> {
    let mut out = Vec::new();
    for cfg in configs() {
        for (tag, alpha, beta) in two_level_intervals(&cfg.values) {
            out.push(TwoLevel {
                name: format!("{}:{tag}", cfg.name),
                values: cfg.values,
                alpha,
                beta,
            });
        }
    }
    out
}

/// The intervals of [`two_level_cells`] for one cell: (tag, alpha, beta).
pub fn two_level_intervals(v: &[f64; 8]) -> Vec<(&'static str, f64, f64)> {
    let fs = face_saddles(v);
    let bs = body_saddles(v);
    if bs.len() != 2 || fs.len() != 6 {
        return Vec::new();
    }
    let mut crit: Vec<f64> = v.to_vec();
    crit.extend(fs);
    crit.extend(bs.iter().map(|b| b.1));
    crit.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let (s1, s2) = {
        let (a, b) = (bs[0].1, bs[1].1);
        (a.min(b), a.max(b))
    };
    let below = |s: f64| {
        crit.iter()
            .copied()
            .filter(|&c| c < s)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let above = |s: f64| {
        crit.iter()
            .copied()
            .filter(|&c| c > s)
            .fold(f64::INFINITY, f64::min)
    };
    let mid = 0.5 * (s1 + s2);
    let lo = s1 - 0.5 * (s1 - below(s1));
    let hi = s2 + 0.5 * (above(s2) - s2);
    let scale = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if s2 - s1 < 1e-3 * scale {
        return Vec::new();
    }
    vec![("around", lo, hi), ("low", lo, mid), ("high", mid, hi)]
}

/// 24 rotations of the cube as corner permutations.
pub fn rotations() -> Vec<[usize; 8]> {
    let perms = [
        [0, 1, 2],
        [1, 2, 0],
        [2, 0, 1],
        [0, 2, 1],
        [2, 1, 0],
        [1, 0, 2],
    ];
    let psign = [1, 1, 1, -1, -1, -1];
    let mut out = Vec::new();
    for (pi, p) in perms.iter().enumerate() {
        for refl in 0..8usize {
            let s = psign[pi] * if refl.count_ones() % 2 == 1 { -1 } else { 1 };
            if s != 1 {
                continue;
            }
            let mut map = [0usize; 8];
            for (c, m) in map.iter_mut().enumerate() {
                let b = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
                let nb: [usize; 3] = std::array::from_fn(|a| b[p[a]] ^ ((refl >> a) & 1));
                *m = nb[0] | nb[1] << 1 | nb[2] << 2;
            }
            out.push(map);
        }
    }
    out
}

fn canon(mask: u8, rots: &[[usize; 8]]) -> u8 {
    let mut best = 255u8;
    for m in [mask, !mask] {
        for r in rots {
            let nm = (0..8)
                .filter(|&c| m >> c & 1 == 1)
                .fold(0u8, |a, c| a | 1 << r[c]);
            best = best.min(nm);
        }
    }
    best
}

/// The classic MC sign class ("0".."14") of a cell at an isovalue (f > iso positive), up to
/// rotation and complement. 11 and 14 are mirror images of each other.
pub fn sign_class(values: &[f64; 8], iso: f64) -> &'static str {
    let reps: [(&str, &[usize]); 15] = [
        ("0", &[]),
        ("1", &[0]),
        ("2", &[0, 1]),
        ("3", &[0, 3]),
        ("4", &[0, 7]),
        ("5", &[0, 1, 2]),
        ("6", &[0, 1, 7]),
        ("7", &[0, 3, 5]),
        ("8", &[0, 1, 2, 3]),
        ("9", &[0, 1, 2, 4]),
        ("10", &[0, 1, 6, 7]),
        ("11", &[0, 1, 3, 7]),
        ("12", &[0, 1, 2, 7]),
        ("13", &[0, 3, 5, 6]),
        ("14", &[1, 0, 2, 6]),
    ];
    let rots = rotations();
    let mask = (0..8).fold(0u8, |m, c| if values[c] > iso { m | 1 << c } else { m });
    let cm = canon(mask, &rots);
    for (n, s) in reps {
        let m = s.iter().fold(0u8, |m, &c| m | 1 << c);
        if canon(m, &rots) == cm {
            return n;
        }
    }
    unreachable!("every mask has a class")
}

/// What the MC33 search buckets cells by (see [`bucket`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Bucket {
    /// MC sign class, 0..=14 (as [`sign_class`]).
    pub class: u8,
    /// Ambiguous faces (two diagonal corners of each sign).
    pub ambiguous: u8,
    /// Ambiguous faces on which the minority corners are joined (face saddle on their side).
    pub joined: u8,
    /// Class 13 with three joined faces: 1 = they share a corner of the joined sign,
    /// 2 = a corner of the other sign, 3 = no common corner; 0 otherwise.
    pub corner: u8,
    /// Body saddles strictly inside the cell on the minority side of the isovalue ...
    pub saddles_in: u8,
    /// ... and on the other side (or at the isovalue).
    pub saddles_out: u8,
}

/// The bucket of a cell with the minority sign taken as "inside" (f > iso if fewer corners
/// are above iso than below). For 4/4 cells both signs are minorities and the smaller of the
/// two buckets is taken, so that a cell and its complement share their bucket.
pub fn bucket(values: &[f64; 8], iso: f64) -> Bucket {
    let above = values.iter().filter(|&&x| x > iso).count();
    match above.cmp(&4) {
        std::cmp::Ordering::Less => oriented_bucket(values, iso, false),
        std::cmp::Ordering::Greater => oriented_bucket(values, iso, true),
        std::cmp::Ordering::Equal => {
            oriented_bucket(values, iso, false).min(oriented_bucket(values, iso, true))
        }
    }
}

/// The bucket with "inside" = f > iso (`flip` false) or f < iso (`flip` true).
fn oriented_bucket(values: &[f64; 8], iso: f64, flip: bool) -> Bucket {
    let s = if flip { -1.0 } else { 1.0 };
    let v: [f64; 8] = values.map(|x| s * (x - iso));
    let inside = |c: usize| v[c] > 0.0;
    let mut ambiguous = 0u8;
    let mut joined_faces = Vec::new();
    for f in &CELL_FACES {
        let [a00, a10, a01, a11] = f.map(&inside);
        if a00 == a11 && a10 == a01 && a00 != a10 {
            ambiguous += 1;
            let sv = face_saddle(v[f[0]], v[f[1]], v[f[2]], v[f[3]])
                .expect("an ambiguous face has an interior saddle");
            if sv > 0.0 {
                joined_faces.push(*f);
            }
        }
    }
    let class: u8 = sign_class(values, iso).parse().expect("numeric class");
    let corner = if class == 13 && joined_faces.len() == 3 {
        match (0..8).find(|c| joined_faces.iter().all(|f| f.contains(c))) {
            Some(c) if inside(c) => 1,
            Some(_) => 2,
            None => 3,
        }
    } else {
        0
    };
    let bs = body_saddles(&v);
    let saddles_in = bs.iter().filter(|b| b.1 > 0.0).count() as u8;
    Bucket {
        class,
        ambiguous,
        joined: joined_faces.len() as u8,
        corner,
        saddles_in,
        saddles_out: bs.len() as u8 - saddles_in,
    }
}

/// The MC33 subcases, in Chernyaev's order.
pub const MC33_FAMILY: [&str; 31] = [
    "1", "2", "3.1", "3.2", "4.1.1", "4.1.2", "5", "6.1.1", "6.1.2", "6.2", "7.1", "7.2", "7.3",
    "7.4.1", "7.4.2", "8", "9", "10.1.1", "10.1.2", "10.2", "11", "12.1.1", "12.1.2", "12.2",
    "13.1", "13.2", "13.3", "13.4", "13.5.1", "13.5.2", "14",
];

/// The MC33 subcase of a cell from its bucket (sign class and face tests) and the reference
/// Betti numbers of {f > iso} (`up`) and {f < iso} (`down`); `None` when they do not fit
/// Chernyaev's description of any subcase (components and tunnels).
pub fn mc33_label(b: &Bucket, up: [usize; 3], down: [usize; 3]) -> Option<&'static str> {
    let tunnel = up[1] + down[1] > 0;
    let comps = up[0].max(down[0]);
    let k = b.joined;
    let (label, want_comps, want_tunnel) = match (b.class, k) {
        (1, _) => ("1", 1, false),
        (2, _) => ("2", 1, false),
        (5, _) => ("5", 1, false),
        (8, _) => ("8", 1, false),
        (9, _) => ("9", 1, false),
        (11, _) => ("11", 1, false),
        (14, _) => ("14", 1, false),
        (3, 0) => ("3.1", 2, false),
        (3, 1) => ("3.2", 1, false),
        (4, 0) if tunnel => ("4.1.2", 1, true),
        (4, 0) => ("4.1.1", 2, false),
        (6, 0) if tunnel => ("6.1.2", 1, true),
        (6, 0) => ("6.1.1", 2, false),
        (6, 1) => ("6.2", 1, false),
        (7, 0) => ("7.1", 3, false),
        (7, 1) => ("7.2", 2, false),
        (7, 2) => ("7.3", 1, false),
        (7, 3) if tunnel => ("7.4.2", 1, true),
        (7, 3) => ("7.4.1", 2, false),
        (10, 0) if tunnel => ("10.1.2", 1, true),
        (10, 0) => ("10.1.1", 2, false),
        (10, 1) => ("10.2", 1, false),
        (12, 0) if tunnel => ("12.1.2", 1, true),
        (12, 0) => ("12.1.1", 2, false),
        (12, 1) => ("12.2", 1, false),
        (13, 0) => ("13.1", 4, false),
        (13, 1) => ("13.2", 3, false),
        (13, 2) => ("13.3", 2, false),
        (13, 3) if b.corner == 1 => ("13.4", 1, false),
        (13, 3) if b.corner == 2 && tunnel => ("13.5.2", 2, true),
        (13, 3) if b.corner == 2 => ("13.5.1", 2, false),
        _ => return None,
    };
    // 13.5.1: two balls on each side (a single component on one side is a thin gap that the
    // sampled reference cannot separate)
    let both = label != "13.5.1" || up[0] == down[0];
    (comps == want_comps && tunnel == want_tunnel && both).then_some(label)
}

pub fn field(cfg: &Config) -> Field {
    Field::cell(cfg.values)
}
