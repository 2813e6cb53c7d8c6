use glam::Vec3;

/// Punctual lights. Radiometric units: a point or spot light's `intensity` is radiant intensity
/// (W/sr, so irradiance at distance d is intensity / d²); a directional light's `irradiance` is
/// W/m² on a surface facing it. glTF's candela and lux are taken as these numbers unchanged.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    /// `direction` is the direction light travels (glTF: the node's -Z), unit length.
    Directional {
        direction: Vec3,
        irradiance: Vec3,
    },
    /// A point light restricted to a cone around `direction` (the direction light travels), with
    /// glTF's smooth falloff between the inner and outer cone angles (radians).
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        inner_cone: f32,
        outer_cone: f32,
    },
}

/// What a light delivers to a surface point: the unit direction towards the light, the distance
/// to it (infinite for directional lights) and the irradiance on a surface facing it.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub to_light: Vec3,
    pub distance: f32,
    pub irradiance: Vec3,
}

impl Light {
    pub fn sample(&self, p_world: Vec3) -> LightSample {
        match *self {
            Light::Point {
                position,
                intensity,
            } => {
                let offset = position - p_world;
                let distance = offset.length();
                LightSample {
                    to_light: offset / distance,
                    distance,
                    irradiance: intensity / (distance * distance),
                }
            }
            Light::Directional {
                direction,
                irradiance,
            } => LightSample {
                to_light: -direction,
                distance: f32::INFINITY,
                irradiance,
            },
            Light::Spot {
                position,
                direction,
                intensity,
                inner_cone,
                outer_cone,
            } => {
                let offset = position - p_world;
                let distance = offset.length();
                let to_light = offset / distance;
                let cos_angle = (-to_light).dot(direction);
                let (cos_outer, cos_inner) = (outer_cone.cos(), inner_cone.cos());
                let t =
                    ((cos_angle - cos_outer) / (cos_inner - cos_outer).max(1e-6)).clamp(0.0, 1.0);
                LightSample {
                    to_light,
                    distance,
                    irradiance: intensity * (t * t) / (distance * distance),
                }
            }
        }
    }

    pub fn is_valid(&self) -> bool {
        match *self {
            Light::Point {
                position,
                intensity,
            } => position.is_finite() && intensity.is_finite() && intensity.min_element() >= 0.0,
            Light::Directional {
                direction,
                irradiance,
            } => {
                direction.is_finite()
                    && direction.length_squared() > 0.0
                    && irradiance.is_finite()
                    && irradiance.min_element() >= 0.0
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_cone,
                outer_cone,
            } => {
                position.is_finite()
                    && direction.is_finite()
                    && direction.length_squared() > 0.0
                    && intensity.is_finite()
                    && intensity.min_element() >= 0.0
                    && inner_cone >= 0.0
                    && outer_cone > inner_cone - 1e-6
            }
        }
    }
}
