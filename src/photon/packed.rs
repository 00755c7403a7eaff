//! The compact photon: 16 bytes, four 32-bit words.
//!
//! | word | bits 31–7 | bits 6–0 |
//! |---|---|---|
//! | 0 | position x: `f32` rounded to 16 mantissa bits | direction bits 0–6 |
//! | 1 | position y, likewise | direction bits 7–13 |
//! | 2 | position z, likewise | direction bits 14–15, kd-tree split axis (2 bits), forward-pass half (1 bit), 2 spare |
//! | 3 | power: shared-exponent RGB (Ward's RGBE), relative to the map's power unit | |
//!
//! The direction of travel is an octahedral map, 8 bits per coordinate (Cigolle et
//! al. 2014). The position keeps 17 significant bits (relative error ≤ 2⁻¹⁷ ≈ 7.6·10⁻⁶,
//! rounded to nearest): at 10 scene units from the origin 8·10⁻⁵, far below any gather
//! radius; its low 7 bits carry the rest, so each coordinate reads as one mask. The
//! power is stored relative to a per-map unit (the nominal photon power), so the common
//! photon of exactly nominal power is encoded without rounding. (Jensen's photon was
//! 20 bytes: three floats, RGBE, two angle bytes and a flag short.)

use crate::math::{Rgb, UnitVec3, Vec3};

/// A stored photon. See the module documentation for the layout.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Photon {
    words: [u32; 4],
}

const _: () = assert!(core::mem::size_of::<Photon>() == 16);

/// The low bits of a position word that carry other fields.
const PAYLOAD: u32 = 0x7f;
/// Where the axis sits in word 2's payload.
const AXIS_SHIFT: u32 = 2;
const AXIS_BITS: u32 = 0b11 << AXIS_SHIFT;
const HALF_BIT: u32 = 1 << 4;

/// `x` rounded to nearest at bit 7 of its pattern (a carry into the exponent is the
/// correct rounding); truncated instead where rounding would overflow to infinity.
#[inline]
fn round_position(x: f32) -> u32 {
    const HALF: u32 = (PAYLOAD + 1) >> 1;
    let rounded = (x.to_bits() + HALF) & !PAYLOAD;
    if f32::from_bits(rounded).is_finite() {
        rounded
    } else {
        x.to_bits() & !PAYLOAD
    }
}

impl Photon {
    /// A photon at `pos` travelling along `dir` with `power` in units of the map's unit.
    pub fn new(pos: Vec3, dir: UnitVec3, power: Rgb) -> Self {
        let d = u16::from_le_bytes(encode_octahedral(dir)) as u32;
        Self {
            words: [
                round_position(pos.x) | (d & PAYLOAD),
                round_position(pos.y) | ((d >> 7) & PAYLOAD),
                round_position(pos.z) | (d >> 14),
                u32::from_le_bytes(encode_rgbe(power)),
            ],
        }
    }

    /// An all-zero photon (const, for static arrays).
    pub(crate) const fn zeroed() -> Self {
        Self { words: [0; 4] }
    }

    /// Where it landed.
    #[inline]
    pub fn position(&self) -> Vec3 {
        Vec3::new(self.coord(0), self.coord(1), self.coord(2))
    }

    /// One coordinate of the position.
    #[inline]
    pub(crate) fn coord(&self, axis: usize) -> f32 {
        f32::from_bits(self.words[axis] & !PAYLOAD)
    }

    /// Its power, in units of the map's power unit.
    #[inline]
    pub fn power(&self) -> Rgb {
        decode_rgbe(self.words[3].to_le_bytes())
    }

    /// Its direction of travel when it landed (decoded to within about 1°).
    #[inline]
    pub fn direction(&self) -> UnitVec3 {
        let [a, b, c, _] = self.words;
        let d = (a & PAYLOAD) | ((b & PAYLOAD) << 7) | ((c & 0b11) << 14);
        decode_octahedral((d as u16).to_le_bytes())
    }

    /// The same photon marked as one of the forward pass's half 1 (`true`) or half 0:
    /// the two independent halves whose difference estimates a gather's noise
    /// ([`Halves`](super::Halves)).
    #[inline]
    pub fn with_half(mut self, half: bool) -> Self {
        self.words[2] = (self.words[2] & !HALF_BIT) | if half { HALF_BIT } else { 0 };
        self
    }

    /// Which half of the forward pass it belongs to (see [`with_half`](Self::with_half)).
    #[inline]
    pub fn half(&self) -> bool {
        self.words[2] & HALF_BIT != 0
    }

    /// The kd-tree split axis of this node (0, 1, 2).
    #[inline]
    pub(crate) fn axis(&self) -> usize {
        // Only 0, 1, 2 are ever set; `min` tells the compiler, which then drops the
        // bounds checks of every `[f32; 3]` indexed by it (kd-tree walks).
        (((self.words[2] & AXIS_BITS) >> AXIS_SHIFT) as usize).min(2)
    }

