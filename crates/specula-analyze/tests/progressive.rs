//! Progressive lenses, clear zones and near vision against closed forms: Minkwitz's theorem on
//! the progressive design, sag grids against the exact sphere and torus they sample, the
//! measured add against the construction, Prentice's rule at a converged near point, and the
//! refusals.

use std::path::PathBuf;
use std::sync::Arc;

use glam::Mat4;
use specula_analyze::lens::near::Near;
use specula_analyze::lens::standard::find;
use specula_analyze::lens::{analyze, default_options, Options, Report};
use specula_analyze::AnalyzeError;
use specula_scene::freeform::{Freeform, Progressive, SagGrid};
use specula_scene::{Prescription, Scene};

mod common;
use common::spectacles;

fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn run(scene: &Scene, adjust: impl FnOnce(&mut Options)) -> Result<Report, AnalyzeError> {
    let mut options = default_options(scene, 0).unwrap();
    options.gaze.h_max_deg = 20.0;
    options.gaze.v_max_deg = 20.0;
    options.gaze.step_deg = 5.0;
    adjust(&mut options);
    analyze(scene, &options, &|_| {})
}

/// The progressive example of scenes/progressive.toml and its front's design.
fn example() -> (Scene, Progressive) {
    let scene = specula_scene::load(
        repository()
            .join("scenes/progressive.toml")
            .to_str()
            .unwrap(),
    )
    .unwrap();
    let front = scene.prescriptions[0].1.front.clone();
    let Some(Freeform::Progressive(design)) = front else {
        panic!("the example's front is the progressive design: {front:?}");
    };
    (scene, design)
}

/// The example's front sampled every half millimetre over ±32 mm (past the 30 mm rim, where
/// the rays leaving the lens's edge still need it), as its CSV holds it.
fn sampled_front(design: &Progressive) -> SagGrid {
    let nodes: Vec<f64> = (-64..=64).map(|k| f64::from(k) * 0.5e-3).collect();
    SagGrid::sampled("progressive-front.csv", nodes.clone(), nodes, |x, y| {
        design.local(x, y).unwrap().sag
    })
}

#[test]
fn the_grid_example_s_csv_is_the_progressive_design_sampled() {
    let (_, design) = example();
    let csv = sampled_front(&design).to_csv();
    let path = repository().join("scenes/progressive-front.csv");
    if std::env::var_os("SPECULA_REGENERATE").is_some() {
        std::fs::write(&path, &csv).unwrap();
    }
    let stored = std::fs::read_to_string(&path).unwrap();
    assert!(
        stored == csv,
        "{} is not the design sampled: regenerate it with SPECULA_REGENERATE=1",
        path.display()
    );
}

/// Minkwitz's theorem in surface terms: beside an umbilic line, to first order,
/// ∂C/∂x = 2 ∂M/∂y, C = (n − 1)|κ1 − κ2| and M = (n − 1)(κ1 + κ2)/2.
#[test]
fn the_design_s_corridor_obeys_minkwitz_s_theorem() {
    let (_, design) = example();
    let n1 = design.index - 1.0;
    let at = |x: f64, y: f64| {
        let [k1, k2] = design.local(x, y).unwrap().principal_curvatures();
        (n1 * (k1 - k2).abs(), n1 * 0.5 * (k1 + k2))
    };
    let e = 1e-5;
    let mut worst: f64 = 0.0;
    // Along the corridor's middle, from 30 % to 70 % of its length, where the mean power
    // rises at least at half its peak rate: towards the corridor's ends the first-order
    // term vanishes and the second-order ones (the profile's curvature) take over.
    for share in [0.3, 0.4, 0.5, 0.6, 0.7] {
        let y = -share * design.corridor_length;
        let y_mm = y * 1e3;
        // On the line itself: umbilic.
        // Umbilic: the principal curvatures' spread cancels to rounding (√ of 1e-14 of M²).
        let on_line = at(0.0, y).0;
        assert!(
            on_line < 1e-5,
            "{on_line} D of cylinder on the corridor at y = {y_mm} mm"
        );
        let dm_dy = (at(0.0, y + e).1 - at(0.0, y - e).1) / (2.0 * e);
        for x_mm in [-2.0, -1.5, -1.0, -0.5, 0.5, 1.0, 1.5, 2.0] {
            let x: f64 = x_mm * 1e-3;
            let dc_dx = (at(x + e, y).0 - at(x - e, y).0) / (2.0 * e) * x.signum();
            let error = (dc_dx / (2.0 * dm_dy.abs()) - 1.0).abs();
            worst = worst.max(error);
        }
    }
    println!(
        "Minkwitz: ∂C/∂x against 2 |∂M/∂y| within {:.2} %",
        worst * 100.0
    );
    assert!(worst < 0.05, "{worst}");
}

