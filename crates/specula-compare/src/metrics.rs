//! Error metrics between a technique's image and the reference, over a pixel mask.
//!
//! - RMSE and PSNR are computed on linear radiance clamped to the displayable range [0, 1]
//!   (the range PNG output shows), averaged over the three channels; PSNR = 20 log10(1 / RMSE).
//! - FLIP (NVIDIA's perceptual difference, through the `nv-flip` crate) is computed on the two
//!   sRGB-encoded 8-bit images as a whole, then pooled over the mask: its mean, and the share
//!   of mask pixels whose FLIP exceeds 0.1 (clearly visible differences).

use serde::Serialize;
use specula_methods::SurfaceClass;
use specula_trace::Image;

/// FLIP above which a pixel's difference counts as clearly visible.
pub const FLIP_VISIBLE: f32 = 0.1;

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Metrics {
    pub mask_pixels: usize,
    pub rmse: f64,
    /// Infinite when the images are identical on the mask (serialised as null).
    pub psnr_db: Option<f64>,
    pub mean_flip: f64,
    pub share_flip_over_0_1: f64,
}

/// Per-pixel FLIP between `reference` and `test`.
pub fn flip_map(reference: &Image, test: &Image) -> Vec<f32> {
    let convert = |i: &Image| {
        let rgb = i.to_srgb8();
        nv_flip::FlipImageRgb8::with_data(rgb.width(), rgb.height(), rgb.as_raw())
    };
    nv_flip::flip(
        convert(reference),
        convert(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    )
    .to_vec()
}

/// A heat-map of a FLIP map (magma colour scale: black = equal, yellow-white = very different).
pub fn heat_map(flip: &[f32], width: u32, height: u32) -> image::RgbImage {
    let errors = nv_flip::FlipImageFloat::with_data(width, height, flip);
    let colored = errors.apply_color_lut(&nv_flip::magma_lut());
    image::RgbImage::from_raw(width, height, colored.to_vec()).expect("size matches")
}

/// The pixels whose primary surface is of a class `keep` accepts (off the mask: never).
pub fn class_mask(
    classes: &[Option<SurfaceClass>],
    keep: impl Fn(SurfaceClass) -> bool,
) -> Vec<bool> {
    classes.iter().map(|c| c.is_some_and(&keep)).collect()
}

/// The figures of `test` against `reference` on the pixels `mask` holds. `flip` is the FLIP
/// map of the whole images ([`flip_map`]): FLIP filters spatially, so a pixel's value depends
/// on its neighbours, masked or not.
pub fn measure(reference: &Image, test: &Image, flip: &[f32], mask: &[bool]) -> Metrics {
    let pixels: Vec<usize> = (0..mask.len()).filter(|&i| mask[i]).collect();
    let n = pixels.len().max(1) as f64;
    let squared: f64 = pixels
        .iter()
        .map(|&i| {
            let d = test.pixels[i].clamp(glam::Vec3::ZERO, glam::Vec3::ONE)
                - reference.pixels[i].clamp(glam::Vec3::ZERO, glam::Vec3::ONE);
            (d.length_squared() / 3.0) as f64
        })
        .sum();
    let rmse = (squared / n).sqrt();
    Metrics {
        mask_pixels: pixels.len(),
        rmse,
        psnr_db: (rmse > 0.0).then(|| 20.0 * (1.0 / rmse).log10()),
        mean_flip: pixels.iter().map(|&i| flip[i] as f64).sum::<f64>() / n,
        share_flip_over_0_1: pixels.iter().filter(|&&i| flip[i] > FLIP_VISIBLE).count() as f64 / n,
    }
}
