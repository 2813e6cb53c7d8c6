//! `specula analyze KIND SCENE... ...`: every analysis of the registry
//! (`specula_analyze::analysis::ANALYSES`), its flags made from its option declarations (name,
//! kind, unit, default, help, group), run with a progress bar on all cores, its summary printed
//! and its JSON and report folder written. Several scenes (or a folder of them) run in turn: a
//! report folder each, one summary table, and `--csv` a row per scene and check. Nothing here
//! knows one analysis from another.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result};
use clap::{Arg, ArgAction, ArgMatches, Command};
use indicatif::{ProgressBar, ProgressStyle};
use specula_analyze::analysis::{
    AnalysisInfo, CheckRow, EyePoints, Progress, RunContext, ANALYSES,
};
use specula_analyze::outcome::Outcome;
use specula_analyze::AnalyzeError;
use specula_params::{OptionSpec, ParamKind};
use specula_scene::builtin::DEFAULT_SCENE;
use specula_trace::SceneAccel;

/// One analysis as the command line asked for it.
pub struct Kind {
    info: &'static AnalysisInfo,
    scenes: Vec<String>,
    /// Every option the command line gave (flags left out are not here: their defaults are the
    /// declaration's).
    values: Vec<(&'static str, String)>,
    json: Option<PathBuf>,
    report: Option<PathBuf>,
    csv: Option<PathBuf>,
    materials: crate::Materials,
}

/// The flag of one option: its help is the declaration's doc, unit and default.
fn flag(spec: &'static OptionSpec) -> Arg {
    let mut help = spec.doc.to_string();
    if spec.repeatable {
        help.push_str(" (repeatable)");
    }
    if !spec.unit.is_empty() {
        help.push_str(&format!(" [unit: {}]", spec.unit));
    }
    let long = spec.name.replace('_', "-");
    let mut arg = Arg::new(spec.name)
        .long(long)
        .help(help)
        .required(spec.required);
    if !spec.group.is_empty() {
        arg = arg.help_heading(spec.group);
    }
    match spec.kind {
        ParamKind::Flag if !spec.repeatable => return arg.action(ArgAction::SetTrue),
        _ if !spec.default.is_empty() => arg = arg.default_value(spec.default),
        _ => {}
    }
    // Negative numbers and coordinates are values, not flags.
    arg = arg.allow_hyphen_values(true);
    match spec.kind {
        ParamKind::Choice(words) => arg = arg.value_parser(words.to_vec()),
        _ => {
            arg = arg.value_parser(move |text: &str| {
                spec.parse("analyze", text)
                    .map(|_| text.to_string())
                    .map_err(|e| e.reason)
            })
        }
    }
    let names = match spec.kind {
        ParamKind::Numbers { names } => names,
        _ if spec.names_an_object() => "NAME",
        ParamKind::Text { expected } if expected.len() < 30 => expected,
        _ => "VALUE",
    };
    arg = arg.value_name(names);
    if spec.repeatable {
        arg = arg.action(ArgAction::Append);
    }
    arg
}

fn command(info: &'static AnalysisInfo) -> Command {
    let mut command = Command::new(info.name)
        .about(info.summary)
        .hide(info.test_only)
        .after_help(format!(
            "Example:\n  {}\n\nEvery option: docs/analyses/{}.md",
            info.example, info.name
        ))
        .arg(
            Arg::new("scene")
                .value_name("SCENE")
                .help(
                    "Built-in scene names, .toml scene files, mesh/scene files or folders of \
                     them: each is analysed in turn",
                )
                .num_args(1..)
                .default_value(DEFAULT_SCENE),
        );
    for spec in info.all_options() {
        command = command.arg(flag(spec));
    }
    <crate::Materials as clap::Args>::augment_args(command)
        .arg(
            Arg::new("json")
                .long("json")
                .help_heading("Output")
                .value_parser(clap::value_parser!(PathBuf))
                .help(format!(
                    "Write the report as JSON here (schema: docs/analyze-{}.schema.json)",
                    info.name
                )),
        )
        .arg(
            Arg::new("report")
                .long("report")
                .help_heading("Output")
                .value_parser(clap::value_parser!(PathBuf))
                .help(
                    "Write a report folder: report.html, report.json and the plots as PNG and \
                     SVG (with several scenes, a folder per scene in it)",
                ),
        )
        .arg(
            Arg::new("csv")
                .long("csv")
                .help_heading("Output")
                .value_parser(clap::value_parser!(PathBuf))
                .help(
                    "Write a CSV file with a row per scene and check (a field, a rule, a \
                     tolerance; a key figure where nothing is judged): its verdict, value, \
                     limit, margin, uncertainty and unit",
                ),
        )
}

impl clap::FromArgMatches for Kind {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let (name, sub) = matches
            .subcommand()
            .ok_or_else(|| clap::Error::new(clap::error::ErrorKind::MissingSubcommand))?;
        let info = ANALYSES
            .iter()
            .copied()
            .find(|a| a.name == name)
            .ok_or_else(|| clap::Error::new(clap::error::ErrorKind::InvalidSubcommand))?;
        let mut values = Vec::new();
        for spec in info.all_options() {
            let given = sub.value_source(spec.name) == Some(clap::parser::ValueSource::CommandLine);
            if !given {
                continue;
            }
            let value = match spec.kind {
                ParamKind::Flag if !spec.repeatable => sub.get_flag(spec.name).to_string(),
                _ => {
                    let all: Vec<String> = sub
                        .get_many::<String>(spec.name)
                        .into_iter()
                        .flatten()
                        .cloned()
                        .collect();
                    all.join(";")
                }
            };
            values.push((spec.name, value));
        }
        Ok(Kind {
            info,
            scenes: sub
                .get_many::<String>("scene")
                .into_iter()
                .flatten()
                .cloned()
                .collect(),
            values,
            json: sub.get_one::<PathBuf>("json").cloned(),
            report: sub.get_one::<PathBuf>("report").cloned(),
            csv: sub.get_one::<PathBuf>("csv").cloned(),
            materials: crate::Materials::from_arg_matches(sub)?,
        })
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = Kind::from_arg_matches(matches)?;
        Ok(())
    }
}

