//! A small STEP writer for bodies of rational B-spline faces, each face bounded by its four
//! iso-parametric edges (edges and vertices shared between faces that meet). It writes the
//! project's own CAD examples, the tests' shapes (spheres, cylinders, tori as rational
//! patches) and the benchmark's file, with the length unit stated the way CAD systems state
//! it. AP214 (`AUTOMOTIVE_DESIGN`) structure: product → shape representation → B-rep.

use std::collections::HashMap;
use std::fmt::Write as _;

use glam::DVec3;

use crate::units::LengthUnit;

/// A rational B-spline surface: `control[i][j]` is the point (file units) and weight of row i
/// along u, column j along v; knot vectors are full (each knot repeated by its multiplicity).
#[derive(Clone, Debug)]
pub struct NurbsPatch {
    pub degree: (usize, usize),
    pub control: Vec<Vec<(DVec3, f64)>>,
    pub knots_u: Vec<f64>,
    pub knots_v: Vec<f64>,
}

impl NurbsPatch {
    /// The patch made of `profile` (a rational curve in the (ρ, z) half-plane: radius from the
    /// axis, height, weight) turned about +Z by the rational arc `turn`: a surface of
    /// revolution written exactly, as CAD systems write spheres, cylinders and tori as NURBS.
    /// u runs along the turn, v along the profile.
    pub fn revolved(
        turn: &RationalArc,
        profile: &[(f64, f64, f64)],
        profile_knots: Vec<f64>,
        profile_degree: usize,
    ) -> NurbsPatch {
        let control = turn
            .points
            .iter()
            .map(|&(x, y, w_turn)| {
                profile
                    .iter()
                    .map(|&(rho, z, w)| (DVec3::new(rho * x, rho * y, z), w_turn * w))
                    .collect()
            })
            .collect();
        NurbsPatch {
            degree: (2, profile_degree),
            control,
            knots_u: turn.knots.clone(),
            knots_v: profile_knots,
        }
    }
}

impl NurbsPatch {
    /// The region of a sphere of `radius` about the origin from longitude `longitude.0` to
    /// `longitude.1` (radians about +Z from +X, in `longitude_spans` spans) and latitude
    /// `latitude.0` to `latitude.1` (radians from the XY plane, one span), written exactly;
    /// its Su × Sv points out of the sphere.
    pub fn sphere_region(
        radius: f64,
        longitude: (f64, f64),
        longitude_spans: usize,
        latitude: (f64, f64),
    ) -> NurbsPatch {
        let arc = RationalArc::new(latitude.0, latitude.1, 1);
        let profile: Vec<_> = arc
            .points
            .iter()
            .map(|&(x, y, w)| (radius * x, radius * y, w))
            .collect();
        let turn = RationalArc::new(longitude.0, longitude.1, longitude_spans);
        NurbsPatch::revolved(&turn, &profile, arc.knots, 2)
    }

    /// The patch with every control point moved by `to` (an affine map keeps a NURBS exact),
    /// weights kept.
    pub fn map_points(mut self, to: impl Fn(DVec3) -> DVec3) -> NurbsPatch {
        for row in &mut self.control {
            for (p, _) in row {
                *p = to(*p);
            }
        }
        self
    }
}

/// A circular arc of unit radius as a rational quadratic B-spline: control points (x, y, w)
/// in its plane and the full knot vector; one span per quarter turn or less.
#[derive(Clone, Debug)]
pub struct RationalArc {
    pub points: Vec<(f64, f64, f64)>,
    pub knots: Vec<f64>,
}

