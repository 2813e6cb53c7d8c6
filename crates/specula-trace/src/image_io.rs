//! Linear-radiance images and their files: PNG (sRGB-encoded, clamped to [0, 1]) and EXR
//! (linear float RGB).

use std::path::Path;

use glam::Vec3;

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: cannot write image: {message}")]
    Write { path: String, message: String },
    #[error("{path}: cannot read image: {message}")]
    Read { path: String, message: String },
    #[error("image has a non-finite pixel at ({x}, {y}): refusing to write it")]
    NonFinite { x: u32, y: u32 },
}

/// Linear RGB radiance, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// sRGB transfer function, encoding linear [0, 1] values.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    fn check_finite(&self) -> Result<(), ImageError> {
        match self.pixels.iter().position(|p| !p.is_finite()) {
            Some(i) => Err(ImageError::NonFinite {
                x: i as u32 % self.width,
                y: i as u32 / self.width,
            }),
            None => Ok(()),
        }
    }

    /// 8-bit sRGB pixels, clamped.
    pub fn to_srgb8(&self) -> image::RgbImage {
        image::RgbImage::from_fn(self.width, self.height, |x, y| {
            let c = self.get(x, y);
            image::Rgb([c.x, c.y, c.z].map(|v| (linear_to_srgb(v) * 255.0).round() as u8))
        })
    }

    pub fn save_png(&self, path: &Path) -> Result<(), ImageError> {
        self.check_finite()?;
        self.to_srgb8().save(path).map_err(|e| ImageError::Write {
            path: path.display().to_string(),
            message: e.to_string(),
        })
    }

    pub fn save_exr(&self, path: &Path) -> Result<(), ImageError> {
        self.check_finite()?;
        let data: Vec<f32> = self.pixels.iter().flat_map(|p| p.to_array()).collect();
        let buffer = image::Rgb32FImage::from_raw(self.width, self.height, data)
            .expect("pixel count matches size");
        buffer
            .save_with_format(path, image::ImageFormat::OpenExr)
            .map_err(|e| ImageError::Write {
                path: path.display().to_string(),
                message: e.to_string(),
            })
    }

    /// Reads a PNG (sRGB, decoded to linear) or EXR (linear) image.
    pub fn load(path: &Path) -> Result<Image, ImageError> {
        let err = |message: String| ImageError::Read {
            path: path.display().to_string(),
            message,
        };
        let img = image::open(path).map_err(|e| err(e.to_string()))?;
        let is_float = matches!(
            img.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let rgb = img.to_rgb32f();
        let pixels = rgb
            .pixels()
            .map(|p| {
                let c = Vec3::from_array(p.0);
                if is_float {
                    c
                } else {
                    c.to_array()
                        .map(specula_scene::texture::srgb_to_linear)
                        .into()
                }
            })
            .collect();
        Ok(Image {
            width: rgb.width(),
            height: rgb.height(),
            pixels,
        })
    }
}
