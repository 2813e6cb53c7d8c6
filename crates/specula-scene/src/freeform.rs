//! Free-form lens surfaces: a sag s(x, y) that is neither a sphere nor a torus, for
//! [`crate::exact_lens::LensSurface`] to trace exactly (Newton on the height field).
//!
//! **Frame and units** (the lens's own, [`crate::exact_lens`]): x to the wearer's right, y up,
//! the sag along the lens axis, positive towards the eye (+Z), measured from the surface's
//! vertex. Files give millimetres; everything here is in metres.
//!
//! **Kinds.**
//! - [`SagGrid`]: sampled sags (a CSV file, below), interpolated by the tensor-product cubic
//!   spline with not-a-knot ends: C² in x and in y, so the curvature is continuous; a cubic
//!   in x and y is reproduced exactly.
//! - [`Polynomial`]: s = Σ c_ij x^i y^j, x, y and s in millimetres.
//! - [`Progressive`]: a progressive addition surface built in code: a far sphere plus an
//!   addition whose mean curvature rises along an umbilic corridor (its doc).
//!
//! **The CSV.** The first row holds the x values in mm, increasing (its first cell is a label
//! and ignored); each further row starts with its y value in mm, increasing down the file,
//! then one sag in mm per x. Refused, naming the row and column (1-based, as a spreadsheet
//! numbers them): a missing or unreadable cell, a value that is not finite, an axis that does
//! not increase, fewer than 4 values on an axis, a sag at (0, 0) that is not 0. A grid coarse
//! for its curvature loads: at each node the sag's fourth differences estimate how far the
//! interpolated curvature may be off (the spline's second derivative errs by about
//! h² |s''''| / 12), and [`SagGrid::curvature_uncertainty`] carries that into every figure that
//! uses the surface there; regions uncertain by more than [`MAX_CURVATURE_ERROR`] are the ones a
//! report marks.

use std::sync::Arc;

use glam::DVec2;

use crate::SceneError;

/// The sag, its gradient (∂s/∂x, ∂s/∂y) and Hessian [s_xx, s_xy, s_yy] at a point, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Local {
    pub sag: f64,
    pub gradient: DVec2,
    pub hessian: [f64; 3],
}

impl Local {
    /// The principal curvatures of the height field (larger first), 1 / metres, positive when
    /// the centre of curvature lies towards +Z: the eigenvalues of the shape operator
    /// I⁻¹ II with I = 1 + ∇s ∇sᵀ and II = Hessian / √(1 + |∇s|²).
    pub fn principal_curvatures(&self) -> [f64; 2] {
        let (p, q) = (self.gradient.x, self.gradient.y);
        let w = (1.0 + p * p + q * q).sqrt();
        let [l, m, n] = self.hessian.map(|h| h / w);
        let (e, f, g) = (1.0 + p * p, p * q, 1.0 + q * q);
        let det = e * g - f * f;
        let mean = (e * n - 2.0 * f * m + g * l) / (2.0 * det);
        let gauss = (l * n - m * m) / det;
        let spread = (mean * mean - gauss).max(0.0).sqrt();
        [mean + spread, mean - spread]
    }
}

/// A sag grid's interpolated curvature uncertain by more than this, 1 / metres (0.024 D of
/// surface power at n = 1.6: a fifth of the standards' tightest tolerance, 0.12 D), is what a
/// report marks as a region the grid is too coarse for.
pub const MAX_CURVATURE_ERROR: f64 = 0.04;

/// A free-form surface (module doc).
#[derive(Clone, Debug, PartialEq)]
pub enum Freeform {
    SagGrid(Arc<SagGrid>),
    Polynomial(Polynomial),
    Progressive(Progressive),
}

impl Freeform {
    /// The sag and its derivatives at (x, y), metres; None outside a grid.
    pub fn local(&self, x: f64, y: f64) -> Option<Local> {
        match self {
            Freeform::SagGrid(grid) => grid.local(x, y),
            Freeform::Polynomial(p) => p.local(x, y),
            Freeform::Progressive(p) => p.local(x, y),
        }
    }

    /// How far the surface's curvature at (x, y) may be off, 1 / metres: a sag grid's
    /// interpolation error there (0 for the surfaces defined in closed form).
    pub fn curvature_uncertainty(&self, x: f64, y: f64) -> f64 {
        match self {
            Freeform::SagGrid(grid) => grid.curvature_uncertainty(x, y).unwrap_or(0.0),
            _ => 0.0,
        }
    }

    /// Where the surface is defined (a grid's extent), metres: [x0, x1] × [y0, y1].
    pub fn extent(&self) -> Option<[[f64; 2]; 2]> {
        match self {
            Freeform::SagGrid(grid) => Some([
                [grid.xs[0], *grid.xs.last().expect("checked")],
                [grid.ys[0], *grid.ys.last().expect("checked")],
            ]),
            _ => None,
        }
    }

