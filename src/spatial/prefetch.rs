//! Hints that a record will soon be read, so that its cache miss overlaps the work
//! before the read instead of stalling it.
//!
//! A prefetch never changes what a program computes: it moves no data the program can
//! see, never faults, and may be ignored by the processor. On targets without a stable
//! prefetch instruction it does nothing.

/// Asks for the cache line holding `item`'s first byte and the one holding its last
/// to be brought towards the core. Returns at once; the read it prepares still happens
/// where the caller makes it.
#[inline(always)]
pub fn prefetch<T>(item: &T) {
    let first = std::ptr::from_ref(item).cast::<u8>();
    line(first);
    // An item no larger than its alignment never straddles two lines.
    if std::mem::size_of::<T>() > std::mem::align_of::<T>() {
        line(first.wrapping_add(std::mem::size_of::<T>() - 1));
    }
}

/// Prefetches the cache line holding the byte at `at`.
#[inline(always)]
fn line(at: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `prefetcht0` is a hint: it reads nothing the program sees and never
    // faults, whatever the address (here always inside or at the end of a live
    // reference), and SSE, which provides it, is part of every x86-64 processor.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(at.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = at;
}

/// Calls `visit(item)` for each of `items` in order until it answers `false`, with
/// three stages of prefetching run ahead of it: `first` on the item `3 × ahead` further
/// on, `second` on the one `2 × ahead` further on and `third` on the one `ahead` further
/// on. Each stage may read what the stage before prefetched (a record, to find the
/// lists it points to), which has then had `ahead` visits' time to arrive.
///
/// Postcondition: `visit` saw the items in order, each once, up to the first `false`;
/// every stage ran on each item before its visit, in order, and on no item more than
/// `3 × ahead` past the last one visited.
#[inline(always)]
pub fn staged<T: Copy>(
    items: &[T],
    ahead: usize,
    first: impl Fn(T),
    second: impl Fn(T),
    third: impl Fn(T),
    mut visit: impl FnMut(T) -> bool,
) {
    for i in 0..3 * ahead {
        at(items, i, &first);
    }
    for i in 0..2 * ahead {
        at(items, i, &second);
    }
    for i in 0..ahead {
        at(items, i, &third);
    }
    for (i, &item) in items.iter().enumerate() {
        at(items, i + 3 * ahead, &first);
        at(items, i + 2 * ahead, &second);
        at(items, i + ahead, &third);
        if !visit(item) {
            return;
        }
    }
}

/// Runs `stage` on `items[i]`, if there is one.
#[inline(always)]
fn at<T: Copy>(items: &[T], i: usize, stage: &impl Fn(T)) {
    if let Some(&item) = items.get(i) {
        stage(item);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `staged` visits the items in order up to the first refusal, and its stages each
    /// see the items in order, the first the furthest ahead, never past the end.
    #[test]
    fn staged_visits_in_order_until_refused_with_its_stages_ahead() {
        use std::cell::RefCell;
        for len in [0usize, 1, 2, 5, 7, 30] {
            for ahead in [0usize, 1, 2, 4] {
                for stop in [None, Some(0), Some(3), Some(len.saturating_sub(1))] {
                    let items: Vec<usize> = (0..len).collect();
                    let log: RefCell<Vec<(usize, usize)>> = RefCell::new(Vec::new());
                    let log = &log;
                    let stage = |s: usize| move |i: usize| log.borrow_mut().push((s, i));
                    let mut visited = Vec::new();
                    staged(&items, ahead, stage(0), stage(1), stage(2), |i| {
                        // Each stage has run on this item before it is visited.
                        for s in 0..3 {
                            assert!(log.borrow().contains(&(s, i)));
                        }
                        visited.push(i);
                        Some(i) != stop
                    });
                    let end = stop.filter(|&s| s < len).map_or(len, |s| s + 1);
                    assert_eq!(visited, (0..end).collect::<Vec<_>>());
                    for s in 0..3 {
                        let seen: Vec<usize> = log
                            .borrow()
                            .iter()
                            .filter(|&&(t, _)| t == s)
                            .map(|&(_, i)| i)
                            .collect();
                        let want: Vec<usize> = match end {
                            0 => Vec::new(),
                            _ => (0..=(end - 1 + (3 - s) * ahead).min(len - 1)).collect(),
                        };
                        assert_eq!(seen, want, "stage {s}, {len} items, {ahead} ahead");
                    }
                }
            }
        }
    }
}