impl RationalArc {
    /// The arc from angle `start` to `end` (radians, anticlockwise), in `spans` equal spans of
    /// at most a quarter turn each.
    pub fn new(start: f64, end: f64, spans: usize) -> RationalArc {
        let step = (end - start) / spans as f64;
        let w = (step / 2.0).cos();
        let mut points = vec![(start.cos(), start.sin(), 1.0)];
        let mut knots = vec![0.0; 3];
        for k in 0..spans {
            let a0 = start + step * k as f64;
            let mid = a0 + step / 2.0;
            let a1 = a0 + step;
            points.push((mid.cos() / w, mid.sin() / w, w));
            points.push((a1.cos(), a1.sin(), 1.0));
            let knot = (k + 1) as f64 / spans as f64;
            knots.extend(if k + 1 == spans {
                vec![knot; 3]
            } else {
                vec![knot; 2]
            });
        }
        RationalArc { points, knots }
    }
}

/// Entities written so far, numbered from 1.
#[derive(Default)]
pub struct StepWriter {
    lines: Vec<String>,
    vertices: HashMap<[u64; 3], u64>,
    /// Edge by its control points in the sense first written: (edge, its first point).
    edges: HashMap<Vec<[u64; 3]>, u64>,
    bodies: Vec<(String, u64)>,
}

fn key(p: DVec3) -> [u64; 3] {
    // Round off the last bits so that a point computed twice meets itself.
    let round = |x: f64| ((x * 1e9).round() / 1e9).to_bits();
    [round(p.x), round(p.y), round(p.z)]
}

fn real(x: f64) -> String {
    let text = format!("{x:?}");
    if text.contains('.') || text.contains('e') || text.contains('E') {
        text.replace('e', "E")
    } else {
        format!("{text}.")
    }
}

fn refs(ids: impl IntoIterator<Item = u64>) -> String {
    let list: Vec<String> = ids.into_iter().map(|i| format!("#{i}")).collect();
    format!("({})", list.join(","))
}

fn reals(values: impl IntoIterator<Item = f64>) -> String {
    let list: Vec<String> = values.into_iter().map(real).collect();
    format!("({})", list.join(","))
}

/// Distinct knots and their multiplicities.
fn knots_and_multiplicities(knots: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut distinct: Vec<f64> = Vec::new();
    let mut multiplicities: Vec<usize> = Vec::new();
    for &k in knots {
        if distinct.last() == Some(&k) {
            *multiplicities.last_mut().expect("a knot before") += 1;
        } else {
            distinct.push(k);
            multiplicities.push(1);
        }
    }
    (distinct, multiplicities)
}

impl StepWriter {
    pub fn new() -> StepWriter {
        StepWriter::default()
    }

    fn add(&mut self, record: String) -> u64 {
        self.lines.push(record);
        self.lines.len() as u64
    }

    fn point(&mut self, p: DVec3) -> u64 {
        self.add(format!(
            "CARTESIAN_POINT('',({},{},{}))",
            real(p.x),
            real(p.y),
            real(p.z)
        ))
    }

    fn vertex(&mut self, p: DVec3) -> u64 {
        if let Some(&id) = self.vertices.get(&key(p)) {
            return id;
        }
        let point = self.point(p);
        let id = self.add(format!("VERTEX_POINT('',#{point})"));
        self.vertices.insert(key(p), id);
        id
    }

