//! Analytic shapes tessellated to meshes at a chosen resolution, with exact analytic normals.
//! Every generator returns an object-space mesh (material 0) whose triangles wind
//! counter-clockwise around the outward (or, for mirrors, the reflecting-side) normal.

use std::f32::consts::{PI, TAU};

use glam::{DVec3, Vec2, Vec3};

use crate::exact::{self, ExactShape, ExactSurface};
use crate::exact_lens::{ExactLens, LensSurface};
use crate::{Mesh, SceneError};

/// One tessellated vertex: position, unit normal, texture coordinate.
pub(crate) struct Sample {
    pub p: Vec3,
    pub n: Vec3,
    pub uv: Vec2,
}

/// Appends a (nu+1) × (nv+1) vertex grid over the parameter square [0,1]², two triangles per
/// cell, each wound counter-clockwise around its vertices' normals. Cells collapsed to a point
/// (poles, apexes) give zero-area triangles, which are removed.
pub(crate) fn append_grid(mesh: &mut Mesh, nu: u32, nv: u32, f: impl Fn(f32, f32) -> Sample) {
    let base = mesh.positions.len() as u32;
    for j in 0..=nv {
        for i in 0..=nu {
            let s = f(i as f32 / nu as f32, j as f32 / nv as f32);
            mesh.positions.push(s.p);
            mesh.normals.push(s.n);
            mesh.uvs.push(s.uv);
        }
    }
    let index = |i: u32, j: u32| base + j * (nu + 1) + i;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            for tri in [[a, b, c], [a, c, d]] {
                push_oriented(mesh, tri);
            }
        }
    }
}

fn push_oriented(mesh: &mut Mesh, [a, b, c]: [u32; 3]) {
    let (pa, pb, pc) = (
        mesh.positions[a as usize],
        mesh.positions[b as usize],
        mesh.positions[c as usize],
    );
    let face = (pb - pa).cross(pc - pa);
    let normal_sum = mesh.normals[a as usize] + mesh.normals[b as usize] + mesh.normals[c as usize];
    if face.dot(normal_sum) >= 0.0 {
        mesh.triangles.push([a, b, c]);
    } else {
        mesh.triangles.push([a, c, b]);
    }
}

/// The angle of grid column `u` around an axis: the last column is the first again exactly, so
/// that the seam's vertices coincide (sin(2π) in floating point is not 0, and a ray along the
/// seam would slip through the crack).
pub(crate) fn turn(u: f32) -> f32 {
    if u >= 1.0 {
        0.0
    } else {
        u * TAU
    }
}

pub(crate) fn finish(mut mesh: Mesh) -> Mesh {
    mesh.drop_degenerate_triangles();
    mesh
}

pub(crate) fn empty(name: &str) -> Mesh {
    Mesh {
        name: name.to_string(),
        ..Default::default()
    }
}

/// Sphere of `radius` centred at the origin; `segments` around Y, `rings` from pole to pole.
pub fn sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    let mut mesh = empty("sphere");
    append_grid(&mut mesh, segments.max(3), rings.max(2), |u, v| {
        let (phi, theta) = (turn(u), v * PI);
        let n = Vec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            theta.sin() * phi.cos(),
        );
        Sample {
            p: n * radius,
            n,
            uv: Vec2::new(u, v),
        }
    });
    mesh.exact = Some(ExactSurface::new(ExactShape::Sphere {
        radius: f64::from(radius),
    }));
    finish(mesh)
}

