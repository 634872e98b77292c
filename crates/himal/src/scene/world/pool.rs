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
    pub fn new(capacity: u32) -> Self {
        SlotPool {
            capacity,
            free: (0..capacity).rev().collect(),
        }
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    pub fn used(&self) -> u32 {
        self.capacity - self.free.len() as u32
    }

    pub fn available(&self) -> u32 {
        self.free.len() as u32
    }

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