    fn surface(&mut self, patch: &NurbsPatch) -> u64 {
        let rows: Vec<Vec<u64>> = patch
            .control
            .iter()
            .map(|row| row.iter().map(|&(p, _)| self.point(p)).collect())
            .collect();
        let points: Vec<String> = rows.into_iter().map(refs).collect();
        let weights: Vec<String> = patch
            .control
            .iter()
            .map(|row| reals(row.iter().map(|&(_, w)| w)))
            .collect();
        let (ku, mu) = knots_and_multiplicities(&patch.knots_u);
        let (kv, mv) = knots_and_multiplicities(&patch.knots_v);
        let counts = |m: Vec<usize>| {
            format!(
                "({})",
                m.iter()
                    .map(|c| c.to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            )
        };
        self.add(format!(
            "( BOUNDED_SURFACE() B_SPLINE_SURFACE({},{},({}),.UNSPECIFIED.,.F.,.F.,.F.) B_SPLINE_SURFACE_WITH_KNOTS({},{},{},{},.UNSPECIFIED.) GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_SURFACE(({})) REPRESENTATION_ITEM('') SURFACE() )",
            patch.degree.0,
            patch.degree.1,
            points.join(","),
            counts(mu),
            counts(mv),
            reals(ku),
            reals(kv),
            weights.join(",")
        ))
    }

    /// The edge along `control` (a rational curve of `degree` on `knots`), shared with a face
    /// that wrote it before in either sense; returns the edge and whether it runs this way.
    fn edge(&mut self, degree: usize, control: &[(DVec3, f64)], knots: &[f64]) -> (u64, bool) {
        let forward: Vec<[u64; 3]> = control.iter().map(|&(p, _)| key(p)).collect();
        let backward: Vec<[u64; 3]> = forward.iter().rev().copied().collect();
        if let Some(&id) = self.edges.get(&forward) {
            return (id, true);
        }
        if let Some(&id) = self.edges.get(&backward) {
            return (id, false);
        }
        let start = self.vertex(control[0].0);
        let end = self.vertex(control[control.len() - 1].0);
        let points: Vec<u64> = control.iter().map(|&(p, _)| self.point(p)).collect();
        let (k, m) = knots_and_multiplicities(knots);
        let curve = self.add(format!(
            "( BOUNDED_CURVE() B_SPLINE_CURVE({degree},{},.UNSPECIFIED.,.F.,.F.) B_SPLINE_CURVE_WITH_KNOTS(({}),{},.UNSPECIFIED.) CURVE() GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_CURVE({}) REPRESENTATION_ITEM('') )",
            refs(points),
            m.iter().map(|c| c.to_string()).collect::<Vec<_>>().join(","),
            reals(k),
            reals(control.iter().map(|&(_, w)| w)),
        ));
        let id = self.add(format!("EDGE_CURVE('',#{start},#{end},#{curve},.T.)"));
        self.edges.insert(forward, id);
        (id, true)
    }

    /// A face of `patch` bounded by its four iso-parametric edges, its outside on Su × Sv.
    pub fn patch_face(&mut self, patch: &NurbsPatch) -> u64 {
        let surface = self.surface(patch);
        let column =
            |j: usize| -> Vec<(DVec3, f64)> { patch.control.iter().map(|row| row[j]).collect() };
        let last_column = patch.control[0].len() - 1;
        let first_row = patch.control[0].clone();
        let last_row = patch.control[patch.control.len() - 1].clone();
        let reverse = |mut c: Vec<(DVec3, f64)>| {
            c.reverse();
            c
        };
        let flip = |knots: &[f64]| -> Vec<f64> {
            let (a, b) = (knots[0], knots[knots.len() - 1]);
            knots.iter().rev().map(|k| a + b - k).collect()
        };
        // Anticlockwise in (u, v): v = v0 (u up), u = u1 (v up), v = v1 (u down), u = u0 (v down).
        let sides = [
            (patch.degree.0, column(0), patch.knots_u.clone()),
            (patch.degree.1, last_row, patch.knots_v.clone()),
            (
                patch.degree.0,
                reverse(column(last_column)),
                flip(&patch.knots_u),
            ),
            (patch.degree.1, reverse(first_row), flip(&patch.knots_v)),
        ];
        let mut oriented = Vec::new();
        for (degree, control, knots) in sides {
            let (edge, sense) = self.edge(degree, &control, &knots);
            oriented.push(self.add(format!(
                "ORIENTED_EDGE('',*,*,#{edge},{})",
                if sense { ".T." } else { ".F." }
            )));
        }
        let edge_loop = self.add(format!("EDGE_LOOP('',{})", refs(oriented)));
        let bound = self.add(format!("FACE_OUTER_BOUND('',#{edge_loop},.T.)"));
        self.add(format!("ADVANCED_FACE('',(#{bound}),#{surface},.T.)"))
    }

    /// A body of `faces`: a solid when `closed`, else a shell-based surface model; `name`
    /// names its product.
    pub fn body(&mut self, name: &str, faces: &[u64], closed: bool) {
        let shell = self.add(format!(
            "{}('',{})",
            if closed { "CLOSED_SHELL" } else { "OPEN_SHELL" },
            refs(faces.iter().copied())
        ));
        let body = if closed {
            self.add(format!("MANIFOLD_SOLID_BREP('{name}',#{shell})"))
        } else {
            self.add(format!("SHELL_BASED_SURFACE_MODEL('{name}',(#{shell}))"))
        };
        self.bodies.push((name.to_string(), body));
    }

    /// The whole file, its coordinates in `unit`.
    pub fn finish(mut self, unit: LengthUnit) -> String {
        let context = self.unit_context(unit);
        let application = self.add(
            "APPLICATION_CONTEXT('core data for automotive mechanical design processes')".into(),
        );
        self.add(format!("APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{application})"));
        let product_context = self.add(format!("PRODUCT_CONTEXT('',#{application},'mechanical')"));
        let definition_context = self.add(format!(
            "PRODUCT_DEFINITION_CONTEXT('part definition',#{application},'design')"
        ));
        for (name, body) in std::mem::take(&mut self.bodies) {
            let representation = self.add(format!(
                "{}('{name}',(#{body}),#{context})",
                if self.lines[body as usize - 1].starts_with("MANIFOLD") {
                    "ADVANCED_BREP_SHAPE_REPRESENTATION"
                } else {
                    "MANIFOLD_SURFACE_SHAPE_REPRESENTATION"
                }
            ));
            let product = self.add(format!(
                "PRODUCT('{name}','{name}','',(#{product_context}))"
            ));
            let formation = self.add(format!("PRODUCT_DEFINITION_FORMATION('','',#{product})"));
            let definition = self.add(format!(
                "PRODUCT_DEFINITION('design','',#{formation},#{definition_context})"
            ));
            let shape = self.add(format!("PRODUCT_DEFINITION_SHAPE('','',#{definition})"));
            self.add(format!(
                "SHAPE_DEFINITION_REPRESENTATION(#{shape},#{representation})"
            ));
        }
        let mut text = String::from(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('specula CAD example'),'2;1');\nFILE_NAME('','',(''),(''),'specula','specula','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n",
        );
        for (i, line) in self.lines.iter().enumerate() {
            let _ = writeln!(text, "#{} = {line};", i + 1);
        }
        text.push_str("ENDSEC;\nEND-ISO-10303-21;\n");
        text
    }

    /// A geometric context stating `unit` for lengths, radians and steradians.
    fn unit_context(&mut self, unit: LengthUnit) -> u64 {
        let si_length =
            |prefix: &str| format!("( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT({prefix},.METRE.) )");
        let length = match unit {
            LengthUnit::Mm => self.add(si_length(".MILLI.")),
            LengthUnit::Cm => self.add(si_length(".CENTI.")),
            LengthUnit::M => self.add(si_length("$")),
            LengthUnit::In => {
                let millimetre = self.add(si_length(".MILLI."));
                let factor = self.add(format!(
                    "LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#{millimetre})"
                ));
                let dimensions = self.add("DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.)".into());
                self.add(format!("( CONVERSION_BASED_UNIT('INCH',#{factor}) LENGTH_UNIT() NAMED_UNIT(#{dimensions}) )"))
            }
        };
        let angle = self.add("( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) )".into());
        let solid = self.add("( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() )".into());
        let uncertainty = self.add(format!("UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#{length},'distance_accuracy_value','confusion accuracy')"));
        self.add(format!(
            "( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{uncertainty})) GLOBAL_UNIT_ASSIGNED_CONTEXT((#{length},#{angle},#{solid})) REPRESENTATION_CONTEXT('','') )"
        ))
    }
}