    /// Sets the kd-tree split axis (0, 1, 2).
    #[inline]
    pub(crate) fn set_axis(&mut self, axis: usize) {
        self.words[2] = (self.words[2] & !AXIS_BITS) | ((axis as u32) << AXIS_SHIFT);
    }
}

/// Ward's RGBE: one 8-bit mantissa per channel and a shared exponent
/// (Graphics Gems II, "Real Pixels"), rounding to nearest.
pub(crate) fn encode_rgbe(c: Rgb) -> [u8; 4] {
    let c = Rgb::new(c.r.max(0.0), c.g.max(0.0), c.b.max(0.0));
    let m = c.max_channel();
    if !(m > 1e-32) || !m.is_finite() {
        return [0; 4];
    }
    // m = f · 2^e with f ∈ [0.5, 1) (`frexpf`; m is normal, so e is its biased
    // exponent less 126, −106 ≤ e ≤ 128): mantissas are channel · 256 / 2^e.
    let mut e = ((m.to_bits() >> 23) & 0xff) as i32 - 126;
    let mut scale = pow2(8 - e);
    if (m * scale + 0.5) as u32 > 255 {
        // Rounding the largest channel up to 256 would overflow: use the next exponent.
        e += 1;
        scale = pow2(8 - e);
    }
    let q = |x: f32| ((x * scale + 0.5) as u32).min(255) as u8;
    [q(c.r), q(c.g), q(c.b), (e + 128).clamp(0, 255) as u8]
}

pub(crate) fn decode_rgbe(v: [u8; 4]) -> Rgb {
    if v[3] == 0 {
        return Rgb::ZERO;
    }
    let f = pow2(v[3] as i32 - (128 + 8));
    Rgb::new(v[0] as f32 * f, v[1] as f32 * f, v[2] as f32 * f)
}

/// `2^k` exactly for `−149 ≤ k ≤ 127` (subnormal below −126), built from its bits:
/// what `ldexpf(1, k)` returns, without its general scaling (a gather decodes one
/// power per photon it sums).
#[inline]
fn pow2(k: i32) -> f32 {
    debug_assert!((-149..=127).contains(&k));
    if k >= -126 {
        f32::from_bits(((k + 127) as u32) << 23)
    } else {
        f32::from_bits(1u32 << (k + 149))
    }
}

/// Octahedral encoding of a unit vector in two bytes.
pub(crate) fn encode_octahedral(d: UnitVec3) -> [u8; 2] {
    let v = d.get();
    let l1 = v.x.abs() + v.y.abs() + v.z.abs();
    let (mut x, mut y) = (v.x / l1, v.y / l1);
    if v.z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * libm::copysignf(1.0, ox);
        y = (1.0 - ox.abs()) * libm::copysignf(1.0, oy);
    }
    let q = |s: f32| ((s.clamp(-1.0, 1.0) * 0.5 + 0.5) * 255.0 + 0.5) as u8;
    [q(x), q(y)]
}