#[test]
fn sag_grids_sampled_from_a_sphere_and_a_torus_analyse_like_them() {
    let p = Prescription {
        sphere: -2.0,
        cylinder: -1.25,
        axis_deg: 30.0,
        index: 1.6,
        abbe: 42.0,
        center_thickness: 0.002,
        base_curve: 4.0,
        diameter: 0.05,
        ..Prescription::default()
    };
    let exact = p.exact_lens();
    let nodes: Vec<f64> = (-26..=26).map(|k| f64::from(k) * 1e-3).collect();
    let grid = |surface: &specula_scene::LensSurface, name: &str| {
        Freeform::SagGrid(Arc::new(SagGrid::sampled(
            name,
            nodes.clone(),
            nodes.clone(),
            |x, y| surface.height(x, y).unwrap().0 - surface.vertex_z,
        )))
    };
    let gridded = Prescription {
        front: Some(grid(&exact.front, "sphere")),
        back: Some(grid(&exact.back, "torus")),
        ..p.clone()
    };
    let a = run(&spectacles(&p, Mat4::IDENTITY), |_| {}).unwrap();
    let b = run(&spectacles(&gridded, Mat4::IDENTITY), |_| {}).unwrap();
    let mut worst: f64 = 0.0;
    for (x, y) in a.grid.iter().zip(&b.grid).chain([(&a.centre, &b.centre)]) {
        for (u, v) in [
            (x.sphere_d, y.sphere_d),
            (x.cylinder_d, y.cylinder_d),
            (x.mean_power_d, y.mean_power_d),
        ] {
            worst = worst.max((u.unwrap() - v.unwrap()).abs());
        }
    }
    for (x, y) in a.focimeter.iter().zip(&b.focimeter) {
        worst = worst
            .max((x.sphere_d - y.sphere_d).abs())
            .max((x.cylinder_d - y.cylinder_d).abs());
    }
    println!("sag grids against the exact sphere and torus: {worst:.2e} D");
    assert!(worst < 0.005, "{worst}");
}

/// The measured add (the focimeter on the progressive front) against the design's: on a lens
/// with a plane back the front's add is the lens's, whatever its thickness and the angle the
/// instrument meets the back at.
#[test]
fn the_measured_add_is_the_construction_s() {
    let design = Progressive::new(1.0 / 0.6, 2.0, 1.6, 0.014, 0.008);
    let p = Prescription {
        sphere: 1.0,
        index: 1.6,
        abbe: 42.0,
        center_thickness: 0.003,
        base_curve: 1.0,
        diameter: 0.06,
        front: Some(Freeform::Progressive(design)),
        add_d: Some(2.0),
        distance_reference: Some(design.far_reference()),
        near_reference: Some(design.near_reference()),
        ..Prescription::default()
    };
    let plano_back = run(&spectacles(&p, Mat4::IDENTITY), |_| {}).unwrap();
    let measured = plano_back.progressive.as_ref().unwrap();
    assert_eq!(measured.measured_on, "front");
    let (_, example_design) = example();
    let (example, _) = example();
    let report = run(&example, |_| {}).unwrap();
    let curved_back = report.progressive.as_ref().unwrap();
    println!(
        "measured add {:.6} D (plane back), {:.4} D (the example, its back −4 D) for {} D",
        measured.add_d, curved_back.add_d, example_design.add_d
    );
    // Measured: 2.0000 (plane back: ADD_PLANE_OFF_D off) and 1.9759 D (the back's share,
    // docs/analyses/lens.md); the issue asks for 0.02 D.
    assert!(
        (measured.add_d - 2.0).abs() < 2.0 * ADD_PLANE_OFF_D,
        "{}",
        measured.add_d
    );
    assert!(
        (curved_back.add_d - 2.0).abs() < 0.05,
        "{}",
        curved_back.add_d
    );
}

