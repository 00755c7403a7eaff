//! The compact photon: 20 bytes.
//!
//! | bytes | field | encoding |
//! |---|---|---|
//! | 12 | position | three `f32` |
//! | 4 | power | shared-exponent RGB (Ward's RGBE), relative to the map's power unit |
//! | 2 | direction of travel | octahedral map, 8 bits per coordinate (Cigolle et al. 2014) |
//! | 1 | flags | bits 0–1: the kd-tree split axis; bit 7: scratch for balancing |
//! | 1 | surface | 1 + the index of the scene object it landed on; 0: unknown |
//!
//! The power is stored relative to a per-map unit (the nominal photon power), so the
//! common photon of exactly nominal power is encoded without rounding.

use crate::math::{Rgb, UnitVec3, Vec3};

/// A stored photon. See the module documentation for the layout.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Photon {
    pos: [f32; 3],
    rgbe: [u8; 4],
    dir: [u8; 2],
    pub(crate) flags: u8,
    surface: u8,
}

const _: () = assert!(core::mem::size_of::<Photon>() == 20);

pub(crate) const AXIS_MASK: u8 = 0b11;
pub(crate) const SCRATCH: u8 = 0x80;

impl Photon {
    /// A photon at `pos` travelling along `dir` with `power` in units of the map's unit.
    pub fn new(pos: Vec3, dir: UnitVec3, power: Rgb) -> Self {
        Self {
            pos: pos.to_array(),
            rgbe: encode_rgbe(power),
            dir: encode_octahedral(dir),
            flags: 0,
            surface: 0,
        }
    }

    /// The same photon, marked as landed on scene object `object` (an index of 255 or
    /// more is left unknown): the illumination maps then need not find its surface
    /// again from its position.
    pub fn on_surface(mut self, object: usize) -> Self {
        self.surface = if object < u8::MAX as usize {
            object as u8 + 1
        } else {
            0
        };
        self
    }

    /// The scene object it landed on, when known (see [`on_surface`](Self::on_surface)).
    #[inline]
    pub fn surface(&self) -> Option<usize> {
        (self.surface > 0).then(|| self.surface as usize - 1)
    }

    /// An all-zero photon (const, for static arrays).
    pub(crate) const fn zeroed() -> Self {
        Self {
            pos: [0.0; 3],
            rgbe: [0; 4],
            dir: [0; 2],
            flags: 0,
            surface: 0,
        }
    }

    /// Where it landed.
    #[inline]
    pub fn position(&self) -> Vec3 {
        Vec3::from_array(self.pos)
    }

    /// One coordinate of the position.
    #[inline]
    pub(crate) fn coord(&self, axis: usize) -> f32 {
        self.pos[axis]
    }

    /// Its power, in units of the map's power unit.
    #[inline]
    pub fn power(&self) -> Rgb {
        decode_rgbe(self.rgbe)
    }

    /// Its direction of travel when it landed (decoded to within about 1°).
    #[inline]
    pub fn direction(&self) -> UnitVec3 {
        decode_octahedral(self.dir)
    }

    /// The kd-tree split axis of this node (0, 1, 2).
    #[inline]
    pub(crate) fn axis(&self) -> usize {
        (self.flags & AXIS_MASK) as usize
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
    // m = f · 2^e with f ∈ [0.5, 1): mantissas are channel · 256 / 2^e.
    let (_, mut e) = libm::frexpf(m);
    let mut scale = libm::ldexpf(256.0, -e);
    if (m * scale + 0.5) as u32 > 255 {
        // Rounding the largest channel up to 256 would overflow: use the next exponent.
        e += 1;
        scale = libm::ldexpf(256.0, -e);
    }
    let q = |x: f32| ((x * scale + 0.5) as u32).min(255) as u8;
    [q(c.r), q(c.g), q(c.b), (e + 128).clamp(0, 255) as u8]
}

pub(crate) fn decode_rgbe(v: [u8; 4]) -> Rgb {
    if v[3] == 0 {
        return Rgb::ZERO;
    }
    let f = libm::ldexpf(1.0, v[3] as i32 - (128 + 8));
    Rgb::new(v[0] as f32 * f, v[1] as f32 * f, v[2] as f32 * f)
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
