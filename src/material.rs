//! Materials and the optics of smooth interfaces.
//!
//! Physical materials (`Diffuse`, `Mirror`, `Dielectric`) are radiometrically exact, so
//! images compare pixel by pixel with an independent physically based renderer; the
//! paper's `Classic` coefficient model is reproduced as the paper states it.

use crate::error::{in_range, positive, Error};
use crate::math::{max_num, min_num, sqrt, Rgb, UnitVec3};

/// The closed set of materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector of albedo ρ: `f_r = ρ/π`.
    Diffuse(Diffuse),
    /// Perfect mirror, on both sides.
    Mirror(Mirror),
    /// Smooth glass-like interface with exact Fresnel and optional Beer absorption.
    Dielectric(Dielectric),
    /// The seed paper's coefficient model (Phong + reflectivity + transparency).
    Classic(Classic),
}

/// See [`Material::Diffuse`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {
    /// Albedo ρ, each channel in `[0, 1]`.
    pub(crate) albedo: Rgb,
}

/// See [`Material::Mirror`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    /// Reflectance, each channel in `[0, 1]`.
    pub(crate) reflectance: Rgb,
}

/// See [`Material::Dielectric`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Index of refraction inside (outside is vacuum, 1).
    pub(crate) ior: f32,
    /// Beer–Lambert absorption coefficient σ per unit length inside.
    pub(crate) absorption: Rgb,
}

/// See [`Material::Classic`]: the paper's section 3.3 coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Classic {
    pub(crate) color: Rgb,
    pub(crate) ambient: f32,
    pub(crate) diffuse: f32,
    pub(crate) specular: f32,
    pub(crate) shininess: f32,
    pub(crate) reflectivity: f32,
    pub(crate) transparency: f32,
    pub(crate) ior: f32,
}

impl Material {
    /// A Lambertian surface of albedo ρ ∈ [0, 1]³.
    pub fn diffuse(albedo: Rgb) -> Result<Self, Error> {
        Ok(Material::Diffuse(Diffuse {
            albedo: albedo.validate_unit("albedo")?,
        }))
    }

    /// A perfect mirror of reflectance ∈ [0, 1]³.
    pub fn mirror(reflectance: Rgb) -> Result<Self, Error> {
        Ok(Material::Mirror(Mirror {
            reflectance: reflectance.validate_unit("reflectance")?,
        }))
    }

    /// A smooth dielectric of index `ior` (> 0) with absorption σ ≥ 0 per unit length.
    pub fn dielectric(ior: f32, absorption: Rgb) -> Result<Self, Error> {
        Ok(Material::Dielectric(Dielectric {
            ior: positive(ior, "ior")?,
            absorption: absorption.validate("absorption")?,
        }))
    }

    /// The paper's coefficient model. All coefficients lie in `[0, 1]` except the
    /// shininess exponent (≥ 0) and `ior` (> 0); `reflectivity + transparency ≤ 1`, so a
    /// photon can choose between them by one random number.
    pub fn classic(c: Classic) -> Result<Self, Error> {
        c.color.validate_unit("color")?;
        in_range(c.ambient, 0.0, 1.0, "ambient")?;
        in_range(c.diffuse, 0.0, 1.0, "diffuse")?;
        in_range(c.specular, 0.0, 1.0, "specular")?;
        in_range(c.shininess, 0.0, 10_000.0, "shininess")?;
        in_range(c.reflectivity, 0.0, 1.0, "reflectivity")?;
        in_range(c.transparency, 0.0, 1.0, "transparency")?;
        in_range(
            c.reflectivity + c.transparency,
            0.0,
            1.0,
            "reflectivity + transparency",
        )?;
        positive(c.ior, "ior")?;
        Ok(Material::Classic(c))
    }

    /// `true` when light bouncing off or through it can form a caustic: a mirror, a
    /// dielectric, or a classic surface with reflectivity or transparency.
    pub fn is_specular(&self) -> bool {
        match self {
            Material::Diffuse(_) => false,
            Material::Mirror(_) | Material::Dielectric(_) => true,
            Material::Classic(c) => c.reflectivity > 0.0 || c.transparency > 0.0,
        }
    }

