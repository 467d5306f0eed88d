//! A max-priority queue of `u64` keys, each naming its item in its low 32 bits, at most
//! one key per item: an implicit 4-ary heap indexed by item, so an item's key is changed
//! or removed in place (no stale entries to pop and skip later). Half as deep as a binary
//! heap, and a node's four children share a cache line, so a walk down the heap takes half
//! the cache misses and unpredictable branches of `BinaryHeap`'s.

/// Where an item not in the queue is.
const OUT: u32 = u32::MAX;

/// The item a key names.
fn item(key: u64) -> usize {
    key as u32 as usize
}

/// The heap: `keys[0]` is the largest, node `i`'s children are `4i + 1 ..= 4i + 4`.
#[derive(Default)]
pub struct Queue {
    keys: Vec<u64>,
    /// Each item's node, [`OUT`] when it has no key.
    node: Vec<u32>,
}

impl Queue {
    /// Sets the key of item [`item`]`(key)` to `key`, adding it if it has none.
    pub fn set(&mut self, key: u64) {
        let t = item(key);
        if self.node.len() <= t {
            self.node.resize(t + 1, OUT);
        }
        match self.node[t] {
            OUT => {
                self.keys.push(key);
                self.up(self.keys.len() - 1, key);
            }
            i if key > self.keys[i as usize] => self.up(i as usize, key),
            i => self.down(i as usize, key),
        }
    }

    /// Removes item `t`'s key, if it has one.
    pub fn remove(&mut self, t: usize) {
        let Some(&i) = self.node.get(t) else { return };
        if i == OUT {
            return;
        }
        self.node[t] = OUT;
        let last = self.keys.pop().expect("an item in the queue has a key");
        let i = i as usize;
        if i < self.keys.len() {
            if last > self.keys[i] {
                self.up(i, last);
            } else {
                self.down(i, last);
            }
        }
    }

    /// The item with the largest key.
    pub fn peek(&self) -> Option<usize> {
        self.keys.first().map(|&k| item(k))
    }

    /// Removes the largest key and returns its item.
    pub fn pop(&mut self) -> Option<usize> {
        let top = item(*self.keys.first()?);
        self.node[top] = OUT;
        let last = self.keys.pop().expect("the queue is not empty");
        if !self.keys.is_empty() {
            self.down(0, last);
        }
        Some(top)
    }

    /// Puts `key` at node `i`, moving the smaller keys above it down until it is in order.
    fn up(&mut self, mut i: usize, key: u64) {
        while i > 0 {
            let parent = (i - 1) / 4;
            let k = self.keys[parent];
            if k >= key {
                break;
            }
            self.place(i, k);
            i = parent;
        }
        self.place(i, key);
    }

    /// Puts `key` at node `i`, moving the larger of its children up until it is in order.
    fn down(&mut self, mut i: usize, key: u64) {
        let n = self.keys.len();
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
            let k = self.keys[best];
            if k <= key {
                break;
            }
            self.place(i, k);
            i = best;
        }
        self.place(i, key);
    }

    /// Writes `key` at node `i`.
    fn place(&mut self, i: usize, key: u64) {
        self.keys[i] = key;
        self.node[item(key)] = i as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_the_largest_current_key_of_each_item() {
        // The reference: each item's current key in a map, the largest found by a scan.
        let mut q = Queue::default();
        let mut reference = std::collections::HashMap::new();
        let mut s = 7u64;
        for round in 0..20_000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let t = (s >> 50) % 300;
            // Mostly sets early, mostly pops late; small keys, so many ties of the high
            // word (the item breaks them).
            match (s >> 40) % 100 {
                r if r < if round < 10_000 { 60 } else { 25 } => {
                    let k = ((s >> 20) % 50) << 32 | t;
                    q.set(k);
                    reference.insert(t, k);
                }
                r if r < 75 => {
                    q.remove(t as usize);
                    reference.remove(&t);
                }
                _ => {
                    let top = reference.values().max().map(|&k| k & 0xffff_ffff);
                    if let Some(t) = top {
                        reference.remove(&t);
                    }
                    assert_eq!(q.peek(), top.map(|t| t as usize));
                    assert_eq!(q.pop(), top.map(|t| t as usize));
                }
            }
        }
        while let Some(t) = reference.values().max().map(|&k| k & 0xffff_ffff) {
            reference.remove(&t);
            assert_eq!(q.pop(), Some(t as usize));
        }
        assert_eq!(q.peek(), None);
        assert_eq!(q.pop(), None);
    }
}
