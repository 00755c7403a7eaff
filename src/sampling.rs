//! Deterministic random and quasi-random numbers of our own: the same seed gives the
//! same numbers on every machine and every thread count.

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit hash with full
/// avalanche, used to derive independent streams from `(seed, pass, light, index)`.
#[inline]
pub const fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Hashes a list of words into one 64-bit key.
#[inline(never)]
pub fn hash(words: &[u64]) -> u64 {
    words
        .iter()
        .fold(0x9e37_79b9_7f4a_7c15, |h, &w| mix64(h ^ mix64(w)))
}

/// `u32` to a float in `[0, 1)`, using the top 24 bits (exact in `f32`).
#[inline]
pub fn unit_f32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// PCG32 (O'Neill 2014, XSH-RR output): small, fast, statistically strong, and
/// identical on 32- and 64-bit targets.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MUL: u64 = 6_364_136_223_846_793_005;

    /// A generator on the stream selected by `key` (any 64-bit value).
    pub fn new(key: u64) -> Self {
        let mut g = Self {
            state: 0,
            inc: (mix64(key ^ 0x5851_f42d_4c95_7f2d) << 1) | 1,
        };
        g.next_u32();
        g.state = g.state.wrapping_add(mix64(key));
        g.next_u32();
        g
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MUL).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// A float uniform in `[0, 1)`.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u32())
    }
}

/// The `i`-th of `n` points of a Hammersley set in `[0, 1)²` (stratified in both
/// dimensions), toroidally shifted by `shift` (Cranley–Patterson rotation) so that
/// different seeds and passes give different, equally well spread, point sets.
#[inline]
pub fn hammersley(i: u32, n: u32, shift: (f32, f32)) -> (f32, f32) {
    let u = (i as f32 + 0.5) / n as f32;
    let v = unit_f32(i.reverse_bits());
    (wrap01(u + shift.0), wrap01(v + shift.1))
}

/// The radical inverse of `i` in base `b` ≥ 2: its base-`b` digits mirrored about the
/// point, `Σ dⱼ·b^−(j+1)` (Halton 1960), in `[0, 1)`.
#[inline]
pub fn radical_inverse(i: u32, b: u32) -> f32 {
    below_one(add_digits(i, b, 0.0, 1.0 / b as f32))
}

/// `r` plus the base-`b` digits of `i`, the first weighted by `f` and each next by `1/b`
/// times the one before: the radical inverse's loop, in its order of operations.
#[inline(always)]
const fn add_digits(mut i: u32, b: u32, mut r: f32, mut f: f32) -> f32 {
    let inv = 1.0 / b as f32;
    while i > 0 {
        r += (i % b) as f32 * f;
        i /= b;
        f *= inv;
    }
    r
}

/// How many levels of thinning by 16 point `j` of a Hammersley set `((j+½)/n, φ₂(j))`
/// survives, 0 to 2, for the choice `c` (any `u32`; its low byte is used): level 2
/// keeps the `j` whose four bytes XOR to `c`'s low byte, level 1 those whose eight
/// nibbles XOR to the XOR of `c`'s two low nibbles (so level 2 lies in level 1).
///
/// For `c` uniform, each point is kept with probability exactly `16⁻ᵛ` (unbiased
/// thinning), one point of every aligned block of `16ᵛ` indices. And the points kept
/// are stratified in both coordinates: each `4v` consecutive bits of `j` are bound by
/// the constraint to the others, so for `n = 2ᵐ` the kept points form a
/// `(0, m − 4v, 2)`-net — one point in every dyadic box of area `16ᵛ/n`, whatever its
/// shape (Niederreiter 1992's elementary intervals; the bits of `j` are `j/n`'s top
/// bits and `φ₂(j)`'s bottom ones). Every 16th point instead fixes `j`'s low nibble,
/// and with it the top four bits of `φ₂(j)`: one sixteenth of the second coordinate.
#[inline]
pub const fn thinning_level(j: u32, c: u32) -> usize {
    let bytes = (j ^ j >> 8 ^ j >> 16 ^ j >> 24) & 0xff;
    let c = c & 0xff;
    if bytes == c {
        2
    } else if (bytes ^ bytes >> 4) & 0xf == (c ^ c >> 4) & 0xf {
        1
    } else {
        0
    }
}

/// A radical inverse's sum kept below 1 (rounding can reach it).
#[inline(always)]
fn below_one(r: f32) -> f32 {
    if r >= 1.0 {
        1.0 - f32::EPSILON / 2.0
    } else {
        r
    }
}