#[test]
fn the_grid_example_analyses_like_the_design() {
    let (design, _) = example();
    let grid = specula_scene::load(
        repository()
            .join("scenes/progressive-grid.toml")
            .to_str()
            .unwrap(),
    )
    .unwrap();
    let a = run(&design, |_| {}).unwrap();
    let b = run(&grid, |_| {}).unwrap();
    // Point by point over the lens map where both see through the lens. The grid ends 2 mm
    // past the rim: the steepest gazes through the lens's bottom edge start their search for
    // the front off it and are outside the lens for the grid alone.
    let (ma, mb) = (a.lens_map.as_ref().unwrap(), b.lens_map.as_ref().unwrap());
    let mut worst: f64 = 0.0;
    for (p, q) in ma.points.iter().zip(&mb.points) {
        match (p.cell.unwanted_cylinder_d, q.cell.unwanted_cylinder_d) {
            (Some(u), Some(v)) => {
                worst = worst
                    .max((u - v).abs())
                    .max((p.cell.mean_power_d.unwrap() - q.cell.mean_power_d.unwrap()).abs())
            }
            (None, None) => {}
            _ => {
                let r = p.at_mm[0].hypot(p.at_mm[1]);
                assert!(r > 26.0, "{:?} is inside for one surface only", p.at_mm);
            }
        }
    }
    println!("lens maps, design against grid: {worst:.2e} D");
    assert!(worst < 0.01, "{worst}");
    let (pa, pb) = (a.progressive.unwrap(), b.progressive.unwrap());
    println!("design: {pa:?}\ngrid: {pb:?}");
    // Measured: the maps 6.5e-3 D apart, the adds 6.5e-6 D, the lengths and widths within
    // 0.004 mm.
    assert!(
        (pa.add_d - pb.add_d).abs() < 1.5e-5,
        "{}",
        pa.add_d - pb.add_d
    );
    for (x, y) in [
        (pa.corridor_length_mm_85, pb.corridor_length_mm_85),
        (pa.corridor_length_mm_95, pb.corridor_length_mm_95),
    ] {
        println!("length apart {:.1e} mm", (x.unwrap() - y.unwrap()).abs());
        assert!((x.unwrap() - y.unwrap()).abs() < 8e-4);
    }
    assert!((pa.corridor_width_mm_100.unwrap() - pb.corridor_width_mm_100.unwrap()).abs() < 9e-3);
    println!(
        "widths apart {:.1e}, {:.1e} mm",
        (pa.corridor_width_mm_100.unwrap() - pb.corridor_width_mm_100.unwrap()).abs(),
        (pa.near_zone_width_mm_050 - pb.near_zone_width_mm_050).abs()
    );
    assert!((pa.near_zone_width_mm_050 - pb.near_zone_width_mm_050).abs() < 9e-3);
}

/// Prentice's rule: looking through a lens of power F at c cm from its centre the eye gets
/// c F prism dioptres; converging on a near point on the midline, the line of sight crosses
/// the lens nasally by about the half PD times the lens's distance over the near point's.
#[test]
fn near_vision_converges_and_follows_prentice_s_rule() {
    let near = Near {
        distance_m: 0.4,
        half_pd_m: 0.032,
        down_deg: Some(0.0),
    };
    // Flat fronts: the plano lens is a plate (no prism of its own), and each lens's principal
    // plane touches its back, where the crossing is measured.
    for sphere in [0.0, 2.0, -3.0] {
        let p = Prescription {
            sphere,
            index: 1.6,
            abbe: 42.0,
            center_thickness: 0.002,
            base_curve: 0.0,
            diameter: 0.06,
            ..Prescription::default()
        };
        let report = run(&spectacles(&p, Mat4::IDENTITY), |o| o.near = Some(near)).unwrap();
        let figures = report.near.unwrap();
        let x_cm = figures.point_on_lens_mm[0] / 10.0;
        let prism = figures.cell.prism_d.unwrap();
        // Base out positive; the line of sight crosses on the nasal side (x < 0, right eye),
        // where a plus lens's base points out.
        let prentice = -x_cm * sphere;
        println!(
            "{sphere:+.2} D: inset {:.3} mm, prism {:.4} Δ out against Prentice's {prentice:.4}",
            figures.inset_mm, prism[0]
        );
        // The centre of rotation is 27 mm behind the back vertex: the line from it to a point
        // 0.4 m away, 32 mm to the nasal side, crosses the lens ~2.2 mm nasally.
        assert!(figures.inset_mm > 1.5 && figures.inset_mm < 3.0);
        assert!(
            (prism[0] - prentice).abs() < 0.015 * prentice.abs() + 1e-4,
            "{prism:?}"
        );
        assert!(prism[1].abs() < 1e-6);
        if sphere == 0.0 {
            let depth = report.vertex_sphere_radius_m;
            let closed = 0.032 * depth / 0.4 * 1e3;
            assert!(
                (figures.inset_mm - closed).abs() < 0.05,
                "{} {closed}",
                figures.inset_mm
            );
        }
    }
}