pub(crate) fn decode_octahedral(e: [u8; 2]) -> UnitVec3 {
    let x = e[0] as f32 * (2.0 / 255.0) - 1.0;
    let y = e[1] as f32 * (2.0 / 255.0) - 1.0;
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        (
            (1.0 - y.abs()) * libm::copysignf(1.0, x),
            (1.0 - x.abs()) * libm::copysignf(1.0, y),
        )
    } else {
        (x, y)
    };
    // Never zero: |x| + |y| + |z| = 1 on the octahedron.
    UnitVec3::new(Vec3::new(x, y, z)).unwrap_or(UnitVec3::Z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    #[test]
    fn pow2_is_ldexpf_of_one_over_its_whole_range() {
        for k in -149..=127 {
            assert_eq!(pow2(k).to_bits(), libm::ldexpf(1.0, k).to_bits(), "2^{k}");
        }
    }

    /// The encoding as first written, with `frexpf` and `ldexpf`: the bit-built one must
    /// give the same bytes.
    fn encode_rgbe_libm(c: Rgb) -> [u8; 4] {
        let c = Rgb::new(c.r.max(0.0), c.g.max(0.0), c.b.max(0.0));
        let m = c.max_channel();
        if !(m > 1e-32) || !m.is_finite() {
            return [0; 4];
        }
        let (_, mut e) = libm::frexpf(m);
        let mut scale = libm::ldexpf(256.0, -e);
        if (m * scale + 0.5) as u32 > 255 {
            e += 1;
            scale = libm::ldexpf(256.0, -e);
        }
        let q = |x: f32| ((x * scale + 0.5) as u32).min(255) as u8;
        [q(c.r), q(c.g), q(c.b), (e + 128).clamp(0, 255) as u8]
    }

    #[test]
    fn rgbe_bytes_are_those_of_frexpf_and_ldexpf() {
        let mut rng = Pcg32::new(11);
        let mut values = std::vec![
            1e-32f32,
            1.000_001e-32,
            0.999_99,
            1.0,
            255.5 / 256.0,
            f32::MAX
        ];
        for _ in 0..20_000 {
            // Magnitudes across the whole encodable range, 2^-110 … 2^127.
            let e = (rng.next_f32() * 237.0) as i32 - 110;
            values.push(libm::ldexpf(0.5 + 0.5 * rng.next_f32(), e));
        }
        for &m in &values {
            for c in [
                Rgb::splat(m),
                Rgb::new(m, 0.3 * m, 0.0),
                Rgb::new(0.01 * m, m, -m),
            ] {
                assert_eq!(encode_rgbe(c), encode_rgbe_libm(c), "{c:?}");
                let bytes = encode_rgbe(c);
                let f = libm::ldexpf(1.0, bytes[3] as i32 - 136);
                let want = if bytes[3] == 0 {
                    Rgb::ZERO
                } else {
                    Rgb::new(
                        bytes[0] as f32 * f,
                        bytes[1] as f32 * f,
                        bytes[2] as f32 * f,
                    )
                };
                assert_eq!(decode_rgbe(bytes), want);
            }
        }
    }

    #[test]
    fn rgbe_round_trips_within_half_a_mantissa_step() {
        for c in [
            Rgb::ONE,
            Rgb::new(0.3, 2.0, 1e-3),
            Rgb::splat(1e-20),
            Rgb::new(5e6, 0.0, 1.0),
            Rgb::splat(0.999_99),
        ] {
            let d = decode_rgbe(encode_rgbe(c));
            let step = libm::ldexpf(1.0, libm::frexpf(c.max_channel()).1 - 8);
            for (a, b) in c.to_array().into_iter().zip(d.to_array()) {
                assert!(
                    (a - b).abs() <= 0.5 * step * 1.0001 + 1e-30,
                    "{c:?} → {d:?}"
                );
            }
        }
        // The unit power is exact, and black is black.
        assert_eq!(decode_rgbe(encode_rgbe(Rgb::ONE)), Rgb::ONE);
        assert_eq!(
            decode_rgbe(encode_rgbe(Rgb::new(0.5, 0.25, 1.0))),
            Rgb::new(0.5, 0.25, 1.0)
        );
        assert_eq!(decode_rgbe(encode_rgbe(Rgb::ZERO)), Rgb::ZERO);
    }

    #[test]
    fn fields_survive_packing_and_the_position_keeps_17_bits() {
        let mut g = Pcg32::new(9);
        for i in 0..5_000 {
            let pos = Vec3::new(g.next_f32() - 0.5, g.next_f32(), g.next_f32() + 3.0)
                * [1e-3, 1.0, 40.0, 1e5][i % 4];
            let dir = UnitVec3::new(Vec3::new(
                g.next_f32() - 0.5,
                g.next_f32() - 0.5,
                g.next_f32() - 0.5,
            ))
            .unwrap();
            let power = Rgb::new(g.next_f32(), g.next_f32(), 2.0);
            let mut p = Photon::new(pos, dir, power).with_half(i % 3 == 0);
            for axis in [2, 0, 1] {
                p.set_axis(axis);
                assert_eq!(p.axis(), axis);
                assert_eq!(p.half(), i % 3 == 0);
                assert_eq!(p.direction(), decode_octahedral(encode_octahedral(dir)));
                assert_eq!(p.power(), decode_rgbe(encode_rgbe(power)));
                for k in 0..3 {
                    let (a, b) = (p.position()[k], pos[k]);
                    assert!((a - b).abs() <= b.abs() * libm::ldexpf(1.0, -17), "{a} {b}");
                }
            }
        }
    }

    #[test]
    fn octahedral_directions_are_within_a_degree() {
        let mut g = Pcg32::new(3);
        let mut worst = 0.0f32;
        for _ in 0..20_000 {
            let v = Vec3::new(g.next_f32() - 0.5, g.next_f32() - 0.5, g.next_f32() - 0.5);
            let Some(d) = UnitVec3::new(v) else { continue };
            let e = decode_octahedral(encode_octahedral(d));
            worst = worst.max(libm::acosf(e.dot(d.get()).min(1.0)));
        }
        assert!(
            worst.to_degrees() < 1.5,
            "worst error {}°",
            worst.to_degrees()
        );
        // The poles and axes survive exactly enough to keep their sign.
        for a in [
            UnitVec3::X,
            UnitVec3::Y,
            UnitVec3::Z,
            -UnitVec3::X,
            -UnitVec3::Y,
            -UnitVec3::Z,
        ] {
            assert!(decode_octahedral(encode_octahedral(a)).dot(a.get()) > 0.999);
        }
    }
}
