//! A compact slot arena for one kind of entity, with serial numbers and a serial index.
//!
//! Records live in a flat `Vec<T>`; a parallel `Vec<Serial>` holds each slot's serial
//! number, with [`Serial::NONE`] marking a dead slot. Dead slots are reused (free list).
//! The serial index is a vector of `(serial, slot)` pairs sorted by serial: new serials
//! are always the largest yet issued, so making an entity appends. Killing an entity does
//! not touch the index; a lookup checks that the slot still carries the serial it looks
//! for, and the index is compacted when stale entries outnumber live ones.

use serde::{Deserialize, Serialize};

use super::ids::Serial;

/// Stale index entries always tolerated before a compaction, on top of one per live
/// entity: keeps small bodies from compacting every few operations.
const STALE_SLACK: usize = 4096;

/// Slot storage for one kind of entity (faces, edges or vertices) of one body.
///
/// Serialized field by field (records, slot serials, free list, serial index), so a
/// saved arena reads back identical. Reading one back checks its structure first (see
/// [`ArenaData`]), so a damaged saved arena is refused instead of panicking later.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "ArenaData<T>")]
#[serde(bound(serialize = "T: Serialize", deserialize = "T: Deserialize<'de>"))]
pub struct Arena<T> {
    items: Vec<T>,
    serials: Vec<Serial>,
    free: Vec<u32>,
    live: usize,
    index_serials: Vec<Serial>,
    index_slots: Vec<u32>,
}

impl<T> Default for Arena<T> {
    fn default() -> Self {
        Self {
            items: Vec::new(),
            serials: Vec::new(),
            free: Vec::new(),
            live: 0,
            index_serials: Vec::new(),
            index_slots: Vec::new(),
        }
    }
}

impl<T> Arena<T> {
    /// Number of live entities.
    #[inline]
    pub fn len(&self) -> usize {
        self.live
    }

    /// Whether no entity lives here.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// Number of slots, live or dead (slot ids are below this).
    #[inline]
    pub fn slots(&self) -> usize {
        self.items.len()
    }

    /// Whether slot `i` holds a live entity.
    #[inline]
    pub fn is_live(&self, i: usize) -> bool {
        i < self.serials.len() && self.serials[i] != Serial::NONE
    }

    /// The record in slot `i`. Panics on an out-of-range slot.
    #[inline]
    pub fn get(&self, i: usize) -> &T {
        &self.items[i]
    }

    /// The record in slot `i`, mutably.
    #[inline]
    pub fn get_mut(&mut self, i: usize) -> &mut T {
        &mut self.items[i]
    }

    /// The serial number of slot `i` ([`Serial::NONE`] when dead).
    #[inline]
    pub fn serial(&self, i: usize) -> Serial {
        self.serials.get(i).copied().unwrap_or(Serial::NONE)
    }

    /// Stores `item` under `serial` and returns its slot.
    ///
    /// Precondition: `serial` is not [`Serial::NONE`] and not already in this arena.
    #[inline]
    pub fn insert(&mut self, item: T, serial: Serial) -> u32 {
        debug_assert!(serial != Serial::NONE);
        let slot = self.alloc(item, serial);
        self.index_insert(serial, slot);
        slot
    }

    /// Puts `item` in a free slot (or a new one) under `serial`, without indexing it.
    #[inline]
    fn alloc(&mut self, item: T, serial: Serial) -> u32 {
        self.live += 1;
        match self.free.pop() {
            Some(slot) => {
                self.items[slot as usize] = item;
                self.serials[slot as usize] = serial;
                slot
            }
            None => {
                self.items.push(item);
                self.serials.push(serial);
                (self.items.len() - 1) as u32
            }
        }
    }

    /// Kills the entity in slot `i`; the slot may be reused.
    ///
    /// Precondition: slot `i` is live.
    #[inline]
    pub fn remove(&mut self, i: usize) {
        debug_assert!(self.is_live(i));
        self.serials[i] = Serial::NONE;
        self.free.push(i as u32);
        self.live -= 1;
        if self.index_serials.len() > 2 * self.live + STALE_SLACK {
            self.compact_index_cold();
        }
    }