#[test]
fn a_near_point_behind_the_eye_and_an_add_without_a_progressive_surface_are_refused() {
    let p = Prescription {
        sphere: 1.0,
        index: 1.6,
        abbe: 42.0,
        center_thickness: 0.003,
        base_curve: 5.0,
        diameter: 0.06,
        ..Prescription::default()
    };
    let single = spectacles(&p, Mat4::IDENTITY);
    let said = |r: Result<Report, AnalyzeError>| r.expect_err("refused").to_string();
    let behind = said(run(&single, |o| {
        o.near = Some(Near {
            distance_m: -0.4,
            half_pd_m: 0.032,
            down_deg: None,
        })
    }));
    assert!(
        behind.starts_with("near: ") && behind.contains("in front of the eyes"),
        "{behind}"
    );
    let inside = said(run(&single, |o| {
        o.near = Some(Near {
            distance_m: 0.02,
            half_pd_m: 0.032,
            down_deg: None,
        })
    }));
    assert!(
        inside.starts_with("near: ") && inside.contains("behind"),
        "{inside}"
    );
    let add = said(run(&single, |o| o.add_d = Some(2.0)));
    assert!(
        add.contains("an add without a progressive surface"),
        "{add}"
    );
    let (example, _) = example();
    let iso1 = said(run(&example, |o| {
        o.standard = Some(find("iso-8980-1").unwrap())
    }));
    assert!(iso1.contains("iso-8980-2"), "{iso1}");
    let iso2 = said(run(&single, |o| {
        o.standard = Some(find("iso-8980-2").unwrap())
    }));
    assert!(iso2.contains("`add`"), "{iso2}");
    let upside_down = said(run(&example, |o| o.near_reference_mm = Some([0.0, 10.0])));
    assert!(
        upside_down.contains("not below the distance reference"),
        "{upside_down}"
    );
    let coarse = said(run(&example, |o| o.lens_step_mm = Some(20.0)));
    assert!(coarse.contains("lens_step"), "{coarse}");
    let no_near = said(run(&example, |o| o.near_reference_mm = None));
    assert!(no_near.contains("near reference"), "{no_near}");
}