impl clap::Subcommand for Kind {
    fn augment_subcommands(command: Command) -> Command {
        ANALYSES.iter().fold(command, |command, info| {
            command.subcommand(self::command(info))
        })
    }

    fn augment_subcommands_for_update(command: Command) -> Command {
        Kind::augment_subcommands(command)
    }

    fn has_subcommand(name: &str) -> bool {
        ANALYSES.iter().any(|a| a.name == name)
    }
}

/// `name` as the command line writes it.
fn as_flag(name: &str) -> String {
    format!("--{}", name.replace('_', "-"))
}

/// Library text in the command line's words: an option named `` `name` `` as its flag.
pub(crate) fn flags_in(text: &str) -> String {
    let mut out = String::new();
    let mut parts = text.split('`');
    out.push_str(parts.next().unwrap_or(""));
    while let Some(quoted) = parts.next() {
        let is_name = !quoted.is_empty()
            && quoted
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
        match is_name {
            true => out.push_str(&as_flag(quoted)),
            false => {
                out.push('`');
                out.push_str(quoted);
                out.push('`');
            }
        }
        out.push_str(parts.next().unwrap_or(""));
    }
    out
}

/// A library error in the command line's words: an option by its flag, a role by its flag.
fn in_flags(e: AnalyzeError) -> anyhow::Error {
    let as_flag = |name: &str| match name.contains('`') {
        true => flags_in(name),
        false => as_flag(name),
    };
    match e {
        AnalyzeError::BadOption { option, reason } => {
            anyhow::anyhow!("{}: {}", as_flag(option), flags_in(&reason))
        }
        AnalyzeError::Option(e) => {
            anyhow::anyhow!("{} {}: {}", as_flag(&e.name), e.value, e.reason)
        }
        // The library's words, with the object's role as its flag.
        AnalyzeError::UnknownObject { role, ref name, .. }
        | AnalyzeError::AmbiguousObject { role, ref name, .. }
        | AnalyzeError::WrongMaterial { role, ref name, .. } => {
            let named = format!("{role} '{name}'");
            let flagged = format!("{} '{name}'", as_flag(role));
            anyhow::anyhow!(flags_in(&e.to_string().replacen(&named, &flagged, 1)))
        }
        other => other.into(),
    }
}

/// The progress bar, its length and stage set as the run reports them.
fn progress_bar() -> ProgressBar {
    let bar = ProgressBar::new(1);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} ({elapsed})")
            .expect("valid template"),
    );
    bar
}

/// What one scene's run gave: its verdict and its checks.
struct SceneRun {
    verdict: Option<Outcome>,
    checks: Vec<CheckRow>,
}

pub fn run(kind: Kind) -> Result<()> {
    let scenes = specula_compare::suite::expand_scenes(&kind.scenes)?;
    let several = scenes.len() > 1;
    if several {
        kind.materials.check_in(&scenes)?;
    }
    if several && kind.json.is_some() {
        anyhow::bail!(
            "--json writes one scene's document: with {} scenes give --report DIR (a report per \
             scene) or --csv FILE",
            scenes.len()
        );
    }
    // Outputs that cannot be written are refused before anything is computed.
    if let Some(path) = &kind.json {
        let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
        if folder.is_some_and(|f| !f.is_dir()) {
            anyhow::bail!(
                "writing {}: its folder {} does not exist",
                path.display(),
                folder.expect("checked").display()
            );
        }
    }
    if let Some(dir) = &kind.report {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let mut csv = kind
        .csv
        .as_ref()
        .map(|path| {
            std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))
        })
        .transpose()?;
    let mut runs = Vec::new();
    let mut only_error = None;
    for scene in &scenes {
        if several {
            println!("== {scene} ==");
        }
        let result = analyse(&kind, scene, several);
        let result = match result {
            Ok(run) => Some(run),
            // One scene: its error is the command's, as it stands.
            Err(e) if !several => {
                only_error = Some(e);
                None
            }
            Err(e) => {
                eprintln!("error: {scene}: {e:#}");
                None
            }
        };
        runs.push((scene.clone(), result));
    }
    if several {
        print_table(&runs);
    }
    if let (Some(file), Some(path)) = (csv.as_mut(), &kind.csv) {
        write_csv(file, kind.info.name, &runs)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("csv: {}", path.display());
    }
    if let Some(e) = only_error {
        return Err(e);
    }
    let failed = runs.iter().filter(|(_, r)| r.is_none()).count();
    if failed > 0 {
        anyhow::bail!(
            "{failed} of {} scenes could not be analysed (see above)",
            runs.len()
        );
    }
    Ok(())
}

