//! Materials given to a loaded scene's objects from outside it: a bare mesh file (OBJ, PLY,
//! STL) carries no mirror or glass, and the command line's `--material NAME=KIND` makes one.
//!
//! `NAME` is an object as the scene names it: an OBJ's `o` or `g` name (`unnamed_object` where
//! it has none), a PLY or STL file's path as given, a STEP body's product name, a glTF mesh's
//! or a scene file's object name, `NAME#k` for a part split on load. Every mesh of that name takes the material. Each
//! `KIND` builds what a scene file's material of that type builds with its defaults, so the
//! same object renders the same whichever way it was made a mirror or glass.

use std::fmt;
use std::str::FromStr;

use glam::Vec3;

use crate::{Material, MaterialKind, Scene, SceneError};

const SYNTAX: &str = "NAME=mirror|glass:IOR|thin-glass:IOR|diffuse|unlit";

/// The object names listed in a message, at most this many, so that a scene of thousands of
/// parts gives a readable line.
const LISTED_NAMES: usize = 12;

/// One object's material from outside the scene: `NAME=mirror`, `NAME=glass:1.5`...
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialOverride {
    pub object: String,
    pub material: MaterialChoice,
}

/// The materials an object can be given, each as a scene file's type with its defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialChoice {
    /// A scene file's `mirror`: F0 0.95 grey, Schlick's Fresnel.
    Mirror,
    /// A scene file's `dielectric` with this `ior`: solid glass.
    Glass { ior: f32 },
    /// A scene file's `dielectric` with this `ior` and `thin = true`: a sheet.
    ThinGlass { ior: f32 },
    /// A scene file's `diffuse`: albedo 0.8 grey.
    Diffuse,
    /// A scene file's `unlit`: emits white.
    Unlit,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MaterialOverrideError {
    #[error("expected {SYNTAX}, got '{text}'")]
    Syntax { text: String },
    /// The scene files' rule: any finite index above 0 (one below 1 is optically thinner than
    /// the air around it, as an air bubble in water is relative to the water).
    #[error("'{text}': the index of refraction must be a finite number above 0 (glass is about 1.5), got '{ior}'")]
    Ior { text: String, ior: String },
}

impl FromStr for MaterialOverride {
    type Err = MaterialOverrideError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let syntax = || MaterialOverrideError::Syntax {
            text: text.to_string(),
        };
        // The kind never holds '=', a name may.
        let (object, kind) = text.rsplit_once('=').ok_or_else(syntax)?;
        // Spaces typed around `=` are common, names that begin or end with one are not.
        let object = object.trim();
        if object.is_empty() {
            return Err(syntax());
        }
        let ior = |value: &str| {
            value
                .trim()
                .parse::<f32>()
                .ok()
                .filter(|n| n.is_finite() && *n > 0.0)
                .ok_or_else(|| MaterialOverrideError::Ior {
                    text: text.to_string(),
                    ior: value.to_string(),
                })
        };
        let material = match kind.trim().split_once(':') {
            None => match kind.trim() {
                "mirror" => MaterialChoice::Mirror,
                "diffuse" => MaterialChoice::Diffuse,
                "unlit" => MaterialChoice::Unlit,
                _ => return Err(syntax()),
            },
            Some(("glass", value)) => MaterialChoice::Glass { ior: ior(value)? },
            Some(("thin-glass", value)) => MaterialChoice::ThinGlass { ior: ior(value)? },
            Some(_) => return Err(syntax()),
        };
        Ok(MaterialOverride {
            object: object.to_string(),
            material,
        })
    }
}

impl fmt::Display for MaterialChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MaterialChoice::Mirror => write!(f, "mirror"),
            MaterialChoice::Glass { ior } => write!(f, "glass:{ior}"),
            MaterialChoice::ThinGlass { ior } => write!(f, "thin-glass:{ior}"),
            MaterialChoice::Diffuse => write!(f, "diffuse"),
            MaterialChoice::Unlit => write!(f, "unlit"),
        }
    }
}

