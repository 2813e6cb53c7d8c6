// Optics shared by every technique, mirroring specula-trace's `optics` module exactly.
// Convention (docs/conventions.md): `d` is the incident direction (towards the surface), `n` the
// unit normal on the side `d` comes from, `eta` = n_incident / n_transmitted. WGSL's built-in
// `reflect(d, n)` and `refract(d, n, eta)` follow the same convention and are used as they are.

// Exact Fresnel reflectances (R_s, R_p) of a dielectric interface; (1, 1) under total internal
// reflection.
fn fresnel_dielectric_sp(cos_i_in: f32, eta: f32) -> vec2<f32> {
    let cos_i = clamp(cos_i_in, 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) {
        return vec2<f32>(1.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return vec2<f32>(r_s * r_s, r_p * r_p);
}

// Exact unpolarised Fresnel reflectance of a dielectric interface: the mean of s and p.
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric_sp(cos_i, eta);
    return 0.5 * (r.x + r.y);
}

// Schlick's approximation for a conductor with normal-incidence reflectance `f0`.
fn fresnel_schlick(f0: vec3<f32>, cos_i: f32) -> vec3<f32> {
    let m = pow(1.0 - clamp(cos_i, 0.0, 1.0), 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * m;
}

// Unpolarised reflectance of a thin non-absorbing sheet, s and p summed apart:
// ½ [2R_s / (1 + R_s) + 2R_p / (1 + R_p)].
fn thin_sheet_reflectance(cos_i: f32, ior: f32) -> f32 {
    let r = fresnel_dielectric_sp(cos_i, 1.0 / ior);
    let sheet = 2.0 * r / (vec2<f32>(1.0) + r);
    return 0.5 * (sheet.x + sheet.y);
}