/// A spherical-cap mirror with its apex at the origin and its reflecting side facing +Z.
///
/// `radius_of_curvature` R > 0; `aperture` is the diameter of the cap's rim (≤ 2R). A convex
/// cap bulges towards +Z (centre of curvature at (0, 0, -R)); a concave one is hollow towards
/// +Z (centre at (0, 0, +R)), so its focal point is at (0, 0, R/2).
pub fn spherical_cap(
    radius_of_curvature: f32,
    aperture: f32,
    concave: bool,
    rings: u32,
    segments: u32,
) -> Result<Mesh, SceneError> {
    let r = radius_of_curvature;
    if !(r > 0.0 && r.is_finite() && aperture > 0.0 && aperture <= 2.0 * r) {
        return Err(SceneError::invalid(
            "spherical cap",
            format!("needs radius of curvature > 0 and 0 < aperture ≤ 2R (got R = {r}, aperture = {aperture})"),
        ));
    }
    let theta_max = (aperture * 0.5 / r).asin();
    let mut mesh = empty(if concave { "concave cap" } else { "convex cap" });
    append_grid(&mut mesh, segments.max(3), rings.max(1), |u, v| {
        let (phi, theta) = (turn(u), v * theta_max);
        let radial = Vec3::new(phi.cos(), phi.sin(), 0.0) * theta.sin();
        let (p, n) = if concave {
            let center = Vec3::new(0.0, 0.0, r);
            let p = center + r * (radial - Vec3::Z * theta.cos());
            (p, (center - p) / r)
        } else {
            let center = Vec3::new(0.0, 0.0, -r);
            let p = center + r * (radial + Vec3::Z * theta.cos());
            (p, (p - center) / r)
        };
        Sample {
            p,
            n,
            uv: Vec2::new(0.5 + p.x / aperture, 0.5 - p.y / aperture),
        }
    });
    mesh.exact = Some(ExactSurface::new(ExactShape::SphericalCap {
        radius_of_curvature: f64::from(r),
        aperture: f64::from(aperture),
        concave,
    }));
    Ok(finish(mesh))
}

/// Point and exact normal of a bicubic Bézier patch, from [`crate::exact`]'s evaluation.
fn bezier_patch_sample(control: &[[DVec3; 4]; 4], u: f32, v: f32) -> (Vec3, Vec3) {
    let (u, v) = (f64::from(u), f64::from(v));
    let (p, _, _) = exact::bezier_patch(control, u, v);
    (
        p.as_vec3(),
        exact::bezier_patch_normal(control, u, v).as_vec3(),
    )
}

/// A bicubic Bézier patch tessellated into `n` × `n` quads ((n+1)² vertices); the normal is
/// Pu × Pv.
pub fn bicubic_patch(control: &[[Vec3; 4]; 4], n: u32) -> Mesh {
    let mut mesh = empty("bicubic patch");
    let control = exact::control_points(control);
    append_grid(&mut mesh, n.max(1), n.max(1), |u, v| {
        let (p, n) = bezier_patch_sample(&control, u, v);
        Sample {
            p,
            n,
            uv: Vec2::new(u, v),
        }
    });
    mesh.exact = Some(ExactSurface::new(ExactShape::BicubicPatch {
        control: Box::new(control),
    }));
    finish(mesh)
}

/// Control points of a free-form car door mirror, 0.2 m × 0.13 m, gently convex towards +Z
/// and a little asymmetric (more curvature on the outer, +X, side), like an aspheric mirror.
pub fn door_mirror_control_points() -> [[Vec3; 4]; 4] {
    let mut control = [[Vec3::ZERO; 4]; 4];
    for (j, row) in control.iter_mut().enumerate() {
        for (i, c) in row.iter_mut().enumerate() {
            let x = -0.10 + 0.2 * i as f32 / 3.0;
            // Rows climb +Y so that Pu × Pv, the patch normal, faces +Z.
            let y = -0.065 + 0.13 * j as f32 / 3.0;
            let bulge = 0.012 * (1.0 - (x / 0.1).powi(2)) + 0.008 * (1.0 - (y / 0.065).powi(2));
            let outer_wrap = if x > 0.0 { -0.10 * x * x / 0.1 } else { 0.0 };
            *c = Vec3::new(x, y, bulge + outer_wrap);
        }
    }
    control
}

