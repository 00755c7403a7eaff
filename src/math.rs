//! Vectors, unit directions and colours: `f32` throughout, on scalar `glam` and `libm`.
//!
//! Every float operation the renderer performs goes through these types or through
//! `libm`, never through the platform's own maths library, so that an x86-64 desktop
//! and a Cortex-M4F compute the same bits. No `mul_add`: Rust never fuses `a * b + c`.

use core::ops::{Add, AddAssign, Mul, MulAssign, Neg, Sub, SubAssign};

use crate::error::{finite, Error};
pub use glam::{Mat3, Vec3};

/// The correctly rounded square root (IEEE 754 requires it of every implementation, so
/// all give the same bits). On ARM with a hardware FPU it is the `vsqrt.f32`
/// instruction — `libm::sqrtf` compiles to ~76 software instructions there — elsewhere
/// `libm::sqrtf`.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        vfp::sqrt(x)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrtf(x)
    }
}

/// The hardware square root of hard-float ARM targets, the one place the crate uses
/// `unsafe`: a leaf function of two instructions in assembly. Under the hard-float ABI
/// (eabihf) the argument and the result travel in `s0`; `.fpu` lets the assembler accept
/// `vsqrt` whatever FPU the target names (every eabihf core has at least this one).
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[allow(unsafe_code)]
mod vfp {
    core::arch::global_asm!(
        ".syntax unified",
        ".section .text.caustic_vsqrt,\"ax\",%progbits",
        ".global caustic_vsqrt",
        ".type caustic_vsqrt,%function",
        ".thumb",
        ".thumb_func",
        ".fpu fpv4-sp-d16",
        "caustic_vsqrt:",
        "vsqrt.f32 s0, s0",
        "bx lr",
        ".size caustic_vsqrt, . - caustic_vsqrt",
    );

    extern "C" {
        fn caustic_vsqrt(x: f32) -> f32;
    }

    /// `vsqrt.f32`: IEEE 754 correctly rounded, like `libm::sqrtf`.
    #[inline]
    pub(super) fn sqrt(x: f32) -> f32 {
        // SAFETY: `caustic_vsqrt` reads s0, writes s0 and returns; it touches no memory
        // and follows the AAPCS-VFP convention that `extern "C"` uses on eabihf.
        unsafe { caustic_vsqrt(x) }
    }
}

/// `a` if it is larger than `b`, else `b`: a plain comparison, which unlike `f32::max`
/// is not a library call on Armv7E-M. (With a NaN `a` it returns `b`.)
#[inline]
pub fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// `f32::max` (IEEE 754-2008 `maxNum`: a NaN operand yields the other one) written as
/// comparisons, the formula of `libm::fmaxf`: on targets without a `vmaxnm`
/// instruction (Armv7-M, RISC-V without Zfa) `f32::max` is a call to `fmaxf`, 2.8 % of
/// the device render before it was replaced. Same bits as `f32::max` for every input
/// but a NaN payload.
#[inline]
pub fn max_num(a: f32, b: f32) -> f32 {
    // `a ≥ b` decides at once unless `a` is NaN or smaller; then `b`, unless `b` is the
    // NaN (then `a`): libm's `a.is_nan() || a < b ? b : a`, one comparison first.
    if a >= b || b.is_nan() {
        a
    } else {
        b
    }
}

/// `f32::min` (`minNum`) as comparisons; see [`max_num`].
#[inline]
pub fn min_num(a: f32, b: f32) -> f32 {
    if a <= b || b.is_nan() {
        a
    } else {
        b
    }
}

