//! What a file holds, above its faces: its bodies (solids and surface models, named after the
//! products they belong to) and their length unit.
//!
//! A body is a `MANIFOLD_SOLID_BREP`, `BREP_WITH_VOIDS` or `SHELL_BASED_SURFACE_MODEL`; a shell
//! that no body holds is a body of its own. A product's shape reaches its bodies through
//! `SHAPE_DEFINITION_REPRESENTATION` → representation, and through
//! `SHAPE_REPRESENTATION_RELATIONSHIP` to the B-rep representation CAD systems hang beside
//! it. The length unit is the `LENGTH_UNIT` in the `GLOBAL_UNIT_ASSIGNED_CONTEXT` of the
//! body's representation: an `SI_UNIT` with its prefix, or a `CONVERSION_BASED_UNIT` (the
//! inch: `LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4), <millimetre>)`).

use std::collections::{HashMap, HashSet};

use super::entities::{enumeration, field, list, real, reference, text, Entities};

/// A shell of a body; `reversed` for an `ORIENTED_CLOSED_SHELL` turned inside out.
#[derive(Clone, Copy, Debug)]
pub(super) struct ShellRef {
    pub id: u64,
    pub reversed: bool,
}

#[derive(Clone, Debug)]
pub(super) struct Body {
    /// The instance that is the body (solid, surface model or lone shell).
    pub id: u64,
    pub name: String,
    /// Names a user may select it by with `body`: its own label, its product's name, `#id`.
    pub aliases: Vec<String>,
    pub shells: Vec<ShellRef>,
    /// Metres per file unit, from its representation's context; `None` where the file says none.
    pub metres_per_unit: Option<f64>,
}

const BODY_TYPES: [&str; 3] = [
    "MANIFOLD_SOLID_BREP",
    "BREP_WITH_VOIDS",
    "SHELL_BASED_SURFACE_MODEL",
];
const SHELL_TYPES: [&str; 4] = [
    "CLOSED_SHELL",
    "OPEN_SHELL",
    "ORIENTED_CLOSED_SHELL",
    "ORIENTED_OPEN_SHELL",
];

/// Every body of the file, in the order of their instance numbers.
pub(super) fn bodies(entities: &Entities) -> Result<Vec<Body>, String> {
    let owners = representation_of_items(entities);
    let products = product_of_representations(entities);
    let mut bodies = Vec::new();
    let mut held_shells = HashSet::new();
    let mut ids: Vec<u64> = BODY_TYPES
        .iter()
        .flat_map(|t| entities.of_type(t))
        .collect();
    ids.sort_unstable();
    for id in ids {
        let (kind, params) = entities.simple(id, &BODY_TYPES, id)?;
        let label = field(entities, id, params, 0, "a name", text)?.to_string();
        let shells = body_shells(entities, id, kind, params)?;
        held_shells.extend(shells.iter().map(|s| s.id));
        let representation = owners.get(&id).copied();
        let product = representation.and_then(|r| products.get(&r).cloned());
        let metres_per_unit = match representation {
            Some(r) => representation_unit(entities, r)?,
            None => None,
        };
        bodies.push(Body {
            id,
            name: String::new(),
            aliases: [Some(label), product, Some(format!("#{id}"))]
                .into_iter()
                .flatten()
                .filter(|a| !a.trim().is_empty())
                .collect(),
            shells,
            metres_per_unit,
        });
    }
    for kind in ["CLOSED_SHELL", "OPEN_SHELL"] {
        for id in entities.of_type(kind) {
            if held_shells.contains(&id) {
                continue;
            }
            let (_, params) = entities.simple(id, &SHELL_TYPES, id)?;
            let label = field(entities, id, params, 0, "a name", text)?.to_string();
            bodies.push(Body {
                id,
                name: String::new(),
                aliases: [label, format!("#{id}")]
                    .into_iter()
                    .filter(|a| !a.trim().is_empty())
                    .collect(),
                shells: vec![ShellRef {
                    id,
                    reversed: false,
                }],
                metres_per_unit: None,
            });
        }
    }
    name_bodies(&mut bodies, &products, &owners);
    Ok(bodies)
}

