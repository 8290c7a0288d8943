//! The samples of a [`crate::ScalarGrid`] in their own storage type.
//!
//! A volume keeps the type its file stores (a 1024³ `uint8` volume takes 1 GiB, not 8): `u8`,
//! `i16`, `u16`, `f32` or `f64`. Readers widen the other file types without loss: `i8` to
//! `i16`; `u32`, `i32`, `u64`, `i64` to `f64` (exact up to 2^53, rounded beyond, as before).
//! Every value is read as an `f64`.
//!
//! Access costs one `match` on the storage type per call, not per sample: [`Samples::get`]
//! for one value, [`Samples::gather`] for a cell's corners, [`Samples::for_each_in`] for a row,
//! [`Samples::par_fold`] for whole-volume reductions. Inside each arm the loop is compiled for
//! that element type.
//!
//! Each arm's [`Buffer`] is a vector of the grid's own or a read-only slice shared with its
//! owner (an array of the caller's, used without a copy); the accessors match its kind once
//! per call too and then read a plain slice. The few writers ([`Samples::as_bytes_mut`],
//! [`Samples::par_map_in_place`]) copy a shared slice first.

use rayon::prelude::*;

use crate::buffer::Buffer;

/// Samples handed to one rayon task by [`Samples::par_fold`].
const PAR_CHUNK: usize = 1 << 16;

/// The samples of a grid, x fastest, in their storage type. Equal when the values are
/// (owned or shared alike); a clone of shared samples shares them too.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    /// Unsigned 8-bit integers.
    U8(Buffer<u8>),
    /// Signed 16-bit integers (also `i8` data).
    I16(Buffer<i16>),
    /// Unsigned 16-bit integers.
    U16(Buffer<u16>),
    /// 32-bit floats.
    F32(Buffer<f32>),
    /// 64-bit floats (also 32- and 64-bit integer data).
    F64(Buffer<f64>),
}

/// The storage types, for messages and reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SampleStorage {
    /// `u8`.
    U8,
    /// `i16`.
    I16,
    /// `u16`.
    U16,
    /// `f32`.
    F32,
    /// `f64`.
    F64,
}

impl SampleStorage {
    /// Bytes per sample.
    pub const fn bytes(self) -> usize {
        match self {
            SampleStorage::U8 => 1,
            SampleStorage::I16 | SampleStorage::U16 => 2,
            SampleStorage::F32 => 4,
            SampleStorage::F64 => 8,
        }
    }

    /// Name as NumPy spells it: `uint8`, `int16`, `uint16`, `float32`, `float64`.
    pub const fn name(self) -> &'static str {
        match self {
            SampleStorage::U8 => "uint8",
            SampleStorage::I16 => "int16",
            SampleStorage::U16 => "uint16",
            SampleStorage::F32 => "float32",
            SampleStorage::F64 => "float64",
        }
    }

    /// Whether every value of this type is an integer.
    pub const fn is_integer(self) -> bool {
        matches!(
            self,
            SampleStorage::U8 | SampleStorage::I16 | SampleStorage::U16
        )
    }

    /// `count` zero samples of this type.
    pub fn zeros(self, count: usize) -> Samples {
        match self {
            SampleStorage::U8 => Samples::from(vec![0u8; count]),
            SampleStorage::I16 => Samples::from(vec![0i16; count]),
            SampleStorage::U16 => Samples::from(vec![0u16; count]),
            SampleStorage::F32 => Samples::from(vec![0f32; count]),
            SampleStorage::F64 => Samples::from(vec![0f64; count]),
        }
    }
}