/// The clear zones of a single-vision lens: the horizontal width through the fitting point
/// from the lens map agrees with where the gaze grid's centre row crosses each criterion, and
/// a rotationally symmetric zone's area is the disc of that width.
#[test]
fn a_single_vision_lens_s_clear_zones_agree_with_its_gaze_grid() {
    let p = Prescription {
        sphere: -4.0,
        index: 1.6,
        abbe: 42.0,
        center_thickness: 0.002,
        base_curve: 2.0,
        diameter: 0.06,
        ..Prescription::default()
    };
    let report = run(&spectacles(&p, Mat4::IDENTITY), |o| {
        o.gaze.h_max_deg = 40.0;
        o.gaze.v_max_deg = 0.0;
        o.gaze.step_deg = 0.5;
    })
    .unwrap();
    let row: Vec<_> = report.grid.iter().filter(|c| !c.outside).collect();
    let mut checked = 0;
    for (zone, value) in report.clear_zones.iter().zip([
        |c: &specula_analyze::lens::Cell| 0.25 - c.unwanted_cylinder_d.unwrap(),
        |c: &specula_analyze::lens::Cell| 0.50 - c.unwanted_cylinder_d.unwrap(),
        |c: &specula_analyze::lens::Cell| 0.25 - c.power_error_d.unwrap().abs(),
    ]) {
        // Where the centre row's margin changes sign, on the right, interpolated.
        let right = row
            .windows(2)
            .filter(|w| w[0].gaze_deg[0] >= 0.0)
            .find(|w| value(w[0]) >= 0.0 && value(w[1]) < 0.0)
            .map(|w| {
                let (a, b) = (value(w[0]), value(w[1]));
                let (xa, xb) = (
                    w[0].back_point_mm.unwrap()[0],
                    w[1].back_point_mm.unwrap()[0],
                );
                xa + (xb - xa) * a / (a - b)
            });
        // Each criterion's edge lies within the 40° row (the lens is chosen so).
        let right = right.unwrap_or_else(|| panic!("{}: no edge within 40°", zone.criterion));
        let disc = std::f64::consts::PI * right * right;
        let (width_off, area_off) = (
            (zone.horizontal_width_mm - 2.0 * right).abs(),
            (zone.lens_area_mm2 / disc - 1.0).abs(),
        );
        println!(
            "{}: width {:.3} mm (gaze grid {:.3}: {width_off:.1e} mm apart), area {:.1} mm² \
             (disc {:.1}: {area_off:.1e} apart)",
            zone.criterion,
            zone.horizontal_width_mm,
            2.0 * right,
            zone.lens_area_mm2,
            disc
        );
        assert!(width_off < WIDTH_BOUND_MM, "{width_off}");
        assert!(area_off < AREA_BOUND, "{area_off}");
        checked += 1;
    }
    assert_eq!(checked, 3);
}

/// The progressive example's front resampled as a lab sends it, every 1 mm and 2 mm, written
/// as CSV and read back: it loads, and its add is within 0.02 D of the 0.5 mm grid's, the
/// stated uncertainty (the grid's interpolation with the focimeter's) covering the difference.
#[test]
fn a_lab_s_coarser_sag_grid_loads_and_states_its_uncertainty() {
    let (scene, design) = example();
    let ordered = scene.prescriptions[0].1.clone();
    let add_of = |step_mm: f64| {
        let reach = (32.0 / step_mm).round() as i32;
        let nodes: Vec<f64> = (-reach..=reach)
            .map(|k| f64::from(k) * step_mm * 1e-3)
            .collect();
        let sampled = SagGrid::sampled("lab.csv", nodes.clone(), nodes, |x, y| {
            design.local(x, y).unwrap().sag
        });
        let grid = SagGrid::parse(&sampled.to_csv(), "lab.csv").unwrap();
        let p = Prescription {
            front: Some(Freeform::SagGrid(Arc::new(grid))),
            ..ordered.clone()
        };
        let at = Mat4::from_translation(glam::Vec3::new(0.0, 0.0, -0.015));
        let report = run(&spectacles(&p, at), |_| {}).unwrap();
        let add = report.progressive.as_ref().unwrap().add_d;
        let u: f64 = report.add_focimeter.iter().map(|r| r.uncertainty_d).sum();
        let g = report.sag_grid.clone().unwrap();
        println!(
            "{step_mm} mm grid: add {add:.5} D ± {u:.2e}; power uncertain by up to {:.2e} D, \
             {:.1} % of the map marked",
            g.largest_d,
            g.marked_share * 100.0
        );
        (add, u, g)
    };
    let (fine, fine_u, _) = add_of(0.5);
    for step_mm in [1.0, 2.0] {
        let (add, u, grid) = add_of(step_mm);
        let difference = (add - fine).abs();
        println!(
            "{step_mm} mm against 0.5 mm: {difference:.2e} D (stated ± {:.2e})",
            u + fine_u
        );
        assert!(difference < 0.02, "{step_mm} mm: {difference}");
        assert!(
            difference <= u + fine_u,
            "{step_mm} mm: {difference} > ±{}",
            u + fine_u
        );
        assert!(grid.largest_d > 0.0);
    }
}

/// The clear zones against the gaze grid, twice the largest measured (1.6e-2 mm, 5.7e-4).
const WIDTH_BOUND_MM: f64 = 0.035;
const AREA_BOUND: f64 = 1.2e-3;
/// The plane-backed progressive lens's measured add off its construction's 2 D (measured).
const ADD_PLANE_OFF_D: f64 = 5e-6;
