//! `specula analyze glare`: a named source or the sun reflected in a surface, in cd/m², the
//! contrast of a display behind it, sun sweeps and solar days.

use std::path::PathBuf;

use anyhow::Result;
use glam::Vec3;
use specula_analyze::frame::{Eyes, VehicleFrame};
use specula_analyze::glare::{self, sweep, Display, Source, Sun};
use specula_analyze::regulation as reg;
use specula_scene::builtin::DEFAULT_SCENE;
use specula_scene::Scene;
use specula_trace::SceneAccel;

use super::{eye_bar, numbers, parse_eyellipse, write_json, EyeArgs};

#[derive(clap::Args)]
pub struct GlareArgs {
    /// Built-in scene name, a .toml scene file, or a mesh/scene file.
    #[arg(default_value = DEFAULT_SCENE)]
    scene: String,
    /// The reflecting surface (a mirror or a glass), as the scene names it.
    #[arg(long)]
    surface: String,
    /// The source (an unlit or lit surface: a window, a lamp), as the scene names it.
    #[arg(help_heading = "Source", long, required_unless_present_any = ["sun", "sun_sweep"], conflicts_with_all = ["sun", "sun_sweep"])]
    source: Option<String>,
    /// The source's luminance in cd/m² (its radiance scaled so that its Y equals it): the glare
    /// then in cd/m² too.
    #[arg(help_heading = "Source", long)]
    source_luminance: Option<f64>,
    /// The sun as the source, at AZ,EL degrees in the vehicle frame: azimuth from the vehicle's
    /// forward axis, positive to its right (90 = right, 180 = behind); elevation above the
    /// ground plane, above 0.
    #[arg(help_heading = "Source", long, value_parser = parse_sun, allow_hyphen_values = true, conflicts_with = "sun_sweep")]
    sun: Option<(f64, f64)>,
    /// The sun's direct-normal illuminance, lux (100,000 lx is an upper bound, a high sun in a
    /// clear sky; the fall at low sun is not modelled: give less).
    #[arg(help_heading = "Source", long, default_value_t = glare::sun::DEFAULT_ILLUMINANCE_LX)]
    sun_illuminance: f64,
    /// Sweep the sun over AZ0,AZ1,EL0,EL1,STEP degrees (vehicle frame), each eye point traced
    /// once and every position looked up.
    #[arg(help_heading = "Sun sweep and solar day", long, value_parser = parse_sweep, allow_hyphen_values = true)]
    sun_sweep: Option<sweep::SweepSpec>,
    /// With --sun-sweep: the site's latitude, degrees north, for the solar day.
    #[arg(help_heading = "Sun sweep and solar day", long, requires_all = ["sun_sweep", "heading", "date"], allow_hyphen_values = true)]
    latitude: Option<f64>,
    /// The vehicle's heading, a compass bearing of its forward axis (0 = north, 90 = east).
    #[arg(
        help_heading = "Sun sweep and solar day",
        long,
        requires = "latitude",
        allow_hyphen_values = true
    )]
    heading: Option<f64>,
    /// The date of the solar day, YYYY-MM-DD.
    #[arg(help_heading = "Sun sweep and solar day", long, requires = "latitude")]
    date: Option<String>,
    /// Minutes between the solar day's looked-up times.
    #[arg(help_heading = "Sun sweep and solar day", long, default_value_t = 5.0)]
    time_step: f64,
    /// A display behind the surface (an unlit or lit mesh, as the scene names it): its contrast
    /// under the glare, per pixel.
    #[arg(help_heading = "Display", long, requires_all = ["symbol_luminance", "background_luminance", "min_contrast"])]
    display: Option<String>,
    /// The display's symbols' luminance, cd/m².
    #[arg(help_heading = "Display", long, requires = "display")]
    symbol_luminance: Option<f64>,
    /// The display's background luminance, cd/m².
    #[arg(help_heading = "Display", long, requires = "display")]
    background_luminance: Option<f64>,
    /// The contrast ratio below which a display pixel is washed out. ISO 15008:2017 §4.3.2
    /// sets a daylight minimum for passenger cars (its value could not be confirmed here, and
    /// its contrast clauses exclude heavy vehicles): give the figure you certify against.
    #[arg(help_heading = "Display", long, requires = "display")]
    min_contrast: Option<f64>,
    #[command(flatten)]
    eyes: EyeArgs,
    /// Eye points on an eyellipse CX,CY,CZ,AX,AY,AZ[,N]: centre and semi-axes along the
    /// vehicle's forward, lateral and up axes (metres), N points on its surface (default 26).
    #[arg(help_heading = "Eye points", long, value_parser = parse_eyellipse, allow_hyphen_values = true, conflicts_with_all = ["eyebox", "ocular", "eyes"])]
    eyellipse: Option<(Vec3, Vec3, usize)>,
    /// The eyellipse's side-view tilt, degrees (its forward axis turned up).
    #[arg(
        help_heading = "Eye points",
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    eyellipse_tilt: f32,
    /// Each eye point's image, WIDTHxHEIGHT (aimed at the surface, fitted to it).
    #[arg(help_heading = "Images", long, default_value = "320x240", value_parser = crate::parse_size)]
    size: (u32, u32),
    /// Luminance factor (the glare's luminance over the source's, dimensionless) above which a
    /// pixel counts as glare.
    #[arg(help_heading = "Images", long, default_value_t = glare::DEFAULT_THRESHOLD)]
    threshold: f64,
    /// Specular bounces a path may take (as the reference's --max-depth).
    #[arg(help_heading = "Images", long, default_value_t = glare::DEFAULT_MAX_DEPTH)]
    max_depth: u32,
    /// Write the report as JSON here (schema: docs/analyze-glare.schema.json).
    #[arg(help_heading = "Output", long)]
    json: Option<PathBuf>,
    /// Write a report folder: report.html, report.json, the eye points' map and the worst eye
    /// point's view with its glare outlined (a sweep adds its map and polar plot), as PNG and
    /// SVG.
    #[arg(help_heading = "Output", long)]
    report: Option<PathBuf>,
}