/// `x` limited to `[lo, hi]` by comparisons: unlike `f32::clamp`, no panic path (which
/// on a device pulls kilobytes of float formatting into flash) when the bounds are not
/// constants. A NaN `x` comes back unchanged.
#[inline]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// `(sin 2πt, cos 2πt)` in `f32` arithmetic only: `t` is reduced to the nearest
/// quarter turn, `4t = q + r` with `|r| ≤ ½` (exactly), and the Taylor polynomials of
/// sine (to `x⁹`) and cosine (to `x¹⁰`) are evaluated at `x = r·π/2`, `|x| ≤ π/4`,
/// where their truncation errors are below `2·10⁻⁹` and `2·10⁻⁹`; the quadrant `q`
/// then swaps and negates them. Within `2·10⁻⁷` of the true values. Unlike
/// `libm::sincosf`, whose kernels work in `f64` (soft-float on every microcontroller:
/// 45 % of the device's forward pass), it is a dozen single-precision operations, the
/// same bits on every IEEE 754 machine.
#[inline]
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    let q4 = 4.0 * t;
    let q = libm::floorf(q4 + 0.5);
    let x = (q4 - q) * core::f32::consts::FRAC_PI_2;
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0)))));
    match (q as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// A direction of unit length.
///
/// # Guarantees
/// The components are finite and the length is 1 to within a few ulps. Constructors
/// normalise; code that takes a `UnitVec3` never re-checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitVec3(Vec3);

impl UnitVec3 {
    /// +X.
    pub const X: Self = Self(Vec3::X);
    /// +Y.
    pub const Y: Self = Self(Vec3::Y);
    /// +Z.
    pub const Z: Self = Self(Vec3::Z);

    /// Normalises `v`; `None` when it is zero, too small to normalise, or not finite.
    ///
    /// `0 < |v|² < ∞` is the whole test: it rejects NaN and infinite components, and
    /// it makes the result finite (each `|vᵢ| ≤ |v|`, so `|vᵢ|/|v| ≤ 1`, and
    /// `1/|v|` is finite for every positive `|v|²` an `f32` holds).
    #[inline]
    pub fn new(v: Vec3) -> Option<Self> {
        let len2 = v.length_squared();
        // Two float comparisons; LLVM turns `< ∞` into a 16-instruction integer test.
        if !(len2 > 0.0) || !(len2 <= f32::MAX) {
            return None;
        }
        Some(Self(v * (1.0 / sqrt(len2))))
    }

    /// Normalises `v`, or reports a [`Error::Degenerate`] direction named `what`.
    pub fn try_new(v: Vec3, what: &'static str) -> Result<Self, Error> {
        if !v.is_finite() {
            return Err(Error::NotFinite { what });
        }
        Self::new(v).ok_or(Error::Degenerate { what })
    }

    /// Wraps a vector the caller knows to be of unit length (a normalised
    /// combination of unit vectors, a basis vector). Checked in debug builds.
    #[inline]
    pub(crate) fn new_unchecked(v: Vec3) -> Self {
        debug_assert!((v.length_squared() - 1.0).abs() < 1e-4, "not unit: {v:?}");
        Self(v)
    }

    /// The vector.
    #[inline]
    pub fn get(self) -> Vec3 {
        self.0
    }

    /// Dot product with any vector.
    #[inline]
    pub fn dot(self, v: Vec3) -> f32 {
        self.0.dot(v)
    }

    /// Two unit vectors that complete `self` to a right-handed orthonormal basis
    /// (Duff et al. 2017, "Building an Orthonormal Basis, Revisited"; no branch on
    /// a threshold, continuous except at z = −1 exactly).
    pub fn basis(self) -> (UnitVec3, UnitVec3) {
        let n = self.0;
        let sign = libm::copysignf(1.0, n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let s = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        (UnitVec3(t), UnitVec3(s))
    }
}

impl Neg for UnitVec3 {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self(-self.0)
    }
}

/// Checks that every component of `v` is finite.
pub(crate) fn finite_vec(v: Vec3, what: &'static str) -> Result<Vec3, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NotFinite { what })
    }
}

/// The largest absolute component: the magnitude that float rounding scales with.
#[inline]
pub fn max_abs(v: Vec3) -> f32 {
    v.abs().max_element() // comparisons, no `fmaxf`
}