/// The bases of the point set's further dimensions: a photon's first random choices
/// (Fresnel's reflect-or-refract at each glass surface) are coordinates 3, 4, … of its
/// Hammersley point, `φ₃(i), φ₅(i), …`, so photons near each other on the light's
/// sphere also split between reflection and refraction in the right proportions.
pub const PATH_BASES: [u32; 4] = [3, 5, 7, 11];

/// The random numbers of one photon's path: the next coordinates of its Hammersley
/// point (index `i` of its set), each shifted by its own Cranley–Patterson rotation
/// derived from `key`; past [`PATH_BASES`], a PCG32 stream keyed by `hash(stream)`,
/// made only then (most paths never get there: a photon through a ball makes two
/// choices).
#[derive(Clone, Debug)]
pub struct PathSampler {
    index: u32,
    key: u64,
    dim: usize,
    stream: [u64; 4],
    rng: Option<Pcg32>,
}

impl PathSampler {
    /// The sampler of point `index` of the set rotated by `key`; `stream` keys the PCG32
    /// stream used past the point's dimensions.
    pub fn new(index: u32, key: u64, stream: [u64; 4]) -> Self {
        Self {
            index,
            key,
            dim: 0,
            stream,
            rng: None,
        }
    }

    /// The next number in `[0, 1)`. One copy for all its callers (a device's flash).
    #[inline(never)]
    pub fn next_f32(&mut self) -> f32 {
        if self.dim >= PATH_BASES.len() {
            let stream = &self.stream;
            return self
                .rng
                .get_or_insert_with(|| Pcg32::new(hash(stream)))
                .next_f32();
        }
        let shift = unit_f32(mix64(self.key ^ self.dim as u64) as u32);
        let r = path_coordinate(self.index, self.dim);
        self.dim += 1;
        wrap01(r + shift)
    }
}

/// Coordinate `dim` (< `PATH_BASES.len()`) of point `i`. With `std`, one copy
/// per base, whose divisions by a constant compile to multiplications (a runtime
/// divide costs 25–40 cycles on x86-64, one per digit), and whose first digits are
/// read from a table ([`Digits`]); a device keeps the one loop, with its 2–12-cycle
/// hardware divide. The same digits and the same float operations either way: the
/// same bits.
#[cfg(feature = "std")]
#[inline(always)]
fn path_coordinate(i: u32, dim: usize) -> f32 {
    match dim {
        0 => DIGITS_3.radical_inverse(i),
        1 => DIGITS_5.radical_inverse(i),
        2 => DIGITS_7.radical_inverse(i),
        _ => DIGITS_11.radical_inverse(i),
    }
}

/// [`radical_inverse`] in base `B` with its first digits looked up: `sums[j]` is the
/// loop's sum after the first `m` digits of any `i` with `i mod Bᵐ = j` (`N = Bᵐ`),
/// `scale` its digit weight `B^−(m+1)` then. The loop adds a zero digit as `+0.0`,
/// which changes no sum, so the table holds, bit for bit, what the first `m`
/// iterations compute, and the rest of the loop goes on from there with the same
/// operations (the photons' path decisions: 3.7M calls on the balls scene at 1.6M
/// photons a light, each of 13 digits in base 3).
#[cfg(feature = "std")]
struct Digits<const B: u32, const N: usize> {
    sums: [f32; N],
    scale: f32,
}

#[cfg(feature = "std")]
impl<const B: u32, const N: usize> Digits<B, N> {
    /// The table, evaluated by the compiler with the loop's own operations.
    const fn new() -> Self {
        let inv = 1.0 / B as f32;
        let mut sums = [0.0f32; N];
        let mut j = 0;
        while j < N {
            sums[j] = add_digits(j as u32, B, 0.0, inv);
            j += 1;
        }
        let mut scale = inv;
        let mut n = 1;
        while n < N {
            scale *= inv;
            n *= B as usize;
        }
        Self { sums, scale }
    }

    /// `radical_inverse(i, B)`, the same bits.
    #[inline(always)]
    fn radical_inverse(&self, i: u32) -> f32 {
        let first = self.sums[i as usize % N];
        below_one(add_digits(i / N as u32, B, first, self.scale))
    }
}