    /// The live slot carrying `serial`, if any.
    pub fn find(&self, serial: Serial) -> Option<usize> {
        let pos = self.index_serials.binary_search(&serial).ok()?;
        let slot = self.index_slots[pos] as usize;
        (self.serials[slot] == serial).then_some(slot)
    }

    /// The least and greatest serial the index may hold (`None` when it is empty): every
    /// live serial of this arena lies in that range, which may also cover dead ones.
    pub fn serial_bounds(&self) -> Option<(Serial, Serial)> {
        Some((*self.index_serials.first()?, *self.index_serials.last()?))
    }

    /// Iterates the live slots in slot order.
    pub fn live_slots(&self) -> impl Iterator<Item = usize> + '_ {
        self.serials
            .iter()
            .enumerate()
            .filter(|(_, s)| **s != Serial::NONE)
            .map(|(i, _)| i)
    }

    /// Bytes held by this arena's vectors (capacity, not just length).
    pub fn heap_bytes(&self) -> usize {
        self.items.capacity() * std::mem::size_of::<T>()
            + self.serials.capacity() * 8
            + self.free.capacity() * 4
            + self.index_serials.capacity() * 8
            + self.index_slots.capacity() * 4
    }

    /// Stores `item` under `serial` without keeping the index sorted; call
    /// [`Self::resort_index`] after a batch of these. For moving many entities between
    /// bodies at once.
    pub(crate) fn insert_unsorted(&mut self, item: T, serial: Serial) -> u32 {
        let slot = self.alloc(item, serial);
        self.index_serials.push(serial);
        self.index_slots.push(slot);
        slot
    }

    /// Drops stale index entries and sorts the index by serial.
    pub(crate) fn resort_index(&mut self) {
        self.compact_index();
        let mut pairs: Vec<(Serial, u32)> = self
            .index_serials
            .iter()
            .copied()
            .zip(self.index_slots.iter().copied())
            .collect();
        pairs.sort_unstable_by_key(|p| p.0);
        self.index_serials = pairs.iter().map(|p| p.0).collect();
        self.index_slots = pairs.iter().map(|p| p.1).collect();
    }

    /// Adds `delta` (modulo 2^64, so a shift down is the two's complement of its size)
    /// to every serial this arena holds, in its slots and its index alike; dead slots
    /// stay dead. The index stays sorted, every entry moving by the same amount, so this
    /// is one linear pass and no sort.
    ///
    /// Precondition: every shifted serial is neither 0 nor wrapped past 2^64.
    /// Postcondition: the entity that carried serial `s` carries `s + delta`, in the same
    /// slot. Inverse: a shift by `delta.wrapping_neg()`.
    pub(crate) fn shift_serials(&mut self, delta: u64) {
        for s in &mut self.serials {
            if *s != Serial::NONE {
                s.0 = s.0.wrapping_add(delta);
            }
        }
        for s in &mut self.index_serials {
            s.0 = s.0.wrapping_add(delta);
        }
    }

    /// Reserves room for `n` more entities.
    pub fn reserve(&mut self, n: usize) {
        self.items.reserve(n);
        self.serials.reserve(n);
        self.index_serials.reserve(n);
        self.index_slots.reserve(n);
    }

    #[inline]
    fn index_insert(&mut self, serial: Serial, slot: u32) {
        match self.index_serials.last() {
            Some(&last) if last >= serial => {
                // Only happens when entities move between bodies (glue, unglue):
                // keep the index sorted.
                let pos = self.index_serials.partition_point(|s| *s < serial);
                self.index_serials.insert(pos, serial);
                self.index_slots.insert(pos, slot);
            }
            _ => {
                self.index_serials.push(serial);
                self.index_slots.push(slot);
            }
        }
    }

    #[cold]
    #[inline(never)]
    fn compact_index_cold(&mut self) {
        self.compact_index();
    }

    fn compact_index(&mut self) {
        let serials = &self.serials;
        let mut w = 0;
        for r in 0..self.index_serials.len() {
            let (s, slot) = (self.index_serials[r], self.index_slots[r]);
            if serials[slot as usize] == s {
                self.index_serials[w] = s;
                self.index_slots[w] = slot;
                w += 1;
            }
        }
        self.index_serials.truncate(w);
        self.index_slots.truncate(w);
    }
}

