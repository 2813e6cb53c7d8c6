//! distance-maps' unit tests: the tracing shader's face bases against the rendered faces.

use super::*;
use glam::{Vec3, Vec4};

/// The lookup's face bases project a direction to the same texture coordinate as the
/// matrices the faces are rendered with.
#[test]
fn face_bases_match_the_rendered_faces() {
    let origin = Vec3::new(0.3, -1.0, 2.0);
    let views = raster::cube_views(origin, 0.01, 100.0, 64);
    for (face, (basis, view)) in face_bases().iter().zip(views.iter()).enumerate() {
        let forward = Vec4::from(basis.forward).truncate();
        let right = Vec4::from(basis.right).truncate();
        let up = Vec4::from(basis.up).truncate();
        for (a, b) in [(0.3, -0.7), (-0.95, 0.2), (0.0, 0.0), (0.6, 0.99)] {
            let d = forward + right * a + up * b;
            let clip =
                glam::Mat4::from_cols_array_2d(&view.clip_from_world) * (origin + d).extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let matrix_uv = (ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
            let z = forward.dot(d);
            let basis_uv = (0.5 + 0.5 * right.dot(d) / z, 0.5 - 0.5 * up.dot(d) / z);
            assert!(
                (matrix_uv.0 - basis_uv.0).abs() < 1e-5 && (matrix_uv.1 - basis_uv.1).abs() < 1e-5,
                "face {face}: {matrix_uv:?} vs {basis_uv:?}"
            );
        }
    }
}
