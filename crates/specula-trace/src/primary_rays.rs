//! The primary rays of the Embree peer benchmark (`shared/bench/embree_rays.py`): a camera on
//! +Z at 2.2 bounding radii from the mesh's box centre, 40° vertical field of view, one ray
//! through each pixel centre of a `size` × `size` image. Casting exactly these lets the hit
//! count be compared with Embree's as a checksum.

use glam::Vec3;

use crate::Ray;

pub fn embree_benchmark_rays(positions: &[Vec3], size: u32) -> Vec<Ray> {
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let center = (lo + hi) / 2.0;
    let radius = (hi - lo).length() / 2.0;
    let eye = center + Vec3::new(0.0, 0.0, 2.2 * radius);
    // Directions in double precision, rounded once, as numpy does in the peer script.
    let t = (40.0f64.to_radians() / 2.0).tan();
    let mut rays = Vec::with_capacity((size * size) as usize);
    for row in 0..size {
        for col in 0..size {
            let px = |i: u32| ((i as f64 + 0.5) / size as f64 * 2.0 - 1.0) * t;
            let dir = glam::DVec3::new(px(col), -px(row), -1.0)
                .normalize()
                .as_vec3();
            rays.push(Ray { origin: eye, dir });
        }
    }
    rays
}