/// An [`Arena`] as read from a serialized form, before its structure is checked.
#[derive(Deserialize)]
pub(crate) struct ArenaData<T> {
    items: Vec<T>,
    serials: Vec<Serial>,
    free: Vec<u32>,
    live: usize,
    index_serials: Vec<Serial>,
    index_slots: Vec<u32>,
}

impl<T> TryFrom<ArenaData<T>> for Arena<T> {
    type Error = &'static str;

    /// Accepts the data only if no arena method can index out of bounds or loop on it:
    /// one serial per record, slots addressable by `u32`, the free list naming each
    /// dead slot exactly once, `live` counting the others, and the serial index sorted
    /// with every entry naming a slot in range. (The index may hold stale entries: a
    /// lookup checks them.)
    fn try_from(d: ArenaData<T>) -> Result<Self, Self::Error> {
        let n = d.items.len();
        if d.serials.len() != n {
            return Err("an arena has a different number of records and serials");
        }
        if u32::try_from(n).is_err() {
            return Err("an arena has more slots than 32-bit ids can name");
        }
        let dead = d.serials.iter().filter(|&&s| s == Serial::NONE).count();
        if d.live != n - dead {
            return Err("an arena's live count disagrees with its serials");
        }
        if d.free.len() != dead {
            return Err("an arena's free list does not name every dead slot");
        }
        let mut seen = vec![false; n];
        for &slot in &d.free {
            let i = slot as usize;
            if i >= n || d.serials[i] != Serial::NONE || seen[i] {
                return Err("an arena's free list names a live, missing or repeated slot");
            }
            seen[i] = true;
        }
        if d.index_serials.len() != d.index_slots.len() {
            return Err("an arena's serial index has unpaired entries");
        }
        if d.index_slots.iter().any(|&slot| slot as usize >= n) {
            return Err("an arena's serial index names a slot that does not exist");
        }
        if d.index_serials.windows(2).any(|w| w[0] > w[1]) {
            return Err("an arena's serial index is not sorted");
        }
        Ok(Arena {
            items: d.items,
            serials: d.serials,
            free: d.free,
            live: d.live,
            index_serials: d.index_serials,
            index_slots: d.index_slots,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An arena with live, dead and reused slots and a stale index entry.
    fn sample() -> Arena<u32> {
        let mut a = Arena::default();
        for s in 1..=5 {
            a.insert(s as u32 * 10, Serial(s));
        }
        a.remove(1);
        a.remove(3);
        a.insert(60, Serial(6));
        a
    }

    fn data(a: &Arena<u32>) -> ArenaData<u32> {
        ArenaData {
            items: a.items.clone(),
            serials: a.serials.clone(),
            free: a.free.clone(),
            live: a.live,
            index_serials: a.index_serials.clone(),
            index_slots: a.index_slots.clone(),
        }
    }

    #[test]
    fn an_arena_reads_back_identical() {
        let a = sample();
        let bytes = postcard::to_allocvec(&a).unwrap();
        let b: Arena<u32> = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(postcard::to_allocvec(&b).unwrap(), bytes);
        assert_eq!(
            (&b.items, &b.serials, &b.free, b.live),
            (&a.items, &a.serials, &a.free, a.live)
        );
        assert_eq!(b.find(Serial(6)), a.find(Serial(6)));
        assert_eq!(b.find(Serial(2)), None);
    }

    #[test]
    fn a_damaged_arena_is_refused() {
        let a = sample();
        assert!(Arena::try_from(data(&a)).is_ok());
        let breakages: [fn(&mut ArenaData<u32>); 7] = [
            |d| {
                d.items.pop();
            },
            |d| d.live += 1,
            |d| d.free.push(0),
            |d| d.free[0] = 0,
            |d| d.free = vec![3, 3],
            |d| d.index_slots[0] = 99,
            |d| d.index_serials.swap(0, 2),
        ];
        for (k, brk) in breakages.iter().enumerate() {
            let mut d = data(&a);
            brk(&mut d);
            assert!(Arena::try_from(d).is_err(), "breakage {k} was accepted");
        }
    }
}
