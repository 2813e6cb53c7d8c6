// Optics shared by every technique, mirroring specula-trace's `optics` module exactly.
// Convention (docs/conventions.md): `d` is the incident direction (towards the surface), `n` the
// unit normal on the side `d` comes from, `eta` = n_incident / n_transmitted. WGSL's built-in
// `reflect(d, n)` and `refract(d, n, eta)` follow the same convention and are used as they are.

// Exact unpolarised Fresnel reflectance of a dielectric interface; 1 under total internal
// reflection.
fn fresnel_dielectric(cos_i_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_i_in, 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_s * r_s + r_p * r_p);
}

// Schlick's approximation for a conductor with normal-incidence reflectance `f0`.
fn fresnel_schlick(f0: vec3<f32>, cos_i: f32) -> vec3<f32> {
    let m = pow(1.0 - clamp(cos_i, 0.0, 1.0), 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * m;
}

// Reflectance of a thin non-absorbing sheet: 2R / (1 + R).
fn thin_sheet_reflectance(cos_i: f32, ior: f32) -> f32 {
    let r = fresnel_dielectric(cos_i, 1.0 / ior);
    return 2.0 * r / (1.0 + r);
}