/// The tables of [`PATH_BASES`] (3, 5, 7, 11): 3⁸, 5⁵, 7⁴ and 11³ entries, 54 KiB in all.
#[cfg(feature = "std")]
static DIGITS_3: Digits<{ PATH_BASES[0] }, 6561> = Digits::new();
#[cfg(feature = "std")]
static DIGITS_5: Digits<{ PATH_BASES[1] }, 3125> = Digits::new();
#[cfg(feature = "std")]
static DIGITS_7: Digits<{ PATH_BASES[2] }, 2401> = Digits::new();
#[cfg(feature = "std")]
static DIGITS_11: Digits<{ PATH_BASES[3] }, 1331> = Digits::new();

/// Coordinate `dim` (< `PATH_BASES.len()`) of point `i`: see the `std` version.
#[cfg(not(feature = "std"))]
#[inline(always)]
fn path_coordinate(i: u32, dim: usize) -> f32 {
    radical_inverse(i, PATH_BASES[dim % PATH_BASES.len()])
}

/// `x − floor(x)` for `x ∈ [0, 2)`, kept strictly below 1.
#[inline]
fn wrap01(x: f32) -> f32 {
    let y = if x >= 1.0 { x - 1.0 } else { x };
    if y >= 1.0 {
        0.0
    } else {
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_one_point_in_every_elementary_box() {
        // n = 2^12 points; level v keeps 2^(12 − 4v), one per dyadic box of every shape.
        let m = 12u32;
        for c in [0u32, 0x5a, 0xff, 0x13] {
            for v in 1..=2usize {
                let kept: std::vec::Vec<u32> = (0..1u32 << m)
                    .filter(|&j| thinning_level(j, c) >= v)
                    .collect();
                let k = m - 4 * v as u32;
                assert_eq!(kept.len(), 1 << k, "c {c:#x}, level {v}");
                for a in 0..=k {
                    // Boxes of 2^-a in j/n by 2^-(k − a) in φ₂(j): each holds one point.
                    let mut seen = std::vec![0u32; 1 << k];
                    for &j in &kept {
                        let x = j >> (m - a);
                        let y = (j.reverse_bits() >> (32 - m)) >> (m - (k - a));
                        seen[((x << (k - a)) | y) as usize] += 1;
                    }
                    assert!(seen.iter().all(|&s| s == 1), "c {c:#x}, level {v}, a {a}");
                }
            }
        }
        // Every 16th point, as the levels were first taken, is no net: its points all
        // share the top four bits of φ₂.
        let stride: std::vec::Vec<u32> = (0..1u32 << m).step_by(16).collect();
        assert!(stride.iter().all(|&j| j.reverse_bits() >> 28 == 0));
    }

    #[test]
    fn thinning_keeps_every_point_with_probability_one_in_16_per_level() {
        for j in [0u32, 1, 17, 4095, 123_456_789, u32::MAX] {
            let mut count = [0u32; 3];
            for c in 0..256 {
                count[thinning_level(j, c)] += 1;
            }
            // Level ≥ 1 for 16 choices of 256, level 2 for one.
            assert_eq!(count, [240, 15, 1], "j {j}");
        }
    }

    #[test]
    fn pcg_is_uniform_enough_and_streams_differ() {
        let mut g = Pcg32::new(1);
        let n = 100_000;
        let mut buckets = [0u32; 10];
        for _ in 0..n {
            let x = g.next_f32();
            assert!((0.0..1.0).contains(&x));
            buckets[(x * 10.0) as usize] += 1;
        }
        for b in buckets {
            // 10 000 expected, σ ≈ 95: 5σ.
            assert!((b as i32 - 10_000).abs() < 500, "{buckets:?}");
        }
        let (mut a, mut b) = (Pcg32::new(1), Pcg32::new(2));
        assert!((0..8).any(|_| a.next_u32() != b.next_u32()));
    }

    /// The step and output of PCG32 against the reference implementation's published
    /// outputs (O'Neill, pcg-c-basic `pcg32-demo`: `pcg32_srandom_r(42, 54)` gives
    /// `0xa15c02b7 0x7b47f409 0xba1d3330 …`), seeded the way the reference seeds.
    #[test]
    fn pcg_matches_the_reference_implementation() {
        let (initstate, initseq) = (42u64, 54u64);
        let mut g = Pcg32 {
            state: 0,
            inc: (initseq << 1) | 1,
        };
        g.next_u32();
        g.state = g.state.wrapping_add(initstate);
        g.next_u32();
        let got: [u32; 6] = core::array::from_fn(|_| g.next_u32());
        assert_eq!(
            got,
            [0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e]
        );
    }

    /// `mix64` is SplitMix64's finaliser: SplitMix64 seeded with 0 first outputs
    /// `0xe220a8397b1dcdaf` (Vigna's reference `splitmix64.c`); and `Pcg32::new` seeds
    /// the reference generator with `(mix64(key), mix64(key ^ 0x5851f42d4c957f2d))`,
    /// whose first outputs for key 42 were computed independently (Python, the
    /// reference algorithm). A change to either changes every image.
    #[test]
    fn mix64_and_the_keyed_streams_are_pinned() {
        assert_eq!(mix64(0x9e37_79b9_7f4a_7c15), 0xe220_a839_7b1d_cdaf);
        assert_eq!(mix64(0), 0);
        let mut g = Pcg32::new(42);
        let got: [u32; 4] = core::array::from_fn(|_| g.next_u32());
        assert_eq!(got, [0xd6d50b79, 0x269212a7, 0xf003a3f6, 0xe18508ae]);
    }

    /// The point's further coordinates split the photons of any small patch of the
    /// light's sphere in the right proportions: in each of 64 cells of the first two
    /// coordinates (64 points each), the share of a path decision below 0.3 is within
    /// 6 of 19.2 — a PCG32 stream, binomial with σ ≈ 3.7, misses that in some cell.
    #[test]
    fn path_decisions_are_stratified_within_small_patches() {
        let n = 4096;
        let mut below = [[0u32; 64]; PATH_BASES.len()];
        for i in 0..n {
            let (u, v) = hammersley(i, n, (0.13, 0.71));
            let cell = (u * 8.0) as usize * 8 + (v * 8.0) as usize;
            let mut path = PathSampler::new(i, 0x5eed, [7; 4]);
            for dim in &mut below {
                dim[cell] += (path.next_f32() < 0.3) as u32;
            }
        }
        for (d, dim) in below.iter().enumerate() {
            let worst = dim
                .iter()
                .map(|&c| (c as f32 - 19.2).abs())
                .fold(0.0, f32::max);
            assert!(worst <= 6.0, "dimension {d}: {dim:?}");
        }
        let mut random = PathSampler::new(0, 0, [7; 4]);
        random.dim = PATH_BASES.len();
        let mut cells = [0u32; 64];
        for i in 0..n {
            let (u, v) = hammersley(i, n, (0.13, 0.71));
            cells[(u * 8.0) as usize * 8 + (v * 8.0) as usize] += (random.next_f32() < 0.3) as u32;
        }
        let worst = cells
            .iter()
            .map(|&c| (c as f32 - 19.2).abs())
            .fold(0.0, f32::max);
        assert!(
            worst > 6.0,
            "the PCG32 stream past the point's dimensions: {worst}"
        );
    }

    #[test]
    fn radical_inverse_mirrors_the_digits() {
        assert_eq!(radical_inverse(0, 3), 0.0);
        assert_eq!(radical_inverse(1, 3), 1.0 / 3.0);
        // 7 = 21₃ → 0.12₃ = 1/3 + 2/9
        assert!((radical_inverse(7, 3) - (1.0 / 3.0 + 2.0 / 9.0)).abs() < 1e-7);
        // 2²⁴ − 1 in base 2 is 0.111…1₂ = 1 − 2⁻²⁴
        assert_eq!(radical_inverse((1 << 24) - 1, 2), 1.0 - 1.0 / 16_777_216.0);
        assert!(radical_inverse(u32::MAX, 11) < 1.0);
    }

    #[test]
    fn hammersley_is_stratified() {
        let n = 256;
        let mut rows = [0u32; 16];
        let mut cols = [0u32; 16];
        for i in 0..n {
            let (u, v) = hammersley(i, n, (0.37, 0.81));
            rows[(u * 16.0) as usize] += 1;
            cols[(v * 16.0) as usize] += 1;
        }
        assert!(
            rows.iter().chain(cols.iter()).all(|&c| c == 16),
            "{rows:?} {cols:?}"
        );
    }

    /// The tables of the path coordinates give `radical_inverse`'s bits: every index
    /// below 40 000 (past each table's size, so across its wrap), and 200 000 spread
    /// over the whole `u32` range.
    #[cfg(feature = "std")]
    #[test]
    fn the_digit_tables_give_the_loops_bits() {
        let mut g = Pcg32::new(3);
        let spread = (0..200_000).map(|_| g.next_u32());
        for i in (0..40_000).chain(spread).chain([u32::MAX]) {
            for (dim, &b) in PATH_BASES.iter().enumerate() {
                let (got, want) = (path_coordinate(i, dim), radical_inverse(i, b));
                assert_eq!(got.to_bits(), want.to_bits(), "i {i}, base {b}");
            }
        }
    }
}
