//! STEP files (ISO 10303-21 exchange structures of AP203, AP214 and AP242): a designer's
//! B-rep bodies, tessellated for rendering, with each triangle's face and each vertex's (u, v)
//! on it kept ([`crate::cad`]).
//!
//! Steps: parse the exchange structure (truck's `ruststep`); index its instances; find the
//! bodies and their products' names and length unit ([`structure`]); read each body's faces,
//! edges and vertices, converting the geometry with truck and naming every instance that
//! cannot be read ([`brep`]); tessellate each face to the chord tolerance ([`tessellate`]);
//! scale to metres and turn the up axis ([`crate::units`]).
//!
//! Read: planes, spheres, cylinders, cones, tori, B-spline surfaces (rational ones as the
//! complex instance), Bézier, uniform and quasi-uniform surfaces, surfaces of revolution and
//! of linear extrusion; `ADVANCED_FACE` (and `FACE_SURFACE`, `ORIENTED_FACE`) with their
//! trimming loops; open and closed shells, solids (with voids), shell-based surface models;
//! products' names. Refused with an error naming the instance: any other surface
//! (`OFFSET_SURFACE`, `RECTANGULAR_TRIMMED_SURFACE`, ...), a reference to a missing
//! instance, a face that does not tessellate. Not applied: assembly placements
//! (`ITEM_DEFINED_TRANSFORMATION`); a file that has them gets a warning.

mod brep;
mod checks;
mod entities;
pub mod examples;
mod fallback;
mod structure;
mod tessellate;
pub mod write;

use std::path::Path;

use truck_stepio::r#in::ruststep;
use truck_stepio::r#in::Table;

use crate::units::{world_from_file, LengthUnit, UpAxis};
use crate::{Mesh, SceneError};
use entities::Entities;

/// truck divides a circle of radius r to a chord tolerance of at least this × r, and any
/// curve or surface to at least this (file units); it panics when asked for less. The
/// tolerance is also kept above this × the farthest point's coordinate.
const TRUCK_RELATIVE_TOLERANCE: f64 = 1.01e-6;

/// The tessellation's default chord tolerance: the most a triangle strays from its face.
pub const DEFAULT_TOLERANCE_MM: f64 = 0.05;

/// How to read a STEP file.
#[derive(Clone, Debug)]
pub struct StepOptions {
    /// One body (product, solid, surface model or shell, by name or `#id`); all when `None`.
    pub body: Option<String>,
    /// Chord tolerance of the tessellation, millimetres.
    pub tolerance_mm: f64,
    /// The file's length unit, overriding the one it states.
    pub unit: Option<LengthUnit>,
    pub up: UpAxis,
}

impl Default for StepOptions {
    fn default() -> Self {
        StepOptions {
            body: None,
            tolerance_mm: DEFAULT_TOLERANCE_MM,
            unit: None,
            up: UpAxis::Y,
        }
    }
}

/// A STEP file's bodies, one world-space mesh each, named after them.
#[derive(Debug)]
pub struct StepFile {
    pub meshes: Vec<Mesh>,
    pub warnings: Vec<String>,
    /// Faces the bodies' shells list, every one of them tessellated.
    pub faces: usize,
}

/// A STEP file as a scene: its bodies in the default grey, framed by the default camera and
/// lit by the default key light (all said in the scene's warnings).
pub fn load(path: &Path) -> Result<crate::Scene, SceneError> {
    let shown = path.display().to_string();
    let file = read(path, &StepOptions::default())?;
    let meshes = file.meshes;
    let mut scene =
        super::scene_from_meshes(&shown, meshes, vec![super::default_material()], vec![]);
    scene.warnings.extend(file.warnings);
    scene.finalize(&shown)?;
    Ok(scene)
}

/// Reads `path` (a `.step` or `.stp` file).
pub fn read(path: &Path, options: &StepOptions) -> Result<StepFile, SceneError> {
    let shown = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| SceneError::io(&shown, e))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        SceneError::invalid(
            &shown,
            format!(
                "not a STEP file: byte {} is not text (STEP files are ASCII)",
                e.utf8_error().valid_up_to()
            ),
        )
    })?;
    parse(&shown, &text, options)
}

