//! Running an analysis as a front end does: by its name, its options as NAME = VALUE texts,
//! through the trait; what the command, a viewer script and the library share.

use std::sync::atomic::AtomicBool;

use specula_analyze::analysis::{self, EyePoints, RunContext};
use specula_trace::SceneAccel;

/// The JSON document of analysis `name` run with `options` on `scene`.
pub fn run_json(name: &str, scene: &specula_scene::Scene, options: &[(&str, &str)]) -> String {
    let mut analysis = analysis::by_name(name).unwrap();
    let mut eyes = EyePoints::default();
    for (option, value) in options {
        analysis.set_option(&mut eyes, option, value).unwrap();
    }
    let accel = SceneAccel::new(scene);
    let cancel = AtomicBool::new(false);
    let context = RunContext {
        progress: &|_| {},
        cancel: &cancel,
    };
    analysis.run(scene, &accel, &eyes, &context).unwrap().json
}