    /// What the surface is, for messages and reports.
    pub fn describe(&self) -> String {
        match self {
            Freeform::SagGrid(grid) => format!(
                "sag grid '{}' ({} × {})",
                grid.source,
                grid.xs.len(),
                grid.ys.len()
            ),
            Freeform::Polynomial(p) => format!("polynomial of {} terms", p.terms.len()),
            Freeform::Progressive(p) => format!(
                "progressive: add {:.2} D at n {}, corridor {:.1} mm",
                p.add_d,
                p.index,
                p.corridor_length * 1e3
            ),
        }
    }
}

/// One axis's spline second derivatives M of the values `f` at the increasing nodes `x`
/// (at least 4), with not-a-knot ends (the third derivative continuous at the second and the
/// last but one node).
fn spline_second_derivatives(x: &[f64], f: &[f64]) -> Vec<f64> {
    let n = x.len() - 1;
    let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    // The interior equations on M_1 .. M_{n−1}, with M_0 and M_n eliminated by the
    // not-a-knot conditions.
    let m = n - 1;
    let (mut sub, mut diag, mut sup, mut rhs) =
        (vec![0.0; m], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    for k in 0..m {
        let i = k + 1;
        sub[k] = h[i - 1];
        diag[k] = 2.0 * (h[i - 1] + h[i]);
        sup[k] = h[i];
        rhs[k] = 6.0 * ((f[i + 1] - f[i]) / h[i] - (f[i] - f[i - 1]) / h[i - 1]);
    }
    let (h0, h1) = (h[0], h[1]);
    diag[0] += h0 * (1.0 + h0 / h1);
    sup[0] -= h0 * h0 / h1;
    let (hl, hp) = (h[n - 1], h[n - 2]);
    diag[m - 1] += hl * (1.0 + hl / hp);
    sub[m - 1] -= hl * hl / hp;
    // Thomas's algorithm.
    for k in 1..m {
        let w = sub[k] / diag[k - 1];
        diag[k] -= w * sup[k - 1];
        rhs[k] -= w * rhs[k - 1];
    }
    let mut inner = vec![0.0; m];
    inner[m - 1] = rhs[m - 1] / diag[m - 1];
    for k in (0..m - 1).rev() {
        inner[k] = (rhs[k] - sup[k] * inner[k + 1]) / diag[k];
    }
    let first = (1.0 + h0 / h1) * inner[0] - h0 / h1 * inner[1.min(m - 1)];
    let last = (1.0 + hl / hp) * inner[m - 1] - hl / hp * inner[m.saturating_sub(2)];
    let mut all = Vec::with_capacity(n + 1);
    all.push(first);
    all.extend(inner);
    all.push(last);
    all
}

/// The cubic spline's basis on one interval at `t`: the weights of the two values and the two
/// second derivatives, and their first and second derivatives by the coordinate.
fn basis(nodes: &[f64], t: f64) -> Option<(usize, [[f64; 4]; 3])> {
    let (first, last) = (nodes[0], *nodes.last()?);
    if !(first..=last).contains(&t) {
        return None;
    }
    let i = nodes.partition_point(|&x| x <= t).clamp(1, nodes.len() - 1) - 1;
    let h = nodes[i + 1] - nodes[i];
    let a = (nodes[i + 1] - t) / h;
    let b = 1.0 - a;
    let h2 = h * h / 6.0;
    Some((
        i,
        [
            [a, b, (a * a * a - a) * h2, (b * b * b - b) * h2],
            [
                -1.0 / h,
                1.0 / h,
                -(3.0 * a * a - 1.0) * h / 6.0,
                (3.0 * b * b - 1.0) * h / 6.0,
            ],
            [0.0, 0.0, a, b],
        ],
    ))
}

/// A sampled sag, interpolated by the bicubic spline (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct SagGrid {
    /// Where it came from (a file's path), for messages.
    pub source: String,
    /// Node coordinates, metres, increasing.
    pub xs: Vec<f64>,
    pub ys: Vec<f64>,
    /// Row by row from the lowest y: sag, s_xx, s_yy and s_xxyy at each node.
    sag: Vec<f64>,
    sxx: Vec<f64>,
    syy: Vec<f64>,
    sxxyy: Vec<f64>,
    /// At each node, how far the interpolated curvature may be off, 1 / metres.
    uncertainty: Vec<f64>,
}

impl SagGrid {
    /// The grid through `sag[row][column]` (metres) at `xs` × `ys` (metres, increasing, each at
    /// least 4); the caller has checked the shapes.
    fn build(source: String, xs: Vec<f64>, ys: Vec<f64>, sag: Vec<f64>) -> SagGrid {
        let (nx, ny) = (xs.len(), ys.len());
        let along_x = |values: &[f64]| -> Vec<f64> {
            values
                .chunks(nx)
                .flat_map(|row| spline_second_derivatives(&xs, row))
                .collect()
        };
        let along_y = |values: &[f64]| -> Vec<f64> {
            let mut out = vec![0.0; nx * ny];
            for i in 0..nx {
                let column: Vec<f64> = (0..ny).map(|j| values[j * nx + i]).collect();
                for (j, m) in spline_second_derivatives(&ys, &column)
                    .into_iter()
                    .enumerate()
                {
                    out[j * nx + i] = m;
                }
            }
            out
        };
        let sxx = along_x(&sag);
        let syy = along_y(&sag);
        let sxxyy = along_y(&sxx);
        let uncertainty = curvature_uncertainty(&xs, &ys, &sag);
        SagGrid {
            source,
            xs,
            ys,
            sag,
            sxx,
            syy,
            sxxyy,
            uncertainty,
        }
    }

