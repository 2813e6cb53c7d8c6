//! The registry: every method specula can run, in the order reports list them. A new technique
//! adds its `INFO` here and nowhere else; the CLI, reports, `specula methods` and the viewer's
//! controls all read this table.

use crate::technique::{MethodInfo, Technique, TechniqueError};

/// Every registered method: the exact reference first, then the techniques.
pub static METHODS: &[&MethodInfo] = &[
    &crate::reference::INFO,
    &crate::gpu_trace::INFO,
    &crate::envmap::INFO,
    &crate::pvrr::INFO,
    &crate::distance_maps::INFO,
    &crate::image_space::INFO,
    &crate::c3rc::INFO,
    &crate::vertex_tracing::INFO,
];

/// The registered method called `name`.
pub fn method(name: &str) -> Result<&'static MethodInfo, TechniqueError> {
    METHODS
        .iter()
        .copied()
        .find(|m| m.name == name)
        .ok_or_else(|| TechniqueError::UnknownMethod {
            name: name.to_string(),
            valid: METHODS
                .iter()
                .map(|m| m.name)
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// A new, unprepared technique by name.
pub fn by_name(name: &str) -> Result<Box<dyn Technique>, TechniqueError> {
    Ok((method(name)?.create)())
}

/// The names of the methods that are not exact (what `compare` and `bench` run by default).
pub fn approximate_methods() -> Vec<String> {
    METHODS
        .iter()
        .filter(|m| !m.exact)
        .map(|m| m.name.to_string())
        .collect()
}

/// The first registered exact method: the reference others are compared against.
pub fn exact_method() -> &'static MethodInfo {
    METHODS
        .iter()
        .copied()
        .find(|m| m.exact)
        .expect("the registry holds an exact method")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::SurfaceClass;

    #[test]
    fn delegations_name_registered_methods_that_shade_the_class_themselves() {
        for info in METHODS {
            for class in SurfaceClass::ALL {
                let count = info
                    .delegates
                    .iter()
                    .filter(|d| d.material == class)
                    .count();
                assert!(count <= 1, "{}: {count} delegations of {class}", info.name);
            }
            for d in info.delegates {
                let delegate = method(d.to).unwrap();
                assert_ne!(delegate.name, info.name);
                assert!(!info.exact, "{}: an exact method delegates", info.name);
                // No chains: the delegate's figure on those pixels is its own.
                assert_eq!(delegate.delegate_for(d.material), None, "{}", info.name);
            }
        }
        // What the code does (module docs): c3rc shades refractors as envmap does.
        let c3rc = method("c3rc").unwrap();
        assert_eq!(c3rc.delegate_for(SurfaceClass::Refractor), Some("envmap"));
        assert_eq!(c3rc.delegate_for(SurfaceClass::Mirror), None);
    }
}