/// Mirror reflection of the travel direction `d` about the normal `n`
/// (paper eq. 1, written for a travel direction: `r = d − 2(n·d)n`).
#[inline]
pub fn reflect(d: UnitVec3, n: UnitVec3) -> UnitVec3 {
    let v = d.get() - n.get() * (2.0 * n.dot(d.get()));
    // Reflection preserves length; renormalise to keep the invariant exact over many bounces.
    UnitVec3::new(v).unwrap_or(d)
}

/// Linear RGB: radiance, irradiance, power or a reflectance, per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rgb {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
}

impl Rgb {
    /// Black.
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0);
    /// White (1, 1, 1).
    pub const ONE: Self = Self::new(1.0, 1.0, 1.0);

    /// From three channels.
    #[inline]
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Self { r, g, b }
    }

    /// The same value in every channel.
    #[inline]
    pub const fn splat(v: f32) -> Self {
        Self::new(v, v, v)
    }

    /// From an `[r, g, b]` array.
    #[inline]
    pub const fn from_array(a: [f32; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }

    /// As an `[r, g, b]` array.
    #[inline]
    pub const fn to_array(self) -> [f32; 3] {
        [self.r, self.g, self.b]
    }

    /// The largest channel.
    #[inline]
    pub fn max_channel(self) -> f32 {
        max_num(max_num(self.r, self.g), self.b)
    }

    /// The smallest channel.
    #[inline]
    pub fn min_channel(self) -> f32 {
        min_num(min_num(self.r, self.g), self.b)
    }

    /// `true` when every channel is exactly zero (or negative): `max_channel() ≤ 0`,
    /// decided by the first positive channel in the common case (three comparisons
    /// instead of two `maxNum`s). All-NaN is not black, as `max_channel` is NaN then.
    #[inline]
    pub fn is_black(self) -> bool {
        let positive = self.r > 0.0 || self.g > 0.0 || self.b > 0.0;
        let all_nan = self.r.is_nan() && self.g.is_nan() && self.b.is_nan();
        !(positive || all_nan)
    }

    /// `true` when every channel is finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite()
    }

    /// Rec. 709 luminance, for statistics and tests.
    #[inline]
    pub fn luminance(self) -> f32 {
        0.2126 * self.r + 0.7152 * self.g + 0.0722 * self.b
    }

    /// `exp(−σ·t)` per channel: Beer–Lambert transmittance over a length `t`.
    /// Costs three `expf` only when `self` (σ) is not black.
    #[inline]
    pub fn beer(self, t: f32) -> Rgb {
        if self.is_black() {
            return Rgb::ONE;
        }
        Rgb::new(
            libm::expf(-self.r * t),
            libm::expf(-self.g * t),
            libm::expf(-self.b * t),
        )
    }

    /// Checks that every channel is finite and at least zero.
    pub fn validate(self, what: &'static str) -> Result<Self, Error> {
        for c in self.to_array() {
            if finite(c, what)? < 0.0 {
                return Err(Error::OutOfRange {
                    what,
                    value: c,
                    min: 0.0,
                    max: f32::MAX,
                });
            }
        }
        Ok(self)
    }

    /// Checks that every channel is in `[0, 1]` (a reflectance or albedo).
    pub fn validate_unit(self, what: &'static str) -> Result<Self, Error> {
        self.validate_at_most(1.0, what)
    }

    /// Checks that every channel is in `[0, max]`.
    pub fn validate_at_most(self, max: f32, what: &'static str) -> Result<Self, Error> {
        for c in self.to_array() {
            crate::error::in_range(c, 0.0, max, what)?;
        }
        Ok(self)
    }
}

