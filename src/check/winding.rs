//! The winding number of the boundary surface at sampled tet centroids: 1 wherever the tets
//! cover the domain once, 2 or more where they overlap.
//!
//! For a closed, consistently oriented surface the winding number at a point off the surface
//! is the signed number of times a ray from it crosses the surface, an integer found exactly
//! with orientation predicates (rays along the axes, through one row of buckets; a ray that
//! grazes an edge or a vertex is replaced by another axis). The generalised winding number
//! (the sum of the triangles' signed solid angles over 4π, van Oosterom–Strackee) is computed
//! by brute force for as many samples as `gwn_budget` allows: it cross-checks the rays on a
//! closed surface and is the only measure on an open one.

use rayon::prelude::*;
use serde::Serialize;

use super::buckets::Buckets;
use super::predicates::{orient, segment_meets_triangle};
use super::{ProblemKind, Problems};

type P = [f64; 3];

/// How far a winding number may be from 1.
pub const WINDING_TOLERANCE: f64 = 1e-6;

/// What the winding numbers at the sampled points were.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct WindingSummary {
    /// Sampled tet centroids.
    pub samples: usize,
    /// Samples whose winding number was counted exactly by ray crossings.
    pub exact: usize,
    /// Samples whose generalised winding number was summed (brute force).
    pub generalised: usize,
    /// Samples that lie on the boundary surface (skipped).
    pub on_boundary: usize,
    /// Smallest and largest winding number found (`NaN` without samples).
    pub min: f64,
    /// See `min`.
    pub max: f64,
    /// Largest difference between the generalised and the exact winding number at the
    /// samples that have both.
    pub max_deviation: f64,
    /// Samples whose winding number is not 1 (within [`WINDING_TOLERANCE`]).
    pub off: usize,
}

/// One ray's verdict.
enum Ray {
    Count(i64),
    Degenerate,
    OnBoundary,
}

/// Signed crossings of the ray from `x` along axis `ax` (towards `dir` = ±1).
fn ray(x: P, ax: usize, dir: i8, tris: &[[P; 3]], b: &Buckets) -> Ray {
    let (o1, o2) = ((ax + 1) % 3, (ax + 2) % 3);
    let mut c = [0u32; 3];
    c[o1] = b.cell(x[o1], o1);
    c[o2] = b.cell(x[o2], o2);
    let s = b.cell(x[ax], ax);
    let far = b.size * (b.dims[ax] as f64 + 2.0);
    let mut q = x;
    q[ax] = if dir > 0 {
        b.origin[ax] + far
    } else {
        b.origin[ax] - 2.0 * b.size
    };
    let cells: Box<dyn Iterator<Item = u32>> = if dir > 0 {
        Box::new(s..b.dims[ax] as u32)
    } else {
        Box::new(0..=s)
    };
    let mut count = 0i64;
    for i in cells {
        c[ax] = i;
        for &t in b.items(b.index(c)) {
            let r = &b.ranges[t as usize];
            // Each triangle once: in the first of its buckets the ray meets.
            let first = if dir > 0 {
                r[0][ax].max(s)
            } else {
                r[1][ax].min(s)
            };
            if first != i {
                continue;
            }
            match crossing(x, q, &tris[t as usize]) {
                Ray::Count(k) => count += k,
                other => return other,
            }
        }
    }
    Ray::Count(count)
}

/// The crossing of segment `x → q` (`q` outside every triangle's box) with triangle `t`:
/// +1 leaving through it (along its outward normal), -1 entering, 0 missing.
fn crossing(x: P, q: P, t: &[P; 3]) -> Ray {
    let sx = orient(t[0], t[1], t[2], x);
    let sq = orient(t[0], t[1], t[2], q);
    if sx == 0 && sq == 0 {
        return if segment_meets_triangle(x, q, t) {
            Ray::Degenerate
        } else {
            Ray::Count(0)
        };
    }
    if sx * sq > 0 {
        return Ray::Count(0);
    }
    let e = [0, 1, 2].map(|k| orient(x, q, t[k], t[(k + 1) % 3]));
    let inside = e.iter().all(|&v| v > 0) || e.iter().all(|&v| v < 0);
    let touches = e.iter().all(|&v| v >= 0) || e.iter().all(|&v| v <= 0);
    match (sx == 0, inside, touches) {
        (true, _, true) => Ray::OnBoundary,
        (false, true, _) if sq != 0 => Ray::Count(sq as i64),
        (false, _, true) => Ray::Degenerate,
        _ => Ray::Count(0),
    }
}