    /// How far the interpolated curvature at (x, y) may be off, 1 / metres: the largest of the
    /// four nodes around it (None outside the grid).
    pub fn curvature_uncertainty(&self, x: f64, y: f64) -> Option<f64> {
        let cell = |nodes: &[f64], t: f64| {
            (nodes[0] <= t && t <= nodes[nodes.len() - 1])
                .then(|| nodes.partition_point(|n| *n <= t).clamp(1, nodes.len() - 1) - 1)
        };
        let (i, j) = (cell(&self.xs, x)?, cell(&self.ys, y)?);
        let nx = self.xs.len();
        Some(
            [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
                .iter()
                .map(|&(a, b)| self.uncertainty[b * nx + a])
                .fold(0.0, f64::max),
        )
    }

    /// A grid sampled from `sag(x, y)` (metres) at the given nodes (metres).
    pub fn sampled(
        source: &str,
        xs: Vec<f64>,
        ys: Vec<f64>,
        sag: impl Fn(f64, f64) -> f64,
    ) -> SagGrid {
        let values = ys
            .iter()
            .flat_map(|&y| xs.iter().map(move |&x| (x, y)))
            .map(|(x, y)| sag(x, y))
            .collect();
        SagGrid::build(source.to_string(), xs, ys, values)
    }

    pub fn local(&self, x: f64, y: f64) -> Option<Local> {
        let (i, bx) = basis(&self.xs, x)?;
        let (j, by) = basis(&self.ys, y)?;
        let nx = self.xs.len();
        let at = |values: &[f64], di: usize, dj: usize| values[(j + dj) * nx + i + di];
        // Coefficient of basis pair (p, q): values for p, q < 2; s_xx for p ≥ 2 > q, s_yy for
        // q ≥ 2 > p, s_xxyy for both.
        let coefficient = |p: usize, q: usize| {
            let values = match (p >= 2, q >= 2) {
                (false, false) => &self.sag,
                (true, false) => &self.sxx,
                (false, true) => &self.syy,
                (true, true) => &self.sxxyy,
            };
            at(values, p % 2, q % 2)
        };
        let sum = |dx: usize, dy: usize| {
            let mut total = 0.0;
            for (p, wx) in bx[dx].iter().enumerate() {
                for (q, wy) in by[dy].iter().enumerate() {
                    total += wx * wy * coefficient(p, q);
                }
            }
            total
        };
        Some(Local {
            sag: sum(0, 0),
            gradient: DVec2::new(sum(1, 0), sum(0, 1)),
            hessian: [sum(2, 0), sum(1, 1), sum(0, 2)],
        })
    }

    /// Parses the CSV `text` of file `source` (module doc).
    pub fn parse(text: &str, source: &str) -> Result<SagGrid, SceneError> {
        let bad = |row: usize, column: usize, message: String| {
            SceneError::invalid(source, format!("row {row}, column {column}: {message}"))
        };
        let number = |cell: &str, row: usize, column: usize, what: &str| {
            csv_number(source, cell, row, column, what)
        };
        let lines: Vec<(usize, &str)> = text
            .lines()
            .enumerate()
            .map(|(k, line)| (k + 1, line))
            .filter(|(_, line)| !line.trim().is_empty())
            .collect();
        let Some(&(header_row, header)) = lines.first() else {
            return Err(SceneError::invalid(source, "the sag grid is empty"));
        };
        let xs_mm = header
            .split(',')
            .enumerate()
            .skip(1)
            .map(|(c, cell)| number(cell, header_row, c + 1, "the x value"))
            .collect::<Result<Vec<f64>, _>>()?;
        let increasing = |values: &[f64], what: &str, at: &dyn Fn(usize) -> (usize, usize)| {
            increasing(source, values, what, at)
        };
        increasing(&xs_mm, "x value", &|k| (header_row, k + 2))?;
        let mut ys_mm = Vec::new();
        let mut sag_mm = Vec::new();
        for &(row, line) in &lines[1..] {
            let cells: Vec<&str> = line.split(',').collect();
            if cells.len() != xs_mm.len() + 1 {
                return Err(bad(
                    row,
                    cells.len().min(xs_mm.len() + 1) + 1,
                    format!(
                        "{} cells where the header has {} (a y value and one sag per x)",
                        cells.len(),
                        xs_mm.len() + 1
                    ),
                ));
            }
            ys_mm.push(number(cells[0], row, 1, "the y value")?);
            for (c, cell) in cells.iter().enumerate().skip(1) {
                sag_mm.push(number(cell, row, c + 1, "the sag")?);
            }
        }
        let rows: Vec<usize> = lines[1..].iter().map(|&(row, _)| row).collect();
        increasing(&ys_mm, "y value", &|k| (rows[k], 1))?;
        let nx = xs_mm.len();
        let to_m = |v: &Vec<f64>| v.iter().map(|v| v * 1e-3).collect::<Vec<f64>>();
        let grid = SagGrid::build(
            source.to_string(),
            to_m(&xs_mm),
            to_m(&ys_mm),
            to_m(&sag_mm),
        );
        match grid.local(0.0, 0.0) {
            None => Err(SceneError::invalid(
                source,
                "the grid does not contain (0, 0), the surface's vertex",
            )),
            Some(vertex) if vertex.sag.abs() > 1e-9 => Err(SceneError::invalid(
                source,
                format!(
                    "the sag at (0, 0) is {:.6} mm: a sag grid is measured from the surface's \
                     vertex, where it is 0",
                    vertex.sag * 1e3
                ),
            )),
            Some(_) => {
                debug_assert_eq!(grid.sag.len(), nx * grid.ys.len());
                Ok(grid)
            }
        }
    }

    /// The grid as the CSV [`SagGrid::parse`] reads, in millimetres.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("y\\x");
        for x in &self.xs {
            out += &format!(",{}", round_mm(x * 1e3));
        }
        out.push('\n');
        for (j, y) in self.ys.iter().enumerate() {
            out += &round_mm(y * 1e3).to_string();
            for i in 0..self.xs.len() {
                out += &format!(",{:.9}", self.sag[j * self.xs.len() + i] * 1e3);
            }
            out.push('\n');
        }
        out
    }
}

