//! The open list: a bucket queue over `f` (plus a 4-ary heap of late keys and an O(1) stack of
//! exact ties).
//!
//! An entry is one `u128` key: the bits of `f` (non-negative floats order like their bit
//! patterns), then the complement of the high 32 bits of `g`'s bits (larger `g` first on equal
//! `f`: deepest first), then the cell index. One integer compare orders two entries.
//!
//! A\* with a consistent heuristic pops `f` in non-decreasing order and pushes keys at most a few
//! cells above the current one, so most entries go to a bucket (`f · BUCKETS_PER_CELL` rounded,
//! an append to a reused vector) and only the current bucket is ordered. Buckets are fine (1/1024
//! of a cell): on the city nearly every bucket holds a single `f`, and such a bucket goes
//! straight to the tie stack below, unsorted; a bucket with several `f` is sorted once when it
//! becomes current, with a 4-ary heap for keys pushed into it later. The pop order is exactly
//! the order of `f`: buckets split `f` monotonically, and the heap orders everything inside the
//! current bucket. Keys below the current bucket (rounding, inconsistent heuristics) join the
//! heap, keys beyond the window wait in an overflow heap, so any key sequence pops in order.
//!
//! In bucket mode (A\*, Dijkstra) keys whose `f` equals the last popped `f` exactly — most keys
//! on open ground, where the octile heuristic is exact along a whole fan of cells — go to a
//! stack of cell indices instead of a heap: push and pop are O(1), and last in, first out among
//! equal `f` goes deepest first like the `g` tie-break (a single-`f` bucket is stacked with its
//! first-pushed key on top). Pops stay in `f` order (a heap key below the stack's `f` pops
//! first); among equal `f` the order is the stack's, which A\* allows. Popped stack keys carry
//! `f` and the index only (callers read `g` from their nodes). Without buckets (JPS, Theta\*)
//! keys pop in exact key order from the heap.

/// Buckets per cell of `f`.
const BUCKETS_PER_CELL: f64 = 1024.0;
/// Buckets in the circular window (a power of two): keys up to 4 cells above the current one (an
/// A\* move raises `f` by at most 2√2 cells; farther keys wait in the overflow heap).
const WINDOW: u64 = 4096;

/// The packed key of an entry (module docs).
#[inline(always)]
pub(crate) fn key(f: f64, g: f64, index: u32) -> u128 {
    debug_assert!(f >= 0.0 && g >= 0.0);
    let g_hi = (g.to_bits() >> 32) as u32;
    (u128::from(f.to_bits()) << 64) | (u128::from(!g_hi) << 32) | u128::from(index)
}

/// The `f` of a key.
#[inline(always)]
pub(crate) fn key_f(key: u128) -> f64 {
    f64::from_bits((key >> 64) as u64)
}

/// The cell index of a key.
#[inline(always)]
pub(crate) fn key_index(key: u128) -> u32 {
    key as u32
}

/// The bucket of a key: `f · BUCKETS_PER_CELL` rounded to the nearest integer, by adding 2⁵²
/// (whose ulp is 1) and reading the bits: four instructions instead of a saturating cast. Any
/// non-decreasing function of `f` keeps the pop order exact; this one is, for every `f ≥ 0`
/// (beyond 2⁵² it stops being the rounded value but stays non-decreasing, and such keys wait in
/// `far`).
#[inline(always)]
fn bucket(key: u128) -> u64 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    (key_f(key) * BUCKETS_PER_CELL + TWO_52).to_bits() - TWO_52.to_bits()
}

/// A 4-ary min-heap of keys.
#[derive(Debug, Default)]
struct QuadHeap {
    keys: Vec<u128>,
}

