//! The photon kd-tree: an implicit kd-tree in in-order layout with bucket leaves,
//! stored in the photon array itself.
//!
//! A range `lo..hi` of the array is a subtree. When it holds at most [`BUCKET`]
//! photons it is a leaf, scanned linearly. Otherwise the photon at its middle,
//! `m = lo + ⌊(hi − lo)/2⌋`, is the median along the longest axis of the range's
//! bounding box: it carries that axis in its two axis bits, `lo..m` holds the photons
//! at or below its plane and `m + 1..hi` those at or above. This is Bentley's kd-tree
//! (*Multidimensional binary search trees used for associative searching*, CACM 1975)
//! with the median split, in the implicit in-order (sorted-array) layout, and with
//! bucket leaves (Friedman, Bentley & Finkel, *An algorithm for finding best matches
//! in logarithmic expected time*, ACM TOMS 1977; nanoflann's `leaf_max_size`).
//!
//! Every subtree is contiguous, so the deep levels of a search — where it spends its
//! time — lie in a few cache lines, and a leaf's photons are read in one sweep; there
//! are no pointers and no extra memory. (Jensen's left-balanced heap layout, §6.3 of
//! *Realistic Image Synthesis Using Photon Mapping*, scatters a subtree's nodes over
//! the whole array and needs a permutation after the partition.)
//!
//! [`balance`] reorders the caller's slice in place: `select_nth_unstable` around each
//! range's middle, with an explicit stack of ranges; cost `O(N log N)`. A range of
//! length `n` has children of lengths `⌊n/2⌋` and `⌊(n − 1)/2⌋`, so a split range at
//! depth `d` holds more than [`BUCKET`] and at most `N/2^d` photons: at most 29 levels
//! of splits for up to `2^32` photons. Queries walk the tree depth first with a stack of
//! the far sides still to search (one per split level at most): nearer child first,
//! the far child only while its splitting plane is within the search radius.

use super::packed::Photon;
use crate::math::Vec3;

/// Most photons in a leaf; a longer range is split. Measured on issue 12's renders
/// (callgrind, 200k photons a light): buckets of 4 and 16 execute 1–4 % more
/// instructions on the scene of two balls, a mirror and a tube than 8 (4 is 0.6 %
/// fewer on the tube scene).
pub const BUCKET: usize = 8;

/// Most levels of splits of an array of up to `2^32` photons: a split range at depth
/// `d` holds more than [`BUCKET`] and at most `2^32/2^d` photons (29 for buckets of 8).
const MAX_DEPTH: usize = {
    let mut d = 0;
    while (u32::MAX >> d) as usize > BUCKET {
        d += 1;
    }
    d
};

// A split range is longer than BUCKET, so both its children are non-empty.
const _: () = assert!(BUCKET >= 2);

/// Balances `photons` in place into the kd-tree [`KdTree::from_balanced`] reads.
pub fn balance(photons: &mut [Photon]) {
    partition(photons, 0, Subtree::root(photons.len()));
}

/// A subtree still to be partitioned: the range `lo..hi` of the whole array, `depth`
/// splits below the root.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Subtree {
    /// First position of the subtree.
    pub lo: usize,
    /// One past its last.
    pub hi: usize,
    /// Its depth in the tree (the root's is 0).
    pub depth: u32,
}

impl Subtree {
    /// The whole array of `n` photons: the root.
    pub fn root(n: usize) -> Self {
        Subtree {
            lo: 0,
            hi: n,
            depth: 0,
        }
    }

    /// The two children of this subtree split at position `m` (of the whole array):
    /// `lo..m` and `m + 1..hi`, one level deeper.
    fn children(&self, m: usize) -> [Subtree; 2] {
        let depth = self.depth + 1;
        [
            Subtree {
                lo: self.lo,
                hi: m,
                depth,
            },
            Subtree {
                lo: m + 1,
                hi: self.hi,
                depth,
            },
        ]
    }
}