/// Reads a STEP file's text; `shown` names it in messages.
pub fn parse(shown: &str, text: &str, options: &StepOptions) -> Result<StepFile, SceneError> {
    let invalid = |message: String| SceneError::invalid(shown, message);
    if !(options.tolerance_mm.is_finite() && options.tolerance_mm > 0.0) {
        return Err(invalid(format!(
            "tolerance_mm must be a positive number of millimetres, got {}",
            options.tolerance_mm
        )));
    }
    if !text.trim_start().starts_with("ISO-10303-21") {
        return Err(invalid(
            "not a STEP file: it does not begin with ISO-10303-21;".into(),
        ));
    }
    check_lexically(text).map_err(&invalid)?;
    // The check above keeps ruststep's parser from what made it panic; should a file still
    // find a panic in it, it becomes this file's error rather than a crash.
    let exchange = std::panic::catch_unwind(|| ruststep::parser::parse(text))
        .map_err(|_| {
            invalid(
                "the file broke the STEP parser (a malformed file the checks did not catch)".into(),
            )
        })?
        .map_err(|e| invalid(syntax_error(text, &e.to_string())))?;
    let entities = Entities::new(&exchange.data).map_err(&invalid)?;
    checks::check_geometry(&entities).map_err(&invalid)?;
    let mut table = Table::default();
    for (id, instance) in entities.instances() {
        table
            .push_instance(instance)
            .map_err(|e| invalid(format!("{}: {e}", entities.describe(id))))?;
    }
    let bodies = chosen_bodies(&entities, options).map_err(&invalid)?;
    let largest_radius = checks::largest_radius(&entities);
    let largest_coordinate = checks::largest_coordinate(&entities);
    let mut file = StepFile {
        meshes: vec![],
        warnings: vec![],
        faces: 0,
    };
    for body in &bodies {
        let metres_per_unit = match (options.unit, body.metres_per_unit) {
            (Some(unit), _) => unit.metres(),
            (None, Some(metres)) => metres,
            (None, None) => {
                file.warnings.push(format!(
                    "{shown}: body '{}' states no length unit; taken as millimetres (set unit = \"mm\"|\"cm\"|\"m\"|\"in\" on its shape to say)",
                    body.name
                ));
                LengthUnit::Mm.metres()
            }
        };
        let brep = brep::read_body(&entities, &table, &body.shells).map_err(&invalid)?;
        let faces: usize = brep.faces.iter().map(Vec::len).sum();
        file.warnings
            .extend(brep.warnings.iter().map(|w| format!("{shown}: {w}")));
        let asked = options.tolerance_mm * 1e-3 / metres_per_unit;
        let mm = |file_units: f64| file_units * metres_per_unit * 1e3;
        // The finest tolerance truck cuts curves to, and a part needs, with why.
        let floors = [
            (
                largest_radius,
                format!("its largest circle's radius, {:.0} mm", mm(largest_radius)),
            ),
            (
                largest_coordinate,
                format!(
                    "its farthest point's coordinate, {:.0} mm",
                    mm(largest_coordinate)
                ),
            ),
            (1.0, "a file unit".to_string()),
        ];
        let (floor, why) = floors
            .iter()
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(size, why)| (TRUCK_RELATIVE_TOLERANCE * size, why))
            .expect("three floors");
        let tolerance = asked.max(floor);
        if tolerance > asked {
            file.warnings.push(format!(
                "{shown}: body '{}': chord tolerance raised from {} mm to {:.4} mm, a millionth of {why}: truck cuts curves no finer",
                body.name,
                options.tolerance_mm,
                mm(tolerance)
            ));
        }
        let (mesh, mut face_warnings) = tessellate::tessellate(
            &entities,
            &body.name,
            brep,
            tolerance,
            world_from_file(metres_per_unit, options.up),
        )
        .map_err(&invalid)?;
        let tessellated = mesh.cad.as_ref().map_or(0, |cad| cad.faces.len());
        if tessellated != faces {
            return Err(invalid(format!(
                "body '{}': {faces} faces in, {tessellated} tessellated",
                body.name
            )));
        }
        file.warnings
            .extend(face_warnings.drain(..).map(|w| format!("{shown}: {w}")));
        file.faces += faces;
        file.meshes.push(mesh);
    }
    file.warnings.extend(unplaced_assembly(shown, &entities));
    Ok(file)
}

/// The file's bodies, or the one `options.body` names.
fn chosen_bodies(
    entities: &Entities,
    options: &StepOptions,
) -> Result<Vec<structure::Body>, String> {
    let mut bodies = structure::bodies(entities)?;
    if bodies.is_empty() {
        return Err(format!(
            "no solid, surface model or shell among its {} instances: nothing to draw",
            entities.len()
        ));
    }
    if let Some(wanted) = &options.body {
        let names: Vec<String> = bodies.iter().map(|b| b.name.clone()).collect();
        bodies.retain(|b| &b.name == wanted || b.aliases.contains(wanted));
        if bodies.is_empty() {
            return Err(format!(
                "no body named '{wanted}'; its bodies are: {}",
                names.join(", ")
            ));
        }
    }
    Ok(bodies)
}

/// A warning where the file places parts in an assembly: specula draws each part in its own
/// coordinates.
fn unplaced_assembly(shown: &str, entities: &Entities) -> Option<String> {
    let placements = entities
        .instances()
        .filter(|(id, _)| {
            entities
                .record(*id, "ITEM_DEFINED_TRANSFORMATION")
                .is_some()
        })
        .count();
    (placements > 0).then(|| {
        format!(
            "{shown}: an assembly with {placements} part placement(s) (ITEM_DEFINED_TRANSFORMATION); specula draws each part in its own coordinates, not placed. Export the parts as one part, or place them with one `step` shape each in a scene file"
        )
    })
}