/// A coordinate in mm without floating-point dust (0.1 × 3 is 0.30000000000000004).
fn round_mm(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// At each node (row by row), the interpolated curvature's uncertainty, 1 / metres: the
/// larger of the estimates along x and along y from the fourth divided differences on the five
/// nodes centred on it (the nearest five at an edge). The fourth divided difference times 24
/// estimates s''''; the spline's curvature errs by about h² |s''''| / 12.
fn curvature_uncertainty(xs: &[f64], ys: &[f64], sag: &[f64]) -> Vec<f64> {
    let fourth = |t: &[f64], f: &[f64]| {
        // Divided differences of order 4 on five nodes.
        let mut d: Vec<f64> = f.to_vec();
        for order in 1..=4 {
            for k in (order..5).rev() {
                d[k] = (d[k] - d[k - 1]) / (t[k] - t[k - order]);
            }
        }
        24.0 * d[4]
    };
    let estimate = |t: &[f64], f: &[f64]| {
        let h = (t[4] - t[0]) / 4.0;
        fourth(t, f).abs() * h * h / 12.0
    };
    let (nx, ny) = (xs.len(), ys.len());
    // The five nodes' first index for node k of n (with 4 nodes there is no estimate).
    let window = |k: usize, n: usize| (n >= 5).then(|| k.saturating_sub(2).min(n - 5));
    let mut out = vec![0.0; nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            let mut worst: f64 = 0.0;
            if let Some(a) = window(i, nx) {
                worst = worst.max(estimate(&xs[a..a + 5], &sag[j * nx + a..j * nx + a + 5]));
            }
            if let Some(b) = window(j, ny) {
                let f: Vec<f64> = (b..b + 5).map(|k| sag[k * nx + i]).collect();
                worst = worst.max(estimate(&ys[b..b + 5], &f));
            }
            out[j * nx + i] = worst;
        }
    }
    out
}

/// s = Σ c x^i y^j with x, y and s in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct Polynomial {
    /// (i, j, c).
    pub terms: Vec<(u32, u32, f64)>,
}

impl Polynomial {
    pub fn local(&self, x: f64, y: f64) -> Option<Local> {
        let (x, y) = (x * 1e3, y * 1e3);
        let power = |v: f64, k: u32, d: u32| -> f64 {
            if d > k {
                return 0.0;
            }
            let falling: f64 = (0..d).map(|m| f64::from(k - m)).product();
            falling * v.powi((k - d) as i32)
        };
        let sum = |dx: u32, dy: u32| -> f64 {
            self.terms
                .iter()
                .map(|&(i, j, c)| c * power(x, i, dx) * power(y, j, dy))
                .sum()
        };
        // mm → m: the sag ×1e-3, slopes ×1, second derivatives ×1e3.
        Some(Local {
            sag: sum(0, 0) * 1e-3,
            gradient: DVec2::new(sum(1, 0), sum(0, 1)),
            hessian: [sum(2, 0) * 1e3, sum(1, 1) * 1e3, sum(0, 2) * 1e3],
        })
    }
}