impl std::fmt::Display for SampleStorage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Runs `$body` with `$v` bound to the typed slice `&[T]`, one arm per storage type (the
/// buffer's kind is matched there, once); `f64::from` converts every element type.
macro_rules! typed {
    ($s:expr, $v:ident => $body:expr) => {
        match $s {
            Samples::U8(b) => {
                let $v: &[u8] = b;
                $body
            }
            Samples::I16(b) => {
                let $v: &[i16] = b;
                $body
            }
            Samples::U16(b) => {
                let $v: &[u16] = b;
                $body
            }
            Samples::F32(b) => {
                let $v: &[f32] = b;
                $body
            }
            Samples::F64(b) => {
                let $v: &[f64] = b;
                $body
            }
        }
    };
}

/// [`typed!`] for writing: `$v` is the typed vector `&mut Vec<T>`, a shared slice copied
/// first.
macro_rules! typed_mut {
    ($s:expr, $v:ident => $body:expr) => {
        match $s {
            Samples::U8(b) => {
                let $v = b.to_mut();
                $body
            }
            Samples::I16(b) => {
                let $v = b.to_mut();
                $body
            }
            Samples::U16(b) => {
                let $v = b.to_mut();
                $body
            }
            Samples::F32(b) => {
                let $v = b.to_mut();
                $body
            }
            Samples::F64(b) => {
                let $v = b.to_mut();
                $body
            }
        }
    };
}

// `f64::from` in `typed!` is the identity in the `F64` arm.
#[allow(clippy::useless_conversion)]
impl Samples {
    /// The storage type.
    #[inline]
    pub fn storage(&self) -> SampleStorage {
        match self {
            Samples::U8(_) => SampleStorage::U8,
            Samples::I16(_) => SampleStorage::I16,
            Samples::U16(_) => SampleStorage::U16,
            Samples::F32(_) => SampleStorage::F32,
            Samples::F64(_) => SampleStorage::F64,
        }
    }

    /// Number of samples.
    #[inline]
    pub fn len(&self) -> usize {
        typed!(self, v => v.len())
    }

    /// Whether there are no samples.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes per sample (1, 2, 4 or 8).
    #[inline]
    pub fn bytes_per_sample(&self) -> usize {
        self.storage().bytes()
    }

    /// The samples' memory as bytes (native byte order); its length is
    /// `len() * bytes_per_sample()`.
    pub fn as_bytes(&self) -> &[u8] {
        typed!(self, v => bytemuck::cast_slice(v))
    }

    /// The samples' memory as writable bytes (native byte order), for readers filling them
    /// straight from a file. Shared samples are copied first.
    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        typed_mut!(self, v => bytemuck::cast_slice_mut(v.as_mut_slice()))
    }

    /// Whether the samples are shared with another owner rather than held by the grid.
    pub fn is_shared(&self) -> bool {
        match self {
            Samples::U8(b) => b.is_shared(),
            Samples::I16(b) => b.is_shared(),
            Samples::U16(b) => b.is_shared(),
            Samples::F32(b) => b.is_shared(),
            Samples::F64(b) => b.is_shared(),
        }
    }

    /// Sample `i` as an `f64` (exact for every storage type). Panics when out of range.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        typed!(self, v => f64::from(v[i]))
    }

    /// Samples at `N` indices (e.g. a cell's eight corners), one `match` for all of them.
    #[inline]
    pub fn gather<const N: usize>(&self, idx: [usize; N]) -> [f64; N] {
        typed!(self, v => idx.map(|i| f64::from(v[i])))
    }

    /// Calls `f(i - range.start, value)` for every sample `i` in `range`, in order: one
    /// `match` per call, the loop compiled per storage type.
    #[inline]
    pub fn for_each_in(&self, range: std::ops::Range<usize>, mut f: impl FnMut(usize, f64)) {
        typed!(self, v => {
            for (i, &x) in v[range].iter().enumerate() {
                f(i, f64::from(x));
            }
        })
    }

    /// Smallest and largest sample in `range` (`(inf, -inf)` when empty), compared in the
    /// storage type (integer rows vectorise); for skipping rows that cannot reach a value.
    #[inline]
    pub fn min_max_in(&self, range: std::ops::Range<usize>) -> (f64, f64) {
        // one pass of plain min/max folds: LLVM vectorises them for the integer types
        fn ints<T: Copy + Ord + Into<f64>>(v: &[T], top: T, bottom: T) -> (f64, f64) {
            if v.is_empty() {
                return (f64::INFINITY, f64::NEG_INFINITY);
            }
            let (a, b) = v
                .iter()
                .fold((top, bottom), |(a, b), &x| (a.min(x), b.max(x)));
            (a.into(), b.into())
        }
        match self {
            Samples::U8(v) => ints(&v[range], u8::MAX, u8::MIN),
            Samples::I16(v) => ints(&v[range], i16::MAX, i16::MIN),
            Samples::U16(v) => ints(&v[range], u16::MAX, u16::MIN),
            Samples::F32(v) => {
                let (a, b) = v[range]
                    .iter()
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    });
                (a.into(), b.into())
            }
            Samples::F64(v) => v[range]
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                }),
        }
    }

    /// Copies the samples from `start` on into `out` as `f64` values.
    #[inline]
    pub fn read_into(&self, start: usize, out: &mut [f64]) {
        typed!(self, v => {
            let n = out.len();
            for (o, &x) in out.iter_mut().zip(&v[start..start + n]) {
                *o = f64::from(x);
            }
        })
    }

    /// All samples as `f64` values (a copy; for small grids and tests).
    pub fn to_f64_vec(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.len()];
        out.par_chunks_mut(PAR_CHUNK)
            .enumerate()
            .for_each(|(c, o)| self.read_into(c * PAR_CHUNK, o));
        out
    }

    /// The samples in order as `f64` values (one `match` per sample: for cold code).
    pub fn iter(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }

    /// A parallel fold over all samples: chunks of consecutive samples are folded with
    /// `fold` from `identity()` in parallel (one `match` per call), the chunk results combined
    /// with `reduce`.
    pub fn par_fold<R, I, F, C>(&self, identity: I, fold: F, reduce: C) -> R
    where
        R: Send,
        I: Fn() -> R + Sync + Send,
        F: Fn(R, f64) -> R + Sync + Send,
        C: Fn(R, R) -> R + Sync + Send,
    {
        typed!(self, v => v
            .par_chunks(PAR_CHUNK)
            .map(|c| c.iter().fold(identity(), |r, &x| fold(r, f64::from(x))))
            .reduce(&identity, &reduce))
    }

    /// Whether `pred` holds for some sample (in parallel).
    pub fn par_any(&self, pred: impl Fn(f64) -> bool + Sync + Send) -> bool {
        typed!(self, v => v
            .par_chunks(PAR_CHUNK)
            .any(|c| c.iter().any(|&x| pred(f64::from(x)))))
    }

    /// Index of the first sample for which `pred` holds.
    pub fn position(&self, pred: impl Fn(f64) -> bool) -> Option<usize> {
        typed!(self, v => v.iter().position(|&x| pred(f64::from(x))))
    }

    /// Smallest and largest sample (`(inf, -inf)` when empty).
    pub fn min_max(&self) -> (f64, f64) {
        self.par_fold(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |(lo, hi), x| (lo.min(x), hi.max(x)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        )
    }

    /// Replaces every sample `x` by `f(x)` in place (in parallel). `f` must return a value of
    /// the storage type: the result is converted with `as` (integers saturate and truncate).
    /// Shared samples are copied first.
    pub fn par_map_in_place(&mut self, f: impl Fn(f64) -> f64 + Sync + Send) {
        match self {
            Samples::U8(v) => v
                .to_mut()
                .par_iter_mut()
                .for_each(|x| *x = f(f64::from(*x)) as u8),
            Samples::I16(v) => v
                .to_mut()
                .par_iter_mut()
                .for_each(|x| *x = f(f64::from(*x)) as i16),
            Samples::U16(v) => v
                .to_mut()
                .par_iter_mut()
                .for_each(|x| *x = f(f64::from(*x)) as u16),
            Samples::F32(v) => v
                .to_mut()
                .par_iter_mut()
                .for_each(|x| *x = f(f64::from(*x)) as f32),
            Samples::F64(v) => v.to_mut().par_iter_mut().for_each(|x| *x = f(*x)),
        }
    }

    /// Whether `x` is held exactly by this storage type.
    pub fn holds(&self, x: f64) -> bool {
        match self.storage() {
            SampleStorage::U8 => x == f64::from(x as u8),
            SampleStorage::I16 => x == f64::from(x as i16),
            SampleStorage::U16 => x == f64::from(x as u16),
            SampleStorage::F32 => x == f64::from(x as f32),
            SampleStorage::F64 => !x.is_nan(),
        }
    }
}