    /// `true` when photons are stored on it (it has a diffuse part).
    pub fn stores_photons(&self) -> bool {
        match self {
            Material::Diffuse(_) => true,
            Material::Classic(c) => c.diffuse > 0.0,
            Material::Mirror(_) | Material::Dielectric(_) => false,
        }
    }

    /// How a surface turns caustic light into radiance towards the eye: the radiance
    /// leaving towards `to_eye` per unit of flux density (W/m²) arriving from
    /// `to_light`. Diffuse: the BRDF `ρ/π`. Classic: `π·kernel` — the paper's eq. 8
    /// divides `Σ kernel·Φ` by `r²`, that is `π·kernel` times the flux density
    /// `Σ Φ/(πr²)`. Mirror and glass: none (light through them is traced on).
    /// Both the gather (a density times this) and the light tracer (a photon's flux
    /// times the camera's importance times this) ask it.
    #[inline]
    pub fn caustic_response(&self, n: UnitVec3, to_light: UnitVec3, to_eye: UnitVec3) -> Rgb {
        match self {
            Material::Diffuse(m) => m.albedo * core::f32::consts::FRAC_1_PI,
            Material::Classic(c) => c.kernel(n, to_light, to_eye) * core::f32::consts::PI,
            Material::Mirror(_) | Material::Dielectric(_) => Rgb::ZERO,
        }
    }
}

impl Classic {
    /// The coefficients, in the order of the scene format: `color`, `ambient`, `diffuse`,
    /// `specular`, `shininess` (Phong exponent), `reflectivity`, `transparency`, `ior`.
    /// Validate with [`Material::classic`].
    #[allow(clippy::too_many_arguments)]
    pub const fn new(
        color: Rgb,
        ambient: f32,
        diffuse: f32,
        specular: f32,
        shininess: f32,
        reflectivity: f32,
        transparency: f32,
        ior: f32,
    ) -> Self {
        Self {
            color,
            ambient,
            diffuse,
            specular,
            shininess,
            reflectivity,
            transparency,
            ior,
        }
    }

    /// The paper's eq. 8 kernel for one photon or one light:
    /// `(max(n·l, 0)·k_d·color + max(n·h, 0)^a·k_s·color)`, with `l` the direction
    /// towards the light (the negated photon direction) and `h` the half vector of `l`
    /// and the direction towards the eye.
    #[inline(never)]
    pub fn kernel(&self, n: UnitVec3, to_light: UnitVec3, to_eye: UnitVec3) -> Rgb {
        let cos_l = max_num(n.dot(to_light.get()), 0.0);
        let spec = match UnitVec3::new(to_light.get() + to_eye.get()) {
            Some(h) if self.specular > 0.0 => {
                powi_real(max_num(n.dot(h.get()), 0.0), self.shininess)
            }
            _ => 0.0,
        };
        self.color * (cos_l * self.diffuse + spec * self.specular)
    }
}

/// `x^a` for `x ∈ [0, 1]`: by repeated squaring when `a` is a whole number (the usual
/// Phong exponent; no `powf` on the device's hot path), else by `libm::powf`.
#[inline]
pub fn powi_real(x: f32, a: f32) -> f32 {
    let whole = a as u32;
    if whole as f32 != a {
        return libm::powf(x, a);
    }
    let (mut base, mut e, mut acc) = (x, whole, 1.0f32);
    while e > 0 {
        if e & 1 == 1 {
            acc *= base;
        }
        base *= base;
        e >>= 1;
    }
    acc
}

/// How light meets a smooth interface between indices `eta_i` (incident side) and
/// `eta_t` (transmitted side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interface {
    /// Fresnel reflectance F ∈ [0, 1] (1 under total internal reflection).
    pub reflectance: f32,
    /// The refracted direction, `None` under total internal reflection.
    pub refracted: Option<UnitVec3>,
}