impl fmt::Display for MaterialOverride {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}={}", self.object, self.material)
    }
}

impl MaterialOverride {
    /// The override as one word of a shell's command line: quoted where the name holds
    /// anything but letters, digits and `_ . / # -` (a space, say), for messages that say what
    /// to type.
    pub fn shell_word(&self) -> String {
        let word = self.to_string();
        let plain = |c: char| c.is_ascii_alphanumeric() || "_./#-=:".contains(c);
        match word.chars().all(plain) {
            true => word,
            false => format!("'{}'", word.replace('\'', "'\\''")),
        }
    }
}

impl MaterialChoice {
    /// The material, built as `toml_scene` builds its type with no colour, texture or abbe
    /// given (a test holds the two together).
    pub fn material(self, name: impl Into<String>) -> Material {
        let dielectric = |ior: f32, thin_walled| MaterialKind::Dielectric {
            ior: Vec3::splat(ior),
            thin_walled,
        };
        match self {
            MaterialChoice::Mirror => Material::mirror(name, Vec3::splat(0.95)),
            MaterialChoice::Glass { ior } => Material::new(name, dielectric(ior, false), Vec3::ONE),
            MaterialChoice::ThinGlass { ior } => {
                Material::new(name, dielectric(ior, true), Vec3::ONE)
            }
            MaterialChoice::Diffuse => Material::diffuse(name, Vec3::splat(0.8)),
            MaterialChoice::Unlit => Material::unlit(name, Vec3::ONE),
        }
    }
}

/// Names for a message: quoted, comma-separated, the first few only where there are many.
pub fn names_listed<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let mut listed: Vec<String> = Vec::new();
    let mut more = 0;
    for name in names {
        match listed.len() < LISTED_NAMES {
            true => listed.push(format!("'{name}'")),
            false => more += 1,
        }
    }
    if more > 0 {
        listed.push(format!("and {more} more"));
    }
    listed.join(", ")
}