/// A progressive addition surface (the front of a progressive lens), built in code:
///
/// s(x, y) = m(y) + [sphere(x, y) − sphere(0, y)] + ½ A(y) h(x), Δc = add / (n − 1),
///
/// - the meridian x = 0 is the plane curve m(y) whose *true* curvature is κ(y) = c + Δc g(y):
///   with S(y) = ∫κ = c y + Δc G'(y) (G'' = g), its slope is m' = S / √(1 − S²) (a plane
///   curve's curvature is d/dy [m' / √(1 + m'²)]), m'' = κ / (1 − S²)^{3/2}, and m is m'
///   integrated (Gauss–Legendre, 16 nodes per piece; exactly the far sphere above the fitting
///   point). So the far zone is the far sphere and the meridian below the corridor has the
///   near sphere's curvature, the focimeter's add at every point of it;
/// - g(y) rises from 0 at the fitting point (y = 0) to 1 a corridor length L below it, as the
///   septic smoothstep of t = −y / L (its first three derivatives vanish at both ends, so the
///   curvature and its rate of change are continuous); 0 above, 1 below;
/// - A(y) = κ √(1 + m'²) − c / √(1 − c²y²) makes the meridian umbilic: across it the normal
///   curvature s_xx / √(1 + m'²) equals κ ([`Progressive::umbilic_blend`]);
/// - h(x) = W² tanh(x²/W²) = x² − x⁶/(3W⁴) + … near the corridor (quadratic to within 0.4 %
///   at W / 4, so the unwanted cylinder rises linearly beside it as Minkwitz's theorem says,
///   ∂C/∂x = 2 ∂M/∂y), bounded beside it: the addition blends into a function of y alone over
///   about W on both sides, where the cylinder is about the add, and largest (1.5 to 2 times
///   the add) where h'' dips below 0. A textbook construction, not an optimised commercial
///   design.
///
/// The fitting point is the vertex (0, 0), the prism reference point too; the design's far
/// and near reference points are (0, +8 mm) and (0, −(L + 3 mm)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progressive {
    /// The far zone's sphere, 1 / metres.
    pub far_curvature: f64,
    /// The surface addition, dioptres, at the glass's index.
    pub add_d: f64,
    pub index: f64,
    /// L, metres.
    pub corridor_length: f64,
    /// W, metres.
    pub blend_width: f64,
}

/// The 16-point Gauss–Legendre nodes and weights on [−1, 1] (Newton on P₁₆).
fn gauss_legendre() -> &'static [(f64, f64); 16] {
    static NODES: std::sync::OnceLock<[(f64, f64); 16]> = std::sync::OnceLock::new();
    NODES.get_or_init(|| {
        let n = 16;
        let mut out = [(0.0, 0.0); 16];
        for (i, node) in out.iter_mut().enumerate() {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut derivative = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / derivative;
                x -= step;
                if step.abs() < 1e-16 {
                    break;
                }
            }
            *node = (x, 2.0 / ((1.0 - x * x) * derivative * derivative));
        }
        out
    })
}

impl Progressive {
    pub fn new(
        far_curvature: f64,
        add_d: f64,
        index: f64,
        corridor_length: f64,
        blend_width: f64,
    ) -> Progressive {
        Progressive {
            far_curvature,
            add_d,
            index,
            corridor_length,
            blend_width,
        }
    }

    /// The design's far (distance) reference point, metres.
    pub fn far_reference(&self) -> DVec2 {
        DVec2::new(0.0, 0.008)
    }

    /// The design's near reference point, metres.
    pub fn near_reference(&self) -> DVec2 {
        DVec2::new(0.0, -(self.corridor_length + 0.003))
    }

    /// Δc, 1 / metres.
    pub fn add_curvature(&self) -> f64 {
        self.add_d / (self.index - 1.0)
    }

    /// g and its y-derivatives [g, g', g''], and G, G' (G'' = g).
    fn profile(&self, y: f64) -> ([f64; 3], [f64; 2]) {
        let l = self.corridor_length;
        let s = -y;
        if s <= 0.0 {
            return ([0.0; 3], [0.0; 2]);
        }
        // ∫₀¹ g = 1/2 and ∫₀¹∫₀ g = 5/36.
        let (p1_end, p2_end) = (0.5, 5.0 / 36.0);
        if s >= l {
            let beyond = s - l;
            let big = l * l * p2_end + l * p1_end * beyond + 0.5 * beyond * beyond;
            let slope = l * p1_end + beyond;
            return ([1.0, 0.0, 0.0], [big, -slope]);
        }
        let t = s / l;
        let (t2, t3) = (t * t, t * t * t);
        let g = t2 * t2 * (35.0 - 84.0 * t + 70.0 * t2 - 20.0 * t3);
        let g_t = 140.0 * t3 * (1.0 - t).powi(3);
        let g_tt = 420.0 * t2 * (1.0 - t).powi(2) * (1.0 - 2.0 * t);
        let p1 = t2 * t3 * (7.0 - 14.0 * t + 10.0 * t2 - 2.5 * t3);
        let p2 = t3 * t3 * (7.0 / 6.0 - 2.0 * t + 1.25 * t2 - 5.0 / 18.0 * t3);
        // d/dy = −d/ds = −(1/L) d/dt.
        ([g, -g_t / l, g_tt / (l * l)], [l * l * p2, -l * p1])
    }

