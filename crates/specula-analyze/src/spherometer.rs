//! A mirror's curvature as the standards measure it with a spherometer: the radii of the normal
//! sections at a point along two perpendicular directions, on the surface itself rather than its
//! facets, each with the uncertainty of its measurement.
//!
//! - On an exact surface ([`crate::mirror_surface::SurfaceModel::Exact`]) the shape operator
//!   comes from the change of the exact normal over a small step (dn = −S dp in the tangent
//!   plane); its uncertainty is its change to twice that step (truncation) and to half of it
//!   (rounding).
//! - On a mesh, vertices are first welded by position (a file with flat normals stores each
//!   triangle's corners apart), and at the point a quadratic height field
//!   z = a x² + b xy + c y² + d x + e y + f is fitted by least squares, in the frame of the
//!   point's normal, to the positions of the vertices around it and, where the file's normals
//!   are one per welded vertex (smooth shading), to the slopes those normals give. The fit
//!   over the 1-ring of the point's triangle is the measurement, each row weighted by its own
//!   rounding (an f32's unit in the last place / √12: heights from positions, slopes from
//!   normals). Its uncertainty: its truncation error, which grows as the square of the
//!   neighbourhood's size ρ, estimated from its change to the fit over the 2-ring as that change
//!   × ρ1² / (ρ2² − ρ1²) (Richardson), plus its standard error, from the rounding, or from the
//!   residuals where they show more than the rounding (normals computed from faces, a surface
//!   the quadric does not follow). Such a fit
//!   does not see the facets: a tessellated sphere reads its radius, not its triangles'.
//!
//! Curvatures are signed convex-positive: positive where the surface bulges towards the
//! `facing` side (the eyes'), so a convex mirror's radii are positive and a concave one's
//! negative.
//!
//! [`Probe`] also locates surface points by their position in the mirror's plane (the plane
//! through its centre perpendicular to its mean normal, axes horizontal and up), where the
//! standards lay out their arcs, rectangles and segments.

use std::collections::HashMap;

use glam::{DMat2, DVec2, DVec3, Vec2, Vec3};

use crate::mirror_surface::MirrorSurface;

/// A curvature with its uncertainty, 1/m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    /// Convex-positive normal curvature, 1/m.
    pub value: f64,
    pub uncertainty: f64,
}

impl Curvature {
    /// Its radius in metres (infinite where the curvature is zero) and that radius's
    /// uncertainty (infinite where the curvature's interval holds zero).
    pub fn radius(self) -> (f64, f64) {
        let r = if self.value == 0.0 {
            f64::INFINITY
        } else {
            1.0 / self.value
        };
        let u = if self.value.abs() <= self.uncertainty {
            f64::INFINITY
        } else {
            // The interval [1/(k + u), 1/(k − u)]'s half-width, bounded by its larger side.
            1.0 / (self.value.abs() - self.uncertainty) - 1.0 / self.value.abs()
        };
        (r, u)
    }

    /// Whether no curvature can be told from zero (the interval holds zero).
    pub fn is_flat(self) -> bool {
        self.value.abs() <= self.uncertainty
    }
}

/// The plane the mirror's layout is measured in.
#[derive(Clone, Copy, Debug)]
pub struct MirrorPlane {
    pub centre: DVec3,
    /// Horizontal in the plane (perpendicular to the vehicle's up), and the plane's up.
    pub h: DVec3,
    pub v: DVec3,
    /// The mean normal, towards the facing side.
    pub n: DVec3,
}

impl MirrorPlane {
    pub fn project(&self, p: DVec3) -> DVec2 {
        let d = p - self.centre;
        DVec2::new(d.dot(self.h), d.dot(self.v))
    }
}

/// The local shape at a point: where it is, its normal towards the facing side, and the
/// normal curvature along any tangent direction.
#[derive(Clone, Copy, Debug)]
pub struct LocalShape {
    pub p: DVec3,
    pub n: DVec3,
    shape: Shape,
}

