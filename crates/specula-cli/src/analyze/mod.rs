//! `specula analyze KIND SCENE ...`: the analyses of `specula_analyze`, on all cores, with a
//! progress bar over the eye points, a table on the terminal and the JSON report.

mod glare;

use std::path::PathBuf;

use anyhow::{Context, Result};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use specula_analyze::frame::{Eyes, VehicleFrame};
use specula_analyze::mirror_surface::SurfaceModel;
use specula_analyze::mirror_view::{self, Region};
use specula_analyze::outcome::Outcome;
use specula_analyze::verdict_page;
use specula_scene::builtin::DEFAULT_SCENE;
use specula_trace::SceneAccel;

#[derive(clap::Subcommand)]
pub enum Kind {
    /// What is seen in a mirror from the eye points: its field of view (horizontal and
    /// vertical extent, solid angle), its footprint on the ground within a range, and the
    /// share of a required region seen by any and by every eye point (its blind part).
    #[command(
        after_help = "Example (R46 class III on the example car):\n  specula analyze mirror-view scenes/car-door-mirror.toml --mirror \"door mirror\" --regulation r46-iii --forward 0,0,-1 --r-point -0.37,0.55,0 --outermost -0.95,0.6,1.5 --vehicle \"car body\" --vehicle \"A-pillar\" --report r46-report"
    )]
    MirrorView(MirrorViewArgs),
    /// Whether and how brightly a source (a named surface or the sun) is seen reflected in a
    /// surface, per eye point: the glare's luminance factor and luminance in cd/m², its veiling
    /// ratio, solid angle and centroid, the contrast of a display behind the cover under it;
    /// sun sweeps and solar days by lookup.
    #[command(
        after_help = "Example:\n  specula analyze glare truck-cover --surface \"cover glass\" --source \"side window\" --source-luminance 8000 --eyebox 0.2,0.1,5,3 --display dial --symbol-luminance 300 --background-luminance 10 --min-contrast 3 --report glare-report"
    )]
    Glare(Box<glare::GlareArgs>),
    /// A spectacle lens as worn, per gaze direction: sphere, cylinder and axis at the vertex
    /// sphere, mean power, prism, lateral colour and distortion, from exact rays (Listing's
    /// law about the eye's centre of rotation).
    #[command(
        after_help = "Example:\n  specula analyze lens scenes/spectacles-wrap.toml --lens \"right lens\" --pantoscopic 10 --wrap 5 --compensate --standard iso-8980-1 --focimeter"
    )]
    Lens(LensArgs),
}