/// A body's name: its product's name where the product has this one body, else its own
/// label, else `#id`; names made unique with the instance number.
fn name_bodies(bodies: &mut [Body], products: &HashMap<u64, String>, owners: &HashMap<u64, u64>) {
    let mut per_product: HashMap<String, usize> = HashMap::new();
    let product_of = |body: &Body| owners.get(&body.id).and_then(|r| products.get(r)).cloned();
    for body in bodies.iter() {
        if let Some(product) = product_of(body) {
            *per_product.entry(product).or_default() += 1;
        }
    }
    for body in bodies.iter_mut() {
        let label = body.aliases.first().cloned().unwrap_or_default();
        body.name = match product_of(body) {
            Some(product) if per_product[&product] == 1 && !product.trim().is_empty() => product,
            _ if !label.trim().is_empty() && !label.starts_with('#') => label,
            _ => format!("#{}", body.id),
        };
    }
    let mut seen: HashMap<String, usize> = HashMap::new();
    for body in bodies.iter() {
        *seen.entry(body.name.clone()).or_default() += 1;
    }
    for body in bodies.iter_mut() {
        if seen[&body.name] > 1 {
            body.name = format!("{} #{}", body.name, body.id);
        }
    }
}

fn body_shells(
    entities: &Entities,
    id: u64,
    kind: &str,
    params: &[truck_stepio::r#in::ruststep::ast::Parameter],
) -> Result<Vec<ShellRef>, String> {
    let refs: Vec<u64> = match kind {
        "SHELL_BASED_SURFACE_MODEL" => field(entities, id, params, 1, "a list of shells", list)?
            .iter()
            .filter_map(reference)
            .collect(),
        "BREP_WITH_VOIDS" => {
            let mut shells = vec![field(entities, id, params, 1, "a shell", reference)?];
            shells.extend(
                field(entities, id, params, 2, "a list of voids", list)?
                    .iter()
                    .filter_map(reference),
            );
            shells
        }
        _ => vec![field(entities, id, params, 1, "a shell", reference)?],
    };
    refs.into_iter()
        .map(|shell| shell_ref(entities, shell, id))
        .collect()
}

/// A shell, looking through `ORIENTED_*_SHELL` to the shell it turns.
fn shell_ref(entities: &Entities, id: u64, referrer: u64) -> Result<ShellRef, String> {
    let (kind, params) = entities.simple(id, &SHELL_TYPES, referrer)?;
    if !kind.starts_with("ORIENTED") {
        return Ok(ShellRef {
            id,
            reversed: false,
        });
    }
    let inner = field(entities, id, params, 2, "a shell", reference)?;
    let orientation = field(
        entities,
        id,
        params,
        3,
        ".T. or .F.",
        super::entities::logical,
    )?;
    let turned = shell_ref(entities, inner, id)?;
    // Reversed when exactly one of the two turns it: the inner shell's own, or this one's .F..
    Ok(ShellRef {
        id: turned.id,
        reversed: turned.reversed == orientation,
    })
}

/// For each representation item, the representation that lists it.
fn representation_of_items(entities: &Entities) -> HashMap<u64, u64> {
    let mut owners = HashMap::new();
    for (id, _) in entities.instances() {
        for name in [
            "ADVANCED_BREP_SHAPE_REPRESENTATION",
            "MANIFOLD_SURFACE_SHAPE_REPRESENTATION",
            "SHAPE_REPRESENTATION",
        ] {
            if let Some(items) = entities
                .record(id, name)
                .and_then(|p| p.get(1))
                .and_then(list)
            {
                for item in items.iter().filter_map(reference) {
                    owners.entry(item).or_insert(id);
                }
            }
        }
    }
    owners
}

/// For each representation, the name of the product whose shape it is: directly
/// (`SHAPE_DEFINITION_REPRESENTATION`) or through a `SHAPE_REPRESENTATION_RELATIONSHIP`
/// without a transformation (CAD systems put the B-rep beside the product's shape that way).
fn product_of_representations(entities: &Entities) -> HashMap<u64, String> {
    let mut products = HashMap::new();
    for id in entities.of_type("SHAPE_DEFINITION_REPRESENTATION") {
        let params = entities
            .record(id, "SHAPE_DEFINITION_REPRESENTATION")
            .unwrap_or_default();
        let (Some(shape), Some(representation)) = (
            params.first().and_then(reference),
            params.get(1).and_then(reference),
        ) else {
            continue;
        };
        if let Some(name) = product_name(entities, shape) {
            products.insert(representation, name);
        }
    }
    for id in entities.of_type("SHAPE_REPRESENTATION_RELATIONSHIP") {
        let params = entities
            .record(id, "SHAPE_REPRESENTATION_RELATIONSHIP")
            .unwrap_or_default();
        let (Some(a), Some(b)) = (
            params.get(2).and_then(reference),
            params.get(3).and_then(reference),
        ) else {
            continue;
        };
        match (products.get(&a).cloned(), products.get(&b).cloned()) {
            (Some(name), None) => {
                products.insert(b, name);
            }
            (None, Some(name)) => {
                products.insert(a, name);
            }
            _ => {}
        }
    }
    products
}

/// PRODUCT_DEFINITION_SHAPE → PRODUCT_DEFINITION → its formation → PRODUCT's name (or id).
fn product_name(entities: &Entities, shape: u64) -> Option<String> {
    let definition = entities
        .record(shape, "PRODUCT_DEFINITION_SHAPE")?
        .get(2)
        .and_then(reference)?;
    let formation = entities
        .record(definition, "PRODUCT_DEFINITION")?
        .get(2)
        .and_then(reference)?;
    let formation_params = entities
        .record(formation, "PRODUCT_DEFINITION_FORMATION")
        .or_else(|| {
            entities.record(
                formation,
                "PRODUCT_DEFINITION_FORMATION_WITH_SPECIFIED_SOURCE",
            )
        })?;
    let product = entities.record(formation_params.get(2).and_then(reference)?, "PRODUCT")?;
    let name = product
        .get(1)
        .and_then(text)
        .filter(|n| !n.trim().is_empty());
    name.or_else(|| product.first().and_then(text))
        .map(str::to_string)
}

/// Metres per unit of a representation's context, `None` where it has no length unit.
fn representation_unit(entities: &Entities, representation: u64) -> Result<Option<f64>, String> {
    let context = [
        "ADVANCED_BREP_SHAPE_REPRESENTATION",
        "MANIFOLD_SURFACE_SHAPE_REPRESENTATION",
        "SHAPE_REPRESENTATION",
    ]
    .iter()
    .find_map(|name| entities.record(representation, name))
    .and_then(|p| p.get(2))
    .and_then(reference);
    let Some(context) = context else {
        return Ok(None);
    };
    let Some(units) = entities
        .record(context, "GLOBAL_UNIT_ASSIGNED_CONTEXT")
        .and_then(|p| p.first())
        .and_then(list)
    else {
        return Ok(None);
    };
    for unit in units.iter().filter_map(reference) {
        if entities.record(unit, "LENGTH_UNIT").is_some() {
            return length_unit_metres(entities, unit, 0).map(Some);
        }
    }
    Ok(None)
}

/// Metres in one `unit`: an SI metre with its prefix, or a conversion-based unit's factor
/// times the unit it is given in.
fn length_unit_metres(entities: &Entities, unit: u64, depth: usize) -> Result<f64, String> {
    if depth > 8 {
        return Err(format!(
            "{}: length units refer to each other in a loop",
            entities.describe(unit)
        ));
    }
    if let Some(si) = entities.record(unit, "SI_UNIT") {
        if si.get(1).and_then(enumeration) != Some("METRE") {
            return Err(format!(
                "{}: a length unit that is not the metre",
                entities.describe(unit)
            ));
        }
        let prefix = si.first().and_then(enumeration).unwrap_or("");
        return si_prefix(prefix)
            .ok_or_else(|| format!("{}: unknown SI prefix .{prefix}.", entities.describe(unit)));
    }
    if let Some(conversion) = entities.record(unit, "CONVERSION_BASED_UNIT") {
        let measure = conversion
            .get(1)
            .and_then(reference)
            .ok_or_else(|| format!("{}: no conversion factor", entities.describe(unit)))?;
        let params = entities
            .record(measure, "LENGTH_MEASURE_WITH_UNIT")
            .or_else(|| entities.record(measure, "MEASURE_WITH_UNIT"))
            .ok_or_else(|| {
                format!(
                    "{}: its factor {} is not a length measure",
                    entities.describe(unit),
                    entities.describe(measure)
                )
            })?;
        let factor = params
            .first()
            .and_then(real)
            .filter(|f| f.is_finite() && *f > 0.0);
        let base = params.get(1).and_then(reference);
        return match (factor, base) {
            (Some(factor), Some(base)) => {
                Ok(factor * length_unit_metres(entities, base, depth + 1)?)
            }
            _ => Err(format!(
                "{}: a conversion factor needs a positive number and a unit",
                entities.describe(measure)
            )),
        };
    }
    Err(format!(
        "{}: a length unit that is neither an SI_UNIT nor a CONVERSION_BASED_UNIT",
        entities.describe(unit)
    ))
}

fn si_prefix(prefix: &str) -> Option<f64> {
    Some(match prefix {
        "" => 1.0,
        "KILO" => 1e3,
        "HECTO" => 1e2,
        "DECA" => 1e1,
        "DECI" => 1e-1,
        "CENTI" => 1e-2,
        "MILLI" => 1e-3,
        "MICRO" => 1e-6,
        "NANO" => 1e-9,
        _ => return None,
    })
}
