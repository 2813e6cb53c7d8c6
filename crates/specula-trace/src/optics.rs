//! Reflection, refraction and Fresnel terms. `d` is the incident direction (towards the
//! surface), `n` the unit normal on the side `d` comes from (`d · n < 0`), and `eta` the ratio
//! n_incident / n_transmitted. Mirrors WGSL's `reflect(e1, e2)` and `refract(e1, e2, e3)`.

use glam::Vec3;

pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell's law; `None` under total internal reflection.
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if k < 0.0 {
        None
    } else {
        Some(eta * d + (eta * cos_i - k.sqrt()) * n)
    }
}

/// Exact Fresnel reflectances (R_s, R_p) of a dielectric interface for light polarised
/// perpendicular (s) and parallel (p) to the plane of incidence. `cos_i` is the cosine between
/// the incident ray and the normal (≥ 0); (1, 1) under total internal reflection.
pub fn fresnel_dielectric_sp(cos_i: f32, eta: f32) -> (f32, f32) {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return (1.0, 1.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (r_s * r_s, r_p * r_p)
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface: the mean of the s and p
/// reflectances. `cos_i` is the cosine between the incident ray and the normal (≥ 0); 1 under
/// total internal reflection. Transmittance is 1 − R (energy is conserved).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (r_s, r_p) = fresnel_dielectric_sp(cos_i, eta);
    0.5 * (r_s + r_p)
}

/// Schlick's approximation for a conductor with normal-incidence reflectance `f0`.
pub fn fresnel_schlick(f0: Vec3, cos_i: f32) -> Vec3 {
    let m = (1.0 - cos_i.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

/// Reflectance of a thin non-absorbing sheet for one polarisation whose single-interface
/// reflectance is `r`: the light bouncing back and forth between the two parallel faces sums to
/// 2r / (1 + r). Both faces share the plane of incidence, so s and p never mix.
pub fn thin_sheet_reflectance_of(r: f32) -> f32 {
    2.0 * r / (1.0 + r)
}

/// Unpolarised reflectance of a thin non-absorbing sheet: s and p summed apart,
/// ½ [2R_s / (1 + R_s) + 2R_p / (1 + R_p)] (2R / (1 + R) of the average R would be 0.7 % high at
/// 31°, 3.3 % at 45° and 7.8 % at 60° for n = 1.5).
pub fn thin_sheet_reflectance(cos_i: f32, ior: f32) -> f32 {
    let (r_s, r_p) = fresnel_dielectric_sp(cos_i, 1.0 / ior);
    0.5 * (thin_sheet_reflectance_of(r_s) + thin_sheet_reflectance_of(r_p))
}

/// Critical angle (radians) for light going from index `n_inside` to `n_outside` < `n_inside`.
pub fn critical_angle(n_inside: f32, n_outside: f32) -> f32 {
    (n_outside / n_inside).asin()
}