macro_rules! from_vec {
    ($($t:ty => $var:ident),*) => {$(
        impl From<Vec<$t>> for Samples {
            fn from(v: Vec<$t>) -> Self {
                Samples::$var(v.into())
            }
        }

        impl From<Buffer<$t>> for Samples {
            fn from(b: Buffer<$t>) -> Self {
                Samples::$var(b)
            }
        }
    )*};
}
from_vec!(u8 => U8, i16 => I16, u16 => U16, f32 => F32, f64 => F64);

impl From<Vec<i8>> for Samples {
    /// `i8` data are held as `i16`.
    fn from(v: Vec<i8>) -> Self {
        Samples::from(v.into_iter().map(i16::from).collect::<Vec<i16>>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all_types() -> Vec<Samples> {
        vec![
            Samples::from(vec![0u8, 7, 255, 3]),
            Samples::from(vec![-5i16, 7, 300, 3]),
            Samples::from(vec![0u16, 7, 65535, 3]),
            Samples::from(vec![-0.5f32, 7.0, 1e30, 3.0]),
            Samples::from(vec![-0.5f64, 7.0, 1e300, 3.0]),
        ]
    }

    #[test]
    fn accessors_agree_for_every_type() {
        for s in all_types() {
            let all: Vec<f64> = s.iter().collect();
            assert_eq!(all.len(), 4);
            assert_eq!(s.to_f64_vec(), all);
            assert_eq!(s.gather([2, 0, 1]), [all[2], all[0], all[1]]);
            let mut row = vec![];
            s.for_each_in(1..4, |i, x| row.push((i, x)));
            assert_eq!(row, vec![(0, all[1]), (1, all[2]), (2, all[3])]);
            let mut buf = [0.0; 2];
            s.read_into(2, &mut buf);
            assert_eq!(buf, [all[2], all[3]]);
            let lo = all.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = all.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(s.min_max(), (lo, hi));
            assert_eq!(s.position(|x| x == 3.0), Some(3));
            assert!(s.par_any(|x| x == 7.0) && !s.par_any(|x| x == 8.0));
            assert_eq!(s.as_bytes().len(), 4 * s.bytes_per_sample());
            assert_eq!(s.storage().bytes(), s.bytes_per_sample());
        }
    }

    /// `s` with its samples in a shared buffer (a copy, held as another owner's slice).
    fn shared(s: &Samples) -> Samples {
        match s {
            Samples::U8(b) => Samples::U8(Buffer::shared(b.to_vec())),
            Samples::I16(b) => Samples::I16(Buffer::shared(b.to_vec())),
            Samples::U16(b) => Samples::U16(Buffer::shared(b.to_vec())),
            Samples::F32(b) => Samples::F32(Buffer::shared(b.to_vec())),
            Samples::F64(b) => Samples::F64(Buffer::shared(b.to_vec())),
        }
    }

    #[test]
    fn shared_samples_read_as_owned_ones_and_are_copied_to_be_written() {
        for owned in all_types() {
            let s = shared(&owned);
            assert!(s.is_shared() && !owned.is_shared());
            assert_eq!(s, owned);
            assert_eq!(s.storage(), owned.storage());
            assert_eq!(s.to_f64_vec(), owned.to_f64_vec());
            assert_eq!(s.gather([3, 1]), owned.gather([3, 1]));
            assert_eq!(s.min_max_in(1..3), owned.min_max_in(1..3));
            assert_eq!(s.as_bytes(), owned.as_bytes());
            let (mut a, mut b) = (s.clone(), owned.clone());
            assert!(a.is_shared(), "a clone shares the samples");
            a.par_map_in_place(|x| x * 0.5);
            b.par_map_in_place(|x| x * 0.5);
            assert!(!a.is_shared() && a == b);
            assert_eq!(s, owned, "the shared samples are not written");
            let mut c = s.clone();
            c.as_bytes_mut()[0] ^= 1;
            assert!(!c.is_shared() && c != s && s == owned);
        }
    }

    #[test]
    fn bytes_per_sample_and_widening() {
        let b: Vec<usize> = all_types().iter().map(Samples::bytes_per_sample).collect();
        assert_eq!(b, vec![1, 2, 2, 4, 8]);
        let s = Samples::from(vec![-128i8, 127]);
        assert_eq!(s.storage(), SampleStorage::I16);
        assert_eq!(s.to_f64_vec(), vec![-128.0, 127.0]);
        assert!(s.holds(-128.0) && !s.holds(0.5) && !s.holds(40000.0));
        assert!(Samples::from(vec![0f32]).holds(0.5) && !Samples::from(vec![0f32]).holds(0.1));
    }
}