/// One step of [`balance`], for a caller that has threads (the core has none): splits
/// subtree `t` — `photons` is the whole array's slice `t.lo..t.hi` — at its median and
/// returns its two children, each with its own slice; `None` for a leaf. Children
/// split further, or balanced with [`balance_subtree`], in any order and on any
/// thread, give the array [`balance`] makes, bit for bit: each range is partitioned
/// by the same steps on the same photons whoever does it.
pub fn split_subtree(photons: &mut [Photon], t: Subtree) -> Option<[(&mut [Photon], Subtree); 2]> {
    debug_assert_eq!(photons.len(), t.hi - t.lo);
    if photons.len() <= BUCKET {
        return None;
    }
    let mid = split(photons);
    let (left, right) = photons.split_at_mut(mid);
    let [l, r] = t.children(t.lo + mid);
    Some([(left, l), (&mut right[1..], r)])
}

/// Balances subtree `t`; `photons` is the whole array's slice `t.lo..t.hi`.
pub fn balance_subtree(photons: &mut [Photon], t: Subtree) {
    debug_assert_eq!(photons.len(), t.hi - t.lo);
    partition(photons, t.lo, t);
}

/// Splits a range longer than [`BUCKET`] at its middle `⌊len/2⌋`, which it returns:
/// the median along the longest axis of the range's bounding box, tagged with that
/// axis.
fn split(range: &mut [Photon]) -> usize {
    let mid = range.len() / 2;
    let axis = longest_axis(range);
    select_median(range, mid, axis);
    range[mid].set_axis(axis);
    mid
}

/// Puts the photon of rank `mid` along `axis` at `mid`, those at or below it before
/// and those at or above after (`select_nth_unstable` by the coordinate's total
/// order). With `std`, one select per axis, each reading a fixed word: its inner loop
/// loads one word per photon instead of indexing by a variable axis (the desktop's
/// balance 10% faster); a device's flash holds one copy (three cost 6 KiB).
#[cfg(feature = "std")]
fn select_median(range: &mut [Photon], mid: usize, axis: usize) {
    match axis {
        0 => select_on::<0>(range, mid),
        1 => select_on::<1>(range, mid),
        _ => select_on::<2>(range, mid),
    }
}

#[cfg(feature = "std")]
#[inline(never)]
fn select_on<const A: usize>(range: &mut [Photon], mid: usize) {
    range.select_nth_unstable_by(mid, |a, b| a.coord(A).total_cmp(&b.coord(A)));
}

#[cfg(not(feature = "std"))]
fn select_median(range: &mut [Photon], mid: usize, axis: usize) {
    range.select_nth_unstable_by(mid, |a, b| a.coord(axis).total_cmp(&b.coord(axis)));
}

/// Partitions `start` and every subtree below it. `photons` holds the positions
/// `base..base + photons.len()` of the whole array.
fn partition(photons: &mut [Photon], base: usize, start: Subtree) {
    // The ranges still to split. Right first, so that the left one is split next: the
    // stack then holds at most one pending right range per level.
    let mut stack = [start; usize::BITS as usize + 1];
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let t = stack[sp];
        if t.hi - t.lo <= BUCKET {
            continue; // a leaf
        }
        let m = t.lo + split(&mut photons[t.lo - base..t.hi - base]);
        let [left, right] = t.children(m);
        (stack[sp], stack[sp + 1]) = (right, left);
        sp += 2;
    }
}

/// The axis along which the photons' bounding box is longest.
fn longest_axis(photons: &[Photon]) -> usize {
    let (lo, hi) = bounding_box(photons);
    let e = hi - lo;
    if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    }
}

/// The bounding box of no photon, `(+∞, −∞)`: merged with any box, that box.
pub(crate) const NO_BOX: (Vec3, Vec3) = (Vec3::INFINITY, Vec3::NEG_INFINITY);

/// The bounding box of the photons' positions, `(lo, hi)`; [`NO_BOX`] without
/// photons. `Vec3::min`/`max` are IEEE minNum/maxNum, `min_num`/`max_num` for
/// finite coordinates (an equal one of the other sign of zero may land either way; no
/// test reads the box's sign of zero). About 2.7 ns a photon on the host whether the
/// photons are in cache or not (5.6 ms for 2.1M; a strict comparison per coordinate
/// measured the same, and executes 10% more instructions in the portable build).
pub(crate) fn bounding_box(photons: &[Photon]) -> (Vec3, Vec3) {
    let (mut lo, mut hi) = NO_BOX;
    for p in photons {
        let q = p.position();
        lo = lo.min(q);
        hi = hi.max(q);
    }
    (lo, hi)
}

