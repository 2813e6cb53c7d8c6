//! `--material NAME=KIND`: declared once here for every command that loads a scene (render,
//! compare, bench, view and each analysis), and given to the scenes they load.

use anyhow::{Context, Result};
use specula_scene::{MaterialOverride, Scene};

#[derive(clap::Args, Clone, Debug, Default)]
pub struct Materials {
    /// Give object NAME a material in place of the scene's: mirror, glass:IOR (solid, e.g.
    /// glass:1.5), thin-glass:IOR (a sheet), diffuse or unlit (repeatable).
    ///
    /// Each is a scene file's material of that type with its defaults; the last given for an
    /// object wins. NAME is the object as the scene names it: an OBJ's `o` or `g` name
    /// (`unnamed_object` where it has none), a PLY or STL file's path as given, a STEP body's
    /// product name; a name the scene lacks is an error listing its objects. With several scenes, each takes those whose
    /// object it has, and a name none has is refused before any runs.
    #[arg(long = "material", value_name = "NAME=KIND", help_heading = "Scene")]
    pub materials: Vec<MaterialOverride>,
}

impl Materials {
    /// Gives `scene` its materials: every one (an object it lacks is an error listing its
    /// objects), or where the run has `several` scenes those whose object it has (each name was
    /// found in one of them by [`Materials::check_in`]).
    pub fn apply(&self, scene: &mut Scene, several: bool) -> Result<()> {
        let given: Vec<MaterialOverride> = match several {
            true => {
                let names = scene.object_names();
                self.materials
                    .iter()
                    .filter(|o| names.contains(&o.object.as_str()))
                    .cloned()
                    .collect()
            }
            false => self.materials.clone(),
        };
        scene.apply_material_overrides(&given).context("--material")
    }

    /// Refuses, before a run over several scenes, a `--material` whose object none of them has:
    /// a misspelt name would otherwise leave every scene as it was. A scene that does not load
    /// is passed over here (the run reports it).
    pub fn check_in(&self, sources: &[String]) -> Result<()> {
        if self.materials.is_empty() {
            return Ok(());
        }
        let mut names: Vec<String> = Vec::new();
        for scene in sources.iter().filter_map(|s| specula_scene::load(s).ok()) {
            for name in scene.object_names() {
                if !names.iter().any(|n| n == name) {
                    names.push(name.to_string());
                }
            }
        }
        match self.materials.iter().find(|o| !names.contains(&o.object)) {
            Some(missing) => anyhow::bail!(
                "--material {}: none of the {} scenes has an object '{}'; their objects are: {}",
                missing.shell_word(),
                sources.len(),
                missing.object,
                specula_scene::material_override::names_listed(names.iter().map(String::as_str))
            ),
            None => Ok(()),
        }
    }
}