fn parse_sun(text: &str) -> Result<(f64, f64), String> {
    let [az, el] = numbers::<2>(text, "AZ,EL")?;
    Ok((f64::from(az), f64::from(el)))
}

fn parse_sweep(text: &str) -> Result<sweep::SweepSpec, String> {
    let [az0, az1, el0, el1, step] = numbers::<5>(text, "AZ0,AZ1,EL0,EL1,STEP")?;
    Ok(sweep::SweepSpec {
        azimuth: [f64::from(az0), f64::from(az1)],
        elevation: [f64::from(el0), f64::from(el1)],
        step_deg: f64::from(step),
    })
}

impl GlareArgs {
    fn options(&self, scene: &Scene) -> Result<glare::Options> {
        let surface = specula_analyze::object(scene, "--surface", &self.surface)?;
        let sun = |(azimuth_deg, elevation_deg)| Sun {
            azimuth_deg,
            elevation_deg,
            illuminance_lx: self.sun_illuminance,
        };
        let source = match (&self.source, self.sun) {
            (Some(name), _) => Source::Named(specula_analyze::object(scene, "--source", name)?),
            (None, Some(at)) => Source::Sun(sun(at)),
            // A sweep: the position is each of the sweep's in turn.
            (None, None) => Source::Sun(sun((0.0, 45.0))),
        };
        let display = match &self.display {
            Some(name) => Some(Display {
                mesh: specula_analyze::object(scene, "--display", name)?,
                symbol_cd_m2: self.symbol_luminance.unwrap_or_default(),
                background_cd_m2: self.background_luminance.unwrap_or_default(),
                min_contrast: self.min_contrast.unwrap_or_default(),
            }),
            None => None,
        };
        let options = glare::Options {
            surface,
            source,
            source_luminance: self.source_luminance,
            display,
            width: self.size.0,
            height: self.size.1,
            max_depth: self.max_depth,
            threshold: self.threshold,
        };
        options.validate(scene)?;
        Ok(options)
    }

    fn eye_points(&self, scene: &Scene) -> Result<(Vec<Vec3>, VehicleFrame)> {
        if let Some((centre, axes, count)) = self.eyellipse {
            let frame = VehicleFrame::new(&scene.camera, self.eyes.forward)?;
            let points = reg::eyellipse_points(&frame, centre, axes, self.eyellipse_tilt, count)?;
            return Ok((points, frame));
        }
        let eyes: Eyes = self.eyes.eyes();
        let frame = VehicleFrame::for_eyes(&scene.camera, self.eyes.forward, &eyes)?;
        Ok((eyes.points(scene.camera.eye, &frame)?, frame))
    }
}