impl QuadHeap {
    #[inline(always)]
    fn push(&mut self, key: u128) {
        let keys = &mut self.keys;
        let mut at = keys.len();
        keys.push(key);
        while at > 0 {
            let up = (at - 1) / 4;
            if keys[up] <= key {
                break;
            }
            keys[at] = keys[up];
            at = up;
        }
        keys[at] = key;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<u128> {
        let keys = &mut self.keys;
        let last = keys.pop()?;
        if keys.is_empty() {
            return Some(last);
        }
        let top = keys[0];
        let n = keys.len();
        let mut at = 0;
        loop {
            let first = 4 * at + 1;
            if first >= n {
                break;
            }
            let end = (first + 4).min(n);
            let mut best = first;
            for c in first + 1..end {
                if keys[c] < keys[best] {
                    best = c;
                }
            }
            if keys[best] >= last {
                break;
            }
            keys[at] = keys[best];
            at = best;
        }
        keys[at] = last;
        Some(top)
    }

    #[inline]
    fn peek(&self) -> Option<u128> {
        self.keys.first().copied()
    }

    fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    fn clear(&mut self) {
        self.keys.clear();
    }
}

#[derive(Debug)]
pub(crate) struct BucketQueue {
    /// `WINDOW` buckets; bucket `b` (absolute) lives at `b % WINDOW`.
    buckets: Vec<Vec<u128>>,
    /// Absolute bucket of `current`; every key in `current` has a bucket ≤ `base` (`u64::MAX`
    /// without buckets).
    base: u64,
    /// Keys in `buckets`.
    in_buckets: usize,
    /// False: every key goes to `current`.
    use_buckets: bool,
    /// Bit `s` set iff bucket slot `s` is non-empty: empty buckets are skipped a word at a time.
    occupied: [u64; (WINDOW / 64) as usize],
    current: QuadHeap,
    /// The keys of bucket `base` when it became current, sorted largest first (popped from the
    /// end) unless they all went to `ties`; keys pushed into it later go to `current`.
    sorted: Vec<u128>,
    /// Keys with a bucket ≥ `base + WINDOW` when pushed.
    far: QuadHeap,
    /// Bits of the `f` of the last key popped from a heap while `ties` was empty (`NO_TIE`
    /// before the first): in bucket mode, keys with exactly this `f` skip the heaps.
    tie_f: u64,
    /// Cell indices of keys whose `f` is `tie_f`, popped last in, first out (module docs).
    ties: Vec<u32>,
}

/// `tie_f` before any pop (no `f` of a key has these bits: keys are non-negative).
const NO_TIE: u64 = u64::MAX;

impl Default for BucketQueue {
    fn default() -> Self {
        Self {
            buckets: (0..WINDOW).map(|_| Vec::new()).collect(),
            base: 0,
            in_buckets: 0,
            use_buckets: true,
            occupied: [0; (WINDOW / 64) as usize],
            current: QuadHeap::default(),
            sorted: Vec::new(),
            far: QuadHeap::default(),
            tie_f: NO_TIE,
            ties: Vec::new(),
        }
    }
}

impl BucketQueue {
    /// Empties the queue, keeping its memory. Without `buckets` every key goes to the heap (for
    /// searches with few, far-apart keys, where buckets only cost).
    pub(crate) fn clear(&mut self, buckets: bool) {
        self.use_buckets = buckets;
        if self.in_buckets > 0 {
            for slot in 0..WINDOW as usize {
                if self.occupied[slot / 64] & (1 << (slot % 64)) != 0 {
                    self.buckets[slot].clear();
                }
            }
        }
        self.occupied = [0; (WINDOW / 64) as usize];
        self.in_buckets = 0;
        self.base = if buckets { 0 } else { u64::MAX };
        self.current.clear();
        self.sorted.clear();
        self.far.clear();
        self.ties.clear();
        self.tie_f = NO_TIE;
    }

    /// Queues a key.
    #[inline(always)]
    pub(crate) fn push(&mut self, key: u128) {
        if (key >> 64) as u64 == self.tie_f {
            self.ties.push(key_index(key));
            return;
        }
        let b = bucket(key);
        // Without buckets `base` is `u64::MAX`: every key goes to `current`.
        if b <= self.base {
            self.current.push(key);
        } else if b - self.base < WINDOW {
            self.put_in_bucket(b, key);
        } else {
            self.far.push(key);
        }
    }

    #[inline(always)]
    fn put_in_bucket(&mut self, b: u64, key: u128) {
        let slot = (b % WINDOW) as usize;
        self.buckets[slot].push(key);
        self.occupied[slot / 64] |= 1 << (slot % 64);
        self.in_buckets += 1;
    }

    /// The first non-empty bucket after `base` (some bucket must be non-empty).
    fn next_occupied(&self) -> u64 {
        let start = ((self.base + 1) % WINDOW) as usize;
        let words = self.occupied.len();
        // Scan the words from `start`'s word, wrapping once; the first word masked below `start`.
        for k in 0..=words {
            let w = (start / 64 + k) % words;
            let mut bits = self.occupied[w];
            if k == 0 {
                bits &= !0u64 << (start % 64);
            }
            if k == words {
                bits &= !(!0u64 << (start % 64));
            }
            if bits != 0 {
                let slot = (w * 64 + bits.trailing_zeros() as usize) as u64;
                let ahead = (slot + WINDOW - start as u64) % WINDOW;
                return self.base + 1 + ahead;
            }
        }
        self.base + 1
    }