#[derive(Clone, Copy, Debug)]
enum Shape {
    /// Convex-positive shape operator in the orthonormal tangent frame (e1, e2), and its
    /// uncertainty (a bound on each entry's error).
    Operator {
        e1: DVec3,
        e2: DVec3,
        s: DMat2,
        uncertainty: f64,
    },
    /// A height field over the frame (x, y, n): its first and second fundamental forms at the
    /// origin, convex-positive, and the curvature's uncertainty for unit directions.
    Graph {
        x: DVec3,
        y: DVec3,
        first: DMat2,
        second: DMat2,
        uncertainty: [f64; 3],
    },
}

impl LocalShape {
    /// The normal curvature along `direction` (projected into the tangent plane).
    pub fn curvature_along(&self, direction: DVec3) -> Option<Curvature> {
        let t = (direction - self.n * direction.dot(self.n)).try_normalize()?;
        Some(match self.shape {
            Shape::Operator {
                e1,
                e2,
                s,
                uncertainty,
            } => {
                let u = DVec2::new(t.dot(e1), t.dot(e2));
                Curvature {
                    value: u.dot(s * u),
                    uncertainty,
                }
            }
            Shape::Graph {
                x,
                y,
                first,
                second,
                uncertainty,
            } => {
                let u = DVec2::new(t.dot(x), t.dot(y));
                let norm = u.dot(first * u);
                // The coefficients' uncertainties (a, b, c) weigh in by u_x², u_x u_y, u_y².
                let du = (uncertainty[0] * u.x * u.x
                    + uncertainty[1] * (u.x * u.y).abs()
                    + uncertainty[2] * u.y * u.y)
                    / norm;
                Curvature {
                    value: u.dot(second * u) / norm,
                    uncertainty: du,
                }
            }
        })
    }
}

/// The mirror measured: its plane, its cells laid in it, and what its curvature comes from.
pub struct Probe<'s, 'a> {
    surface: &'s MirrorSurface<'a>,
    pub plane: MirrorPlane,
    /// Each cell's corners in the plane, mm, and the cells binned by a uniform grid.
    flat: Vec<[DVec2; 3]>,
    bins: Bins,
    fit: Option<MeshFit>,
}

impl<'s, 'a> Probe<'s, 'a> {
    /// The probe of `surface`, its plane horizontal along `up` × normal, its normal turned
    /// towards `facing` (a point on the reflecting side, e.g. the eyes).
    pub fn new(surface: &'s MirrorSurface<'a>, up: Vec3, facing: Vec3) -> Probe<'s, 'a> {
        let mut triangles = Vec::with_capacity(surface.cells());
        let (mut normal, mut centre, mut area) = (DVec3::ZERO, DVec3::ZERO, 0.0);
        for cell in 0..surface.cells() {
            let p = [0, 1, 2].map(|k| surface.corner(cell, k));
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            normal += n;
            let a = 0.5 * n.length();
            centre += (p[0] + p[1] + p[2]) / 3.0 * a;
            area += a;
            triangles.push(p);
        }
        let centre = centre / area.max(1e-30);
        let mut n = normal.normalize_or_zero();
        if n.dot(facing.as_dvec3() - centre) < 0.0 {
            n = -n;
        }
        let h = up
            .as_dvec3()
            .cross(n)
            .try_normalize()
            .unwrap_or_else(|| n.any_orthonormal_vector());
        let v = n.cross(h);
        let plane = MirrorPlane { centre, h, v, n };
        let flat: Vec<[DVec2; 3]> = triangles
            .iter()
            .map(|t| t.map(|p| plane.project(p) * 1e3))
            .collect();
        let bins = Bins::new(&flat);
        let fit = surface.mesh().map(MeshFit::new);
        Probe {
            surface,
            plane,
            flat,
            bins,
            fit,
        }
    }

    /// The cells laid in the plane, mm.
    pub fn flat_cells(&self) -> &[[DVec2; 3]] {
        &self.flat
    }

    /// The cell and barycentric coordinates over plane point `q_mm`.
    pub fn locate(&self, q_mm: DVec2) -> Option<(usize, Vec2)> {
        self.bins.candidates(q_mm).find_map(|&cell| {
            let [a, b, c] = self.flat[cell];
            let m = DMat2::from_cols(b - a, c - a);
            if m.determinant().abs() < 1e-18 {
                return None;
            }
            let w = m.inverse() * (q_mm - a);
            let eps = -1e-9;
            (w.x >= eps && w.y >= eps && w.x + w.y <= 1.0 - eps)
                .then(|| (cell, w.as_vec2().clamp(Vec2::ZERO, Vec2::ONE)))
        })
    }