/// The exact winding number at `x` (`None` on the surface, or when every axis ray grazes an
/// edge: then the caller sums solid angles).
fn exact(x: P, tris: &[[P; 3]], b: &Buckets) -> Result<Option<i64>, ()> {
    for ax in 0..3 {
        for dir in [1, -1] {
            match ray(x, ax, dir, tris, b) {
                Ray::Count(k) => return Ok(Some(k)),
                Ray::OnBoundary => return Ok(None),
                Ray::Degenerate => {}
            }
        }
    }
    Err(())
}

/// Signed solid angle of triangle `t` seen from `x`, over 4π (van Oosterom–Strackee).
fn solid_angle(x: P, t: &[P; 3]) -> f64 {
    let [a, b, c] = t.map(|p| [p[0] - x[0], p[1] - x[1], p[2] - x[2]]);
    let dot = |u: P, v: P| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let len = |u: P| dot(u, u).sqrt();
    let cross = [
        b[1] * c[2] - b[2] * c[1],
        b[2] * c[0] - b[0] * c[2],
        b[0] * c[1] - b[1] * c[0],
    ];
    let (la, lb, lc) = (len(a), len(b), len(c));
    let num = dot(a, cross);
    let den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    2.0 * num.atan2(den) / (4.0 * std::f64::consts::PI)
}

/// The generalised winding number at `x`, summed in fixed blocks (deterministic).
fn generalised(x: P, tris: &[[P; 3]]) -> f64 {
    let parts: Vec<f64> = tris
        .par_chunks(1 << 12)
        .map(|c| c.iter().map(|t| solid_angle(x, t)).sum())
        .collect();
    parts.iter().sum()
}

/// Winding numbers at `samples` (`(tet id, point)`) of the surface `tris`; `closed` says
/// whether the surface is a closed, consistently oriented manifold (rays count exactly).
pub(crate) fn winding(
    samples: &[(usize, P)],
    tris: &[[P; 3]],
    buckets: &Buckets,
    closed: bool,
    gwn_budget: usize,
    problems: &mut Problems,
) -> WindingSummary {
    let n = tris.len().max(1);
    let gwn_samples = (gwn_budget / n).max(1).min(samples.len());
    // Per sample: (exact winding, generalised winding).
    let found: Vec<(Option<i64>, Option<f64>, bool)> = samples
        .par_iter()
        .enumerate()
        .map(|(i, &(_, x))| {
            if !closed {
                return (None, (i < gwn_samples).then(|| generalised(x, tris)), false);
            }
            match exact(x, tris, buckets) {
                Ok(Some(k)) => (
                    Some(k),
                    (i < gwn_samples).then(|| generalised(x, tris)),
                    false,
                ),
                Ok(None) => (None, None, true),
                Err(()) => (None, Some(generalised(x, tris)), false),
            }
        })
        .collect();
    let mut s = WindingSummary {
        samples: samples.len(),
        min: f64::NAN,
        max: f64::NAN,
        ..WindingSummary::default()
    };
    for (&(tet, _), &(k, g, on)) in samples.iter().zip(&found) {
        s.on_boundary += usize::from(on);
        s.exact += usize::from(k.is_some());
        s.generalised += usize::from(g.is_some());
        if let (Some(k), Some(g)) = (k, g) {
            s.max_deviation = s.max_deviation.max((g - k as f64).abs());
        }
        let Some(w) = k.map(|k| k as f64).or(g) else {
            continue;
        };
        s.min = if s.min.is_nan() { w } else { s.min.min(w) };
        s.max = if s.max.is_nan() { w } else { s.max.max(w) };
        if (w - 1.0).abs() > WINDING_TOLERANCE {
            s.off += 1;
            problems.add(ProblemKind::WindingNumber, vec![tet]);
        }
    }
    s
}