/// A two-surface lens. Light is taken to travel along +Z: the front surface's vertex is at the
/// origin and the back surface's at (0, 0, `center_thickness`). Radii follow the optics sign
/// convention: positive when the centre of curvature lies on the +Z side of the vertex;
/// infinite means flat. Biconvex: front > 0, back < 0; biconcave: front < 0, back > 0;
/// meniscus: same signs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensSpec {
    pub front_radius: f32,
    pub back_radius: f32,
    pub center_thickness: f32,
    pub diameter: f32,
    /// Rings from the axis to the rim, per surface.
    pub rings: u32,
    /// Segments around the axis.
    pub segments: u32,
}

/// Sag of a spherical surface of signed radius `r` at distance `rho` from the axis, measured
/// from its vertex along +Z.
fn sag(r: f32, rho: f32) -> f32 {
    if r.is_infinite() {
        0.0
    } else {
        r - r.signum() * (r * r - rho * rho).max(0.0).sqrt()
    }
}

/// Outward unit normal of the front (faces -Z) or back (faces +Z) surface at `p`.
fn lens_surface_normal(r: f32, vertex_z: f32, p: Vec3, front: bool) -> Vec3 {
    let n = if r.is_infinite() {
        -Vec3::Z
    } else {
        (p - Vec3::new(0.0, 0.0, vertex_z + r)) / r
    };
    if front {
        n
    } else {
        -n
    }
}

pub fn lens(spec: &LensSpec) -> Result<Mesh, SceneError> {
    let LensSpec {
        front_radius: r1,
        back_radius: r2,
        center_thickness: t,
        diameter,
        rings,
        segments,
    } = *spec;
    let rim = diameter * 0.5;
    let bad = |msg: String| SceneError::invalid("lens", msg);
    if !(diameter > 0.0 && diameter.is_finite() && t > 0.0 && t.is_finite()) {
        return Err(bad(format!(
            "needs diameter > 0 and centre thickness > 0 (got {diameter}, {t})"
        )));
    }
    for (which, r) in [("front", r1), ("back", r2)] {
        if r.is_nan() || r == 0.0 || (r.is_finite() && r.abs() < rim) {
            return Err(bad(format!(
                "{which} radius {r} must be infinite (flat) or at least half the diameter ({rim})"
            )));
        }
    }
    let edge_thickness = t + sag(r2, rim) - sag(r1, rim);
    if edge_thickness <= 0.0 {
        return Err(bad(format!(
            "the surfaces cross before the rim (edge thickness {edge_thickness:.5} m): make the lens thicker or smaller"
        )));
    }
    let segments = segments.max(3);
    let rings = rings.max(1);
    let mut mesh = empty("lens");
    for (front, r, vertex_z) in [(true, r1, 0.0), (false, r2, t)] {
        append_grid(&mut mesh, segments, rings, |u, v| {
            let (phi, rho) = (turn(u), v * rim);
            let p = Vec3::new(rho * phi.cos(), rho * phi.sin(), vertex_z + sag(r, rho));
            Sample {
                p,
                n: lens_surface_normal(r, vertex_z, p, front),
                uv: Vec2::new(0.5 + p.x / diameter, 0.5 - p.y / diameter),
            }
        });
    }
    let (z_front, z_back) = (sag(r1, rim), t + sag(r2, rim));
    append_grid(&mut mesh, segments, 1, |u, v| {
        let phi = turn(u);
        let radial = Vec3::new(phi.cos(), phi.sin(), 0.0);
        Sample {
            p: radial * rim + Vec3::Z * (z_front + v * (z_back - z_front)),
            n: radial,
            uv: Vec2::new(u, v),
        }
    });
    let mut mesh = finish(mesh);
    let curvature = |r: f32| 1.0 / f64::from(r);
    mesh.exact = Some(ExactSurface::new(ExactShape::Lens(Box::new(ExactLens {
        front: LensSurface::sphere(curvature(r1), 0.0),
        back: LensSurface::sphere(curvature(r2), f64::from(t)),
        diameter: f64::from(diameter),
    }))));
    Ok(mesh)
}

