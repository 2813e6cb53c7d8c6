//! A body's faces, edges and vertices as truck's compressed shells, read with an error for
//! every face that cannot be read (truck's own `to_compressed_shell` drops such a face with a
//! line on stderr). Geometry is converted by truck (`Surface`, `Curve3D`); the topology walk is
//! ours, so that every missing or unsupported instance is named.

use std::collections::HashMap;

use truck_stepio::r#in::alias::{Curve3D, Invertible, Point3, Surface};
use truck_stepio::r#in::ruststep::ast::Name;
use truck_stepio::r#in::ruststep::tables::{EntityTable, IntoOwned, PlaceHolder};
use truck_stepio::r#in::{EdgeCurveHolder, SurfaceAnyHolder, Table, VertexPointHolder};
use truck_topology::compress::{
    CompressedEdge, CompressedEdgeIndex, CompressedFace, CompressedShell,
};

use super::entities::{field, list, logical, reference, Entities};
use super::structure::ShellRef;

/// The surface types truck converts; anything else as a face's geometry is named in an error.
const SURFACE_TYPES: [&str; 11] = [
    "PLANE",
    "SPHERICAL_SURFACE",
    "CYLINDRICAL_SURFACE",
    "CONICAL_SURFACE",
    "TOROIDAL_SURFACE",
    "B_SPLINE_SURFACE_WITH_KNOTS",
    "BEZIER_SURFACE",
    "UNIFORM_SURFACE",
    "QUASI_UNIFORM_SURFACE",
    "SURFACE_OF_LINEAR_EXTRUSION",
    "SURFACE_OF_REVOLUTION",
];

pub(super) type Shell = CompressedShell<Point3, Curve3D, Surface>;

/// One face read: its instance number and whether an `ORIENTED_FACE` (or a reversed shell)
/// turned it over.
#[derive(Clone, Copy, Debug)]
pub(super) struct FaceRef {
    pub entity: u64,
    pub reversed: bool,
}

/// A body's shells, read.
pub(super) struct BodyBrep {
    pub shells: Vec<Shell>,
    /// Per shell, its faces in the order of `shell.faces`.
    pub faces: Vec<Vec<FaceRef>>,
    /// What is wrong with a closed shell but does not stop it being drawn: its faces turned
    /// inconsistently (an edge run the same way by both its faces), which turns a glass
    /// solid's normals partly inwards.
    pub warnings: Vec<String>,
}

pub(super) fn read_body(
    entities: &Entities,
    table: &Table,
    shells: &[ShellRef],
) -> Result<BodyBrep, String> {
    let mut reader = Reader {
        entities,
        table,
        vertices: HashMap::new(),
        edges: HashMap::new(),
        shell: Shell {
            vertices: vec![],
            edges: vec![],
            faces: vec![],
        },
    };
    let mut brep = BodyBrep {
        shells: vec![],
        faces: vec![],
        warnings: vec![],
    };
    for shell in shells {
        let (kind, params) =
            entities.simple(shell.id, &["CLOSED_SHELL", "OPEN_SHELL"], shell.id)?;
        let mut faces = Vec::new();
        for face in field(entities, shell.id, params, 1, "a list of faces", list)? {
            let id = reference(face).ok_or_else(|| {
                format!(
                    "{}: a face that is not a reference",
                    entities.describe(shell.id)
                )
            })?;
            let mut face = reader.face(id, shell.id)?;
            face.reversed ^= shell.reversed;
            faces.push(face);
        }
        if kind == "CLOSED_SHELL" {
            brep.warnings
                .extend(turned_faces(entities, shell.id, &reader.shell, &faces));
        }
        brep.shells.push(std::mem::replace(
            &mut reader.shell,
            Shell {
                vertices: vec![],
                edges: vec![],
                faces: vec![],
            },
        ));
        reader.vertices.clear();
        reader.edges.clear();
        brep.faces.push(faces);
    }
    Ok(brep)
}