    /// The smallest key of the current bucket (`sorted` or `current`).
    #[inline(always)]
    fn peek_current(&self) -> Option<u128> {
        match (self.sorted.last(), self.current.peek()) {
            (Some(&a), Some(b)) => Some(a.min(b)),
            (a, b) => a.copied().or(b),
        }
    }

    /// Removes the smallest key of the current bucket.
    #[inline(always)]
    fn pop_current(&mut self) -> Option<u128> {
        match (self.sorted.last(), self.current.peek()) {
            (Some(&a), Some(b)) if b < a => self.current.pop(),
            (Some(_), _) => self.sorted.pop(),
            (None, _) => self.current.pop(),
        }
    }

    /// Removes the smallest key.
    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<u128> {
        loop {
            if let Some(&index) = self.ties.last() {
                // A key below `tie_f` (rounding) still comes first.
                if self
                    .peek_current()
                    .is_none_or(|top| ((top >> 64) as u64) >= self.tie_f)
                {
                    self.ties.pop();
                    return Some((u128::from(self.tie_f) << 64) | u128::from(index));
                }
                return self.pop_current();
            }
            if let Some(k) = self.pop_current() {
                if self.use_buckets {
                    self.tie_f = (k >> 64) as u64;
                }
                return Some(k);
            }
            if !self.advance() {
                return None;
            }
        }
    }