    /// The surface point over plane point `q_mm`.
    pub fn point(&self, q_mm: DVec2) -> Option<DVec3> {
        let (cell, b) = self.locate(q_mm)?;
        Some(self.surface.position(cell, b).as_dvec3())
    }

    /// The local shape over plane point `q_mm`.
    pub fn shape(&self, q_mm: DVec2) -> Option<LocalShape> {
        let (cell, b) = self.locate(q_mm)?;
        match &self.fit {
            Some(fit) => fit.shape(self.surface, cell, b, self.plane.n),
            None => self.exact_shape(cell, b),
        }
    }

    /// The shape operator from the exact normal's change over central differences of step h
    /// in the surface's own parameters, its uncertainty its changes to steps 2h (truncation)
    /// and h/2 (rounding).
    fn exact_shape(&self, cell: usize, b: Vec2) -> Option<LocalShape> {
        let MirrorSurface::Exact(exact) = self.surface else {
            return None;
        };
        let h = 1e-4;
        let uv = MirrorSurface::exact_uv(cell, b)
            .clamp(DVec2::splat(2.0 * h), DVec2::splat(1.0 - 2.0 * h));
        let at = |uv: DVec2| {
            let s = exact.at(uv);
            let n = if s.n_world.dot(self.plane.n) < 0.0 {
                -s.n_world
            } else {
                s.n_world
            };
            (s.p_world, n)
        };
        let (p, n) = at(uv);
        let e1 = (at(uv + DVec2::new(h, 0.0)).0 - at(uv - DVec2::new(h, 0.0)).0)
            .reject_from(n)
            .try_normalize()?;
        let e2 = n.cross(e1);
        let in_plane = |v: DVec3| DVec2::new(v.dot(e1), v.dot(e2));
        let operator = |step: f64| -> Option<DMat2> {
            let difference = |d: DVec2| {
                let ((p1, n1), (p0, n0)) = (at(uv + d), at(uv - d));
                (in_plane(p1 - p0), in_plane(n1 - n0))
            };
            let (dp_u, dn_u) = difference(DVec2::new(step, 0.0));
            let (dp_v, dn_v) = difference(DVec2::new(0.0, step));
            let dp = DMat2::from_cols(dp_u, dp_v);
            let dn = DMat2::from_cols(dn_u, dn_v);
            (dp.determinant().abs() > 1e-30).then(|| {
                // dn = −S dp with n towards the facing side; convex-positive is −S.
                let s = dn * dp.inverse();
                let off = 0.5 * (s.x_axis.y + s.y_axis.x);
                DMat2::from_cols(DVec2::new(s.x_axis.x, off), DVec2::new(off, s.y_axis.y))
            })
        };
        let (fine, coarse, finer) = (operator(h)?, operator(2.0 * h)?, operator(0.5 * h)?);
        let largest = |m: DMat2| {
            [m.x_axis, m.y_axis]
                .iter()
                .map(|c| c.x.abs().max(c.y.abs()))
                .fold(0.0, f64::max)
        };
        Some(LocalShape {
            p,
            n,
            shape: Shape::Operator {
                e1,
                e2,
                s: fine,
                uncertainty: largest(fine - coarse) + largest(fine - finer),
            },
        })
    }
}

/// A uniform grid of bins over the cells' bounds in the plane.
struct Bins {
    lo: DVec2,
    size: DVec2,
    count: [usize; 2],
    cells: Vec<Vec<usize>>,
}