/// One scene's run: the analysis with the command line's options, its summary printed, its
/// JSON and report folder written (in a folder of the scene's own with several).
fn analyse(kind: &Kind, scene_name: &str, several: bool) -> Result<SceneRun> {
    let scene = crate::load_scene(scene_name, &kind.materials, several)?;
    let mut analysis = (kind.info.create)();
    let mut eyes = EyePoints::default();
    for (name, value) in &kind.values {
        analysis
            .set_option(&mut eyes, name, value)
            .map_err(in_flags)?;
    }
    analysis.check(&scene, &eyes).map_err(in_flags)?;
    let accel = SceneAccel::new(&scene);
    let bar = progress_bar();
    let cancel = AtomicBool::new(false);
    let progress = |p: Progress| {
        bar.set_length(p.total as u64);
        bar.set_position(p.done as u64);
        bar.set_message(p.stage);
    };
    let context = RunContext {
        progress: &progress,
        cancel: &cancel,
    };
    let report = analysis
        .run(&scene, &accel, &eyes, &context)
        .map_err(in_flags)?;
    bar.finish_and_clear();
    print!("{}", flags_in(&analysis.summary(&report)));
    if let Some(path) = &kind.json {
        std::fs::write(path, &report.json)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(dir) = &kind.report {
        let dir = match several {
            true => dir.join(folder_name(scene_name)),
            false => dir.clone(),
        };
        let html = analysis
            .write_report(&report, &dir, &scene, &accel)
            .map_err(in_flags)?;
        println!("report: {}", html.display());
    }
    Ok(SceneRun {
        verdict: report.verdict,
        checks: analysis.checks(&report),
    })
}

/// A scene's report folder: its file's stem, or its built-in name.
fn folder_name(scene: &str) -> String {
    std::path::Path::new(scene)
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| scene.to_string())
}

/// The runs in one table: scene, verdict, and how many checks pass, fail or are undecided.
fn print_table(runs: &[(String, Option<SceneRun>)]) {
    let width = runs.iter().map(|(s, _)| s.len()).max().unwrap_or(5).max(5);
    println!("{:<width$}  {:<10}  checks", "scene", "verdict");
    for (scene, run) in runs {
        let Some(run) = run else {
            println!("{scene:<width$}  {:<10}  -", "error");
            continue;
        };
        let count = |o: Outcome| run.checks.iter().filter(|c| c.verdict == Some(o)).count();
        let judged = count(Outcome::Pass) + count(Outcome::Fail) + count(Outcome::Undecided);
        let checks = match judged {
            0 => format!("{} figures", run.checks.len()),
            _ => format!(
                "{} pass, {} fail, {} undecided",
                count(Outcome::Pass),
                count(Outcome::Fail),
                count(Outcome::Undecided)
            ),
        };
        let verdict = run.verdict.map_or("-", |v| v.lower());
        println!("{scene:<width$}  {verdict:<10}  {checks}");
    }
}

/// A CSV cell: quoted where it holds a comma, a quote or a line break.
fn cell(text: &str) -> String {
    match text.contains([',', '"', '\n']) {
        true => format!("\"{}\"", text.replace('"', "\"\"")),
        false => text.to_string(),
    }
}

/// A row per scene and check: scene, analysis, check, verdict, value, limit, margin,
/// uncertainty, unit (a scene that could not be analysed: one row, verdict `error`).
fn write_csv(
    out: &mut impl std::io::Write,
    analysis: &str,
    runs: &[(String, Option<SceneRun>)],
) -> std::io::Result<()> {
    writeln!(
        out,
        "scene,analysis,check,verdict,value,limit,margin,uncertainty,unit"
    )?;
    let number = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
    for (scene, run) in runs {
        let Some(run) = run else {
            writeln!(out, "{},{analysis},,error,,,,,", cell(scene))?;
            continue;
        };
        for c in &run.checks {
            writeln!(
                out,
                "{},{analysis},{},{},{},{},{},{},{}",
                cell(scene),
                cell(&c.check),
                c.verdict.map_or("", |v| v.lower()),
                number(c.value),
                number(c.limit),
                number(c.margin),
                number(c.uncertainty),
                cell(c.unit)
            )?;
        }
    }
    Ok(())
}