/// Exact Fresnel reflectance and Snell refraction for unpolarised light.
///
/// `d` is the travel direction, `n` the normal on the incident side (`d·n < 0`),
/// `eta = eta_i / eta_t`. With `cos_i = −d·n`, Snell's law gives
/// `cos²t = 1 − η²(1 − cos²i)`, evaluated as `(1 − η)(1 + η) + (η cos_i)²`, which does
/// not cancel: with `η = 1` it is exactly `cos²i`, so the direction passes unchanged
/// even at near-grazing incidence, where `1 − cos²i` would round to 1 and report total
/// internal reflection. Total internal reflection when `cos²t ≤ 0` (or is undefined,
/// as for an `η` that overflows); else `cos_t = √cos²t`,
/// `t = η d + (η cos_i − cos_t) n` (the vector form of paper eqs. 3–6), and
/// `F = ½(r_s² + r_p²)` with `r_s = (η_i cos_i − η_t cos_t)/(η_i cos_i + η_t cos_t)`,
/// `r_p = (η_t cos_i − η_i cos_t)/(η_t cos_i + η_i cos_t)` (Born & Wolf; pbrt-v4 §9.5).
/// Both denominators are positive whenever `cos²t > 0`, so `F` is never NaN.
#[inline(never)]
pub fn interface(d: UnitVec3, n: UnitVec3, eta: f32) -> Interface {
    let cos_i = (-n.dot(d.get())).clamp(0.0, 1.0);
    let eta_cos_i = eta * cos_i;
    let cos2_t = (1.0 - eta) * (1.0 + eta) + eta_cos_i * eta_cos_i;
    if !(cos2_t > 0.0) {
        return Interface {
            reflectance: 1.0,
            refracted: None,
        };
    }
    let cos_t = sqrt(min_num(cos2_t, 1.0));
    // In units of eta_t: eta_i = eta, eta_t = 1.
    let rs = (eta_cos_i - cos_t) / (eta_cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let reflectance = 0.5 * (rs * rs + rp * rp);
    let reflectance = if reflectance.is_finite() {
        reflectance.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let t = d.get() * eta + n.get() * (eta_cos_i - cos_t);
    let refracted = UnitVec3::new(t);
    Interface {
        reflectance: if refracted.is_some() {
            reflectance
        } else {
            1.0
        },
        refracted,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn dir_at(theta: f32) -> UnitVec3 {
        // Travelling down onto the +y normal at angle theta from it.
        UnitVec3::new(Vec3::new(libm::sinf(theta), -libm::cosf(theta), 0.0)).unwrap()
    }

    #[test]
    fn fresnel_normal_incidence_is_the_classic_formula() {
        for n in [1.33f32, 1.5, 2.4] {
            let f = interface(dir_at(0.0), UnitVec3::Y, 1.0 / n);
            let expect = ((n - 1.0) / (n + 1.0)).powi(2);
            assert!(
                (f.reflectance - expect).abs() < 1e-6,
                "{n}: {} vs {expect}",
                f.reflectance
            );
            // Straight through.
            assert!((f.refracted.unwrap().get() + Vec3::Y).length() < 1e-6);
        }
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let eta = 1.5f32; // glass to air
        let critical = libm::asinf(1.0 / eta);
        let inside = interface(dir_at(critical - 0.01), UnitVec3::Y, eta);
        assert!(inside.refracted.is_some() && inside.reflectance < 1.0);
        let beyond = interface(dir_at(critical + 0.01), UnitVec3::Y, eta);
        assert_eq!(
            beyond,
            Interface {
                reflectance: 1.0,
                refracted: None
            }
        );
        // Reflectance rises to 1 continuously as the critical angle nears.
        let near = interface(dir_at(critical - 1e-4), UnitVec3::Y, eta);
        assert!(near.reflectance > 0.9, "{}", near.reflectance);
    }

    #[test]
    fn snell_law_over_all_angles() {
        for eta in [1.0 / 1.5, 1.5, 1.0, 1.0 / 2.4] {
            for k in 0..=90 {
                let theta = (k as f32).to_radians().min(core::f32::consts::FRAC_PI_2);
                let f = interface(dir_at(theta), UnitVec3::Y, eta);
                assert!((0.0..=1.0).contains(&f.reflectance));
                if let Some(t) = f.refracted {
                    let sin_t = (t.get() - Vec3::Y * t.get().y).length();
                    assert!(
                        (eta * libm::sinf(theta) - sin_t).abs() < 1e-5,
                        "snell eta={eta} k={k}"
                    );
                    assert!(t.get().y < 0.0 || k == 90);
                }
            }
            // ior 1: no reflection (away from grazing), direction unchanged.
            if eta == 1.0 {
                let d = dir_at(0.7);
                let f = interface(d, UnitVec3::Y, 1.0);
                assert!(f.reflectance < 1e-6);
                assert!((f.refracted.unwrap().get() - d.get()).length() < 1e-6);
            }
        }
        // Grazing incidence reflects everything.
        let g = interface(dir_at(core::f32::consts::FRAC_PI_2), UnitVec3::Y, 1.0 / 1.5);
        assert!((g.reflectance - 1.0).abs() < 1e-6);
    }

    /// At Brewster's angle `tan θ_B = n` (from air into index `n`) the p-polarised
    /// reflectance vanishes, so the unpolarised `F = ½ R_s = ½((n² − 1)/(n² + 1))²`.
    #[test]
    fn fresnel_at_brewster_angle_is_half_the_s_reflectance() {
        for n in [1.33f64, 1.5, 2.4] {
            let theta = libm::atan(n) as f32;
            let f = interface(dir_at(theta), UnitVec3::Y, (1.0 / n) as f32).reflectance as f64;
            let want = 0.5 * ((n * n - 1.0) / (n * n + 1.0)).powi(2);
            assert!((f - want).abs() < 2e-6, "n = {n}: {f} vs {want}");
            // And from inside, at the internal Brewster angle tan θ = 1/n.
            let inside = libm::atan(1.0 / n) as f32;
            let f = interface(dir_at(inside), UnitVec3::Y, n as f32).reflectance as f64;
            assert!((f - want).abs() < 2e-6, "n = {n} inside: {f} vs {want}");
        }
    }

    /// The hemispherical (cosine-weighted) reflectance `2∫₀^{π/2} F(θ) cos θ sin θ dθ`
    /// of `interface`, integrated by the midpoint rule, against its closed form for
    /// light from air (Stern 1964; the classic value 0.0918 at n = 1.5) and, from
    /// inside, against `1 − (1 − r_e)/n²` (reciprocity; the total internal
    /// reflection beyond the critical angle is most of it).
    #[test]
    fn hemispherical_reflectance_matches_the_closed_form() {
        fn outside(n: f64) -> f64 {
            let (n2, n4) = (n * n, n * n * n * n);
            0.5 + (n - 1.0) * (3.0 * n + 1.0) / (6.0 * (n + 1.0).powi(2))
                + n2 * (n2 - 1.0).powi(2) / (n2 + 1.0).powi(3) * libm::log((n - 1.0) / (n + 1.0))
                - 2.0 * n * n2 * (n2 + 2.0 * n - 1.0) / ((n2 + 1.0) * (n4 - 1.0))
                + 8.0 * n4 * (n4 + 1.0) / ((n2 + 1.0) * (n4 - 1.0).powi(2)) * libm::log(n)
        }
        fn integral(eta: f32) -> f64 {
            let steps = 20_000;
            let h = core::f64::consts::FRAC_PI_2 / steps as f64;
            (0..steps)
                .map(|i| {
                    let theta = (i as f64 + 0.5) * h;
                    let f = interface(dir_at(theta as f32), UnitVec3::Y, eta).reflectance;
                    2.0 * f as f64 * libm::cos(theta) * libm::sin(theta) * h
                })
                .sum()
        }
        assert!((outside(1.5) - 0.0918).abs() < 1e-4);
        for n in [1.33f64, 1.5, 2.4] {
            let (re, ri) = (integral((1.0 / n) as f32), integral(n as f32));
            let want = outside(n);
            assert!((re - want).abs() < 1e-4, "n = {n}: {re} vs {want}");
            let want = 1.0 - (1.0 - outside(n)) / (n * n);
            assert!((ri - want).abs() < 1e-4, "n = {n} inside: {ri} vs {want}");
        }
    }

    /// The paper's eq. 8 kernel against a hand computation. Normal `+y`, light at 45°
    /// in the x–y plane (`n·l = cos 45° = √2/2`). Eye straight above: the half vector
    /// lies at 22.5° from the normal, `n·h = cos 22.5°`. Eye at the mirror direction of
    /// the light: `h = n`, full highlight. Light below the horizon: no diffuse part.
    #[test]
    fn classic_kernel_matches_a_hand_computation() {
        let c = Classic::new(Rgb::new(0.5, 1.0, 0.25), 0.1, 0.8, 0.3, 4.0, 0.0, 0.0, 1.5);
        let unit = |x: f32, y: f32| UnitVec3::new(Vec3::new(x, y, 0.0)).unwrap();
        let (n, l) = (UnitVec3::Y, unit(1.0, 1.0));
        let close = |got: Rgb, k: f64| {
            for (g, col) in got.to_array().into_iter().zip([0.5f64, 1.0, 0.25]) {
                assert!((g as f64 - col * k).abs() < 1e-6, "{got:?} vs {k}·color");
            }
        };
        let cos45 = core::f64::consts::FRAC_1_SQRT_2;
        let cos22 = libm::cos(core::f64::consts::PI / 8.0);
        // 0.8·cos 45° + 0.3·cos⁴ 22.5° = 0.565685 + 0.218566.
        close(
            c.kernel(n, l, UnitVec3::Y),
            0.8 * cos45 + 0.3 * cos22.powi(4),
        );
        close(c.kernel(n, l, unit(-1.0, 1.0)), 0.8 * cos45 + 0.3);
        // A non-integer exponent goes through powf: cos^2.5 22.5°.
        let c25 = Classic::new(Rgb::new(0.5, 1.0, 0.25), 0.1, 0.8, 0.3, 2.5, 0.0, 0.0, 1.5);
        close(
            c25.kernel(n, l, UnitVec3::Y),
            0.8 * cos45 + 0.3 * cos22.powf(2.5),
        );
        // Light from below: the diffuse part is 0; the half vector of (1,−1) and (−1,1)
        // is undefined (they cancel), so no highlight either.
        close(c.kernel(n, unit(1.0, -1.0), unit(-1.0, 1.0)), 0.0);
        // k_s = 0: diffuse only, whatever the eye.
        let matte = Classic::new(Rgb::new(0.5, 1.0, 0.25), 0.1, 0.8, 0.0, 4.0, 0.0, 0.0, 1.5);
        close(matte.kernel(n, l, unit(-1.0, 1.0)), 0.8 * cos45);
    }

    #[test]
    fn integer_powers_match_powf() {
        for a in [0.0f32, 1.0, 2.0, 7.0, 20.0, 20.5] {
            for x in [0.0f32, 0.3, 0.9, 1.0] {
                let (p, q) = (powi_real(x, a), libm::powf(x, a));
                assert!(
                    (p - q).abs() <= 1e-6 * q.max(1e-30) + 1e-7,
                    "{x}^{a}: {p} {q}"
                );
            }
        }
    }

    #[test]
    fn constructors_validate() {
        assert!(Material::diffuse(Rgb::new(1.2, 0.0, 0.0)).is_err());
        assert!(Material::dielectric(0.0, Rgb::ZERO).is_err());
        assert!(Material::dielectric(1.5, Rgb::new(-1.0, 0.0, 0.0)).is_err());
        assert!(Material::mirror(Rgb::splat(f32::NAN)).is_err());
        let c = Classic::new(Rgb::ONE, 0.3, 0.9, 0.2, 20.0, 0.6, 0.7, 1.25);
        assert!(
            Material::classic(c).is_err(),
            "reflectivity + transparency > 1"
        );
    }
}
