//! The CAD examples in `scenes/cad/`, written by [`super::write`]: what a designer's STEP
//! export of a door mirror's glass and of a spectacle lens holds. `cargo test -p specula-scene
//! --test step` holds the files to these functions (`SPECULA_REGENERATE=1` rewrites them).

use glam::DVec3;

use super::write::{NurbsPatch, StepWriter};
use crate::units::LengthUnit;

/// A convex spherical door-mirror glass, radius of curvature 1,600 mm, 200 mm wide and 130 mm
/// high, in millimetres: one rational biquadratic B-spline face (as CAD systems export a
/// sphere trimmed to a mirror's outline), its apex at the origin and its reflecting side
/// facing +Z, split in four faces along its middle lines, as a designer's glass often is.
pub fn door_mirror() -> String {
    const RADIUS_MM: f64 = 1600.0;
    let half_width = (100.0 / RADIUS_MM).asin();
    let half_height = (65.0 / RADIUS_MM).asin();
    let mut writer = StepWriter::new();
    let mut faces = Vec::new();
    for (u0, u1) in [(-half_width, 0.0), (0.0, half_width)] {
        for (v0, v1) in [(-half_height, 0.0), (0.0, half_height)] {
            let patch = NurbsPatch::sphere_region(RADIUS_MM, (u0, u1), 1, (v0, v1));
            faces.push(writer.patch_face(&patch.map_points(facing_z(RADIUS_MM))));
        }
    }
    writer.body("door mirror glass", &faces, false);
    writer.finish(LengthUnit::Mm)
}

/// Turns a sphere region about +X (as [`NurbsPatch::sphere_region`] makes it) to face +Z, its
/// width along X and its height along Y (x' = y, y' = z, z' = x, a rotation), and moves it back
/// by `radius` so that its middle is at the origin.
pub fn facing_z(radius: f64) -> impl Fn(DVec3) -> DVec3 {
    move |p| DVec3::new(p.y, p.z, p.x - radius)
}

/// A meniscus spectacle lens as a closed solid, in millimetres, light along +Z: front radius
/// 100 mm (convex), back radius 125 mm (concave), 2.2 mm thick at the centre, cut to a
/// 50 mm × 36 mm rectangle. Six rational B-spline faces: the two optical faces and the four
/// ruled faces of its edge, sharing their edges as a CAD solid does.
pub fn spectacle_lens() -> String {
    let front = lens_surface(100.0, 0.0);
    let back = lens_surface(125.0, 2.2);
    let sides: Vec<NurbsPatch> = boundaries(&front)
        .into_iter()
        .zip(boundaries(&back))
        .map(|((front_edge, knots), (back_edge, _))| {
            let side = NurbsPatch {
                degree: (2, 1),
                control: front_edge
                    .into_iter()
                    .zip(back_edge)
                    .map(|(f, b)| vec![f, b])
                    .collect(),
                knots_u: knots,
                knots_v: vec![0.0, 0.0, 1.0, 1.0],
            };
            // The edge faces the way from the lens's axis to its middle.
            let toward = corners_middle(&side) * DVec3::new(1.0, 1.0, 0.0);
            outward(side, toward)
        })
        .collect();
    let mut writer = StepWriter::new();
    let mut faces = vec![
        writer.patch_face(&outward(front, DVec3::NEG_Z)),
        writer.patch_face(&outward(back, DVec3::Z)),
    ];
    faces.extend(sides.iter().map(|side| writer.patch_face(side)));
    writer.body("spectacle lens", &faces, true);
    writer.finish(LengthUnit::Mm)
}

/// A sphere of `radius` whose vertex is at z = `vertex_z`, its centre on +Z beyond it, cut to
/// 50 mm × 36 mm.
fn lens_surface(radius: f64, vertex_z: f64) -> NurbsPatch {
    let half_width = (25.0 / radius).asin();
    let half_height = (18.0 / radius).asin();
    // About +X outwards → about −Z outwards with the centre on +Z (x' = −y, y' = z, z' = −x:
    // a rotation), then moved so that the vertex is at z = vertex_z.
    NurbsPatch::sphere_region(
        radius,
        (-half_width, half_width),
        1,
        (-half_height, half_height),
    )
    .map_points(|p| DVec3::new(-p.y, p.z, radius + vertex_z - p.x))
}

/// A control point and its weight.
type WeightedPoint = (DVec3, f64);

/// The four boundary curves of a patch (control points with weights, and knots) in the order
/// u = u0, u = u1, v = v0, v = v1; two patches made alike give matching curves.
fn boundaries(patch: &NurbsPatch) -> Vec<(Vec<WeightedPoint>, Vec<f64>)> {
    let column = |j: usize| patch.control.iter().map(|row| row[j]).collect::<Vec<_>>();
    let last = patch.control[0].len() - 1;
    vec![
        (patch.control[0].clone(), patch.knots_v.clone()),
        (
            patch.control[patch.control.len() - 1].clone(),
            patch.knots_v.clone(),
        ),
        (column(0), patch.knots_u.clone()),
        (column(last), patch.knots_u.clone()),
    ]
}

/// The middle of a patch's four corners, which lie on its surface.
fn corners_middle(patch: &NurbsPatch) -> DVec3 {
    let rows = patch.control.len() - 1;
    let columns = patch.control[0].len() - 1;
    (patch.control[0][0].0
        + patch.control[0][columns].0
        + patch.control[rows][0].0
        + patch.control[rows][columns].0)
        / 4.0
}

/// The patch with its Su × Sv (from its corners) turned towards `toward`: its rows reversed
/// where it faced the other way.
fn outward(mut patch: NurbsPatch, toward: DVec3) -> NurbsPatch {
    let rows = patch.control.len() - 1;
    let columns = patch.control[0].len() - 1;
    let along_u = patch.control[rows][0].0 - patch.control[0][0].0;
    let along_v = patch.control[0][columns].0 - patch.control[0][0].0;
    if along_u.cross(along_v).dot(toward) < 0.0 {
        patch.control.reverse();
        let (a, b) = (patch.knots_u[0], patch.knots_u[patch.knots_u.len() - 1]);
        patch.knots_u = patch.knots_u.iter().rev().map(|k| a + b - k).collect();
    }
    patch
}
