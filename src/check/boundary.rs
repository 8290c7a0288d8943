//! The boundary surface (the faces of one tet) as a closed oriented 2-manifold: every edge in
//! exactly two triangles, which run it in opposite directions, and every vertex's link one
//! cycle.

use rayon::prelude::*;

use super::{ProblemKind, Problems};

/// Checks the triangles `tris` (outward-oriented) and returns whether they form a closed,
/// consistently oriented 2-manifold.
pub(crate) fn manifold(tris: &[[u32; 3]], problems: &mut Problems) -> bool {
    let before = problems.total();
    edges(tris, problems);
    links(tris, problems);
    problems.total() == before
}

/// Every undirected edge in two triangles, once in each direction.
fn edges(tris: &[[u32; 3]], problems: &mut Problems) {
    // (min << 32 | max) << 1 | reversed
    let mut keys: Vec<u128> = tris
        .par_iter()
        .flat_map_iter(|t| {
            (0..3).map(move |k| {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (a.min(b) as u128) << 32 | a.max(b) as u128;
                key << 1 | u128::from(a > b)
            })
        })
        .collect();
    keys.par_sort_unstable();
    let mut i = 0;
    while i < keys.len() {
        let e = keys[i] >> 1;
        let mut j = i;
        while j < keys.len() && keys[j] >> 1 == e {
            j += 1;
        }
        let ids = vec![(e >> 32) as usize, (e as u32) as usize];
        match j - i {
            1 => problems.add(ProblemKind::OpenBoundaryEdge, ids),
            2 if keys[i] & 1 == keys[i + 1] & 1 => {
                problems.add(ProblemKind::InconsistentBoundaryOrientation, ids)
            }
            2 => {}
            _ => problems.add(ProblemKind::NonManifoldBoundaryEdge, ids),
        }
        i = j;
    }
}

/// Every boundary vertex's link (the far edges of its triangles) one cycle: connected, every
/// link vertex met twice.
fn links(tris: &[[u32; 3]], problems: &mut Problems) {
    let mut spokes: Vec<[u32; 3]> = tris
        .par_iter()
        .flat_map_iter(|t| (0..3).map(move |k| [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]))
        .collect();
    spokes.par_sort_unstable();
    let mut starts: Vec<usize> = (0..spokes.len())
        .into_par_iter()
        .filter(|&i| i == 0 || spokes[i][0] != spokes[i - 1][0])
        .collect();
    starts.push(spokes.len());
    let bad: Vec<usize> = starts
        .par_windows(2)
        .filter_map(|w| {
            let link = &spokes[w[0]..w[1]];
            (!one_cycle(link)).then_some(link[0][0] as usize)
        })
        .collect();
    for v in bad {
        problems.add(ProblemKind::NonManifoldBoundaryVertex, vec![v]);
    }
}

/// Whether the link edges `[_, b, c]` form one cycle.
fn one_cycle(link: &[[u32; 3]]) -> bool {
    let mut ends: Vec<u32> = link.iter().flat_map(|s| [s[1], s[2]]).collect();
    ends.sort_unstable();
    // Every link vertex in exactly two link edges.
    if ends.chunks(2).any(|c| c.len() != 2 || c[0] != c[1]) || ends.windows(3).any(|w| w[0] == w[2])
    {
        return false;
    }
    // Walk the cycle from the first edge; it must visit every edge.
    let n = link.len();
    let mut used = vec![false; n];
    used[0] = true;
    let (first, mut at) = (link[0][1], link[0][2]);
    let mut visited = 1;
    while at != first {
        let Some(k) = (0..n).find(|&k| !used[k] && (link[k][1] == at || link[k][2] == at)) else {
            return false;
        };
        used[k] = true;
        visited += 1;
        at = if link[k][1] == at {
            link[k][2]
        } else {
            link[k][1]
        };
    }
    visited == n
}