impl Scene {
    /// The objects' names, each once, in the scene's order.
    pub fn object_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for mesh in &self.meshes {
            if !names.contains(&mesh.name.as_str()) {
                names.push(&mesh.name);
            }
        }
        names
    }

    /// [`Scene::object_names`] for a message ([`names_listed`]).
    pub fn object_names_listed(&self) -> String {
        names_listed(self.object_names())
    }

    /// Gives each override's object its material (the last override naming an object wins),
    /// then splits an object made a mirror or glass that holds several separate objects as
    /// loading does ([`Scene::finalize`]), so that it is the same scene a file with that
    /// material would have given. An object the scene does not have is an error listing its
    /// objects, and nothing is changed.
    pub fn apply_material_overrides(
        &mut self,
        overrides: &[MaterialOverride],
    ) -> Result<(), SceneError> {
        if let Some(unknown) = overrides
            .iter()
            .find(|o| !self.meshes.iter().any(|m| m.name == o.object))
        {
            return Err(SceneError::UnknownObject {
                scene: self.name.clone(),
                name: unknown.object.clone(),
                material: unknown.material.to_string(),
                objects: self.object_names_listed(),
            });
        }
        let first_new = self.materials.len();
        for (i, given) in overrides.iter().enumerate() {
            if overrides[i + 1..].iter().any(|o| o.object == given.object) {
                continue;
            }
            let index = self.materials.len();
            self.materials
                .push(given.material.material(given.to_string()));
            for mesh in self.meshes.iter_mut().filter(|m| m.name == given.object) {
                mesh.material = index;
            }
        }
        let source = self.name.clone();
        self.split_separate_reflectors(&source, |mesh| mesh.material >= first_new);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(text: &str) -> Result<MaterialOverride, MaterialOverrideError> {
        text.parse()
    }

    #[test]
    fn each_kind_parses() {
        let cases = [
            ("plate=mirror", "plate", MaterialChoice::Mirror),
            ("lens=glass:1.5", "lens", MaterialChoice::Glass { ior: 1.5 }),
            (
                "cover glass=thin-glass:1.52",
                "cover glass",
                MaterialChoice::ThinGlass { ior: 1.52 },
            ),
            ("floor=diffuse", "floor", MaterialChoice::Diffuse),
            ("lamp=unlit", "lamp", MaterialChoice::Unlit),
            // A name may hold '=' (the kind never does) and a path's characters.
            ("a=b=mirror", "a=b", MaterialChoice::Mirror),
            (
                "dir/bunny.ply=mirror",
                "dir/bunny.ply",
                MaterialChoice::Mirror,
            ),
        ];
        for (text, object, material) in cases {
            let given = parsed(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(given.object, object, "{text}");
            assert_eq!(given.material, material, "{text}");
        }
    }

    #[test]
    fn a_text_it_cannot_read_says_what_it_expects() {
        for text in [
            "plate",
            "plate=",
            "=mirror",
            "plate=chrome",
            "plate=glass",
            "plate=mirror:0.9",
            "plate=steel:1.5",
        ] {
            let e = parsed(text).expect_err(text);
            assert_eq!(
                e.to_string(),
                format!(
                    "expected NAME=mirror|glass:IOR|thin-glass:IOR|diffuse|unlit, got '{text}'"
                ),
            );
        }
    }

    #[test]
    fn a_shell_word_is_quoted_where_a_shell_would_split_it() {
        let word = |object: &str| {
            MaterialOverride {
                object: object.into(),
                material: MaterialChoice::Glass { ior: 1.5 },
            }
            .shell_word()
        };
        assert_eq!(word("plate"), "plate=glass:1.5");
        assert_eq!(word("dir/part#2"), "dir/part#2=glass:1.5");
        assert_eq!(word("door mirror"), "'door mirror=glass:1.5'");
        assert_eq!(word("it's"), "'it'\\''s=glass:1.5'");
    }

    #[test]
    fn an_index_of_refraction_must_be_finite_and_above_zero() {
        for (text, ior) in [
            ("lens=glass:0", "0"),
            ("lens=glass:-1.5", "-1.5"),
            ("lens=glass:inf", "inf"),
            ("lens=glass:NaN", "NaN"),
            ("lens=thin-glass:", ""),
            ("lens=glass:one", "one"),
        ] {
            let e = parsed(text).expect_err(text);
            assert_eq!(
                e,
                MaterialOverrideError::Ior {
                    text: text.into(),
                    ior: ior.into()
                }
            );
            assert!(e.to_string().contains("finite number above 0"), "{e}");
        }
        assert_eq!(
            parsed("bubble=glass:0.75").unwrap().material,
            MaterialChoice::Glass { ior: 0.75 }
        );
    }

    /// A small scene file: `material` for its objects, which are two balls merged into one
    /// mesh ("pair") and a floor.
    fn scene_file(materials: &str) -> Scene {
        let text = format!(
            r#"
            {materials}
            [materials.grey]
            type = "diffuse"
            [[objects]]
            name = "pair"
            material = "chosen"
            shape = {{ type = "merged", parts = [
                {{ translate = [-1, 0, 0], shape = {{ type = "sphere", radius = 0.3 }} }},
                {{ translate = [1, 0, 0], shape = {{ type = "sphere", radius = 0.3 }} }},
            ] }}
            [[objects]]
            name = "floor"
            material = "grey"
            translate = [0, -0.5, 0]
            shape = {{ type = "plane", size = [4, 4] }}
            "#
        );
        crate::loaders::toml_scene::parse("test.toml", &text, std::path::Path::new("."))
            .expect("the test scene loads")
    }

    /// The material of the object `object`, or of its first part where loading split it.
    fn material_of<'a>(scene: &'a Scene, object: &str) -> &'a Material {
        let part = format!("{object}#1");
        let mesh = scene
            .meshes
            .iter()
            .find(|m| m.name == object || m.name == part)
            .unwrap_or_else(|| panic!("no mesh '{object}'"));
        &scene.materials[mesh.material]
    }

    const DIFFUSE: &str = "[materials.chosen]\ntype = \"diffuse\"";

    #[test]
    fn each_kind_is_the_scene_files_material_of_that_type() {
        for (kind, table) in [
            ("mirror", "type = \"mirror\""),
            ("glass:1.5", "type = \"dielectric\"\nior = 1.5"),
            (
                "thin-glass:1.52",
                "type = \"dielectric\"\nior = 1.52\nthin = true",
            ),
            ("diffuse", "type = \"diffuse\""),
            ("unlit", "type = \"unlit\""),
        ] {
            let from_file = scene_file(&format!("[materials.chosen]\n{table}"));
            let mut overridden = scene_file(DIFFUSE);
            let given: MaterialOverride = format!("pair={kind}").parse().unwrap();
            overridden.apply_material_overrides(&[given]).unwrap();
            let (ours, theirs) = (
                material_of(&overridden, "pair"),
                material_of(&from_file, "pair"),
            );
            // Everything but the name, which each route makes its own.
            assert_eq!(
                (&ours.kind, ours.color, ours.texture),
                (&theirs.kind, theirs.color, theirs.texture),
                "{kind}"
            );
        }
    }

    #[test]
    fn a_merged_mesh_made_a_mirror_is_split_as_a_mirror_file_splits_it() {
        let from_file = scene_file("[materials.chosen]\ntype = \"mirror\"");
        let mut overridden = scene_file(DIFFUSE);
        assert_eq!(overridden.object_names(), ["pair", "floor"]);
        overridden
            .apply_material_overrides(&["pair=mirror".parse().unwrap()])
            .unwrap();
        let shape = |scene: &Scene| -> Vec<(String, usize)> {
            let mut meshes: Vec<(String, usize)> = scene
                .meshes
                .iter()
                .map(|m| (m.name.clone(), m.triangles.len()))
                .collect();
            meshes.sort();
            meshes
        };
        assert_eq!(shape(&overridden), shape(&from_file));
        assert_eq!(overridden.object_names(), ["pair#1", "pair#2", "floor"]);
        assert!(
            overridden
                .warnings
                .iter()
                .any(|w| w.contains("mesh 'pair' holds 2 separate objects")),
            "{:?}",
            overridden.warnings
        );
        // The floor was not named: it keeps its material and is not split.
        assert_eq!(material_of(&overridden, "floor").name, "grey");
    }

    #[test]
    fn an_unknown_object_is_refused_naming_the_scenes_objects() {
        let mut scene = scene_file(DIFFUSE);
        let before = scene.materials.clone();
        let e = scene
            .apply_material_overrides(&[
                "floor=mirror".parse().unwrap(),
                "bunny=mirror".parse().unwrap(),
            ])
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "test.toml: no object 'bunny' to make mirror; the scene's objects are: 'pair', 'floor'"
        );
        assert_eq!(scene.materials, before, "nothing changed");
        assert_eq!(material_of(&scene, "floor").name, "grey");
    }

    #[test]
    fn the_last_material_given_an_object_wins() {
        let mut scene = scene_file(DIFFUSE);
        let materials = scene.materials.len();
        scene
            .apply_material_overrides(&[
                "floor=mirror".parse().unwrap(),
                "floor=unlit".parse().unwrap(),
            ])
            .unwrap();
        assert_eq!(material_of(&scene, "floor").kind, MaterialKind::Unlit);
        assert_eq!(material_of(&scene, "floor").name, "floor=unlit");
        assert_eq!(scene.materials.len(), materials + 1, "no unused material");
    }

    #[test]
    fn a_long_list_of_objects_is_cut_short() {
        let mut scene = Scene::new("many");
        for i in 0..20 {
            let mut mesh = crate::generators::sphere(0.1, 4, 4);
            mesh.name = format!("part {i}");
            scene.meshes.push(mesh);
        }
        let listed = scene.object_names_listed();
        assert!(listed.starts_with("'part 0', 'part 1'"), "{listed}");
        assert!(listed.ends_with("'part 11', and 8 more"), "{listed}");
    }
}
