//! [`Buffer`], the storage of one arm of [`crate::Samples`]: a vector the grid owns, or a
//! read-only slice it shares with its owner (e.g. an array of the caller's, used without a
//! copy).
//!
//! Both read as a `&[T]` through [`Deref`]: the kind is matched once per dereference, so a
//! loop over the slice has no branch per element. Writing ([`Buffer::to_mut`]) first copies a
//! shared slice into a vector of its own (copy on write); the shared owner is never written.

use std::fmt;
use std::ops::Deref;
use std::sync::Arc;

/// Samples of one type, owned or shared read-only.
pub enum Buffer<T> {
    /// A vector of its own.
    Owned(Vec<T>),
    /// A read-only slice held by its owner for as long as this reference lives. The owner
    /// must not change the slice's contents while any reference to it is alive.
    Shared(Arc<dyn AsRef<[T]> + Send + Sync>),
}

impl<T> Buffer<T> {
    /// A buffer reading `owner`'s slice without copying it.
    pub fn shared(owner: impl AsRef<[T]> + Send + Sync + 'static) -> Self {
        Buffer::Shared(Arc::new(owner))
    }

    /// Whether the samples are shared with another owner (not a vector of their own).
    pub fn is_shared(&self) -> bool {
        matches!(self, Buffer::Shared(_))
    }

    /// The samples as a slice.
    #[inline]
    pub fn as_slice(&self) -> &[T] {
        match self {
            Buffer::Owned(v) => v,
            Buffer::Shared(s) => (**s).as_ref(),
        }
    }
}

impl<T: Clone> Buffer<T> {
    /// The samples as a vector of their own, for writing: a shared slice is copied into one
    /// first (and the buffer holds the copy from then on).
    pub fn to_mut(&mut self) -> &mut Vec<T> {
        if let Buffer::Shared(s) = self {
            *self = Buffer::Owned((**s).as_ref().to_vec());
        }
        match self {
            Buffer::Owned(v) => v,
            Buffer::Shared(_) => unreachable!("a shared buffer was just copied"),
        }
    }

    /// The samples as a vector: this buffer's own, or a copy of the shared slice.
    pub fn into_vec(self) -> Vec<T> {
        match self {
            Buffer::Owned(v) => v,
            Buffer::Shared(s) => (*s).as_ref().to_vec(),
        }
    }
}

impl<T> Deref for Buffer<T> {
    type Target = [T];

    #[inline]
    fn deref(&self) -> &[T] {
        self.as_slice()
    }
}

impl<T> AsRef<[T]> for Buffer<T> {
    #[inline]
    fn as_ref(&self) -> &[T] {
        self.as_slice()
    }
}

/// A clone of a shared buffer shares the same slice; an owned one is copied.
impl<T: Clone> Clone for Buffer<T> {
    fn clone(&self) -> Self {
        match self {
            Buffer::Owned(v) => Buffer::Owned(v.clone()),
            Buffer::Shared(s) => Buffer::Shared(Arc::clone(s)),
        }
    }
}

/// The samples, as a slice's (an owned and a shared buffer print alike).
impl<T: fmt::Debug> fmt::Debug for Buffer<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_slice(), f)
    }
}

/// Equal contents, whatever the storage.
impl<T: PartialEq> PartialEq for Buffer<T> {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl<T> From<Vec<T>> for Buffer<T> {
    fn from(v: Vec<T>) -> Self {
        Buffer::Owned(v)
    }
}

impl<T> Default for Buffer<T> {
    fn default() -> Self {
        Buffer::Owned(Vec::new())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// An external slice that counts the owners dropped.
    struct Outside(Vec<u16>, Arc<AtomicUsize>);

    impl AsRef<[u16]> for Outside {
        fn as_ref(&self) -> &[u16] {
            &self.0
        }
    }

    impl Drop for Outside {
        fn drop(&mut self) {
            self.1.fetch_add(1, Ordering::SeqCst);
        }
    }

    #[test]
    fn shared_reads_the_owners_slice_without_a_copy() {
        let dropped = Arc::new(AtomicUsize::new(0));
        let data = vec![3u16, 1, 4, 1, 5];
        let ptr = data.as_ptr();
        let b = Buffer::shared(Outside(data, dropped.clone()));
        assert!(b.is_shared());
        assert_eq!(&*b, &[3, 1, 4, 1, 5]);
        assert_eq!(b.as_ptr(), ptr, "the owner's memory, not a copy");
        let c = b.clone();
        assert!(
            c.is_shared() && c.as_ptr() == ptr,
            "a clone shares the slice too"
        );
        drop(b);
        assert_eq!(
            dropped.load(Ordering::SeqCst),
            0,
            "the clone keeps the owner"
        );
        drop(c);
        assert_eq!(
            dropped.load(Ordering::SeqCst),
            1,
            "the last reference drops it"
        );
    }

    #[test]
    fn writing_copies_a_shared_slice_first() {
        let dropped = Arc::new(AtomicUsize::new(0));
        let mut b = Buffer::shared(Outside(vec![1, 2, 3], dropped.clone()));
        let other = b.clone();
        b.to_mut()[0] = 9;
        assert!(!b.is_shared());
        assert_eq!(&*b, &[9, 2, 3]);
        assert_eq!(&*other, &[1, 2, 3], "the shared slice is not written");
        assert_ne!(b.as_ptr(), other.as_ptr());
        drop(other);
        assert_eq!(dropped.load(Ordering::SeqCst), 1);
        let mut owned = Buffer::from(vec![1u16, 2, 3]);
        let ptr = owned.as_ptr();
        owned.to_mut()[2] = 4;
        assert_eq!(owned.as_ptr(), ptr, "an owned vector is written in place");
        assert_eq!(owned.into_vec(), vec![1, 2, 4]);
    }

    #[test]
    fn equality_and_debug_by_contents() {
        let dropped = Arc::new(AtomicUsize::new(0));
        let shared = Buffer::shared(Outside(vec![7, 8], dropped));
        let owned = Buffer::from(vec![7u16, 8]);
        assert_eq!(shared, owned);
        assert_eq!(owned, shared);
        assert_ne!(shared, Buffer::from(vec![7u16, 9]));
        assert_ne!(shared, Buffer::from(vec![7u16]));
        assert_eq!(format!("{shared:?}"), format!("{owned:?}"));
        assert_eq!(format!("{owned:?}"), "[7, 8]");
        assert_eq!(shared.clone().into_vec(), vec![7, 8]);
    }
}