/// Axis-aligned box centred at the origin with flat faces.
pub fn cuboid(size: Vec3) -> Mesh {
    let mut mesh = empty("box");
    append_box_faces(&mut mesh, size, Vec3::ZERO, false);
    finish(mesh)
}

/// The inside of a closed `size` box standing on y = 0, centred over the origin: six walls whose
/// normals point inwards, UVs in metres along each wall.
pub fn room(size: Vec3) -> Mesh {
    let mut mesh = empty("room");
    append_box_faces(&mut mesh, size, Vec3::new(0.0, size.y * 0.5, 0.0), true);
    finish(mesh)
}

/// The six faces of the `size` box around `centre`, one quad each. Outward normals and UVs
/// over [0, 1]² per face; or, seen from inside, inward normals and UVs in metres.
fn append_box_faces(mesh: &mut Mesh, size: Vec3, centre: Vec3, inside: bool) {
    let half = size * 0.5;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut outward = Vec3::ZERO;
            outward[axis] = sign;
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            let (t1, t2) = (Vec3::from_array(unit(a1)), Vec3::from_array(unit(a2)));
            let (n, uv_scale) = if inside {
                (-outward, Vec2::new(size[a1], size[a2]))
            } else {
                (outward, Vec2::ONE)
            };
            append_grid(mesh, 1, 1, |u, v| Sample {
                p: centre + (outward + t1 * (2.0 * u - 1.0) + t2 * (2.0 * v - 1.0)) * half,
                n,
                uv: Vec2::new(u, v) * uv_scale,
            });
        }
    }
}

fn unit(axis: usize) -> [f32; 3] {
    let mut a = [0.0; 3];
    a[axis] = 1.0;
    a
}

/// A `size.x` × `size.y` rectangle in the XZ plane centred at the origin, facing +Y, split into
/// `subdivisions`² quads. UV (0,0) is at (-x, -z).
pub fn plane(size: Vec2, subdivisions: u32) -> Mesh {
    let mut mesh = empty("plane");
    let n = subdivisions.max(1);
    append_grid(&mut mesh, n, n, |u, v| Sample {
        p: Vec3::new((u - 0.5) * size.x, 0.0, (v - 0.5) * size.y),
        n: Vec3::Y,
        uv: Vec2::new(u, v),
    });
    finish(mesh)
}

const TEAPOT_PATCHES: &str = include_str!("../data/teapot_patches.txt");

/// The control points of the Utah teapot's 32 Bézier patches, turned from the data's Z-up to
/// Y-up. The teapot stands on y = 0 and is 3.15 units tall.
pub fn teapot_patches() -> Vec<[[Vec3; 4]; 4]> {
    let mut points = Vec::new();
    let mut patches = Vec::new();
    for line in TEAPOT_PATCHES.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let c: Vec<f32> = words.map(|w| w.parse().expect("teapot data")).collect();
                points.push(Vec3::new(c[0], c[2], -c[1]));
            }
            Some("p") => {
                let idx: Vec<usize> = words.map(|w| w.parse().expect("teapot data")).collect();
                let mut patch = [[Vec3::ZERO; 4]; 4];
                for (k, &i) in idx.iter().enumerate() {
                    patch[k / 4][k % 4] = points[i - 1];
                }
                patches.push(patch);
            }
            _ => {}
        }
    }
    patches
}

/// The Utah teapot from its Bézier patch data, each patch cut into `n` × `n` quads.
pub fn teapot(n: u32) -> Mesh {
    let mut mesh = empty("teapot");
    for control in teapot_patches() {
        let control = exact::control_points(&control);
        append_grid(&mut mesh, n.max(1), n.max(1), |u, v| {
            let (p, n) = bezier_patch_sample(&control, u, v);
            Sample {
                p,
                n,
                uv: Vec2::new(u, v),
            }
        });
    }
    finish(mesh)
}
