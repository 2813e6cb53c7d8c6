//! The data section as a table of entity instances by number, with the accessors the reader
//! needs and the words its errors use: every message about an instance names it as
//! `#123 = OFFSET_SURFACE`.

use std::collections::HashMap;

use truck_stepio::r#in::ruststep::ast::{DataSection, EntityInstance, Name, Parameter, Record};

pub(super) struct Entities<'a> {
    by_id: HashMap<u64, &'a EntityInstance>,
}

impl<'a> Entities<'a> {
    /// All instances of the file's data sections; a number given twice is an error.
    pub fn new(sections: &'a [DataSection]) -> Result<Self, String> {
        let mut by_id = HashMap::new();
        for instance in sections.iter().flat_map(|s| &s.entities) {
            let id = match instance {
                EntityInstance::Simple { id, .. } | EntityInstance::Complex { id, .. } => *id,
            };
            if by_id.insert(id, instance).is_some() {
                return Err(format!("#{id} is defined twice"));
            }
        }
        Ok(Entities { by_id })
    }

    pub fn instances(&self) -> impl Iterator<Item = (u64, &'a EntityInstance)> + '_ {
        self.by_id.iter().map(|(&id, &instance)| (id, instance))
    }

    pub fn len(&self) -> usize {
        self.by_id.len()
    }

    /// The instance's type: its record's name, or a complex instance's names in parentheses.
    pub fn type_name(&self, id: u64) -> String {
        match self.by_id.get(&id) {
            Some(EntityInstance::Simple { record, .. }) => record.name.clone(),
            Some(EntityInstance::Complex { subsuper, .. }) => format!(
                "({})",
                subsuper
                    .0
                    .iter()
                    .map(|r| r.name.as_str())
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
            None => "(missing)".into(),
        }
    }

    /// `#123 = OFFSET_SURFACE`, as messages name an instance.
    pub fn describe(&self, id: u64) -> String {
        format!("#{id} = {}", self.type_name(id))
    }

    /// The parameters of `id`, a simple instance of one of `types`; `referrer` is who pointed
    /// at it, for the message when it is missing or of another type.
    pub fn simple(
        &self,
        id: u64,
        types: &[&str],
        referrer: u64,
    ) -> Result<(&'a str, &'a [Parameter]), String> {
        match self.by_id.get(&id) {
            None => Err(format!(
                "{} refers to #{id}, which is not in the file",
                self.describe(referrer)
            )),
            Some(EntityInstance::Simple { record, .. })
                if types.contains(&record.name.as_str()) =>
            {
                Ok((record.name.as_str(), parameters(record)))
            }
            Some(_) => Err(format!(
                "{} refers to {}, where specula reads {}",
                self.describe(referrer),
                self.describe(id),
                types.join(" or ")
            )),
        }
    }

    /// The parameters of record `name` of instance `id`, simple or complex.
    pub fn record(&self, id: u64, name: &str) -> Option<&'a [Parameter]> {
        match self.by_id.get(&id)? {
            EntityInstance::Simple { record, .. } => {
                (record.name == name).then(|| parameters(record))
            }
            EntityInstance::Complex { subsuper, .. } => {
                subsuper.0.iter().find(|r| r.name == name).map(parameters)
            }
        }
    }

    pub fn contains(&self, id: u64) -> bool {
        self.by_id.contains_key(&id)
    }

    /// The ids of the simple instances of `name`, in file order of their numbers.
    pub fn of_type(&self, name: &str) -> Vec<u64> {
        let mut ids: Vec<u64> = self
            .by_id
            .iter()
            .filter(|(_, instance)| {
                matches!(instance, EntityInstance::Simple { record, .. } if record.name == name)
            })
            .map(|(&id, _)| id)
            .collect();
        ids.sort_unstable();
        ids
    }
}

fn parameters(record: &Record) -> &[Parameter] {
    match &record.parameter {
        Parameter::List(list) => list,
        other => std::slice::from_ref(other),
    }
}

pub(super) fn reference(p: &Parameter) -> Option<u64> {
    match p {
        Parameter::Ref(Name::Entity(id)) => Some(*id),
        _ => None,
    }
}

pub(super) fn list(p: &Parameter) -> Option<&[Parameter]> {
    match p {
        Parameter::List(items) => Some(items),
        _ => None,
    }
}

pub(super) fn text(p: &Parameter) -> Option<&str> {
    match p {
        Parameter::String(s) => Some(s),
        _ => None,
    }
}

pub(super) fn logical(p: &Parameter) -> Option<bool> {
    match p {
        Parameter::Enumeration(e) if e == "T" || e == "TRUE" => Some(true),
        Parameter::Enumeration(e) if e == "F" || e == "FALSE" => Some(false),
        _ => None,
    }
}

pub(super) fn enumeration(p: &Parameter) -> Option<&str> {
    match p {
        Parameter::Enumeration(e) => Some(e),
        _ => None,
    }
}

/// A number, also inside a typed measure such as `LENGTH_MEASURE(25.4)`.
pub(super) fn real(p: &Parameter) -> Option<f64> {
    match p {
        Parameter::Real(x) => Some(*x),
        Parameter::Integer(i) => Some(*i as f64),
        Parameter::Typed { parameter, .. } => real(parameter),
        _ => None,
    }
}

/// Parameter `index` of `params` read by `read`, or a message naming the instance, the
/// parameter's position and what it should be.
pub(super) fn field<'p, T>(
    entities: &Entities,
    id: u64,
    params: &'p [Parameter],
    index: usize,
    what: &str,
    read: impl Fn(&'p Parameter) -> Option<T>,
) -> Result<T, String> {
    params.get(index).and_then(read).ok_or_else(|| {
        format!(
            "{}: parameter {} should be {what}",
            entities.describe(id),
            index + 1
        )
    })
}