    /// S(y) = c y + Δc G'(y): the sine of the meridian's slope angle.
    fn sine(&self, y: f64) -> f64 {
        self.far_curvature * y + self.add_curvature() * self.profile(y).1[1]
    }

    /// The meridian's height m(y) less the far sphere's at (0, y): ∫₀^y of their slopes'
    /// difference, zero above the fitting point.
    fn meridian_excess(&self, y: f64) -> Option<f64> {
        if y >= 0.0 {
            return Some(0.0);
        }
        let c = self.far_curvature;
        let excess = |t: f64| -> Option<f64> {
            let s = self.sine(t);
            let (u, k2) = (1.0 - s * s, 1.0 - c * c * t * t);
            (u > 1e-12 && k2 > 1e-12).then(|| s / u.sqrt() - c * t / k2.sqrt())
        };
        let integral = |a: f64, b: f64| -> Option<f64> {
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            gauss_legendre()
                .iter()
                .try_fold(0.0, |sum, &(x, w)| Some(sum + w * excess(mid + half * x)?))
                .map(|sum| sum * half)
        };
        let corner = y.max(-self.corridor_length);
        let mut total = integral(0.0, corner)?;
        if y < corner {
            total += integral(corner, y)?;
        }
        Some(total)
    }

    pub fn local(&self, x: f64, y: f64) -> Option<Local> {
        let c = self.far_curvature;
        let r2 = x * x + y * y;
        let k2 = 1.0 - c * c * r2;
        if k2 <= 1e-12 {
            return None;
        }
        let k = k2.sqrt();
        let k3 = k2 * k;
        let sphere = Local {
            sag: c * r2 / (1.0 + k),
            gradient: DVec2::new(c * x / k, c * y / k),
            hessian: [
                c / k + c * c * c * x * x / k3,
                c * c * c * x * y / k3,
                c / k + c * c * c * y * y / k3,
            ],
        };
        // The sphere's meridian at (0, y), which the progressive meridian replaces.
        let k0 = (1.0 - c * c * y * y).sqrt();
        let (sphere_y0, sphere_yy0) = (c * y / k0, c / (k0 * k0 * k0));
        let dc = self.add_curvature();
        let ([g, _, _], _) = self.profile(y);
        let s = self.sine(y);
        let u = 1.0 - s * s;
        if u <= 1e-12 {
            return None;
        }
        let (m_y, m_yy) = (s / u.sqrt(), (c + dc * g) / (u * u.sqrt()));
        let w2 = self.blend_width * self.blend_width;
        let v = x * x / w2;
        let t = v.tanh();
        let sech2 = 1.0 - t * t;
        let (h, h_x, h_xx) = (w2 * t, 2.0 * x * sech2, 2.0 * sech2 * (1.0 - 4.0 * v * t));
        let [a, a_y, a_yy] = self.umbilic_blend(y)?;
        Some(Local {
            sag: sphere.sag + self.meridian_excess(y)? + 0.5 * a * h,
            gradient: DVec2::new(
                sphere.gradient.x + 0.5 * a * h_x,
                sphere.gradient.y - sphere_y0 + m_y + 0.5 * a_y * h,
            ),
            hessian: [
                sphere.hessian[0] + 0.5 * a * h_xx,
                sphere.hessian[1] + 0.5 * a_y * h_x,
                sphere.hessian[2] - sphere_yy0 + m_yy + 0.5 * a_yy * h,
            ],
        })
    }

    /// The blend's coefficient A(y) and its y-derivatives (type doc): with κ = c + Δc g,
    /// u = 1 − S², k = √(1 − c²y²), A = κ/√u − c/k.
    fn umbilic_blend(&self, y: f64) -> Option<[f64; 3]> {
        let (c, dc) = (self.far_curvature, self.add_curvature());
        let ([g, g_y, g_yy], _) = self.profile(y);
        let (kappa, kappa_y, kappa_yy) = (c + dc * g, dc * g_y, dc * g_yy);
        let s = self.sine(y);
        let u = 1.0 - s * s;
        let k2 = 1.0 - c * c * y * y;
        if u <= 1e-12 || k2 <= 1e-12 {
            return None;
        }
        let (ru, k) = (u.sqrt(), k2.sqrt());
        let (u3, u5) = (u * ru, u * u * ru);
        let (k3, k5) = (k2 * k, k2 * k2 * k);
        let (c3, c5) = (c * c * c, c * c * c * c * c);
        let a = kappa / ru - c / k;
        let a_y = kappa_y / ru + kappa * kappa * s / u3 - c3 * y / k3;
        let a_yy = kappa_yy / ru
            + 3.0 * kappa * kappa_y * s / u3
            + kappa * kappa * kappa / u3
            + 3.0 * kappa * kappa * kappa * s * s / u5
            - c3 / k3
            - 3.0 * c5 * y * y / k5;
        Some([a, a_y, a_yy])
    }
}

