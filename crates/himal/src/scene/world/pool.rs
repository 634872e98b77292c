//! Fixed-size allocators for the streamed GPU pools: nothing grows after
//! creation; a full pool is the caller's cue to evict.

/// `capacity` interchangeable slots (terrain tile layers, instance blocks).
/// Freed slots are reused lowest first, so the same sequence of calls
/// gives the same slots.
#[derive(Clone, Debug)]
pub struct SlotPool {
    capacity: u32,
    /// Free slots, highest first (pop gives the lowest).
    free: Vec<u32>,
}

impl SlotPool {
    /// A pool of `capacity` free slots.
    pub fn new(capacity: u32) -> Self {
        SlotPool {
            capacity,
            free: (0..capacity).rev().collect(),
        }
    }

    /// Number of slots, fixed at creation.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Slots handed out.
    pub fn used(&self) -> u32 {
        self.capacity - self.free.len() as u32
    }

    /// Slots free.
    pub fn available(&self) -> u32 {
        self.free.len() as u32
    }

    /// The lowest free slot, or `None` when the pool is full.
    pub fn alloc(&mut self) -> Option<u32> {
        self.free.pop()
    }

    /// `n` slots, or none (and nothing taken) if fewer are free.
    pub fn alloc_n(&mut self, n: u32) -> Option<Vec<u32>> {
        if n > self.available() {
            return None;
        }
        Some((0..n).filter_map(|_| self.free.pop()).collect())
    }

    /// Returns `slot`; freeing a slot twice or one out of range is a bug
    /// caught in debug builds and ignored in release.
    pub fn free(&mut self, slot: u32) {
        debug_assert!(slot < self.capacity && !self.free.contains(&slot));
        if slot >= self.capacity {
            return;
        }
        // Keep `free` sorted descending so allocation stays lowest-first.
        let at = self.free.partition_point(|&s| s > slot);
        self.free.insert(at, slot);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_are_reused_lowest_first_and_never_exceed_capacity() {
        let mut p = SlotPool::new(4);
        let a: Vec<u32> = (0..4).filter_map(|_| p.alloc()).collect();
        assert_eq!(a, [0, 1, 2, 3]);
        assert_eq!(p.alloc(), None);
        p.free(2);
        p.free(0);
        assert_eq!(p.used(), 2);
        assert_eq!(p.alloc_n(3), None);
        assert_eq!(p.alloc_n(2), Some(vec![0, 2]));
        assert_eq!(p.available(), 0);
    }
}

/// One kind's instance region: `live` instances packed at the front of
/// `capacity` slots. Removing a sector moves the region's last instances
/// into its holes (swap-remove), so the region never fragments and the
/// culling pass tests only live slots plus what the region was sized for.
#[derive(Clone, Debug)]
pub struct DensePool<K: Copy + Eq> {
    capacity: u32,
    /// Per live slot: its owner and the owner's index of it.
    owner: Vec<(K, u32)>,
}

impl<K: Copy + Eq> DensePool<K> {
    /// An empty region of `capacity` slots.
    pub fn new(capacity: u32) -> Self {
        DensePool {
            capacity,
            owner: Vec::new(),
        }
    }

    /// Number of slots, fixed at creation.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Instances held: slots `0..live` are in use.
    pub fn live(&self) -> u32 {
        self.owner.len() as u32
    }

    /// Slots free.
    pub fn available(&self) -> u32 {
        self.capacity - self.live()
    }

    /// The owner of `slot` and its index there.
    pub fn owner(&self, slot: u32) -> Option<(K, u32)> {
        self.owner.get(slot as usize).copied()
    }

    /// Appends `n` slots for `key` (its indices 0..n); `None` if they do not fit.
    pub fn push(&mut self, key: K, n: u32) -> Option<Vec<u32>> {
        if n > self.available() {
            return None;
        }
        let first = self.live();
        self.owner.extend((0..n).map(|i| (key, i)));
        Some((first..first + n).collect())
    }

    /// Frees `slots` (all of one owner). Each hole is filled with the last
    /// live slot: `moved(owner, index, new slot)` tells the moved slot's
    /// owner; every slot whose content changed or emptied is appended to
    /// `dirty`.
    pub fn remove(
        &mut self,
        slots: &[u32],
        dirty: &mut Vec<u32>,
        mut moved: impl FnMut(K, u32, u32),
    ) {
        let mut holes = slots.to_vec();
        // Highest first: a hole is never filled from the freed owner itself.
        holes.sort_unstable_by(|a, b| b.cmp(a));
        for s in holes {
            let Some(last) = self.owner.len().checked_sub(1) else {
                return;
            };
            if (s as usize) < last {
                let (k, i) = self.owner[last];
                self.owner[s as usize] = (k, i);
                moved(k, i, s);
                dirty.push(s);
            }
            if (s as usize) <= last {
                self.owner.pop();
                dirty.push(last as u32);
            }
        }
    }
}

#[cfg(test)]
mod dense_tests {
    use super::*;

    #[test]
    fn removal_keeps_the_region_packed_and_tells_the_moved_owners() {
        let mut p = DensePool::<char>::new(8);
        let a = p.push('a', 3).unwrap();
        let b = p.push('b', 2).unwrap();
        let _c = p.push('c', 2).unwrap();
        assert_eq!((a, b), (vec![0, 1, 2], vec![3, 4]));
        assert_eq!(p.push('d', 2), None);
        let mut dirty = Vec::new();
        let mut moves = Vec::new();
        p.remove(&[0, 2, 1], &mut dirty, |k, i, s| moves.push((k, i, s)));
        // c1 (slot 6) -> 2, c0 (5) -> 1, b1 (4) -> 0.
        assert_eq!(moves, [('c', 1, 2), ('c', 0, 1), ('b', 1, 0)]);
        assert_eq!(p.live(), 4);
        let owners: Vec<_> = (0..4).map(|s| p.owner(s).unwrap()).collect();
        assert_eq!(owners, [('b', 1), ('c', 0), ('c', 1), ('b', 0)]);
        dirty.sort_unstable();
        dirty.dedup();
        assert_eq!(dirty, [0, 1, 2, 4, 5, 6]);
    }
}
