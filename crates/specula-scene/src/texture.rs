use std::path::Path;

use glam::{Vec2, Vec3};

use crate::SceneError;

/// An RGB texture in linear radiance units, sampled bilinearly with repeat wrapping. `uv` (0, 0)
/// is the top-left texel's corner, as in glTF.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
}

/// sRGB transfer function, decoded to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// Decodes an image. 8-bit images are sRGB-encoded colour unless `srgb` is false; float
    /// images (HDR, EXR) are taken as linear.
    pub fn from_image(
        name: &str,
        img: image::DynamicImage,
        srgb: bool,
    ) -> Result<Self, SceneError> {
        let (width, height) = (img.width(), img.height());
        if width == 0 || height == 0 {
            return Err(SceneError::invalid(name, "image has no pixels"));
        }
        let is_float = matches!(
            img.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let rgb = img.to_rgb32f();
        let texels: Vec<Vec3> = rgb
            .pixels()
            .map(|p| {
                let c = Vec3::from_array(p.0);
                if srgb && !is_float {
                    Vec3::new(
                        srgb_to_linear(c.x),
                        srgb_to_linear(c.y),
                        srgb_to_linear(c.z),
                    )
                } else {
                    c
                }
            })
            .collect();
        if let Some(i) = texels.iter().position(|t| !t.is_finite()) {
            return Err(SceneError::invalid(
                name,
                format!(
                    "texel ({}, {}) is not finite",
                    i as u32 % width,
                    i as u32 / width
                ),
            ));
        }
        Ok(Texture {
            name: name.to_string(),
            width,
            height,
            texels,
        })
    }

    pub fn load(path: &Path, srgb: bool) -> Result<Self, SceneError> {
        let shown = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| SceneError::io(&shown, e))?;
        let img = image::load_from_memory(&bytes)
            .map_err(|e| SceneError::invalid(&shown, format!("cannot decode image: {e}")))?;
        Self::from_image(&shown, img, srgb)
    }

    /// A texture built from a closure giving linear RGB at each texel centre in [0,1]².
    pub fn procedural(name: &str, width: u32, height: u32, f: impl Fn(Vec2) -> Vec3) -> Self {
        let mut texels = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            for x in 0..width {
                let uv = Vec2::new(
                    (x as f32 + 0.5) / width as f32,
                    (y as f32 + 0.5) / height as f32,
                );
                texels.push(f(uv));
            }
        }
        Texture {
            name: name.to_string(),
            width,
            height,
            texels,
        }
    }

    /// A `side` × `side` texel checkerboard of `squares` × `squares` squares in colours `a`
    /// (the top-left square) and `b`.
    pub fn checker(name: &str, squares: u32, side: u32, a: Vec3, b: Vec3) -> Self {
        Texture::procedural(name, side, side, |uv| {
            let (i, j) = (
                (uv.x * squares as f32) as u32,
                (uv.y * squares as f32) as u32,
            );
            if (i + j) % 2 == 0 {
                a
            } else {
                b
            }
        })
    }

    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.texels[y * self.width as usize + x]
    }

    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }
}
