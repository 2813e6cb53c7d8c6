//! The registry: every method specula can run, in the order reports list them. A technique is
//! registered by one line of the crate root's [`techniques!`] list, which declares its module
//! and lists its `INFO` in [`METHODS`](crate::METHODS); the CLI, reports, `specula methods` and
//! the viewer's controls all read that table.

use specula_core::{MethodInfo, Technique, TechniqueError};

use crate::METHODS;

/// Declares each technique's module (`pub mod NAME;`, whose `INFO` describes it) and lists them
/// all, in order, as `METHODS`: first the techniques, each a folder `NAME/` with its `mod.rs`,
/// then the test-only ones (`#[cfg(test)]`), each one file `NAME.rs`. For the tests it lists
/// the techniques' `mod.rs` sources too, as `MODULE_SOURCES`.
macro_rules! techniques {
    ($($module:ident,)* $(#[cfg(test)] $test_only:ident,)*) => {
        $(pub mod $module;)*
        $(#[cfg(test)] pub mod $test_only;)*

        /// Every registered method: the exact reference first, then the techniques.
        pub static METHODS: &[&specula_core::MethodInfo] =
            &[$(&$module::INFO,)* $(#[cfg(test)] &$test_only::INFO,)*];

        /// Each technique's `INFO`, its module's path in the crate's `src` and that source, whose
        /// top doc the registry's tests read (the test-only ones have no such doc).
        #[cfg(test)]
        pub(crate) const MODULE_SOURCES: &[(&specula_core::MethodInfo, &str, &str)] = &[$((
            &$module::INFO,
            concat!(stringify!($module), "/mod.rs"),
            include_str!(concat!(stringify!($module), "/mod.rs")),
        ),)*];
    };
}
pub(crate) use techniques;

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

/// The seed techniques: each has a `paper` preset, held by a test to the "Beyond the paper"
/// list of its module's top doc.
pub const SEED_TECHNIQUES: &[&str] = &[
    "pvrr",
    "distance-maps",
    "c3rc",
    "image-space",
    "vertex-tracing",
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MODULE_SOURCES;
    use specula_core::lifecycle::GpuTechnique;
    use specula_core::raster::RasterSpec;
    use specula_core::{ParamSet, ParamValue, SurfaceClass};

    /// The lines that open and close the parameter table of a module's top doc.
    const TABLE_BEGIN: &str = "//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;\n//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->\n";
    const TABLE_END: &str = "//! <!-- end of the parameter table -->\n";

    /// Every technique's module doc holds the table its parameter declarations make, as they
    /// are now (`SPECULA_REGENERATE=1` writes it again).
    #[test]
    fn every_module_doc_holds_its_parameter_table() {
        let regenerate = std::env::var_os("SPECULA_REGENERATE").is_some();
        let mut stale = Vec::new();
        for (info, path, source) in MODULE_SOURCES {
            let begin = source
                .find(TABLE_BEGIN)
                .unwrap_or_else(|| panic!("{path}: no table"));
            let start = begin + TABLE_BEGIN.len();
            let end = start + source[start..].find(TABLE_END).expect("the table closes");
            let table = specula_core::params::doc_table(info.params);
            if source[start..end] == table {
                continue;
            }
            if regenerate {
                let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("src")
                    .join(path);
                let written = format!("{}{table}{}", &source[..start], &source[end..]);
                std::fs::write(&file, written).unwrap();
            } else {
                stale.push(*path);
            }
        }
        assert!(
            stale.is_empty(),
            "parameter tables out of date in {stale:?}: run SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc"
        );
        // Every method has its source listed (the test-only toy has no module doc table).
        for info in METHODS.iter().filter(|m| m.name != "toy-normals") {
            assert!(
                MODULE_SOURCES.iter().any(|(i, ..)| i.name == info.name),
                "{}",
                info.name
            );
        }
    }

    /// Each seed technique's name and module source, whose top doc is read: every one of
    /// [`SEED_TECHNIQUES`], in that order.
    fn seed_sources() -> Vec<(&'static str, &'static str)> {
        let sources: Vec<_> = SEED_TECHNIQUES
            .iter()
            .filter_map(|name| {
                let (.., source) = MODULE_SOURCES.iter().find(|(i, ..)| i.name == *name)?;
                Some((*name, *source))
            })
            .collect();
        assert_eq!(
            sources.len(),
            SEED_TECHNIQUES.len(),
            "a seed technique's source"
        );
        sources
    }

    /// The module's top doc, one string per line (the `//!` stripped).
    fn top_doc(source: &str) -> Vec<&str> {
        source
            .lines()
            .map_while(|l| l.strip_prefix("//!"))
            .map(|l| l.strip_prefix(' ').unwrap_or(l))
            .collect()
    }

    /// The items of the doc's "Beyond the paper" list: from the line starting so to the first
    /// empty line, one string per `- ` item (its lines joined).
    fn beyond_the_paper(doc: &[&str]) -> Vec<String> {
        let start = doc
            .iter()
            .position(|l| l.starts_with("Beyond the paper"))
            .expect("the top doc has a \"Beyond the paper\" list");
        let mut items: Vec<String> = Vec::new();
        for line in doc[start + 1..].iter().take_while(|l| !l.trim().is_empty()) {
            match line.strip_prefix("- ") {
                Some(item) => items.push(item.to_string()),
                None => {
                    let last = items.last_mut().expect("the list starts with an item");
                    last.push(' ');
                    last.push_str(line.trim());
                }
            }
        }
        items
    }

    /// The settings named in `(paper: `A=1`, `B=2`)` markers of `text`.
    fn paper_markers(text: &str) -> Vec<String> {
        let mut settings = Vec::new();
        let mut rest = text;
        while let Some(at) = rest.find("(paper: ") {
            let marker = &rest[at..];
            let end = marker.find(')').expect("a (paper: marker closes");
            settings.extend(
                marker[..end]
                    .split('`')
                    .skip(1)
                    .step_by(2)
                    .map(str::to_string),
            );
            rest = &marker[end..];
        }
        settings
    }

    #[test]
    fn every_step_beyond_the_paper_is_switched_off_by_the_paper_preset() {
        for (name, source) in seed_sources() {
            let info = method(name).unwrap();
            let preset = info
                .preset("paper")
                .unwrap_or_else(|| panic!("{name} has no paper preset"));
            let doc = top_doc(source);
            let items = beyond_the_paper(&doc);
            assert!(!items.is_empty(), "{name}: an empty Beyond the paper list");
            for item in &items {
                let switches = paper_markers(item);
                assert!(
                    !switches.is_empty(),
                    "{name}: this step beyond the paper names no (paper: `NAME=VALUE`) \
                     switch: {item}"
                );
                for switch in &switches {
                    assert!(
                        preset.settings.contains(&switch.as_str()),
                        "{name}: the paper preset lacks {switch}, which switches off: {item}"
                    );
                    let (param, value) = switch.split_once('=').expect("NAME=VALUE");
                    let spec = info
                        .param(param)
                        .unwrap_or_else(|| panic!("{name}: no parameter {param}"));
                    // The step runs by default and the preset turns it off.
                    assert_ne!(
                        spec.parse(info.name, value).unwrap(),
                        spec.parse(info.name, spec.default).unwrap(),
                        "{name}: {switch} is the default: it switches nothing off"
                    );
                }
            }
            // Every setting of the preset is documented: a switch above, or a published
            // default marked where its parameter is described.
            let documented = paper_markers(&doc.join(" "));
            for setting in preset.settings {
                assert!(
                    documented.iter().any(|d| d == setting),
                    "{name}: the paper preset's {setting} is not marked (paper: `{setting}`) \
                     in the module doc"
                );
            }
            for marked in &documented {
                assert!(
                    preset.settings.contains(&marked.as_str()),
                    "{name}: the doc marks (paper: `{marked}`) but the preset lacks it"
                );
            }
            // And every setting applies.
            let label = crate::preset::Label::parse(&format!("{name}:paper")).unwrap();
            label
                .create()
                .unwrap_or_else(|e| panic!("{name}:paper: {e}"));
        }
        for info in METHODS {
            assert_eq!(
                info.preset("paper").is_some(),
                SEED_TECHNIQUES.contains(&info.name),
                "{}: a paper preset exactly for the seed techniques",
                info.name
            );
        }
    }

    /// The lifecycle's scene raster by default: [`RasterSpec::scene`] at the technique's own
    /// `shadow_resolution`; none for the technique that says it draws none (gpu-trace).
    #[test]
    fn gpu_techniques_draw_the_scene_raster_at_their_shadow_resolution() {
        fn drawn<T: GpuTechnique + Default>() -> Option<String> {
            let mut technique = T::default();
            let value = ParamValue::Integer(77);
            if let Some(set) = technique.params_mut().set("shadow_resolution", &value) {
                set.unwrap();
            }
            technique.scene_raster().map(|spec| format!("{spec:?}"))
        }
        let scene = Some(format!("{:?}", RasterSpec::scene(77)));
        assert_eq!(drawn::<crate::envmap::EnvMap>(), scene);
        assert_eq!(drawn::<crate::pvrr::Pvrr>(), scene);
        assert_eq!(drawn::<crate::distance_maps::DistanceMaps>(), scene);
        assert_eq!(drawn::<crate::image_space::ImageSpace>(), scene);
        assert_eq!(drawn::<crate::c3rc::C3rcMethod>(), scene);
        assert_eq!(drawn::<crate::toy_normals::ToyNormals>(), scene);
        assert_eq!(drawn::<crate::gpu_trace::GpuTrace>(), None);
    }

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