/// What ruststep's parser would panic or overflow its stack on, refused with the line: an
/// integer, exponent or instance number of more than 18 digits (it parses them into an `i64`
/// with `expect`), lists nested deeper than 32 (it recurses once per level). Strings and
/// comments are skipped; a real's digits may be as many as they like.
fn check_lexically(text: &str) -> Result<(), String> {
    const MAX_DIGITS: usize = 18;
    const MAX_DEPTH: usize = 32;
    let bytes = text.as_bytes();
    let (mut line, mut depth, mut i) = (1, 0usize, 0);
    while i < bytes.len() {
        match bytes[i] {
            b'\n' => line += 1,
            b'\'' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'\'' {
                    line += usize::from(bytes[i] == b'\n');
                    i += 1;
                }
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i + 1 < bytes.len() && !(bytes[i] == b'*' && bytes[i + 1] == b'/') {
                    line += usize::from(bytes[i] == b'\n');
                    i += 1;
                }
                i += 1;
            }
            b'(' => {
                depth += 1;
                if depth > MAX_DEPTH {
                    return Err(format!("line {line}: parentheses nested deeper than {MAX_DEPTH}; no STEP entity nests so deep"));
                }
            }
            b')' => depth = depth.saturating_sub(1),
            b'0'..=b'9' => {
                let start = i;
                while i + 1 < bytes.len() && bytes[i + 1].is_ascii_digit() {
                    i += 1;
                }
                let fraction = start > 0 && bytes[start - 1] == b'.';
                let integral_of_real = bytes.get(i + 1) == Some(&b'.');
                if i + 1 - start > MAX_DIGITS && !fraction && !integral_of_real {
                    return Err(format!(
                        "line {line}: a whole number of {} digits, more than the {MAX_DIGITS} an integer, an exponent or an instance number may have",
                        i + 1 - start
                    ));
                }
            }
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

/// ruststep's message cut to what a user can act on: the line where parsing stopped.
fn syntax_error(text: &str, message: &str) -> String {
    let complete = text.contains("END-ISO-10303-21");
    let first = message
        .lines()
        .filter(|l| !l.trim().is_empty())
        .take(4)
        .collect::<Vec<_>>()
        .join(" | ");
    let first: String = first.chars().take(300).collect();
    if complete {
        format!("not a valid STEP exchange structure: {first}")
    } else {
        format!("the file is cut short (no END-ISO-10303-21;) or not a valid STEP exchange structure: {first}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loaders::step::write::{NurbsPatch, StepWriter};
    use glam::DVec2;
    use truck_stepio::r#in::alias::ParametricSurface;

    /// The grid fallback covers the same face as truck's tessellation: the same area within
    /// its stepped rim, every vertex on the surface, every kept triangle inside the loop.
    #[test]
    fn the_grid_fallback_covers_the_face_truck_tessellates() {
        let patch = NurbsPatch::sphere_region(50.0, (0.0, 1.2), 1, (-0.5, 0.5));
        let mut writer = StepWriter::new();
        let face = writer.patch_face(&patch);
        writer.body("patch", &[face], false);
        let text = writer.finish(LengthUnit::Mm);
        let exchange = ruststep::parser::parse(&text).unwrap();
        let entities = Entities::new(&exchange.data).unwrap();
        let mut table = Table::default();
        for (_, instance) in entities.instances() {
            table.push_instance(instance).unwrap();
        }
        let bodies = structure::bodies(&entities).unwrap();
        let brep = brep::read_body(&entities, &table, &bodies[0].shells).unwrap();
        let shell = &brep.shells[0];
        let boundaries: Vec<Vec<(usize, bool)>> = shell.faces[0]
            .boundaries
            .iter()
            .map(|wire| wire.iter().map(|e| (e.index, e.orientation)).collect())
            .collect();
        let surface = &shell.faces[0].surface.clone();
        let grid = fallback::grid_polygon(surface, &shell.edges, &boundaries, 0.05)
            .expect("the grid places the loop");
        let area = |uv: &[DVec2], triangles: &[[u32; 3]]| -> f64 {
            triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| {
                        let p = surface.subs(uv[i as usize].x, uv[i as usize].y);
                        glam::DVec3::new(p.x, p.y, p.z)
                    });
                    (b - a).cross(c - a).length() / 2.0
                })
                .sum()
        };
        let gridded = area(&grid.uv, &grid.triangles);
        let (mesh, warnings) =
            tessellate::tessellate(&entities, "patch", brep, 0.05, glam::DMat4::IDENTITY).unwrap();
        assert!(
            warnings.is_empty(),
            "truck tessellates this face: {warnings:?}"
        );
        let cad = mesh.cad.unwrap();
        let truck = area(&cad.uv, &mesh.triangles);
        // 1.2 rad of longitude by ±0.5 rad of latitude of a 50 mm sphere: 50² × 1.2 × 2 sin 0.5
        // = 2,876.7 mm². Measured: the grid's area differs from truck's by 2.6e-4 of it.
        let exact = 2500.0 * 1.2 * 2.0 * 0.5f64.sin();
        assert!(
            (truck - exact).abs() / exact < 1e-3,
            "truck {truck} mm², exact {exact}"
        );
        assert!(
            (gridded - truck).abs() / truck < 5e-4,
            "grid {gridded} mm², truck {truck} mm²"
        );
    }
}
