//! Large pixel buffers kept from one picture for the next.
//!
//! A picture's buffers (z-buffer keys and faces, shadow maps, output pixels) take
//! megabytes. The system allocator hands out blocks that large as fresh pages, and the
//! first touch of each page (a fault, and the kernel zeroing it) costs about a quarter of
//! a picture's time. Buffers given back with [`give`] are handed out again by [`take`]
//! instead: at most [`KEEP`] of each element type, and at most [`KEEP_BYTES`] bytes in
//! all of them per type.

use std::sync::{Mutex, PoisonError};

/// Buffers kept per element type.
pub const KEEP: usize = 8;

/// Bytes kept per element type.
pub const KEEP_BYTES: usize = 128 << 20;

/// An element type with a pool of its own.
pub trait Pooled: Copy + Default + Send + 'static {
    /// The buffers of this type given back and not yet taken.
    fn pool() -> &'static Mutex<Vec<Vec<Self>>>;
}

macro_rules! pooled {
    ($($t:ty),*) => {$(
        impl Pooled for $t {
            fn pool() -> &'static Mutex<Vec<Vec<$t>>> {
                static POOL: Mutex<Vec<Vec<$t>>> = Mutex::new(Vec::new());
                &POOL
            }
        }
    )*};
}

pooled!(f32, u32, u16, u8);

/// A buffer of `len` values. Postcondition: `len` values long; they are left over from an
/// earlier picture (or zeros), so a caller must write every value it reads.
pub fn take<T: Pooled>(len: usize) -> Vec<T> {
    let found = {
        let mut pool = T::pool().lock().unwrap_or_else(PoisonError::into_inner);
        // The smallest buffer that is large enough.
        let best = pool
            .iter()
            .enumerate()
            .filter(|(_, v)| v.capacity() >= len)
            .min_by_key(|(_, v)| v.capacity())
            .map(|(i, _)| i);
        best.map(|i| pool.swap_remove(i))
    };
    match found {
        Some(mut v) => {
            v.resize(len, T::default());
            v.truncate(len);
            v
        }
        None => vec![T::default(); len],
    }
}

/// Gives `buffer` back for a later [`take`]. Kept unless the pool is full (then the
/// smallest buffer is let go), or the buffer alone is larger than [`KEEP_BYTES`].
pub fn give<T: Pooled>(buffer: Vec<T>) {
    let bytes = |v: &Vec<T>| v.capacity() * size_of::<T>();
    if buffer.capacity() == 0 || bytes(&buffer) > KEEP_BYTES {
        return;
    }
    let mut pool = T::pool().lock().unwrap_or_else(PoisonError::into_inner);
    pool.push(buffer);
    while pool.len() > KEEP || pool.iter().map(bytes).sum::<usize>() > KEEP_BYTES {
        let smallest = pool
            .iter()
            .enumerate()
            .min_by_key(|(_, v)| v.capacity())
            .map(|(i, _)| i);
        match smallest {
            Some(i) => drop(pool.swap_remove(i)),
            None => break,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_buffer_given_back_is_taken_again_at_the_requested_length() {
        let mut v = take::<u8>(12_345);
        assert_eq!(v.len(), 12_345);
        v[0] = 7;
        let at = v.as_ptr();
        give(v);
        let again = take::<u8>(12_000);
        assert_eq!(again.len(), 12_000);
        // Tests running alongside share the pool and may have taken it in between.
        if again.as_ptr() == at {
            assert_eq!(again[0], 7);
        }
        give(again);
        let longer = take::<u8>(20_000);
        assert_eq!(longer.len(), 20_000);
    }

    #[test]
    fn the_pool_keeps_at_most_its_share() {
        for _ in 0..3 * KEEP {
            give(vec![0u32; 1000]);
        }
        assert!(u32::pool().lock().unwrap().len() <= KEEP);
        give(vec![0u8; KEEP_BYTES + 1]);
        assert!(
            u8::pool()
                .lock()
                .unwrap()
                .iter()
                .all(|v| v.capacity() <= KEEP_BYTES)
        );
    }
}