pub fn run(args: GlareArgs) -> Result<()> {
    let scene = crate::load_scene(&args.scene)?;
    let options = args.options(&scene)?;
    let (eyes, frame) = args.eye_points(&scene)?;
    let accel = SceneAccel::new(&scene);
    let bar = eye_bar(eyes.len());
    let progress = |done: usize| bar.set_position(done as u64);
    let result = match &args.sun_sweep {
        Some(spec) => {
            let day = args.latitude.map(|latitude_deg| sweep::Day {
                latitude_deg,
                heading_deg: args.heading.unwrap_or_default(),
                date: args.date.clone().unwrap_or_default(),
                step_min: args.time_step,
            });
            sweep::sweep(
                &scene,
                &accel,
                &eyes,
                &frame,
                &options,
                spec,
                day.as_ref(),
                &progress,
            )?
        }
        None => glare::analyze(&scene, &accel, &eyes, &frame, &options, &progress)?,
    };
    bar.finish_and_clear();
    print_report(&result.report);
    write_json(args.json.as_deref(), &result.report)?;
    if let Some(dir) = &args.report {
        let html = specula_analyze::report::write_glare(dir, &result, &frame)?;
        println!("report: {}", html.display());
    }
    Ok(())
}

fn print_report(r: &glare::Report) {
    println!(
        "{}: '{}' reflected in '{}', {}x{} per eye point",
        r.scene, r.source, r.surface, r.width, r.height
    );
    if let Some(sun) = &r.sun {
        println!(
            "sun at azimuth {:.1}°, elevation {:.1}°{}: {:.0} lx, disc {:.3e} cd/m²",
            sun.azimuth_deg,
            sun.elevation_deg,
            if r.sweep.is_some() {
                " (the sweep's worst position)"
            } else {
                ""
            },
            sun.illuminance_lx,
            sun.luminance_cd_m2
        );
    }
    print_eyes(r);
    let washed = glare::washed_out_text(r)
        .map(|w| format!("; {w}"))
        .unwrap_or_default();
    match r.worst_eye {
        Some(k) => println!(
            "glare seen from {:.0} % of the eye points{washed}; the worst: eye {}",
            r.share_with_glare * 100.0,
            k + 1,
        ),
        None => println!(
            "no glare: no eye point sees '{}' reflected in '{}'{washed}",
            r.source, r.surface
        ),
    }
    if let Some(s) = &r.sweep {
        print_sweep(s);
    }
}

fn print_eyes(r: &glare::Report) {
    println!(
        "{:<36}{:>6}{:>11}{:>11}{:>11}{:>12}{:>11}{}",
        "eye point",
        "glare",
        "factor",
        "max cd/m²",
        "mean cd/m²",
        "veiling",
        "solid sr",
        if r.display.is_some() {
            format!(
                "{:>8}{:>11}{:>10}{:>9}",
                "τ", "veil cd/m²", "contrast", "washed"
            )
        } else {
            String::new()
        }
    );
    for (k, e) in r.eyes.iter().enumerate() {
        let [x, y, z] = e.position;
        let display = e
            .display
            .as_ref()
            .map(|d| {
                format!(
                    "{:>8.4}{:>11}{:>10.3}{:>8.1}%",
                    d.transmittance,
                    glare::luminance_text(Some(d.veiling_luminance_cd_m2)),
                    d.min_contrast,
                    d.washed_out_share * 100.0
                )
            })
            .unwrap_or_default();
        println!(
            "{:<36}{:>6}{:>11.5}{:>11}{:>11}{:>12}{:>11}{display}",
            format!("eye {} ({x:.3}, {y:.3}, {z:.3})", k + 1),
            if e.glare { "yes" } else { "no" },
            e.max_luminance_factor,
            glare::luminance_text(e.max_luminance_cd_m2),
            glare::luminance_text(e.mean_luminance_cd_m2),
            glare::veiling_text(e.max_veiling_ratio),
            specula_analyze::verdict_page::number(e.solid_angle_sr, ""),
        );
    }
    println!("{}", glare::VEILING_MEANS);
}

fn print_sweep(s: &sweep::SweepReport) {
    let glaring = s.positions.iter().filter(|p| p.glare()).count();
    let washed = s.positions.iter().filter(|p| p.washed_out()).count();
    println!(
        "sweep: {} sun positions, {glaring} glare from some eye point, {washed} wash the \
         display out; traced in {:.2} s, looked up in {:.3} s",
        s.positions.len(),
        s.trace_s,
        s.lookup_s
    );
    if let Some(day) = &s.day {
        println!(
            "{} at {}° N, heading {}°: glare {}; washed out {} (apparent solar time)",
            day.date,
            day.latitude_deg,
            day.heading_deg,
            specula_analyze::report::solar_runs(&day.glare_hours),
            specula_analyze::report::solar_runs(&day.washed_out_hours)
        );
    }
}