/// A warning where two faces of a closed shell run an edge the same way: one of them is
/// turned inside out (each edge of a consistently oriented closed shell is run once each way).
fn turned_faces(
    entities: &Entities,
    shell_id: u64,
    shell: &Shell,
    faces: &[FaceRef],
) -> Option<String> {
    let mut runs: HashMap<(usize, bool), Vec<u64>> = HashMap::new();
    for (face, face_ref) in shell.faces.iter().zip(faces) {
        for edge in face.boundaries.iter().flatten() {
            let forward = edge.orientation != face_ref.reversed;
            runs.entry((edge.index, forward))
                .or_default()
                .push(face_ref.entity);
        }
    }
    let clash = runs.values().find(|faces| faces.len() > 1)?;
    Some(format!(
        "{}: faces #{} and #{} run an edge the same way, so one of them is turned inside out (its normals point into the solid; glass would refract the wrong way there): check the faces' orientation in your CAD system",
        entities.describe(shell_id),
        clash[0],
        clash[1]
    ))
}

struct Reader<'a, 'e> {
    entities: &'a Entities<'e>,
    table: &'a Table,
    /// Instance number → index in `shell.vertices` / `shell.edges`.
    vertices: HashMap<u64, usize>,
    edges: HashMap<u64, usize>,
    shell: Shell,
}

impl Reader<'_, '_> {
    fn face(&mut self, id: u64, shell: u64) -> Result<FaceRef, String> {
        let entities = self.entities;
        let (kind, params) = entities.simple(
            id,
            &["ADVANCED_FACE", "FACE_SURFACE", "ORIENTED_FACE"],
            shell,
        )?;
        if kind == "ORIENTED_FACE" {
            let inner = field(entities, id, params, 2, "a face", reference)?;
            let orientation = field(entities, id, params, 3, ".T. or .F.", logical)?;
            let mut face = self.face(inner, id)?;
            face.reversed ^= !orientation;
            return Ok(face);
        }
        let surface_id = field(entities, id, params, 2, "a surface", reference)?;
        let same_sense = field(entities, id, params, 3, ".T. or .F.", logical)?;
        let mut surface = self.surface(surface_id, id)?;
        if !same_sense {
            surface.invert();
        }
        let mut boundaries = Vec::new();
        for bound in field(entities, id, params, 1, "a list of bounds", list)? {
            let bound = reference(bound).ok_or_else(|| {
                format!("{}: a bound that is not a reference", entities.describe(id))
            })?;
            if let Some(edges) = self.bound(bound, id)? {
                boundaries.push(edges);
            }
        }
        self.shell.faces.push(CompressedFace {
            surface,
            boundaries,
            orientation: true,
        });
        Ok(FaceRef {
            entity: id,
            reversed: false,
        })
    }

    fn surface(&self, id: u64, face: u64) -> Result<Surface, String> {
        let entities = self.entities;
        if !entities.contains(id) {
            return Err(format!(
                "{} refers to #{id}, which is not in the file",
                entities.describe(face)
            ));
        }
        let rational_b_spline = entities.record(id, "RATIONAL_B_SPLINE_SURFACE").is_some()
            || entities.record(id, "B_SPLINE_SURFACE").is_some();
        let name = entities.type_name(id);
        if !rational_b_spline && !SURFACE_TYPES.contains(&name.as_str()) {
            return Err(format!(
                "{} (the surface of {}) is a surface type specula cannot read; it reads {} and rational B-spline surfaces. Export the part with its surfaces as B-splines (most CAD systems have an option to convert offset and trimmed surfaces to NURBS)",
                entities.describe(id),
                entities.describe(face),
                SURFACE_TYPES.join(", ")
            ));
        }
        let any = PlaceHolder::<SurfaceAnyHolder>::Ref(Name::Entity(id))
            .into_owned(self.table)
            .map_err(|e| format!("{}: {e}", entities.describe(id)))?;
        Surface::try_from(&any).map_err(|e| format!("{}: {e}", entities.describe(id)))
    }

