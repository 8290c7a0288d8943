//! Buckets of a region's boundary faces over index space, kept up to date as faces come and go
//! and their corners move, so that the embedding guard ([`super::embed`]) finds the faces a
//! new boundary face could cross wherever they are in the region, not only next to it.

use rustc_hash::FxHashMap;
use smallvec::SmallVec;

/// Side of a bucket (index units).
const BUCKET: f64 = 1.0;

/// A range of buckets: lowest and highest bucket coordinates.
type Cells = ([i32; 3], [i32; 3]);

/// The buckets of the faces of a region, each face keyed by its sorted corners.
#[derive(Clone, Default)]
pub struct FaceGrid {
    buckets: FxHashMap<[i32; 3], SmallVec<[[u32; 3]; 4]>>,
    /// The buckets each face was put in.
    at: FxHashMap<[u32; 3], Cells>,
}

/// The buckets the bounding box of the points `p` overlaps.
pub fn cells_of(p: &[[f64; 3]]) -> Cells {
    let c = |x: f64| (x / BUCKET).floor().clamp(-1e6, 1e6) as i32;
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    for q in p {
        for a in 0..3 {
            lo[a] = lo[a].min(c(q[a]));
            hi[a] = hi[a].max(c(q[a]));
        }
    }
    (lo, hi)
}

fn each_cell((lo, hi): Cells, mut f: impl FnMut([i32; 3])) {
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                f([x, y, z]);
            }
        }
    }
}

impl FaceGrid {
    /// Puts face `key` with corners at `p` in its buckets (moving it if it was in others).
    pub fn put(&mut self, key: [u32; 3], p: [[f64; 3]; 3]) {
        let cells = cells_of(&p);
        if self.at.get(&key) == Some(&cells) {
            return;
        }
        self.remove(key);
        each_cell(cells, |c| self.buckets.entry(c).or_default().push(key));
        self.at.insert(key, cells);
    }

    /// Takes face `key` out of its buckets, if it is in any.
    pub fn remove(&mut self, key: [u32; 3]) {
        if let Some(cells) = self.at.remove(&key) {
            each_cell(cells, |c| {
                if let Some(list) = self.buckets.get_mut(&c) {
                    if let Some(i) = list.iter().position(|k| *k == key) {
                        list.swap_remove(i);
                    }
                }
            });
        }
    }

    /// The faces in the buckets that the bounding box of `p` overlaps (each once).
    pub fn near(&self, p: &[[f64; 3]]) -> SmallVec<[[u32; 3]; 64]> {
        let mut out: SmallVec<[[u32; 3]; 64]> = SmallVec::new();
        each_cell(cells_of(p), |c| {
            if let Some(list) = self.buckets.get(&c) {
                for k in list {
                    if !out.contains(k) {
                        out.push(*k);
                    }
                }
            }
        });
        out
    }
}
