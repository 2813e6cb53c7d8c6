use glam::Vec3;

/// How a surface interacts with light (DESIGN.md, "Scene semantics").
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// Emits `color` × texture, lit by nothing.
    Unlit,
    /// Lambertian reflector with albedo `color` × texture, lit by the scene's lights (hard
    /// shadows) and the scene's ambient radiance.
    Diffuse,
    /// Conductor mirror with normal-incidence reflectance F0 = `color`: Schlick's Fresnel when
    /// `fresnel`, exactly F0 otherwise.
    Mirror { fresnel: bool },
    /// Dielectric with one index of refraction per RGB channel (all equal unless dispersive):
    /// exact unpolarised Fresnel, total internal reflection. A thin-walled one is a sheet:
    /// Fresnel reflection and straight-through transmission.
    Dielectric { ior: Vec3, thin_walled: bool },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kind: MaterialKind,
    /// Base colour (unlit, diffuse) or F0 (mirror); linear RGB.
    pub color: Vec3,
    /// Index into `Scene::textures`, multiplied with `color` (unlit and diffuse only).
    pub texture: Option<usize>,
}

impl Material {
    pub fn new(name: impl Into<String>, kind: MaterialKind, color: Vec3) -> Self {
        Material {
            name: name.into(),
            kind,
            color,
            texture: None,
        }
    }

    pub fn diffuse(name: impl Into<String>, color: Vec3) -> Self {
        Self::new(name, MaterialKind::Diffuse, color)
    }

    pub fn unlit(name: impl Into<String>, color: Vec3) -> Self {
        Self::new(name, MaterialKind::Unlit, color)
    }

    pub fn mirror(name: impl Into<String>, f0: Vec3) -> Self {
        Self::new(name, MaterialKind::Mirror { fresnel: true }, f0)
    }

    pub fn glass(name: impl Into<String>, ior: f32) -> Self {
        Self::new(
            name,
            MaterialKind::Dielectric {
                ior: Vec3::splat(ior),
                thin_walled: false,
            },
            Vec3::ONE,
        )
    }

    /// True for a dielectric with different indices per colour channel: its paths split per
    /// channel.
    pub fn is_dispersive(&self) -> bool {
        matches!(self.kind, MaterialKind::Dielectric { ior, .. } if ior.x != ior.y || ior.y != ior.z)
    }

    /// True for the surfaces the techniques treat specially (mirrors and dielectrics).
    pub fn is_specular(&self) -> bool {
        matches!(
            self.kind,
            MaterialKind::Mirror { .. } | MaterialKind::Dielectric { .. }
        )
    }
}

/// Reflectance at normal incidence (F0) of a conductor with index of refraction `n` and
/// extinction coefficient `k` per channel, seen from air:
/// ((n − 1)² + k²) / ((n + 1)² + k²), the formula Umenhoffer et al. (GPU Gems 3, ch. 17) give for
/// Schlick's Fresnel on metals; k = 0 gives a dielectric's F0.
pub fn conductor_f0(n: Vec3, k: Vec3) -> Vec3 {
    let k2 = k * k;
    ((n - Vec3::ONE) * (n - Vec3::ONE) + k2) / ((n + Vec3::ONE) * (n + Vec3::ONE) + k2)
}

/// Per-channel IOR (R, G, B) of a glass with d-line index `ior` and Abbe number `abbe`.
///
/// The Abbe number is V = (n_d − 1) / (n_F − n_C); taking the red, green and blue channels at the
/// C, d and F lines (with n_d midway) gives n_F − n_C = (n_d − 1) / V, so each of red and blue
/// lies half of that spread from green. This is the mapping glTF's `KHR_materials_dispersion`
/// uses (its `dispersion` is 20 / V).
pub fn ior_from_abbe(ior: f32, abbe: f32) -> Vec3 {
    let half_spread = (ior - 1.0) / abbe * 0.5;
    Vec3::new(ior - half_spread, ior, ior + half_spread)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conductor_f0_has_the_closed_form_values() {
        // Glass: ((1.5 − 1) / (1.5 + 1))² = 0.04.
        assert!(
            (conductor_f0(Vec3::splat(1.5), Vec3::ZERO) - Vec3::splat(0.04))
                .abs()
                .max_element()
                < 1e-6
        );
        // n = 0.2, k = 3: (0.64 + 9) / (1.44 + 9) = 0.923372.
        let f0 = conductor_f0(Vec3::splat(0.2), Vec3::splat(3.0));
        assert!((f0.x - 9.64 / 10.44).abs() < 1e-6, "{f0}");
        // No absorption and index 1: nothing reflects.
        assert_eq!(conductor_f0(Vec3::ONE, Vec3::ZERO), Vec3::ZERO);
    }
}