impl Bins {
    fn new(flat: &[[DVec2; 3]]) -> Bins {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in flat.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let side = ((flat.len() as f64).sqrt().ceil() as usize).clamp(1, 256);
        let size = ((hi - lo) / side as f64).max(DVec2::splat(1e-9));
        let mut cells = vec![Vec::new(); side * side];
        for (k, t) in flat.iter().enumerate() {
            let a = (t[0].min(t[1]).min(t[2]) - lo) / size;
            let b = (t[0].max(t[1]).max(t[2]) - lo) / size;
            let clamp = |x: f64| (x.floor().max(0.0) as usize).min(side - 1);
            for j in clamp(a.y)..=clamp(b.y) {
                for i in clamp(a.x)..=clamp(b.x) {
                    cells[j * side + i].push(k);
                }
            }
        }
        Bins {
            lo,
            size,
            count: [side, side],
            cells,
        }
    }

    fn candidates(&self, q: DVec2) -> std::slice::Iter<'_, usize> {
        let g = (q - self.lo) / self.size;
        // A point on the bounds' far edge belongs to the last bin.
        let bin = |g: f64, count: usize| {
            let last = count as f64;
            if (last..=last + 1e-9).contains(&g) {
                last - 1.0
            } else {
                g.floor()
            }
        };
        let c = DVec2::new(bin(g.x, self.count[0]), bin(g.y, self.count[1]));
        let inside = c.x >= 0.0
            && c.y >= 0.0
            && (c.x as usize) < self.count[0]
            && (c.y as usize) < self.count[1];
        if inside {
            self.cells[c.y as usize * self.count[0] + c.x as usize].iter()
        } else {
            [].iter()
        }
    }
}

/// A mesh welded by position, ready for local fits.
struct MeshFit {
    positions: Vec<DVec3>,
    /// One normal per welded vertex, where the file's normals agree at every welded vertex
    /// (smooth shading); None where they do not (flat shading: the normals are the facets').
    normals: Option<Vec<DVec3>>,
    /// Each mesh vertex's welded index.
    welded: Vec<usize>,
    neighbours: Vec<Vec<usize>>,
}