/// One photon found by a query: its squared distance and index in the tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Neighbor {
    /// Squared distance from the query point.
    pub dist2: f32,
    /// Index of the photon in the tree's array.
    pub index: u32,
}

/// The result of a k-nearest query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    /// How many photons were found (≤ k).
    pub count: usize,
    /// The squared search radius at the end: the `k`-th nearest distance when `k`
    /// photons were found, else the maximum radius asked for.
    pub radius2: f32,
}

/// A balanced photon array, ready for queries.
#[derive(Clone, Copy, Debug)]
pub struct KdTree<'a> {
    photons: &'a [Photon],
}

impl<'a> KdTree<'a> {
    /// Views an array already balanced by [`balance`] (at most `u32::MAX` photons: a
    /// [`Neighbor`] names its photon by a `u32`).
    pub fn from_balanced(photons: &'a [Photon]) -> Self {
        debug_assert!(photons.len() <= u32::MAX as usize);
        Self { photons }
    }

    /// The photons, in the tree's order.
    pub fn photons(&self) -> &'a [Photon] {
        self.photons
    }

    /// Number of photons.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// `true` when the tree holds no photon.
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Calls `visit(index, dist2)` for each photon with squared distance `< radius2`
    /// from `x`; `visit` returns the (possibly smaller) radius² to search on with, and
    /// a radius² of 0 (or NaN) ends the search.
    ///
    /// Depth first from the root: each splitting photon on the way is tested when its
    /// plane is within reach (it can be no nearer), and the walk goes on into the child
    /// on `x`'s side of its plane, keeping the other child on a stack when the plane is
    /// within reach (at most one per split level: a fixed 29 entries of 8 bytes, never
    /// zeroed). A leaf is scanned in order; then the deepest kept far side whose plane
    /// is still within the current radius — recomputed, as a k-nearest search shrinks
    /// it — is searched. A splitting photon is scanned as a range of one, by the
    /// leaves' loop, so `visit` has one call site: inlined twice, a gather's kernel cost
    /// a Cortex-M4F 1 KiB of flash.
    #[inline]
    pub fn search(&self, x: Vec3, radius2: f32, visit: impl FnMut(usize, f32) -> f32) {
        self.search_boxed(x, radius2, [f32::INFINITY; 3], visit);
    }

    /// [`search`](Self::search) that also skips every part of the tree outside the box
    /// `|p − x|ᵢ < sqrt(half2[i])` about `x`: a far side is kept only when its plane is
    /// within both the radius and the box's half-extent on its axis. Photons inside the
    /// box are visited in the same order as by `search`; some outside it are not
    /// visited at all. A footprint gather passes the bounding box of its
    /// parallelogram, which a ball about a thin one holds many times over.
    #[inline]
    pub fn search_boxed(
        &self,
        x: Vec3,
        mut radius2: f32,
        half2: [f32; 3],
        mut visit: impl FnMut(usize, f32) -> f32,
    ) {
        let photons = self.photons;
        // An array, not `Vec3`: glam indexes a `Vec3` by a `match`, an array by address.
        let xa = x.to_array();
        // A splitting photon's axis, and x's signed distance from its plane.
        let plane = |m: usize| {
            let p = &photons[m];
            let axis = p.axis();
            (axis, xa[axis] - p.coord(axis))
        };
        let mut far: heapless::Vec<Far, MAX_DEPTH> = heapless::Vec::new();
        let (mut lo, mut hi) = (0usize, photons.len());
        loop {
            // One step: the splitting photon of a range and the descent into the child
            // on x's side, or a whole leaf. Both scan photons in one loop, so that
            // `visit` is inlined once.
            let leaf = hi - lo <= BUCKET;
            let scan = if leaf {
                lo..hi
            } else {
                let m = lo + (hi - lo) / 2;
                let (axis, delta) = plane(m);
                // The far side can hold photons within reach only if its plane is (the
                // radius may shrink at `m`: the pop tests again).
                let d2 = delta * delta;
                if d2 < radius2 && d2 < half2[axis] {
                    // Cannot fail: one entry per split level above, ≤ MAX_DEPTH of them.
                    let _ = far.push(Far {
                        split: m as u32,
                        end: if delta < 0.0 { hi } else { lo } as u32,
                    });
                }
                // Into the child on x's side: a branch, not a select. With a select
                // (`cmov`) each level waits for its splitting photon's load before the
                // next can start; a branch is predicted, and the next level's load
                // starts at once. Successive gathers (the sub-pixels of a pixel, its
                // neighbours) descend the same way, so the prediction is mostly right.
                // [`cold`] only keeps the compiler from turning the branch into a
                // select (either arm will do): the gathers' time on the tuning scenes
                // at 1.6M photons a light fell 10–33%.
                if delta < 0.0 {
                    cold();
                    hi = m;
                } else {
                    lo = m + 1;
                }
                // The splitting photon is no nearer than its plane: its rounded squared
                // distance is a sum of non-negative terms, `d2` one of them. Beyond the
                // radius it is not read (most of a small search's descent).
                if d2 < radius2 {
                    m..m + 1
                } else {
                    m..m
                }
            };
            let first = scan.start;
            for (i, p) in photons[scan].iter().enumerate() {
                let d2 = (p.position() - x).length_squared();
                if d2 < radius2 {
                    radius2 = visit(first + i, d2);
                    if !(radius2 > 0.0) {
                        return;
                    }
                }
            }
            if !leaf {
                continue;
            }
            // The deepest pending far side whose plane is still within the (possibly
            // shrunk) radius.
            loop {
                let Some(next) = far.pop() else { return };
                let split = next.split as usize;
                let (_, delta) = plane(split);
                if delta * delta < radius2 {
                    let end = next.end as usize;
                    (lo, hi) = if end > split {
                        (split + 1, end)
                    } else {
                        (end, split)
                    };
                    break;
                }
            }
        }
    }

    /// The `k` nearest photons to `x` closer than `sqrt(max_radius2)` (`k` at most the
    /// capacity `K`), as a max-heap on distance in `out` (the farthest first). `out` is
    /// the caller's fixed-capacity buffer; it is cleared first, and its storage is never
    /// zeroed (on a microcontroller that would cost as much as the search).
    pub fn k_nearest<const K: usize>(
        &self,
        x: Vec3,
        max_radius2: f32,
        k: usize,
        out: &mut heapless::Vec<Neighbor, K>,
    ) -> Found {
        out.clear();
        let k = k.min(K);
        if k == 0 {
            return Found {
                count: 0,
                radius2: max_radius2,
            };
        }
        self.search(x, max_radius2, |index, dist2| {
            let nb = Neighbor {
                dist2,
                index: index as u32,
            };
            if out.len() < k {
                // Cannot fail: len < k ≤ K.
                let _ = out.push(nb);
                let last = out.len() - 1;
                sift_up(out, last);
                if out.len() == k {
                    return out[0].dist2;
                }
                max_radius2
            } else {
                // The search only offers photons closer than out[0].
                out[0] = nb;
                sift_down(out, 0);
                out[0].dist2
            }
        });
        let count = out.len();
        let radius2 = if count == k {
            out[0].dist2
        } else {
            max_radius2
        };
        Found { count, radius2 }
    }
}