    /// A face bound's edges, in the order and sense truck's tessellation expects; `None` for a
    /// `VERTEX_LOOP`, a single point that trims nothing (a cone's apex, a sphere's pole).
    fn bound(&mut self, id: u64, face: u64) -> Result<Option<Vec<CompressedEdgeIndex>>, String> {
        let entities = self.entities;
        let (_, params) = entities.simple(id, &["FACE_OUTER_BOUND", "FACE_BOUND"], face)?;
        let loop_id = field(entities, id, params, 1, "a loop", reference)?;
        let orientation = field(entities, id, params, 2, ".T. or .F.", logical)?;
        let (kind, loop_params) = entities.simple(loop_id, &["EDGE_LOOP", "VERTEX_LOOP"], id)?;
        if kind == "VERTEX_LOOP" {
            return Ok(None);
        }
        let mut edges = Vec::new();
        for oriented in field(entities, loop_id, loop_params, 1, "a list of edges", list)? {
            let oriented = reference(oriented).ok_or_else(|| {
                format!(
                    "{}: an edge that is not a reference",
                    entities.describe(loop_id)
                )
            })?;
            let (_, edge_params) = entities.simple(oriented, &["ORIENTED_EDGE"], loop_id)?;
            let edge = field(entities, oriented, edge_params, 3, "an edge", reference)?;
            let sense = field(entities, oriented, edge_params, 4, ".T. or .F.", logical)?;
            edges.push(CompressedEdgeIndex {
                index: self.edge(edge, oriented)?,
                orientation: sense == orientation,
            });
        }
        if !orientation {
            edges.reverse();
        }
        Ok(Some(edges))
    }

    fn edge(&mut self, id: u64, referrer: u64) -> Result<usize, String> {
        if let Some(&index) = self.edges.get(&id) {
            return Ok(index);
        }
        let entities = self.entities;
        let (_, params) = entities.simple(id, &["EDGE_CURVE"], referrer)?;
        let start = self.vertex(field(entities, id, params, 1, "a vertex", reference)?, id)?;
        let end = self.vertex(field(entities, id, params, 2, "a vertex", reference)?, id)?;
        let curve_id = field(entities, id, params, 3, "a curve", reference)?;
        if !entities.contains(curve_id) {
            return Err(format!(
                "{} refers to #{curve_id}, which is not in the file",
                entities.describe(id)
            ));
        }
        let edge = EntityTable::<EdgeCurveHolder>::get_owned(self.table, id)
            .map_err(|e| format!("{}: {e}", entities.describe(id)))?;
        let curve = edge.parse_curve3d().map_err(|e| {
            format!(
                "{} (its curve {}): {e}",
                entities.describe(id),
                entities.describe(curve_id)
            )
        })?;
        self.shell.edges.push(CompressedEdge {
            vertices: (start, end),
            curve,
        });
        self.edges.insert(id, self.shell.edges.len() - 1);
        Ok(self.shell.edges.len() - 1)
    }

    fn vertex(&mut self, id: u64, edge: u64) -> Result<usize, String> {
        if let Some(&index) = self.vertices.get(&id) {
            return Ok(index);
        }
        let entities = self.entities;
        let (_, params) = entities.simple(id, &["VERTEX_POINT"], edge)?;
        let point = field(entities, id, params, 1, "a point", reference)?;
        entities.simple(point, &["CARTESIAN_POINT"], id)?;
        let vertex = EntityTable::<VertexPointHolder>::get_owned(self.table, id)
            .map_err(|e| format!("{}: {e}", entities.describe(id)))?;
        self.shell
            .vertices
            .push(Point3::from(&vertex.vertex_geometry));
        self.vertices.insert(id, self.shell.vertices.len() - 1);
        Ok(self.shell.vertices.len() - 1)
    }
}