impl MeshFit {
    fn new(mesh: &specula_scene::Mesh) -> MeshFit {
        let mut index: HashMap<[u32; 3], usize> = HashMap::new();
        let mut positions = Vec::new();
        let mut normal_sets: Vec<Vec<Vec3>> = Vec::new();
        let welded: Vec<usize> = mesh
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let key = p.to_array().map(f32::to_bits);
                let k = *index.entry(key).or_insert_with(|| {
                    positions.push(p.as_dvec3());
                    normal_sets.push(Vec::new());
                    positions.len() - 1
                });
                if let Some(n) = mesh.normals.get(i) {
                    normal_sets[k].push(*n);
                }
                k
            })
            .collect();
        let smooth = normal_sets.iter().all(|set| {
            !set.is_empty()
                && set[0].length() > 0.5
                && set
                    .iter()
                    .all(|n| n.normalize_or_zero().dot(set[0].normalize()) > 0.999_999)
        });
        let normals = smooth.then(|| {
            normal_sets
                .iter()
                .map(|set| set[0].as_dvec3().normalize())
                .collect()
        });
        let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); positions.len()];
        for t in &mesh.triangles {
            let w = t.map(|i| welded[i as usize]);
            for &a in &w {
                for &b in &w {
                    if a != b && !neighbours[a].contains(&b) {
                        neighbours[a].push(b);
                    }
                }
            }
        }
        MeshFit {
            positions,
            normals,
            welded,
            neighbours,
        }
    }

    /// The vertices within `rings` edges of `seeds`.
    fn rings(&self, seeds: &[usize], rings: usize) -> Vec<usize> {
        let mut set: Vec<usize> = seeds.to_vec();
        let mut frontier = set.clone();
        for _ in 0..rings {
            let mut next = Vec::new();
            for &v in &frontier {
                for &w in &self.neighbours[v] {
                    if !set.contains(&w) {
                        set.push(w);
                        next.push(w);
                    }
                }
            }
            frontier = next;
        }
        set
    }

    /// The shape at barycentric `b` of triangle `cell`: the 1-ring fit, its uncertainty its
    /// truncation error (from its change to the 2-ring fit) plus its standard error.
    fn shape(
        &self,
        surface: &MirrorSurface,
        cell: usize,
        b: Vec2,
        facing: DVec3,
    ) -> Option<LocalShape> {
        let mesh = surface.mesh()?;
        let corners = mesh.triangles[cell].map(|i| self.welded[i as usize]);
        let [p0, p1, p2] = corners.map(|k| self.positions[k]);
        let (b1, b2) = (f64::from(b.x), f64::from(b.y));
        let origin = p0 * (1.0 - b1 - b2) + p1 * b1 + p2 * b2;
        let face = (p1 - p0).cross(p2 - p0).try_normalize()?;
        let n = match &self.normals {
            Some(normals) => {
                let [n0, n1, n2] = corners.map(|k| normals[k]);
                (n0 * (1.0 - b1 - b2) + n1 * b1 + n2 * b2)
                    .try_normalize()
                    .unwrap_or(face)
            }
            None => face,
        };
        let n = if n.dot(facing) < 0.0 { -n } else { n };
        let x = (p1 - p0).reject_from(n).try_normalize()?;
        let y = n.cross(x);
        let near = self.fit(&self.rings(&corners, 1), origin, x, y, n)?;
        let far = self.fit(&self.rings(&corners, 2), origin, x, y, n)?;
        // A fit's truncation error grows as the square of its neighbourhood's size: the 1-ring
        // fit's is its change to the 2-ring fit times ρ1² / (ρ2² − ρ1²) (Richardson).
        let share = near.spread2 / (far.spread2 - near.spread2).max(1e-30);
        let uncertainty =
            [0, 1, 2].map(|k| (near.c[k] - far.c[k]).abs() * share.min(1.0) + near.se[k]);
        // At the origin: gradient (d, e), Hessian [[2a, b], [b, 2c]]; z = height along n, so a
        // surface bulging towards n (convex) has a negative Hessian: convex-positive is −II.
        let (a, bb, c, d, e) = (near.c[0], near.c[1], near.c[2], near.c[3], near.c[4]);
        let first = DMat2::from_cols(
            DVec2::new(1.0 + d * d, d * e),
            DVec2::new(d * e, 1.0 + e * e),
        );
        let scale = 1.0 / (1.0 + d * d + e * e).sqrt();
        let second = DMat2::from_cols(DVec2::new(2.0 * a, bb), DVec2::new(bb, 2.0 * c)) * -scale;
        // The coefficients' uncertainties carry the same factors (2 on a and c).
        let uncertainty = [
            2.0 * uncertainty[0] * scale,
            2.0 * uncertainty[1] * scale,
            2.0 * uncertainty[2] * scale,
        ];
        let normal = (n - x * d - y * e).normalize();
        Some(LocalShape {
            p: origin + n * near.c[5],
            n: normal,
            shape: Shape::Graph {
                x,
                y,
                first,
                second,
                uncertainty,
            },
        })
    }

    /// The least-squares height field over `vertices` in the frame (x, y, n) at `origin`:
    /// heights from positions, slopes from normals where they are smooth.
    fn fit(&self, vertices: &[usize], origin: DVec3, x: DVec3, y: DVec3, n: DVec3) -> Option<Fit> {
        let reach = vertices
            .iter()
            .map(|&k| (self.positions[k] - origin).length())
            .fold(0.0, f64::max)
            .max(1e-9);
        // Each row weighted by its rounding: an f32 rounded to the nearest carries a uniform
        // error of a unit in its last place / √12 (heights here in units of the reach; slopes
        // from normals whose components are at most 1).
        let rounding = |x: f64| f32_ulp(x) / 12f64.sqrt();
        let mut rows: Vec<([f64; 6], f64)> = Vec::new();
        let mut weighted = |a: [f64; 6], y: f64, sigma: f64| {
            rows.push((a.map(|a| a / sigma), y / sigma));
        };
        for &k in vertices {
            let p = self.positions[k];
            let d = p - origin;
            let (u, v, z) = (d.dot(x) / reach, d.dot(y) / reach, d.dot(n) / reach);
            let height_sigma = rounding(p.abs().max_element().max(reach)) / reach;
            weighted([u * u, u * v, v * v, u, v, 1.0], z, height_sigma);
            if let Some(normals) = &self.normals {
                let m = normals[k];
                let mz = m.dot(n);
                if mz.abs() > 1e-6 {
                    let slope_sigma = rounding(1.0) / mz.abs();
                    weighted(
                        [2.0 * u, v, 0.0, 1.0, 0.0, 0.0],
                        -m.dot(x) / mz,
                        slope_sigma,
                    );
                    weighted(
                        [0.0, u, 2.0 * v, 0.0, 1.0, 0.0],
                        -m.dot(y) / mz,
                        slope_sigma,
                    );
                }
            }
        }
        let (c, se) = least_squares(&rows)?;
        let spread2 = vertices
            .iter()
            .map(|&k| (self.positions[k] - origin).length_squared())
            .sum::<f64>()
            / vertices.len() as f64;
        // Back from the unit reach: z/L = a (x/L)² + ... so a_metres = a / L, d unchanged,
        // f_metres = f L.
        let per_length = [1.0 / reach, 1.0 / reach, 1.0 / reach, 1.0, 1.0, reach];
        Some(Fit {
            c: [0, 1, 2, 3, 4, 5].map(|k| c[k] * per_length[k]),
            se: [0, 1, 2, 3, 4, 5].map(|k| se[k] * per_length[k]),
            spread2,
        })
    }
}