/// Marks the branch it is called in as the unlikely one: the compiler then keeps the
/// branch instead of a select (`core::hint::cold_path` from Rust 1.95; this form, as in
/// hashbrown, builds on the crate's minimum Rust).
#[inline(always)]
#[cold]
fn cold() {}

/// A far side a search has still to visit: the child of the range split at `split`
/// that ends at `end`, i.e. `split + 1..end` when `end > split`, else `end..split`.
/// Eight bytes, so that the stack costs a device 8·[`MAX_DEPTH`] bytes of RAM.
#[derive(Clone, Copy, Debug)]
struct Far {
    split: u32,
    end: u32,
}

fn sift_up(heap: &mut [Neighbor], mut i: usize) {
    while i > 0 {
        let parent = (i - 1) / 2;
        if heap[parent].dist2 >= heap[i].dist2 {
            break;
        }
        heap.swap(parent, i);
        i = parent;
    }
}

fn sift_down(heap: &mut [Neighbor], mut i: usize) {
    let n = heap.len();
    loop {
        let (l, r) = (2 * i + 1, 2 * i + 2);
        let mut largest = i;
        if l < n && heap[l].dist2 > heap[largest].dist2 {
            largest = l;
        }
        if r < n && heap[r].dist2 > heap[largest].dist2 {
            largest = r;
        }
        if largest == i {
            return;
        }
        heap.swap(i, largest);
        i = largest;
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::math::{Rgb, UnitVec3};
    use crate::sampling::Pcg32;

    fn photon(p: Vec3, tag: u32) -> Photon {
        // Tag photons through their power so that identity survives balancing: with the
        // red channel in [128, 256) every channel is an exact 8-bit RGBE mantissa.
        assert!(tag < 1 << 15);
        Photon::new(
            p,
            UnitVec3::Y,
            Rgb::new((128 + (tag & 127)) as f32, (tag >> 7) as f32, 0.0),
        )
    }

    fn tag(p: &Photon) -> u32 {
        let c = p.power();
        (c.r as u32 - 128) | ((c.g as u32) << 7)
    }

    fn random_set(n: usize, seed: u64) -> Vec<Photon> {
        let mut g = Pcg32::new(seed);
        (0..n)
            .map(|i| {
                photon(
                    Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 10.0,
                    i as u32,
                )
            })
            .collect()
    }

    /// Every split range is split by its middle photon: the photons before it are at
    /// or below its plane, those after it at or above.
    fn assert_tree_property(photons: &[Photon]) {
        let mut stack = std::vec![(0, photons.len())];
        while let Some((lo, hi)) = stack.pop() {
            if hi - lo <= BUCKET {
                continue;
            }
            let m = lo + (hi - lo) / 2;
            let axis = photons[m].axis();
            let split = photons[m].coord(axis);
            assert!(
                photons[lo..m].iter().all(|p| p.coord(axis) <= split),
                "{lo}..{hi}"
            );
            assert!(
                photons[m + 1..hi].iter().all(|p| p.coord(axis) >= split),
                "{lo}..{hi}"
            );
            stack.push((lo, m));
            stack.push((m + 1, hi));
        }
    }

    fn brute_k_nearest(photons: &[Photon], x: Vec3, r2: f32, k: usize) -> Vec<f32> {
        let mut d: Vec<f32> = photons
            .iter()
            .map(|p| (p.position() - x).length_squared())
            .filter(|&d| d < r2)
            .collect();
        d.sort_by(f32::total_cmp);
        d.truncate(k);
        d
    }

    fn check_queries(photons: &[Photon], seed: u64) {
        let mut tree_photons = photons.to_vec();
        balance(&mut tree_photons);
        // Nothing lost, nothing duplicated.
        let mut before: Vec<u32> = photons.iter().map(tag).collect();
        let mut after: Vec<u32> = tree_photons.iter().map(tag).collect();
        before.sort_unstable();
        after.sort_unstable();
        assert_eq!(before, after);
        assert_tree_property(&tree_photons);
        let tree = KdTree::from_balanced(&tree_photons);
        let mut g = Pcg32::new(seed);
        for q in 0..60 {
            let x = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 12.0 - Vec3::ONE;
            let k = [1, 2, 7, 32][q % 4];
            let r2 = [0.5f32, 4.0, 1e9][q % 3];
            let mut out: heapless::Vec<Neighbor, 32> = heapless::Vec::new();
            let found = tree.k_nearest(x, r2, k, &mut out);
            let mut got: Vec<f32> = out[..found.count].iter().map(|n| n.dist2).collect();
            got.sort_by(f32::total_cmp);
            let want = brute_k_nearest(photons, x, r2, k);
            assert_eq!(got, want, "query {q} k={k} r2={r2}");
            // Each reported distance belongs to the photon it names.
            for nb in &out[..found.count] {
                assert_eq!(
                    (tree_photons[nb.index as usize].position() - x).length_squared(),
                    nb.dist2
                );
            }
            // A radius query sees exactly the brute-force set.
            let mut inside = 0;
            tree.search(x, r2, |_, _| {
                inside += 1;
                r2
            });
            assert_eq!(inside, brute_k_nearest(photons, x, r2, usize::MAX).len());
            // A boxed search visits every photon in the box and the ball, in the order
            // the plain search visits them, and fewer outside the box.
            let h = Vec3::new(g.next_f32(), g.next_f32() * 0.1, g.next_f32() * 3.0);
            let in_box = |i: usize| {
                let d = (tree_photons[i].position() - x).abs();
                d.x < h.x && d.y < h.y && d.z < h.z
            };
            let (mut plain, mut boxed, mut boxed_visits) = (Vec::new(), Vec::new(), 0);
            tree.search(x, r2, |i, _| {
                plain.extend(Some(i).filter(|&i| in_box(i)));
                r2
            });
            tree.search_boxed(x, r2, (h * h).to_array(), |i, _| {
                boxed_visits += 1;
                boxed.extend(Some(i).filter(|&i| in_box(i)));
                r2
            });
            assert_eq!(boxed, plain, "query {q}: the box's photons, in order");
            assert!(
                boxed_visits <= inside,
                "query {q}: {boxed_visits} > {inside}"
            );
        }
    }

    #[test]
    fn the_step_wise_balance_is_the_balance() {
        for n in [0usize, 1, 2, 7, BUCKET, BUCKET + 1, 100, 1000, 4097] {
            let base = random_set(n, 31 + n as u64);
            let mut whole = base.clone();
            balance(&mut whole);
            for levels in [0u32, 1, 3, 20] {
                let mut parts = base.clone();
                // Split the top `levels` levels, then balance the subtrees below them
                // right to left: the order must not matter.
                let mut pending = std::vec![(&mut parts[..], Subtree::root(n))];
                let mut bottom = Vec::new();
                while let Some((slice, t)) = pending.pop() {
                    if t.depth == levels {
                        bottom.push((slice, t));
                    } else if let Some(children) = split_subtree(slice, t) {
                        pending.extend(children);
                    }
                }
                for (slice, t) in bottom {
                    assert_eq!((slice.len(), t.depth), (t.hi - t.lo, levels));
                    balance_subtree(slice, t);
                }
                assert_eq!(parts, whole, "n={n} levels={levels}");
            }
        }
    }

    #[test]
    fn random_sets_of_many_sizes_agree_with_brute_force() {
        for n in [
            0usize,
            1,
            2,
            3,
            5,
            BUCKET - 1,
            BUCKET,
            BUCKET + 1,
            2 * BUCKET + 1,
            2 * BUCKET + 2,
            17,
            64,
            100,
            255,
            256,
            1000,
            4097,
            30_000,
        ] {
            check_queries(&random_set(n, n as u64), 99 + n as u64);
        }
    }

    #[test]
    fn degenerate_sets_agree_with_brute_force() {
        // All photons on a plane, on a line, and all at one point (duplicates).
        let mut g = Pcg32::new(5);
        let plane: Vec<Photon> = (0..500)
            .map(|i| photon(Vec3::new(g.next_f32() * 10.0, 0.0, g.next_f32() * 10.0), i))
            .collect();
        check_queries(&plane, 1);
        let line: Vec<Photon> = (0..300)
            .map(|i| photon(Vec3::new(1.0, 2.0, (i % 37) as f32 * 0.25), i))
            .collect();
        check_queries(&line, 2);
        let point: Vec<Photon> = (0..129).map(|i| photon(Vec3::splat(3.0), i)).collect();
        check_queries(&point, 3);
        // Collinear along a diagonal, and small point sets of every length around a
        // bucket.
        let diagonal: Vec<Photon> = (0..400)
            .map(|i| photon(Vec3::splat(g.next_f32() * 10.0), i))
            .collect();
        check_queries(&diagonal, 4);
        for n in [1, BUCKET, BUCKET + 1, 3 * BUCKET] {
            let point: Vec<Photon> = (0..n as u32).map(|i| photon(Vec3::splat(3.0), i)).collect();
            check_queries(&point, 5);
        }
    }

    #[test]
    fn a_zero_radius_ends_the_search_and_a_shrunk_one_prunes_it() {
        let photons = {
            let mut p = random_set(3000, 8);
            balance(&mut p);
            p
        };
        let tree = KdTree::from_balanced(&photons);
        let x = Vec3::splat(5.0);
        let mut calls = 0;
        tree.search(x, 1e9, |_, _| {
            calls += 1;
            0.0
        });
        assert_eq!(calls, 1);
        // Shrinking the radius to each visit's distance offers only ever-closer
        // photons, and the last offered is the nearest.
        let mut last = f32::INFINITY;
        tree.search(x, 1e9, |_, d2| {
            assert!(d2 < last);
            last = d2;
            d2
        });
        let nearest = brute_k_nearest(&photons, x, 1e9, 1)[0];
        assert_eq!(last, nearest);
    }
}
