//! Warnings for sizes that point at a wrong length unit. Mesh files carry no unit and CAD tools
//! export millimetres, so a 200 mm mirror read as metres loads silently as a 200 m one and every
//! analysis of it is nonsense; these say so, and what to do, without refusing the scene.

use crate::{Aabb, MaterialKind, Mesh, Scene};

/// Larger than any mirror or lens a scene models (a truck's mirror is under 0.5 m).
const LARGEST_OPTIC_M: f32 = 5.0;
/// Smaller than any mirror or lens a scene models (a contact lens is about 10 mm).
const SMALLEST_OPTIC_M: f32 = 1e-3;
/// A mesh file read as metres that spans more than this is more likely in millimetres.
const LARGEST_UNITLESS_FILE_M: f32 = 5.0;

/// One warning per mirror or glass object (its meshes by name, together) whose largest extent
/// is implausible for an optical part.
pub(crate) fn optic_size_warnings(scene: &Scene, source: &str) -> Vec<String> {
    let mut optics: Vec<(&str, &'static str, Aabb)> = Vec::new();
    for mesh in &scene.meshes {
        let what = match scene.materials[mesh.material].kind {
            MaterialKind::Mirror { .. } => "mirror",
            MaterialKind::Dielectric { .. } => "glass",
            MaterialKind::Diffuse | MaterialKind::Unlit => continue,
        };
        match optics.iter_mut().find(|(name, ..)| *name == mesh.name) {
            Some((_, _, bounds)) => *bounds = bounds.union(&mesh.bounds()),
            None => optics.push((&mesh.name, what, mesh.bounds())),
        }
    }
    optics
        .into_iter()
        .filter_map(|(name, what, bounds)| {
            let size = bounds.extent().max_element();
            let advice = if size > LARGEST_OPTIC_M {
                format!(
                    "a mirror or lens over {LARGEST_OPTIC_M} m is implausible: if its file is in \
                     millimetres, place it with unit = \"mm\" in a scene file"
                )
            } else if size < SMALLEST_OPTIC_M {
                format!(
                    "a mirror or lens under {} mm is implausible: check the unit and scale that \
                     place it (unit = \"mm\" is for a file in millimetres)",
                    SMALLEST_OPTIC_M * 1e3
                )
            } else {
                return None;
            };
            Some(format!(
                "{source}: {what} '{name}' is {} m across; {advice}",
                three_figures(size)
            ))
        })
        .collect()
}

/// The warning for meshes read from `shown`, a file that gives no unit, when together they span
/// more than a file in metres plausibly does.
pub(crate) fn unitless_file_warning(shown: &str, meshes: &[Mesh]) -> Option<String> {
    let size = meshes
        .iter()
        .fold(Aabb::EMPTY, |b, m| b.union(&m.bounds()))
        .extent()
        .max_element();
    (size > LARGEST_UNITLESS_FILE_M).then(|| {
        format!(
            "{shown}: the mesh is {} m across, read as metres since a mesh file gives no unit; \
             its units look like millimetres: if so, place it with unit = \"mm\" in a scene \
             file's mesh shape (or with fit = its size in metres, if its units are arbitrary)",
            three_figures(size)
        )
    })
}

/// `x` to three significant figures, without an exponent (sizes from microns to kilometres).
fn three_figures(x: f32) -> String {
    let decimals = (2.0 - x.abs().log10().floor()).clamp(0.0, 9.0) as usize;
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::three_figures;

    #[test]
    fn sizes_print_to_three_significant_figures() {
        assert_eq!(three_figures(199.99998), "200");
        assert_eq!(three_figures(1392.855), "1393");
        assert_eq!(three_figures(0.2), "0.200");
        assert_eq!(three_figures(0.000_234_5), "0.000234");
    }
}