#[derive(clap::Args)]
pub struct LensArgs {
    /// Built-in scene name, a .toml scene file, or a mesh/scene file.
    #[arg(default_value = "spectacle-lens")]
    scene: String,
    /// The lens (a solid glass), as the scene names it.
    #[arg(long)]
    lens: String,
    /// The eye behind the lens: it decides which way is base in and base out.
    #[arg(help_heading = "The eye", long, value_enum, default_value = "right")]
    eye: EyeSide,
    /// The eye's centre of rotation X,Y,Z (default: --vertex-distance and
    /// --rotation-behind-cornea behind the lens's back vertex along the camera's view axis).
    #[arg(help_heading = "The eye", long, value_parser = parse_point, allow_hyphen_values = true, conflicts_with = "vertex_distance")]
    rotation_centre: Option<Vec3>,
    /// From the cornea to the lens's back surface along the primary line of sight, mm.
    #[arg(help_heading = "The eye", long)]
    vertex_distance: Option<f64>,
    /// From the cornea to the eye's centre of rotation, mm (the entrance pupil, for spectacle
    /// magnification, is 3 mm behind the cornea).
    #[arg(help_heading = "The eye", long, default_value_t = 15.0)]
    rotation_behind_cornea: f64,
    /// Pantoscopic tilt, degrees: the lens turned about the horizontal through the fitting
    /// point, its lower edge towards the face (at most 30).
    #[arg(
        help_heading = "The eye",
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pantoscopic: f64,
    /// Face-form wrap, degrees: the lens turned about the vertical through the fitting point,
    /// its temporal edge towards the face (at most 30).
    #[arg(
        help_heading = "The eye",
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    wrap: f64,
    /// The gaze grid H_MAX,V_MAX,STEP in degrees (cells at 0 included).
    #[arg(help_heading = "The eye", long, default_value = "30,30,2.5", value_parser = parse_gaze)]
    gaze: [f64; 3],
    /// The object's distance from the eye's centre of rotation, metres (default: infinity;
    /// e.g. 0.4 for near vision).
    #[arg(help_heading = "The eye", long)]
    object_distance: Option<f64>,
    /// The prescription SPHERE[,CYLINDER,AXIS][,PRISM...] (prisms such as 1.5BO, 0.5BU): what
    /// the power error and unwanted cylinder are taken against and what --standard checks
    /// (default: the one a spectacle-lens shape was made from, if any).
    #[arg(help_heading = "Prescription and standard", long, value_parser = parse_rx, allow_hyphen_values = true)]
    prescription: Option<specula_analyze::lens::Rx>,
    /// The vertex distance the prescription was refracted at, mm: it is re-referenced to the
    /// lens's by F / (1 − d F) per meridian, d the distance the lens moved towards the eye.
    #[arg(help_heading = "Prescription and standard", long)]
    refraction_vertex: Option<f64>,
    /// Solve the prescription to order (sphere, cylinder, axis) whose lens, on the same blank
    /// and worn the same way, gives the prescription at the fitting point; --standard then
    /// checks against it.
    #[arg(help_heading = "Prescription and standard", long)]
    compensate: bool,
    /// Check the focimeter reading against a standard's tolerances: ansi-z80.1, iso-8980-1, or
    /// iso-8980-2 (progressive lenses; with --add, ansi-z80.1 uses its progressive table).
    #[arg(help_heading = "Prescription and standard", long, value_parser = parse_standard)]
    standard: Option<&'static specula_analyze::lens::standard::Table>,
    /// Print the focimeter's readings (they are always in the JSON).
    #[arg(help_heading = "Prescription and standard", long)]
    focimeter: bool,
    /// The distance reference point X,Y, mm from the back vertex (the lens's right and up;
    /// default: a spectacle-lens shape's, else 0,0).
    #[arg(help_heading = "Prescription and standard", long, value_parser = parse_pair, allow_hyphen_values = true)]
    distance_reference: Option<[f64; 2]>,
    /// The prism reference point X,Y, mm from the back vertex.
    #[arg(help_heading = "Prescription and standard", long, value_parser = parse_pair, allow_hyphen_values = true, default_value = "0,0")]
    prism_reference: [f64; 2],
    /// A progressive lens's ordered addition, dioptres: reads the add on the progressive
    /// surface's side and reports the corridor, the zones and the largest unwanted cylinder
    /// (default: a spectacle-lens shape's `add`).
    #[arg(help_heading = "Progressive lenses and near vision", long)]
    add: Option<f64>,
    /// A progressive lens's near reference point X,Y, mm from the back vertex (default: a
    /// spectacle-lens shape's).
    #[arg(help_heading = "Progressive lenses and near vision", long, value_parser = parse_pair, allow_hyphen_values = true)]
    near_reference: Option<[f64; 2]>,
    /// Turn both eyes to a near point on the midline this many metres away (convergence) and
    /// report the near zone's power, prism and inset.
    #[arg(
        help_heading = "Progressive lenses and near vision",
        long,
        allow_hyphen_values = true
    )]
    near: Option<f64>,
    /// The interpupillary distance for --near, mm.
    #[arg(
        help_heading = "Progressive lenses and near vision",
        long,
        default_value_t = 64.0
    )]
    pd: f64,
    /// The near point's depression below the primary gaze, degrees (default: so that the line
    /// of sight crosses the near reference point's height, else 0).
    #[arg(
        help_heading = "Progressive lenses and near vision",
        long,
        allow_hyphen_values = true
    )]
    near_down: Option<f64>,
    /// The lens map's spacing, mm: the clear zones and the progressive figures come from it.
    #[arg(help_heading = "Progressive lenses and near vision", long, default_value_t = specula_analyze::lens::DEFAULT_LENS_STEP_MM)]
    lens_step: f64,
    /// The lens's surface: its exact one (the default where the scene made it from a `lens` or
    /// `spectacle-lens` shape), its triangles (mesh) or a smooth fit to them.
    #[arg(help_heading = "Surface", long, value_enum)]
    surface: Option<SurfaceArg>,
    /// The bundle's half-width at the lens, millimetres (each figure is also taken at half of
    /// it, and the change reported).
    #[arg(help_heading = "Surface", long, default_value_t = 0.5)]
    step_mm: f64,
    /// Write the report as JSON here (schema: docs/analyze-lens.schema.json).
    #[arg(help_heading = "Output", long)]
    json: Option<PathBuf>,
    /// Write a report folder: report.html, report.json, the maps (mean power, cylinder, prism,
    /// lateral colour) and the distortion picture as PNG and SVG.
    #[arg(help_heading = "Output", long)]
    report: Option<PathBuf>,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum EyeSide {
    Right,
    Left,
}

fn parse_rx(text: &str) -> Result<specula_analyze::lens::Rx, String> {
    specula_analyze::lens::Rx::parse(text)
}

fn parse_standard(text: &str) -> Result<&'static specula_analyze::lens::standard::Table, String> {
    specula_analyze::lens::standard::find(text)
}

fn parse_pair(text: &str) -> Result<[f64; 2], String> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected X,Y in millimetres, got '{text}'"))?;
    values
        .try_into()
        .map_err(|_| format!("expected X,Y (2 numbers), got '{text}'"))
}

/// In double precision: a step of 0.1 as a float would end the grid at 29.9°.
fn parse_gaze(text: &str) -> Result<[f64; 3], String> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected H_MAX,V_MAX,STEP, got '{text}'"))?;
    values
        .try_into()
        .map_err(|_| format!("expected H_MAX,V_MAX,STEP (3 numbers), got '{text}'"))
}

/// Where the eyes are, in the vehicle frame.
#[derive(clap::Args)]
pub struct EyeArgs {
    /// An eye point X,Y,Z in metres (repeatable; default: the camera's eye).
    #[arg(help_heading = "Eye points", long = "eye", value_parser = parse_point, allow_hyphen_values = true, conflicts_with_all = ["eyebox", "ocular"])]
    eyes: Vec<Vec3>,
    /// A grid of NX × NY eye points spanning W × H metres, centred on the camera's eye,
    /// horizontal and vertical in the vehicle frame: W,H,NX,NY.
    #[arg(help_heading = "Eye points", long, value_parser = parse_eyebox, conflicts_with = "ocular")]
    eyebox: Option<Eyes>,
    /// UN ECE R46's two ocular points: 65 mm apart across the vehicle, centred on the
    /// camera's eye.
    #[arg(help_heading = "Eye points", long)]
    ocular: bool,
    /// The vehicle's longitudinal axis X,Y,Z (default: the camera's view direction projected on
    /// the ground plane); up is +Y.
    #[arg(help_heading = "Eye points", long, value_parser = parse_point, allow_hyphen_values = true)]
    forward: Option<Vec3>,
}

impl EyeArgs {
    fn eyes(&self) -> Eyes {
        if self.ocular {
            Eyes::Ocular
        } else if let Some(eyebox) = &self.eyebox {
            eyebox.clone()
        } else if !self.eyes.is_empty() {
            Eyes::Points(self.eyes.clone())
        } else {
            Eyes::Camera
        }
    }
}

