//! The tessellation of a face that truck's could not make: a (u, v) grid over the face's
//! trimming loops, fine enough that no cell's middle strays from its corners' plane by more
//! than the tolerance, keeping the triangles whose middles lie inside the loops (even-odd
//! rule). Its rim is stepped (a cell wide at most) where truck's follows the trimming curves;
//! the reader says so in a warning naming the face.

use glam::DVec2;
use truck_stepio::r#in::alias::{
    BoundedCurve, ParametricSurface, Point3, PolylineCurve, SearchNearestParameter, SearchParameter,
};
use truck_stepio::r#in::alias::{Curve3D, Surface};
use truck_topology::compress::CompressedEdge;

use super::tessellate::FacePolygon;

/// The face of `surface` bounded by `boundaries` (each a loop of edges with their sense),
/// gridded to `tolerance`; `None` where a loop's point cannot be placed on the surface.
pub(super) fn grid_polygon(
    surface: &Surface,
    edges: &[CompressedEdge<Curve3D>],
    boundaries: &[Vec<(usize, bool)>],
    tolerance: f64,
) -> Option<FacePolygon> {
    let loops: Vec<Vec<DVec2>> = boundaries
        .iter()
        .map(|boundary| loop_in_uv(surface, edges, boundary, tolerance))
        .collect::<Option<_>>()?;
    let (min, max) = loops.iter().flatten().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    if !(min.is_finite() && max.is_finite()) || (max - min).min_element() <= 0.0 {
        return None;
    }
    let cells = cells_for(surface, min, max, tolerance);
    let at = |i: usize, j: usize| {
        min + (max - min) * DVec2::new(i as f64 / cells as f64, j as f64 / cells as f64)
    };
    let index = |i: usize, j: usize| (i * (cells + 1) + j) as u32;
    let uv: Vec<DVec2> = (0..=cells)
        .flat_map(|i| (0..=cells).map(move |j| at(i, j)))
        .collect();
    let mut triangles = Vec::new();
    for i in 0..cells {
        for j in 0..cells {
            for triangle in [
                [index(i, j), index(i + 1, j), index(i + 1, j + 1)],
                [index(i, j), index(i + 1, j + 1), index(i, j + 1)],
            ] {
                let middle = triangle.iter().map(|&k| uv[k as usize]).sum::<DVec2>() / 3.0;
                if inside(&loops, middle) {
                    triangles.push(triangle);
                }
            }
        }
    }
    Some(FacePolygon { uv, triangles })
}

/// A loop's edges cut to the tolerance and placed on the surface, unwrapped across a periodic
/// surface's seam so that the polygon closes in (u, v).
fn loop_in_uv(
    surface: &Surface,
    edges: &[CompressedEdge<Curve3D>],
    boundary: &[(usize, bool)],
    tolerance: f64,
) -> Option<Vec<DVec2>> {
    let mut points: Vec<Point3> = Vec::new();
    for &(edge, forward) in boundary {
        let curve = &edges.get(edge)?.curve;
        let mut polyline = PolylineCurve::from_curve(curve, curve.range_tuple(), tolerance).0;
        if !forward {
            polyline.reverse();
        }
        points.extend(polyline.into_iter().skip(usize::from(!points.is_empty())));
    }
    let (u_period, v_period) = (surface.u_period(), surface.v_period());
    let mut previous: Option<(f64, f64)> = None;
    let mut uv = Vec::with_capacity(points.len());
    for p in points {
        let (mut u, mut v) =
            SearchParameter::search_parameter(surface, p, previous, 100).or_else(|| {
                SearchNearestParameter::search_nearest_parameter(surface, p, previous, 100)
            })?;
        if let Some((u0, v0)) = previous {
            if let Some(period) = u_period {
                u -= ((u - u0) / period).round() * period;
            }
            if let Some(period) = v_period {
                v -= ((v - v0) / period).round() * period;
            }
        }
        previous = Some((u, v));
        uv.push(DVec2::new(u, v));
    }
    (uv.len() >= 3).then_some(uv)
}

/// Cells per side: doubled from 8 until every cell's middle is within `tolerance` of the
/// average of its corners (a bilinear cell's chord error), at most 512.
fn cells_for(surface: &Surface, min: DVec2, max: DVec2, tolerance: f64) -> usize {
    let point = |uv: DVec2| {
        let p = surface.subs(uv.x, uv.y);
        glam::DVec3::new(p.x, p.y, p.z)
    };
    let mut cells = 8;
    while cells < 512 {
        let step = (max - min) / cells as f64;
        let worst = (0..cells)
            .flat_map(|i| (0..cells).map(move |j| min + step * DVec2::new(i as f64, j as f64)))
            .map(|corner| {
                let corners = [DVec2::ZERO, DVec2::X, DVec2::Y, DVec2::ONE]
                    .map(|d| point(corner + step * d))
                    .iter()
                    .sum::<glam::DVec3>()
                    / 4.0;
                (point(corner + step * 0.5) - corners).length()
            })
            .fold(0.0, f64::max);
        if worst <= tolerance {
            break;
        }
        cells *= 2;
    }
    cells
}

/// Even-odd: inside the outer loop and outside every hole.
fn inside(loops: &[Vec<DVec2>], p: DVec2) -> bool {
    let mut crossings = 0;
    for polygon in loops {
        for k in 0..polygon.len() {
            let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                crossings += 1;
            }
        }
    }
    crossings % 2 == 1
}