/// The spacing of f32 values at `x`'s size.
fn f32_ulp(x: f64) -> f64 {
    let x = (x.abs() as f32).max(f32::MIN_POSITIVE);
    f64::from(f32::from_bits(x.to_bits() + 1) - x)
}

struct Fit {
    c: [f64; 6],
    se: [f64; 6],
    /// The mean squared distance of the fit's vertices from its origin, m².
    spread2: f64,
}

/// The least-squares solution of `rows` and each coefficient's standard error (from the
/// residuals' variance); None when the system is singular or has no spare rows.
fn least_squares(rows: &[([f64; 6], f64)]) -> Option<([f64; 6], [f64; 6])> {
    if rows.len() <= 6 {
        return None;
    }
    let (ata, aty) = normal_equations(rows);
    let inverse = invert6(&ata)?;
    let mut c = [0.0f64; 6];
    for i in 0..6 {
        c[i] = (0..6).map(|j| inverse[i][j] * aty[j]).sum();
    }
    let residual: f64 = rows
        .iter()
        .map(|(a, y)| {
            let fit: f64 = (0..6).map(|k| a[k] * c[k]).sum();
            (fit - y).powi(2)
        })
        .sum();
    // Rows weighted by their rounding: a reduced χ² of 1 is rounding alone; more is what the
    // data show beyond it (a surface the quadric does not follow, normals computed from faces).
    let variance = (residual / (rows.len() - 6) as f64).max(1.0);
    let se = [0, 1, 2, 3, 4, 5].map(|k| (variance * inverse[k][k].max(0.0)).sqrt());
    Some((c, se))
}

/// The normal equations AᵀA c = Aᵀy of the rows' system A c = y.
pub(crate) fn normal_equations(rows: &[([f64; 6], f64)]) -> ([[f64; 6]; 6], [f64; 6]) {
    let mut ata = [[0.0f64; 6]; 6];
    let mut aty = [0.0f64; 6];
    for (a, y) in rows {
        for i in 0..6 {
            aty[i] += a[i] * y;
            for j in 0..6 {
                ata[i][j] += a[i] * a[j];
            }
        }
    }
    (ata, aty)
}

/// The inverse of a symmetric 6 × 6 matrix by Gauss–Jordan elimination with partial pivoting.
fn invert6(m: &[[f64; 6]; 6]) -> Option<[[f64; 6]; 6]> {
    let mut a = *m;
    let mut inv = [[0.0f64; 6]; 6];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let scale = (0..6).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    for col in 0..6 {
        let pivot = (col..6).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[pivot][col].abs() <= 1e-13 * scale {
            return None;
        }
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let p = a[col][col];
        for k in 0..6 {
            a[col][k] /= p;
            inv[col][k] /= p;
        }
        for r in 0..6 {
            if r != col {
                let f = a[r][col];
                for k in 0..6 {
                    a[r][k] -= f * a[col][k];
                    inv[r][k] -= f * inv[col][k];
                }
            }
        }
    }
    Some(inv)
}