#[derive(clap::Args)]
pub struct MirrorViewArgs {
    /// Built-in scene name, a .toml scene file, or a mesh/scene file.
    #[arg(default_value = DEFAULT_SCENE)]
    scene: String,
    /// The mirror, as the scene names it (`NAME#k` for a component).
    #[arg(long)]
    mirror: String,
    #[command(flatten)]
    eyes: EyeArgs,
    /// The ground plane's height Y in metres (default: the lowest point of the scene).
    #[arg(
        help_heading = "Ground and precision",
        long,
        allow_hyphen_values = true
    )]
    ground: Option<f32>,
    /// Ground farther than this from an eye point, horizontally, is not counted (metres).
    #[arg(help_heading = "Ground and precision", long, default_value_t = mirror_view::DEFAULT_RANGE_M)]
    range: f32,
    /// A required region on the ground, X0,Z0,X1,Z1 in metres.
    #[arg(help_heading = "Ground and precision", long, value_parser = parse_region, allow_hyphen_values = true)]
    region: Option<Region>,
    /// Refinement stops when the solid angle and the areas change by less than this share.
    #[arg(help_heading = "Ground and precision", long, default_value_t = mirror_view::Precision::REPORT.tolerance)]
    tolerance: f64,
    /// ... and the extents by less than this many degrees.
    #[arg(help_heading = "Ground and precision", long, default_value_t = mirror_view::Precision::REPORT.tolerance_deg)]
    tolerance_deg: f64,
    /// Judge the mirror against a regulation's prescribed fields and mirror rules: r46-i,
    /// r46-ii, r46-iii, r46-iv, r46-v, fmvss111 (the driver's flat mirror) or fmvss111-convex
    /// (the passenger's convex mirror) (see docs/analyses/mirror-view.md).
    #[arg(help_heading = "Regulation (UN R46, FMVSS 111)", long)]
    regulation: Option<String>,
    /// The driver's R point X,Y,Z: R46's ocular points lie 635 mm above it, 65 mm apart across
    /// the vehicle.
    #[arg(help_heading = "Regulation (UN R46, FMVSS 111)", long, value_parser = parse_point, allow_hyphen_values = true, requires = "regulation")]
    r_point: Option<Vec3>,
    /// The vehicle's outermost point X,Y,Z on the mirror's side: the fields' inner boundary
    /// plane passes through it, parallel to the median plane (default: the outermost point of
    /// the --vehicle parts).
    #[arg(help_heading = "Regulation (UN R46, FMVSS 111)", long, value_parser = parse_point, allow_hyphen_values = true, requires = "regulation")]
    outermost: Option<Vec3>,
    /// A point X,Y,Z of the vehicle's median longitudinal plane (class I's field is centred on
    /// it; default: the plane through the ocular points).
    #[arg(help_heading = "Regulation (UN R46, FMVSS 111)", long, value_parser = parse_point, allow_hyphen_values = true, requires = "regulation")]
    median: Option<Vec3>,
    /// The side of the vehicle the mirror serves (default: the side it lies on).
    #[arg(
        help_heading = "Regulation (UN R46, FMVSS 111)",
        long,
        value_enum,
        requires = "regulation"
    )]
    side: Option<SideArg>,
    /// An eyellipse CX,CY,CZ,AX,AY,AZ[,N]: centre and semi-axes along the vehicle's forward,
    /// lateral and up axes (metres), N points on its surface (default 26), each judged alone.
    #[arg(help_heading = "Regulation (UN R46, FMVSS 111)", long, value_parser = parse_eyellipse, allow_hyphen_values = true, requires = "regulation", conflicts_with = "r_point")]
    eyellipse: Option<(Vec3, Vec3, usize)>,
    /// The eyellipse's side-view tilt, degrees (its forward axis turned up).
    #[arg(
        help_heading = "Regulation (UN R46, FMVSS 111)",
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    eyellipse_tilt: f32,
    /// A part of the vehicle's own body or fittings (repeatable): with --regulation only these
    /// hide the mirror and the road, and what they hide is reported apart.
    #[arg(
        help_heading = "Regulation (UN R46, FMVSS 111)",
        long = "vehicle",
        requires = "regulation"
    )]
    vehicle: Vec<String>,
    /// Turn the mirror about this pivot X,Y,Z (yaw and pitch within ±20°) and report the poses
    /// that pass, the widest-margin one and, failing all, the most seen.
    #[arg(help_heading = "Regulation (UN R46, FMVSS 111)", long, value_parser = parse_point, allow_hyphen_values = true, requires = "regulation")]
    adjust: Option<Vec3>,
    /// The pose grid's step, degrees.
    #[arg(
        help_heading = "Regulation (UN R46, FMVSS 111)",
        long,
        default_value_t = 5.0
    )]
    adjust_step: f32,
    /// The surface the samples lie on: the mirror's exact one (a generated patch, sphere or
    /// cap; the default where there is one), its triangles as the renderer shades them, or a
    /// smooth surface fitted to them.
    #[arg(help_heading = "Ground and precision", long, value_enum)]
    surface: Option<SurfaceArg>,
    /// Write the report as JSON here (schema: docs/analyze-mirror-view.schema.json).
    #[arg(help_heading = "Output", long)]
    json: Option<PathBuf>,
    /// Write a report folder: report.html (figures, parameters, plots), report.json, the
    /// ground map and the mirror seen from the first eye point as PNG and SVG.
    #[arg(help_heading = "Output", long)]
    report: Option<PathBuf>,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum SideArg {
    Left,
    Right,
}