    /// Moves `base` to the next non-empty bucket and loads it (and due overflow keys) into
    /// `sorted`, or onto the tie stack if they all have one `f`; false if the queue is empty.
    #[cold]
    fn advance(&mut self) -> bool {
        loop {
            if self.in_buckets == 0 {
                // Nothing in the window: jump to the overflow's first bucket.
                let Some(top) = self.far.peek() else {
                    return false;
                };
                self.base = self.base.max(bucket(top));
            } else {
                self.base = self.next_occupied();
                let slot = (self.base % WINDOW) as usize;
                self.occupied[slot / 64] &= !(1 << (slot % 64));
                let keys = &mut self.buckets[slot];
                self.in_buckets -= keys.len();
                // `sorted` is empty here: take the bucket's vector (its keys), leave it ours.
                std::mem::swap(&mut self.sorted, keys);
            }
            while let Some(k) = self.far.peek() {
                let b = bucket(k);
                if b - self.base.min(b) >= WINDOW {
                    break;
                }
                self.far.pop();
                if b <= self.base {
                    self.sorted.push(k);
                } else {
                    // Now inside the window.
                    self.put_in_bucket(b, k);
                }
            }
            if !self.sorted.is_empty() {
                let f = (self.sorted[0] >> 64) as u64;
                if self.use_buckets && self.sorted.iter().all(|&k| (k >> 64) as u64 == f) {
                    // One `f` (the usual case with fine buckets): no sort, the tie stack takes
                    // them, the first pushed on top.
                    self.ties
                        .extend(self.sorted.iter().rev().map(|&k| key_index(k)));
                    self.tie_f = f;
                    self.sorted.clear();
                    return true;
                }
                self.sorted.sort_unstable_by(|a, b| b.cmp(a));
                return true;
            }
            if !self.current.is_empty() {
                return true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::TestCaseError;
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    /// Pops one key from each queue and checks they have the same `f` (bucket mode may order
    /// equal-`f` keys differently); `popped` collects (f bits, index) per side.
    fn pop_both(
        queue: &mut BucketQueue,
        heap: &mut BinaryHeap<Reverse<u128>>,
        popped: &mut [Vec<(u64, u32)>; 2],
    ) -> Result<Option<f64>, TestCaseError> {
        let (a, b) = (queue.pop(), heap.pop().map(|Reverse(k)| k));
        prop_assert_eq!(a.map(key_f), b.map(key_f));
        if let (Some(a), Some(b)) = (a, b) {
            popped[0].push(((a >> 64) as u64, key_index(a)));
            popped[1].push(((b >> 64) as u64, key_index(b)));
        }
        Ok(a.map(key_f))
    }

    fn same_entries(popped: &mut [Vec<(u64, u32)>; 2]) -> Result<(), TestCaseError> {
        popped[0].sort_unstable();
        popped[1].sort_unstable();
        prop_assert_eq!(&popped[0], &popped[1]);
        popped[0].clear();
        popped[1].clear();
        Ok(())
    }

    proptest! {
        /// Any interleaving of pushes and pops pops a binary heap's `f` sequence and the same
        /// entries (the exact key order without buckets), for keys that mostly rise from the
        /// last pop (A\*) but also fall below it, tie, or jump far ahead.
        #[test]
        fn pops_in_key_order(
            ops in proptest::collection::vec((0u8..4, 0.0f64..3.0, 0u8..3, 0u32..50), 1..400)
        ) {
            let mut queue = BucketQueue::default();
            let mut heap = BinaryHeap::new();
            let mut popped = [Vec::new(), Vec::new()];
            let mut buckets = true;
            let mut last_f = 0.0f64;
            for (k, (op, step, g, index)) in ops.into_iter().enumerate() {
                if op == 0 {
                    if !buckets {
                        let (a, b) = (queue.pop(), heap.pop().map(|Reverse(k)| k));
                        prop_assert_eq!(a, b);
                        if let Some(a) = a { last_f = key_f(a); }
                    } else if let Some(f) = pop_both(&mut queue, &mut heap, &mut popped)? {
                        last_f = f;
                    }
                } else {
                    let f = match k % 7 {
                        0 => (last_f - step * 0.01).max(0.0),  // a little below the current key
                        1 => last_f + step * 100.0,            // far ahead, past the window
                        2 | 3 => last_f,                       // a tie
                        4 => last_f + step * 1e-3,             // another f in the same bucket
                        _ => last_f + step,
                    };
                    let key = key(f, f64::from(g), index);
                    prop_assert_eq!((key_f(key), key_index(key)), (f, index));
                    queue.push(key);
                    heap.push(Reverse(key));
                }
                if k % 50 == 49 {
                    if k % 200 == 199 {
                        // Cleared with keys left: nothing to compare.
                        popped[0].clear();
                        popped[1].clear();
                    } else {
                        while !heap.is_empty() {
                            pop_both(&mut queue, &mut heap, &mut popped)?;
                        }
                        prop_assert!(queue.pop().is_none());
                        same_entries(&mut popped)?;
                    }
                    buckets = k % 100 == 49;
                    queue.clear(buckets);
                    heap.clear();
                    last_f = 0.0;
                }
            }
            while !heap.is_empty() {
                pop_both(&mut queue, &mut heap, &mut popped)?;
            }
            same_entries(&mut popped)?;
            prop_assert!(queue.pop().is_none());
        }
    }

    proptest! {
        /// Octile costs `s + d√2` (the A\* keys: many exact ties, distinct `f` closer than a
        /// bucket) pushed in any order and popped at any time: the `f` sequence of a binary
        /// heap, and the same entries.
        #[test]
        fn octile_costs_pop_in_f_order(
            ops in proptest::collection::vec((any::<bool>(), 0u32..30, 0u32..30, 0u32..1000), 1..500)
        ) {
            let mut queue = BucketQueue::default();
            let mut heap = BinaryHeap::new();
            let mut popped = [Vec::new(), Vec::new()];
            for (pop, s, d, index) in ops {
                if pop {
                    pop_both(&mut queue, &mut heap, &mut popped)?;
                } else {
                    let f = crate::nodes::counts_cost(s, d);
                    let g = crate::nodes::counts_cost(s / 2, d / 2);
                    queue.push(key(f, g, index));
                    heap.push(Reverse(key(f, g, index)));
                }
            }
            while !heap.is_empty() {
                pop_both(&mut queue, &mut heap, &mut popped)?;
            }
            prop_assert!(queue.pop().is_none());
            same_entries(&mut popped)?;
        }
    }

    #[test]
    fn bucket_is_monotone_in_f() {
        let mut last = 0;
        for k in 0..100_000u32 {
            let f = f64::from(k) * 0.013_7;
            let b = bucket(key(f, 0.0, 0));
            assert!(b >= last, "f {f}");
            assert_eq!(b, (f * BUCKETS_PER_CELL).round_ties_even() as u64);
            last = b;
        }
        for f in [1e12, 1e15, 1e300, f64::MAX] {
            let b = bucket(key(f, 0.0, 0));
            assert!(b >= last);
            last = b;
        }
    }

    #[test]
    fn keys_order_by_f_then_larger_g_then_index() {
        assert!(key(1.0, 0.0, 0) < key(1.5, 9.0, 0));
        assert!(key(2.0, 1.5, 7) < key(2.0, 1.0, 3));
        assert!(key(2.0, 1.0, 3) < key(2.0, 1.0, 4));
    }
}
