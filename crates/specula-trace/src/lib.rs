//! specula's exact side: the BVH, the optics every technique shares (reflect, refract,
//! Fresnel), and the Whitted-style reference renderer whose output defines "accurate".
//!
//! Direction convention (docs/conventions.md): a ray direction `d` points the way light is
//! traced, from the eye into the scene; at a surface, `d` is the *incident* direction (pointing
//! towards the surface), as in WGSL's `reflect` and `refract`.

pub mod accel;
pub mod bvh;
pub mod image_io;
pub mod optics;
pub mod primary_rays;
pub mod reference;
pub mod wide_bvh;

pub use accel::{Hit, Ray, SceneAccel};
pub use bvh::{Bvh, BvhNode};
pub use image_io::{Image, ImageError};
pub use reference::{render, RenderSettings};