pub(crate) fn parse_eyellipse(text: &str) -> Result<(Vec3, Vec3, usize), String> {
    let what = "CX,CY,CZ,AX,AY,AZ[,N]";
    let (values, count) = match numbers::<7>(text, what) {
        Ok(v) => {
            let n = v[6];
            if !(n.fract() == 0.0 && n >= 0.0) {
                return Err(format!("N must be a whole number of points, got '{text}'"));
            }
            ([v[0], v[1], v[2], v[3], v[4], v[5]], n as usize)
        }
        Err(_) => (numbers::<6>(text, what)?, 26),
    };
    Ok((
        Vec3::new(values[0], values[1], values[2]),
        Vec3::new(values[3], values[4], values[5]),
        count,
    ))
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum SurfaceArg {
    Exact,
    Mesh,
    Smooth,
}

impl SurfaceArg {
    fn model(self) -> SurfaceModel {
        match self {
            SurfaceArg::Exact => SurfaceModel::Exact,
            SurfaceArg::Mesh => SurfaceModel::Mesh,
            SurfaceArg::Smooth => SurfaceModel::Smooth,
        }
    }
}

pub(crate) fn numbers<const N: usize>(text: &str, what: &str) -> Result<[f32; N], String> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| v.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected {what}, got '{text}'"))?;
    let values: [f32; N] = values
        .try_into()
        .map_err(|_| format!("expected {what} ({N} numbers), got '{text}'"))?;
    if values.iter().any(|v| !v.is_finite()) {
        return Err(format!("expected {what}, finite numbers, got '{text}'"));
    }
    Ok(values)
}

pub(crate) fn parse_point(text: &str) -> Result<Vec3, String> {
    numbers::<3>(text, "X,Y,Z").map(Vec3::from_array)
}

fn parse_eyebox(text: &str) -> Result<Eyes, String> {
    let values = numbers::<4>(text, "W,H,NX,NY")?;
    Eyes::eyebox(values).map_err(|e| format!("{e} ('{text}')"))
}

fn parse_region(text: &str) -> Result<Region, String> {
    let [x0, z0, x1, z1] = numbers::<4>(text, "X0,Z0,X1,Z1")?;
    Region::new(x0, z0, x1, z1).map_err(|e| e.to_string())
}

/// The progress bar over `count` eye points.
pub(crate) fn eye_bar(count: usize) -> ProgressBar {
    let bar = ProgressBar::new(count as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} eye points ({elapsed})")
            .expect("valid template"),
    );
    bar
}