/// A grid cell `row`, `column` of `source` saying why it is bad.
fn bad_cell(source: &str, row: usize, column: usize, message: String) -> SceneError {
    SceneError::invalid(source, format!("row {row}, column {column}: {message}"))
}

/// The number in a CSV cell, or why it is none (empty, not a number, not finite).
fn csv_number(
    source: &str,
    cell: &str,
    row: usize,
    column: usize,
    what: &str,
) -> Result<f64, SceneError> {
    let bad = |row: usize, column: usize, message: String| bad_cell(source, row, column, message);
    let cell = cell.trim();
    if cell.is_empty() {
        return Err(bad(
            row,
            column,
            format!("{what} is missing (an empty cell)"),
        ));
    }
    let value: f64 = cell
        .parse()
        .map_err(|_| bad(row, column, format!("{what} '{cell}' is not a number")))?;
    if !value.is_finite() {
        return Err(bad(row, column, format!("{what} is {value}: not finite")));
    }
    Ok(value)
}

/// The axis values increase, and there are at least 4 of them; else the first cell (`at`
/// gives its row and column) that does not.
fn increasing(
    source: &str,
    values: &[f64],
    what: &str,
    at: &dyn Fn(usize) -> (usize, usize),
) -> Result<(), SceneError> {
    let bad = |row: usize, column: usize, message: String| bad_cell(source, row, column, message);
    if let Some(k) = (1..values.len()).find(|&k| values[k] <= values[k - 1]) {
        let (row, column) = at(k);
        return Err(bad(
            row,
            column,
            format!(
                "{what} {} mm does not increase from {} mm: the {what}s must increase",
                values[k],
                values[k - 1]
            ),
        ));
    }
    if values.len() < 4 {
        return Err(SceneError::invalid(
            source,
            format!(
                "{} {what}s: the bicubic interpolation needs at least 4",
                values.len()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn finite_differences(f: &Freeform, x: f64, y: f64) -> Local {
        let e = 1e-5;
        let s = |x: f64, y: f64| f.local(x, y).unwrap().sag;
        let g = |x: f64, y: f64| f.local(x, y).unwrap().gradient;
        Local {
            sag: s(x, y),
            gradient: DVec2::new(
                (s(x + e, y) - s(x - e, y)) / (2.0 * e),
                (s(x, y + e) - s(x, y - e)) / (2.0 * e),
            ),
            hessian: [
                (g(x + e, y).x - g(x - e, y).x) / (2.0 * e),
                (g(x, y + e).x - g(x, y - e).x) / (2.0 * e),
                (g(x, y + e).y - g(x, y - e).y) / (2.0 * e),
            ],
        }
    }

    fn agrees(a: &Local, b: &Local, tolerance: f64) {
        assert!(
            (a.gradient - b.gradient).length() < tolerance,
            "{a:?} {b:?}"
        );
        for k in 0..3 {
            assert!(
                (a.hessian[k] - b.hessian[k]).abs() < tolerance * 1e3,
                "{a:?} {b:?}"
            );
        }
    }

    #[test]
    fn a_sag_grid_reproduces_a_cubic_and_its_derivatives() {
        // Uneven nodes: the not-a-knot spline holds any cubic exactly.
        let xs: Vec<f64> = [-20.0, -13.0, -5.0, 0.0, 4.0, 11.0, 20.0]
            .iter()
            .map(|v| v * 1e-3)
            .collect();
        let ys = xs.clone();
        let cubic = |x: f64, y: f64| 0.4 * x * x * x - 2.0 * x * y * y + 3.0 * x * y + 1.5 * y * y;
        let grid = Freeform::SagGrid(Arc::new(SagGrid::sampled("cubic", xs, ys, cubic)));
        for (x, y) in [(0.0031, -0.0172), (-0.0199, 0.019), (0.012, 0.0)] {
            let local = grid.local(x, y).unwrap();
            assert!((local.sag - cubic(x, y)).abs() < 1e-15);
            let exact = Local {
                sag: cubic(x, y),
                gradient: DVec2::new(
                    1.2 * x * x - 2.0 * y * y + 3.0 * y,
                    -4.0 * x * y + 3.0 * x + 3.0 * y,
                ),
                hessian: [2.4 * x, -4.0 * y + 3.0, -4.0 * x + 3.0],
            };
            agrees(&local, &exact, 1e-12);
        }
        assert!(grid.local(0.021, 0.0).is_none());
    }

    #[test]
    fn the_progressive_surface_has_the_derivatives_it_states() {
        let design = Freeform::Progressive(Progressive::new(1.0 / 0.12, 2.0, 1.6, 0.014, 0.01));
        for (x, y) in [
            (0.003, -0.007),
            (-0.012, -0.002),
            (0.02, -0.02),
            (0.0, 0.005),
        ] {
            agrees(
                &design.local(x, y).unwrap(),
                &finite_differences(&design, x, y),
                1e-7,
            );
        }
    }

    #[test]
    fn a_polynomial_in_millimetres_has_metre_derivatives() {
        // s = x²/(2R) + y²/(2R) in mm for R = 100 mm: curvature 10 / m.
        let p = Freeform::Polynomial(Polynomial {
            terms: vec![(2, 0, 0.005), (0, 2, 0.005), (1, 1, 0.0001)],
        });
        let local = p.local(0.0, 0.0).unwrap();
        assert!((local.hessian[0] - 10.0).abs() < 1e-12);
        assert!((local.hessian[1] - 0.1).abs() < 1e-12);
        agrees(
            &p.local(0.01, -0.007).unwrap(),
            &finite_differences(&p, 0.01, -0.007),
            1e-7,
        );
    }

    /// Along the meridian the surface is umbilic with the true curvature c + Δc g: the far
    /// sphere above the fitting point, the near sphere's below the corridor, however far down.
    #[test]
    fn the_progressive_meridian_has_the_far_and_near_spheres_true_curvature() {
        let design = Progressive::new(1.0 / 0.12, 2.0, 1.6, 0.014, 0.008);
        for y_mm in [8.0, 0.0, -3.5, -7.0, -14.0, -17.0, -25.0] {
            let y = y_mm * 1e-3;
            let [k1, k2] = design.local(0.0, y).unwrap().principal_curvatures();
            let want = design.far_curvature + design.add_curvature() * design.profile(y).0[0];
            assert!(
                (k1 - want).abs() < 1e-6 && (k2 - want).abs() < 1e-6,
                "{y_mm} mm: {k1} {k2} against {want}"
            );
        }
    }

    #[test]
    fn principal_curvatures_of_a_sphere_are_its_own_everywhere() {
        let sphere = Freeform::Progressive(Progressive::new(1.0 / 0.09, 0.0, 1.5, 0.014, 0.01));
        let [k1, k2] = sphere.local(0.02, -0.025).unwrap().principal_curvatures();
        assert!((k1 - 1.0 / 0.09).abs() < 1e-9 && (k2 - 1.0 / 0.09).abs() < 1e-9);
    }

    #[test]
    fn bad_sag_grids_are_refused_naming_the_row_and_column() {
        let good =
            "y\\x,-2,-1,0,1,2\n-2,0,0,0,0,0\n-1,0,0,0,0,0\n0,0,0,0,0,0\n1,0,0,0,0,0\n2,0,0,0,0,0\n";
        assert!(SagGrid::parse(good, "g.csv").is_ok());
        let cases = [
            (
                good.replace("\n-1,0,0,0,0,0", "\n-1,0,,0,0,0"),
                "row 3, column 3: the sag is missing",
            ),
            (
                good.replace("\n-1,0,0,0,0,0", "\n-1,0,NaN,0,0,0"),
                "row 3, column 3: the sag is NaN",
            ),
            (
                good.replace("\n-1,0,0,0,0,0", "\n-1,0,abc,0,0,0"),
                "'abc' is not a number",
            ),
            (
                good.replace("-2,-1,0,1,2", "-2,-1,0,-1,2"),
                "row 1, column 5: x value -1 mm does not increase",
            ),
            (
                good.replace("\n1,0,0,0,0,0", "\n-3,0,0,0,0,0"),
                "row 5, column 1: y value -3 mm does not increase",
            ),
            (good.replace("\n1,0,0,0,0,0", "\n1,0,0,0,0"), "row 5"),
            (
                good.replace("y\\x,-2,-1,0,1,2", "y\\x,-2,-1,0"),
                "3 x values: the bicubic interpolation needs at least 4",
            ),
        ];
        for (text, wanted) in cases {
            let message = SagGrid::parse(&text, "g.csv").unwrap_err().to_string();
            assert!(message.starts_with("g.csv: "), "{message}");
            assert!(
                message.contains(wanted),
                "{message:?} should say {wanted:?}"
            );
        }
        // A grid too coarse for a spike loads, its curvature there uncertain by the fourth
        // differences' estimate, not refused.
        let spiked =
            SagGrid::parse(&good.replace("\n0,0,0,0,0,0", "\n0,0,0,0,0.5,0"), "g.csv").unwrap();
        let flat = SagGrid::parse(good, "g.csv").unwrap();
        assert!(spiked.curvature_uncertainty(0.001, 0.0).unwrap() > MAX_CURVATURE_ERROR);
        assert_eq!(flat.curvature_uncertainty(0.001, 0.0), Some(0.0));
        assert_eq!(flat.curvature_uncertainty(0.003, 0.0), None);
        let lifted = good.replace(",0,0,0,0,0\n", ",0.01,0.01,0.01,0.01,0.01\n");
        let message = SagGrid::parse(&lifted, "g.csv").unwrap_err().to_string();
        assert!(message.contains("the sag at (0, 0)"), "{message}");
    }
}
