//! A max-priority queue of `u64` keys: an implicit 4-ary heap. Half as deep as a binary
//! heap, and a node's four children share a cache line, so a pop's walk down the heap
//! takes half the cache misses and unpredictable branches of `BinaryHeap`'s.

/// The heap: `keys[0]` is the largest, node `i`'s children are `4i + 1 ..= 4i + 4`.
#[derive(Default)]
pub struct Queue {
    keys: Vec<u64>,
}

impl Queue {
    /// Adds `key`.
    pub fn push(&mut self, key: u64) {
        let mut i = self.keys.len();
        self.keys.push(key);
        while i > 0 {
            let parent = (i - 1) / 4;
            if self.keys[parent] >= key {
                break;
            }
            self.keys[i] = self.keys[parent];
            i = parent;
        }
        self.keys[i] = key;
    }

    /// Removes and returns the largest key.
    pub fn pop(&mut self) -> Option<u64> {
        let last = self.keys.pop()?;
        let n = self.keys.len();
        if n == 0 {
            return Some(last);
        }
        let top = self.keys[0];
        // Moves the last key down from the root, each step to the largest child.
        let mut i = 0;
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let mut best = first;
            for c in first + 1..(first + 4).min(n) {
                if self.keys[c] > self.keys[best] {
                    best = c;
                }
            }
            if self.keys[best] <= last {
                break;
            }
            self.keys[i] = self.keys[best];
            i = best;
        }
        self.keys[i] = last;
        Some(top)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_the_order_of_a_binary_heap() {
        let mut q = Queue::default();
        let mut reference = std::collections::BinaryHeap::new();
        let mut s = 7u64;
        for round in 0..20_000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Mostly pushes early, mostly pops late; small keys, so many ties.
            if (s >> 40) % 100 < if round < 10_000 { 70 } else { 30 } {
                let k = (s >> 20) % 500;
                q.push(k);
                reference.push(k);
            } else {
                assert_eq!(q.pop(), reference.pop());
            }
        }
        while let Some(k) = reference.pop() {
            assert_eq!(q.pop(), Some(k));
        }
        assert_eq!(q.pop(), None);
    }
}