/// `Rgb ∘ Rgb` channel by channel and its assigning form `∘=`, for `+`, `−` and `×`.
macro_rules! channelwise {
    ($($Op:ident::$op:ident, $OpAssign:ident::$op_assign:ident, $sym:tt;)*) => {$(
        impl $Op for Rgb {
            type Output = Rgb;
            #[inline]
            fn $op(self, o: Rgb) -> Rgb {
                Rgb::new(self.r $sym o.r, self.g $sym o.g, self.b $sym o.b)
            }
        }

        impl $OpAssign for Rgb {
            #[inline]
            fn $op_assign(&mut self, o: Rgb) {
                *self = *self $sym o;
            }
        }
    )*};
}

channelwise! {
    Add::add, AddAssign::add_assign, +;
    Sub::sub, SubAssign::sub_assign, -;
    Mul::mul, MulAssign::mul_assign, *;
}

impl Mul<f32> for Rgb {
    type Output = Rgb;
    #[inline]
    fn mul(self, s: f32) -> Rgb {
        Rgb::new(self.r * s, self.g * s, self.b * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_vectors_reject_degenerate_input() {
        assert!(UnitVec3::new(Vec3::ZERO).is_none());
        assert!(UnitVec3::new(Vec3::new(f32::NAN, 0.0, 1.0)).is_none());
        assert!(UnitVec3::new(Vec3::new(f32::INFINITY, 0.0, 1.0)).is_none());
        let u = UnitVec3::new(Vec3::new(3.0, 4.0, 0.0)).unwrap();
        assert!((u.get().length() - 1.0).abs() < 1e-6);
        // Tiny but representable vectors still normalise.
        assert!(UnitVec3::new(Vec3::new(1e-18, 0.0, 0.0)).is_some());
    }

    #[test]
    fn basis_is_orthonormal_everywhere() {
        for &n in &[
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(1.0, -2.0, 0.3),
            Vec3::new(0.0, 0.0, -0.999_999),
        ] {
            let n = UnitVec3::new(n).unwrap();
            let (t, s) = n.basis();
            for (a, b) in [(t, s), (t, n), (s, n)] {
                assert!(a.dot(b.get()).abs() < 1e-5, "{n:?}");
            }
            assert!((t.get().length() - 1.0).abs() < 1e-5 && (s.get().length() - 1.0).abs() < 1e-5);
            // Right-handed: t × s = n.
            assert!((t.get().cross(s.get()) - n.get()).length() < 1e-5);
        }
    }

    #[test]
    fn max_num_and_min_num_are_f32_max_and_min() {
        let v = [
            f32::NAN,
            f32::NEG_INFINITY,
            -1.5,
            -0.0,
            0.0,
            2.0,
            f32::INFINITY,
        ];
        for a in v {
            for b in v {
                let same =
                    |x: f32, y: f32| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
                // Zeros of either sign are equal, and either may come back.
                let zeros = a == 0.0 && b == 0.0;
                assert!(same(max_num(a, b), a.max(b)) || zeros, "max {a} {b}");
                assert!(same(min_num(a, b), a.min(b)) || zeros, "min {a} {b}");
            }
        }
    }

    #[test]
    fn sin_cos_turns_is_within_2e_7() {
        let mut worst = 0.0f64;
        for i in 0..=100_000 {
            let t = i as f32 / 100_000.0;
            let (s, c) = sin_cos_turns(t);
            let a = 2.0 * core::f64::consts::PI * t as f64;
            worst = worst
                .max((s as f64 - a.sin()).abs())
                .max((c as f64 - a.cos()).abs());
        }
        assert!(worst < 2e-7, "{worst}");
        // Negative turns and whole turns reduce too.
        let (s, c) = sin_cos_turns(-0.25);
        assert!((s + 1.0).abs() < 1e-7 && c.abs() < 1e-7);
        assert_eq!(sin_cos_turns(3.0), (0.0, 1.0));
    }

    #[test]
    fn reflection_mirrors_the_normal_component() {
        let d = UnitVec3::new(Vec3::new(1.0, -1.0, 0.0)).unwrap();
        let r = reflect(d, UnitVec3::Y);
        assert!((r.get() - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }
}