/// Writes `report` as JSON to `path`, where one was asked for.
pub(crate) fn write_json(
    path: Option<&std::path::Path>,
    report: &impl serde::Serialize,
) -> Result<()> {
    if let Some(path) = path {
        std::fs::write(path, serde_json::to_string_pretty(report)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

pub fn run(kind: Kind) -> Result<()> {
    match kind {
        Kind::MirrorView(args) => mirror_view(args),
        Kind::Glare(args) => glare::run(*args),
        Kind::Lens(args) => lens(args),
    }
}

fn lens(args: LensArgs) -> Result<()> {
    use specula_analyze::lens;
    let scene = crate::load_scene(&args.scene)?;
    let mesh = lens::find_lens(&scene, &args.lens)?;
    let mut options = lens::default_options_with(&scene, mesh, false)?;
    options.rotation_behind_cornea_m = args.rotation_behind_cornea * 1e-3;
    options.rotation_centre = match args.rotation_centre {
        Some(centre) => centre.as_dvec3(),
        None => lens::rotation_centre_behind(
            &scene,
            mesh,
            args.vertex_distance
                .map_or(lens::DEFAULT_VERTEX_DISTANCE_M, |d| d * 1e-3),
            options.rotation_behind_cornea_m,
        )?,
    };
    options.eye = match args.eye {
        EyeSide::Right => lens::Eye::Right,
        EyeSide::Left => lens::Eye::Left,
    };
    let [h, v, step] = args.gaze;
    options.gaze = lens::Gaze {
        h_max_deg: h,
        v_max_deg: v,
        step_deg: step,
    };
    options.object_distance_m = args.object_distance;
    if !(args.step_mm.is_finite() && args.step_mm > 0.0) {
        anyhow::bail!(
            "--step-mm {}: the bundle needs a positive width",
            args.step_mm
        );
    }
    options.step_m = args.step_mm * 1e-3;
    if let Some(surface) = args.surface {
        options.surface = surface.model();
    }
    options.wear = lens::Wear {
        pantoscopic_deg: args.pantoscopic,
        wrap_deg: args.wrap,
    };
    if args.prescription.is_some() {
        options.prescription = args.prescription;
    }
    options.refraction_vertex_m = args.refraction_vertex.map(|d| d * 1e-3);
    options.compensate = args.compensate;
    options.standard = args.standard;
    options.reference_points_mm = [
        args.distance_reference
            .unwrap_or(options.reference_points_mm[0]),
        args.prism_reference,
    ];
    if args.add.is_some() {
        options.add_d = args.add;
    }
    if args.near_reference.is_some() {
        options.near_reference_mm = args.near_reference;
    }
    options.near = args.near.map(|distance_m| lens::near::Near {
        distance_m,
        half_pd_m: args.pd * 0.5e-3,
        down_deg: args.near_down,
    });
    options.lens_step_mm = Some(args.lens_step);
    let rows = options.gaze.vertical().len();
    let bar = ProgressBar::new(rows as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} gaze rows ({elapsed})")
            .expect("valid template"),
    );
    let report = lens::analyze(&scene, &options, &|done| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    if let Some(v) = &report.verdict {
        println!("{}: {}", v.edition, v.verdict.word());
        print_reasons(&verdict_page::lens_reasons(v, &report));
    }
    print_lens(&report);
    print_lens_checks(&report, args.focimeter);
    write_json(args.json.as_deref(), &report)?;
    if let Some(dir) = &args.report {
        let html = specula_analyze::report::write_lens(dir, &report)?;
        println!("report: {}", html.display());
    }
    Ok(())
}

fn print_lens(r: &specula_analyze::lens::Report) {
    let number = |v: Option<f64>, digits: usize| {
        v.map(|v| format!("{v:.digits$}"))
            .unwrap_or_else(|| "outside".into())
    };
    println!(
        "{}: '{}', {} eye, centre of rotation ({:.4}, {:.4}, {:.4}), object {}",
        r.scene,
        r.lens,
        match r.eye {
            specula_analyze::lens::Eye::Right => "right",
            specula_analyze::lens::Eye::Left => "left",
        },
        r.rotation_centre[0],
        r.rotation_centre[1],
        r.rotation_centre[2],
        r.object_distance_m
            .map(|d| format!("at {d} m"))
            .unwrap_or_else(|| "at infinity".into())
    );
    println!(
        "{:<14}{:>10}{:>10}{:>8}{:>10}{:>16}{:>10}{:>10}",
        "gaze h, v °",
        "sphere D",
        "cyl D",
        "axis °",
        "mean D",
        "prism Δ (h, v)",
        "colour ′",
        "dist. %"
    );
    let h = r.gaze.horizontal();
    let v = r.gaze.vertical();
    // Across the centre row, then down the centre column, every few cells from the centre.
    let every = h.len().max(v.len()).div_ceil(7).max(1) as i64;
    let shown = |values: &[f64], x: f64| {
        let i = values.iter().position(|y| *y == x).unwrap_or(0) as i64;
        (i - (values.len() / 2) as i64) % every == 0
    };
    let across = r
        .grid
        .iter()
        .filter(|c| c.gaze_deg[1] == 0.0 && shown(&h, c.gaze_deg[0]));
    let down = r
        .grid
        .iter()
        .filter(|c| c.gaze_deg[0] == 0.0 && c.gaze_deg[1] != 0.0 && shown(&v, c.gaze_deg[1]));
    for c in across.chain(down) {
        // An axis means nothing without cylinder.
        let axis = c
            .axis_deg
            .filter(|_| c.cylinder_d.is_some_and(|x| x.abs() >= 0.005));
        println!(
            "{:<14}{:>10}{:>10}{:>8}{:>10}{:>16}{:>10}{:>10}",
            format!("{}, {}", c.gaze_deg[0], c.gaze_deg[1]),
            number(c.sphere_d, 3),
            number(c.cylinder_d, 3),
            if c.outside {
                "outside".into()
            } else {
                axis.map(|a| format!("{a:.0}"))
                    .unwrap_or_else(|| "–".into())
            },
            number(c.mean_power_d, 3),
            c.prism_d
                .map(|[a, b]| format!("{a:.2}, {b:.2}"))
                .unwrap_or_else(|| "outside".into()),
            number(c.lateral_colour_arcmin, 2),
            number(c.distortion_percent, 2),
        );
    }
    let outside = r.grid.iter().filter(|c| c.outside).count();
    println!(
        "{} gaze directions, {outside} outside the lens; finite differences changed by at most {:.1e} D",
        r.grid.len(),
        r.finite_difference_change_d
    );
}

/// The lens's magnification, base curve, focimeter readings (with `focimeter`), ordered
/// prescription and verdict.
fn print_lens_checks(r: &specula_analyze::lens::Report, focimeter: bool) {
    let [sh, sv] = r.spectacle_magnification;
    println!(
        "surface {}{}; vertex distance {:.2} mm, pantoscopic {}°, wrap {}°; spectacle \
         magnification {sh:.4} (h), {sv:.4} (v)",
        r.surface.name(),
        r.surface_uncertainty_d
            .map(|u| format!(" (surface uncertainty {u:.4} D)"))
            .unwrap_or_default(),
        r.vertex_distance_mm,
        r.wear.pantoscopic_deg,
        r.wear.wrap_deg
    );
    if let Some(b) = r.base_curve {
        println!(
            "base curve {:.2} D in the lens's index, {:.2} D in the 1.53 tooling index",
            b.lens_index_d, b.tooling_index_d
        );
    }
    if focimeter {
        for f in &r.focimeter {
            println!(
                "focimeter at the {} ({:.1}, {:.1} mm): {:.3} / {:.3} × {:.1}, prism {:.3} \
                 out, {:.3} up (± {:.1e} D)",
                f.point,
                f.at_mm[0],
                f.at_mm[1],
                f.sphere_d,
                f.cylinder_d,
                f.axis_deg,
                f.prism_d[0],
                f.prism_d[1],
                f.uncertainty_d
            );
        }
    }
    if let Some(t) = r.target {
        println!(
            "as worn the wearer should get {:.3} / {:.3} × {:.1}",
            t.sphere_d, t.cylinder_d, t.axis_deg
        );
    }
    if let Some(c) = r.compensated {
        println!(
            "compensated, to order: {:.3} / {:.3} × {:.1} (residual {:.1e} D)",
            c.ordered.sphere_d, c.ordered.cylinder_d, c.ordered.axis_deg, c.residual_d
        );
    }
    print_zones(r);
    if let Some(v) = &r.verdict {
        println!("{}: {}", v.edition, v.verdict.word());
        for c in &v.checks {
            println!(
                "  {:<10}{:>12}  measured {:>8.3}  ordered {:>8.3}  off by {:.3} of ± {:.3} {}  margin {:>7.3} ± {:.3}  {}{}",
                c.quantity,
                c.meridian
                    .map(|m| format!("at {m:.0}°"))
                    .unwrap_or_default(),
                c.measured,
                c.ordered,
                c.value,
                c.limit,
                c.unit,
                c.margin,
                c.uncertainty,
                c.verdict.word(),
                c.note
                    .as_deref()
                    .map(|n| format!(" ({n})"))
                    .unwrap_or_default()
            );
        }
    }
}

/// The clear zones, a progressive lens's figures and the near figures.
fn print_zones(r: &specula_analyze::lens::Report) {
    for z in &r.clear_zones {
        println!(
            "clear where {}: {:.0} mm² of lens, {:.4} sr of gaze, {:.1} mm wide through the \
             fitting point",
            z.criterion, z.lens_area_mm2, z.solid_angle_sr, z.horizontal_width_mm
        );
    }
    if let Some(p) = &r.progressive {
        let length = |v: Option<f64>| {
            v.map(|v| format!("{v:.1} mm"))
                .unwrap_or_else(|| "not reached".into())
        };
        println!(
            "progressive: add {:.3} D measured on the {} (ordered {:.2}; far {:.3}, near {:.3} \
             D; as worn {:.3} D); corridor length {} (85 %), {} (95 %); corridor width {} \
             (0.50 D), {} (1.00 D); far zone {:.1} mm, near zone {:.1} mm wide (0.50 D); \
             largest unwanted cylinder {:.2} D at ({:.1}, {:.1}) mm",
            p.add_d,
            p.measured_on,
            p.ordered_add_d,
            p.far_power_d,
            p.near_power_d,
            p.map_add_d,
            length(p.corridor_length_mm_85),
            length(p.corridor_length_mm_95),
            length(p.corridor_width_mm_050),
            length(p.corridor_width_mm_100),
            p.far_zone_width_mm_050,
            p.near_zone_width_mm_050,
            p.max_unwanted_cylinder_d,
            p.max_unwanted_cylinder_at_mm[0],
            p.max_unwanted_cylinder_at_mm[1]
        );
    }
    if let Some(n) = &r.near {
        let c = &n.cell;
        println!(
            "near point {:.3} m away, {:.1}° down (PD {:.0} mm): through the lens at ({:.2}, \
             {:.2}) mm, inset {:.2} mm; power {} D for the object's {:.3} D (error {} D, \
             unwanted cylinder {} D), prism {}",
            n.distance_m,
            n.down_deg,
            n.pd_mm,
            n.point_on_lens_mm[0],
            n.point_on_lens_mm[1],
            n.inset_mm,
            n.power_d
                .map_or_else(|| "outside".into(), |p| format!("{p:.3}")),
            n.object_vergence_d,
            c.power_error_d
                .map_or_else(|| "–".into(), |v| format!("{v:.3}")),
            c.unwanted_cylinder_d
                .map_or_else(|| "–".into(), |v| format!("{v:.3}")),
            c.prism_d
                .map(|[a, b]| format!("{a:.2} Δ out, {b:.2} Δ up"))
                .unwrap_or_else(|| "–".into())
        );
    }
}

fn mirror_view(args: MirrorViewArgs) -> Result<()> {
    let scene = crate::load_scene(&args.scene)?;
    let mirror = specula_analyze::object(&scene, "--mirror", &args.mirror)?;
    let frame = VehicleFrame::new(&scene.camera, args.eyes.forward)?;
    let eyes = args.eyes.eyes().points(scene.camera.eye, &frame)?;
    let mut options =
        mirror_view::Options::new(&scene, mirror, frame, mirror_view::Precision::REPORT);
    options.ground_y = args.ground.unwrap_or(options.ground_y);
    options.range_m = args.range;
    options.region = args.region;
    options.tolerance = args.tolerance;
    options.tolerance_deg = args.tolerance_deg;
    if let Some(surface) = args.surface {
        options.surface = surface.model();
    }
    options.validate(&scene)?;
    if let Some(name) = &args.regulation {
        return regulation(&args, name, &scene, options, eyes);
    }
    let accel = SceneAccel::new(&scene);
    let bar = eye_bar(eyes.len());
    let view = mirror_view::analyze(&scene, &accel, &eyes, &options, &|done| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    print_mirror_view(&view.report);
    write_json(args.json.as_deref(), &view.report)?;
    if let Some(dir) = &args.report {
        let page = specula_analyze::report::MirrorViewPage {
            view: &view,
            scene: &scene,
            accel: &accel,
            mirror,
            regulation: None,
        };
        let html = specula_analyze::report::write_mirror_view(dir, &page)?;
        println!("report: {}", html.display());
    }
    Ok(())
}

fn share(value: Option<f64>) -> String {
    value
        .map(|v| format!("{:.1} %", v * 100.0))
        .unwrap_or_else(|| "-".into())
}

fn print_mirror_view(r: &mirror_view::Report) {
    println!(
        "{}: mirror '{}', ground y = {} m, range {} m{}",
        r.scene,
        r.mirror,
        r.ground_y,
        r.range_m,
        r.region
            .map(|g| format!(", region x {}..{}, z {}..{}", g.x0, g.x1, g.z0, g.z1))
            .unwrap_or_default()
    );
    println!(
        "{:<28}{:>10}{:>10}{:>12}{:>12}{:>10}{:>10}{:>12}",
        "eye point",
        "horiz °",
        "vert °",
        "solid sr",
        "ground m²",
        "region",
        "blind m²",
        "samples/m²"
    );
    let row = |label: String, f: &mirror_view::Figures, density: String| {
        println!(
            "{label:<28}{:>10.2}{:>10.2}{:>12.5}{:>12.2}{:>10}{:>10}{:>12}",
            f.horizontal_deg,
            f.vertical_deg,
            f.solid_angle_sr,
            f.ground_area_m2,
            share(f.region_seen_by_any),
            f.blind_area_m2
                .map(|b| format!("{b:.2}"))
                .unwrap_or_else(|| "-".into()),
            density
        )
    };
    for eye in &r.eyes {
        let [x, y, z] = eye.position;
        row(
            format!("({x:.3}, {y:.3}, {z:.3})"),
            &eye.figures,
            format!(
                "{:.0}{}",
                eye.density_per_m2,
                if eye.converged {
                    ""
                } else {
                    " (not converged)"
                }
            ),
        );
    }
    if r.eyes.len() > 1 {
        row("all eye points (any)".into(), &r.figures, String::new());
        println!(
            "region seen by every eye point: {}",
            share(r.figures.region_seen_by_all)
        );
    }
}

/// `mirror-view --regulation NAME`: the vehicle and the eyes from the options, the verdict
/// printed and written, and with `--adjust` the pose search.
fn regulation(
    args: &MirrorViewArgs,
    name: &str,
    scene: &specula_scene::Scene,
    mut options: mirror_view::Options,
    camera_eyes: Vec<Vec3>,
) -> Result<()> {
    use specula_analyze::regulation::{self as reg, EyeRule};
    let regulation = reg::by_name(name)?;
    let frame = options.frame;
    let vehicle_parts = args
        .vehicle
        .iter()
        .map(|n| specula_analyze::object(scene, "--vehicle", n))
        .collect::<Result<Vec<_>, _>>()?;
    options.obstacles = mirror_view::Obstacles::Vehicle(vehicle_parts.clone());
    options.validate(scene)?;
    if regulation.eyes == EyeRule::DriversEyes && args.r_point.is_some() {
        anyhow::bail!(
            "--r-point: {} judges from the driver's eyes (--eye or --eyellipse), not from R46's \
             ocular points",
            regulation.name
        );
    }
    let (eyes, eye_sets, eyes_option, reference) = regulation_eyes(args, &frame, camera_eyes)?;
    let vehicle = regulation_vehicle(args, scene, &options, &vehicle_parts, reference)?;
    let request = reg::Request {
        regulation,
        vehicle: vehicle.clone(),
        eyes: eyes.clone(),
        eye_sets,
        eyes_option,
        view: options,
    };
    let accel = SceneAccel::new(scene);
    let bar = eye_bar(eyes.len());
    let judged = reg::evaluate(scene, &accel, &request, &|done| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let adjustment = args
        .adjust
        .map(|pivot| adjust_mirror(scene, &request, pivot, args.adjust_step))
        .transpose()?;
    let report = reg::Document {
        view: &judged.view.report,
        vehicle: reg::VehicleReport {
            reference: vehicle.reference.to_array(),
            side: vehicle.side,
            outermost: vehicle.outermost.map(|p| p.to_array()),
            median: vehicle.median.to_array(),
            eyes_from: eyes_option,
            vehicle_parts: args.vehicle.clone(),
        },
        regulation: &judged.verdict,
        adjustment: adjustment.as_ref(),
    };
    print_verdict(&report, &vehicle, args.median.is_none());
    if let Some(a) = &adjustment {
        print_adjustment(a);
    }
    write_json(args.json.as_deref(), &report)?;
    if let Some(dir) = &args.report {
        let page = specula_analyze::report::MirrorViewPage {
            view: &judged.view,
            scene,
            accel: &accel,
            mirror: request.view.mirror,
            regulation: Some((&report, request.regulation, &vehicle)),
        };
        let html = specula_analyze::report::write_mirror_view(dir, &page)?;
        println!("report: {}", html.display());
    }
    Ok(())
}

/// The eye points a regulation judges from: an eyellipse's (each alone), R46's ocular points
/// above the R point, or the given eyes (together); the option they came from and the
/// reference point of the vehicle frame.
fn regulation_eyes(
    args: &MirrorViewArgs,
    frame: &VehicleFrame,
    camera_eyes: Vec<Vec3>,
) -> Result<(
    Vec<Vec3>,
    specula_analyze::regulation::EyeSets,
    &'static str,
    Vec3,
)> {
    use specula_analyze::regulation::{self as reg, EyeSets};
    let frame = *frame;
    Ok(if let Some((centre, axes, count)) = args.eyellipse {
        let points = reg::eyellipse_points(&frame, centre, axes, args.eyellipse_tilt, count)?;
        (points, EyeSets::EachAlone, "--eyellipse", centre)
    } else if let Some(r) = args.r_point {
        let ocular = reg::ocular_points(&frame, r);
        (
            ocular.to_vec(),
            EyeSets::Together,
            "--r-point",
            r + frame.up * reg::OCULAR_HEIGHT_M,
        )
    } else {
        let centre = camera_eyes.iter().copied().sum::<Vec3>() / camera_eyes.len() as f32;
        (camera_eyes, EyeSets::Together, "--eye", centre)
    })
}

/// The vehicle the fields are laid out for: its side (given, or the mirror's), its outermost
/// point (given, or its parts'), its median plane and ground.
fn regulation_vehicle(
    args: &MirrorViewArgs,
    scene: &specula_scene::Scene,
    options: &mirror_view::Options,
    vehicle_parts: &[usize],
    reference: Vec3,
) -> Result<specula_analyze::regulation::Vehicle> {
    use specula_analyze::mirror_surface::MirrorSurface;
    use specula_analyze::regulation::{self as reg, Side, Vehicle};
    let frame = options.frame;
    let surface =
        MirrorSurface::new(scene, options.mirror, options.surface).expect("options were validated");
    let (mirror_centre, _) = reg::mirror_centre_and_normal(&surface);
    let side = match args.side {
        Some(SideArg::Left) => Side::Left,
        Some(SideArg::Right) => Side::Right,
        None => Vehicle::side_of(&frame, reference, mirror_centre),
    };
    let outward = match side {
        Side::Right => frame.right,
        Side::Left => -frame.right,
    };
    let outermost = args.outermost.or_else(|| {
        vehicle_parts
            .iter()
            .flat_map(|&m| scene.meshes[m].positions.iter().copied())
            .max_by(|a, b| a.dot(outward).total_cmp(&b.dot(outward)))
    });
    let vehicle = Vehicle {
        frame,
        reference,
        side,
        outermost,
        median: args.median.unwrap_or(reference),
        ground_y: options.ground_y,
    };
    vehicle.validate()?;
    vehicle.validate()?;
    Ok(vehicle)
}

/// The poses of the mirror about `pivot` that pass, with a progress bar.
fn adjust_mirror(
    scene: &specula_scene::Scene,
    request: &specula_analyze::regulation::Request,
    pivot: Vec3,
    step_deg: f32,
) -> Result<specula_analyze::regulation::Adjustment> {
    use specula_analyze::regulation as reg;
    reg::check_pivot(scene, request.view.mirror, pivot)?;
    let bar = ProgressBar::new(1);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} mirror poses ({elapsed})")
            .expect("valid template"),
    );
    let adjust = reg::AdjustRequest {
        pivot,
        step_deg,
        limit_deg: 20.0,
    };
    let adjustment = reg::adjust(scene, request, &adjust, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    Ok(adjustment)
}

fn print_verdict(
    document: &specula_analyze::regulation::Document,
    vehicle: &specula_analyze::regulation::Vehicle,
    median_assumed: bool,
) {
    let v = document.regulation;
    println!(
        "{} ({}): {}",
        v.title,
        v.edition,
        match v.verdict {
            Outcome::Pass => "PASSES",
            Outcome::Fail => "FAILS",
            Outcome::Undecided => "UNDECIDED (a margin within its uncertainty)",
        }
    );
    println!("{}", document.judged_from());
    let [x, y, z] = vehicle.reference.to_array();
    println!(
        "fields from ({x:.3}, {y:.3}, {z:.3}), {} side{}; the body may hide {:.0} % unexcused",
        match vehicle.side {
            specula_analyze::regulation::Side::Left => "left",
            specula_analyze::regulation::Side::Right => "right",
        },
        if median_assumed {
            ", median plane through the ocular points (give --median)"
        } else {
            ""
        },
        v.allowance_share * 100.0
    );
    println!(
        "{:<46}{:>9}{:>9}{:>9}{:>10}{:>9}{:>9}{:>9}  verdict",
        "field", "seen", "±", "body", "blind m²", "beyond", "horizon", "margin"
    );
    for f in &v.fields {
        let g = &f.figures;
        println!(
            "{:<46}{:>9}{:>9}{:>9}{:>10.2}{:>9}{:>9}{:>9}  {}",
            f.name,
            format!("{:.2} %", g.seen_share * 100.0),
            format!(
                "{:.2} %",
                (g.seen_share_uncertainty + f.surface_uncertainty.unwrap_or(0.0)) * 100.0
            ),
            format!("{:.2} %", g.hidden_by_vehicle_share * 100.0),
            g.blind_area_m2,
            g.beyond_range_seen_share
                .map(|s| format!("{:.1} %", s * 100.0))
                .unwrap_or_else(|| "-".into()),
            g.horizon_seen
                .map(|h| if h { "seen" } else { "NOT" }.to_string())
                .unwrap_or_else(|| "-".into()),
            format!("{:.2} m", g.outer_margin_m.min(g.near_margin_m)),
            g.verdict.word()
        );
        if let Some(w) = &f.worst_eye {
            let [x, y, z] = w.position;
            println!(
                "    worst eye point ({x:.3}, {y:.3}, {z:.3}): {:.2} % seen",
                w.seen_share * 100.0
            );
        }
    }
    for c in &v.mirror_checks {
        let number =
            |x: Option<f64>| x.map_or_else(|| "-".to_string(), |x| verdict_page::number(x, ""));
        println!(
            "mirror: {} ({}): required {}; measured {}; value {} {unit}, limit {} {unit}, \
             margin {} ± {} {unit}: {}",
            c.name,
            c.source,
            c.required,
            c.measured,
            number(c.value),
            verdict_page::number(c.limit, ""),
            number(c.margin),
            number(c.uncertainty),
            c.verdict.word(),
            unit = c.unit,
        );
    }
    print_reasons(&verdict_page::regulation_reasons(v));
}

/// Why a verdict is not a pass, a line each.
fn print_reasons(reasons: &[String]) {
    if !reasons.is_empty() {
        println!("why:");
        for reason in reasons {
            println!("  - {reason}");
        }
    }
}

fn print_adjustment(a: &specula_analyze::regulation::Adjustment) {
    let range = |r: Option<[f32; 2]>| {
        r.map(|[lo, hi]| format!("{lo:+.1}° to {hi:+.1}°"))
            .unwrap_or_else(|| "none".into())
    };
    println!(
        "adjustment about ({:.3}, {:.3}, {:.3}), ±{}° in steps of {}°: {} of {} poses pass the fields (confirmed at the command's tolerances); yaw {}, pitch {}",
        a.pivot[0],
        a.pivot[1],
        a.pivot[2],
        a.limit_deg,
        a.step_deg,
        a.passing_poses,
        a.poses.len(),
        range(a.passing_yaw_deg),
        range(a.passing_pitch_deg)
    );
    let b = &a.best;
    println!(
        "{} pose: yaw {:+.1}°, pitch {:+.1}°: least share {:.2} % ('{}'), least margin {:.2} m; at the command's tolerance its fields {}",
        if a.passing_poses > 0 { "widest-margin" } else { "most-seen" },
        b.yaw_deg,
        b.pitch_deg,
        b.least_share * 100.0,
        b.least_share_field,
        b.least_margin_m,
        Outcome::all(a.best_verdict.fields.iter().map(|f| f.figures.verdict)).lower()
    );
}
