//! `mpirun -np 3 specula render --method vertex-tracing --distributed` on loopback: the image
//! equals the single-process one bit for bit, a slowed worker is given less work, and a worker
//! killed mid-frame does not stop the frame. Built only with `--features mpi` (scripts/test.sh
//! turns it on); without `mpirun` on the PATH they fail, unless the runner opts out with
//! `SPECULA_ALLOW_SKIP=mpi`.
#![cfg(feature = "mpi")]

use std::path::Path;
use std::process::Command;

use specula_trace::Image;

const SIZE: [&str; 4] = ["-W", "160", "-H", "120"];

fn mpirun() -> Option<Command> {
    let found = Command::new("mpirun").arg("--version").output().is_ok();
    if !found {
        specula_testkit::missing(
            specula_testkit::Requirement::Mpi,
            "distributed vertex tracing",
            "`mpirun --version` could not be run",
        );
        return None;
    }
    let mut command = Command::new("mpirun");
    // As root mpirun refuses to start without this; three ranks on two cores need
    // oversubscription; a dying rank must not take the job down; idle ranks yield the core.
    let root = std::env::var("USER").is_ok_and(|u| u == "root")
        || Command::new("id")
            .arg("-u")
            .output()
            .is_ok_and(|o| o.stdout.starts_with(b"0"));
    if root {
        command.arg("--allow-run-as-root");
    }
    command.args([
        "--oversubscribe",
        "--enable-recovery",
        "--mca",
        "mpi_yield_when_idle",
        "1",
        "-x",
        "RAYON_NUM_THREADS=1",
    ]);
    Some(command)
}

fn specula() -> &'static str {
    env!("CARGO_BIN_EXE_specula")
}

/// The single-process image (CPU visibility, as every rank computes it).
fn single_process(dir: &Path, tracing: &str) -> Image {
    let exr = dir.join("single.exr");
    let status = Command::new(specula())
        .args(["render", "truck-cover", "--method", "vertex-tracing"])
        .args(SIZE)
        .args(["-p", "visibility=cpu", "-p", tracing, "-o"])
        .arg(dir.join("single.png"))
        .arg("--exr")
        .arg(&exr)
        .env("RAYON_NUM_THREADS", "1")
        .status()
        .unwrap();
    assert!(status.success());
    Image::load(&exr).unwrap()
}

/// Runs `mpirun -np 3 specula render truck-cover --distributed` with `extra` arguments;
/// returns its image and report. mpirun's status is not checked (a killed rank makes it
/// non-zero): the image and the report are.
fn distributed(dir: &Path, name: &str, extra: &[&str]) -> Option<(Image, serde_json::Value)> {
    let mut command = mpirun()?;
    let (exr, report) = (
        dir.join(format!("{name}.exr")),
        dir.join(format!("{name}.json")),
    );
    let output = command
        .args(["-np", "3", specula(), "render", "truck-cover"])
        .args(["--method", "vertex-tracing", "--distributed"])
        // The cover's vertices, in packages: what is distributed (auto traces it per pixel
        // at this size, on the master).
        .args(["-p", "tracing=vertices"])
        .args(SIZE)
        .arg("-o")
        .arg(dir.join(format!("{name}.png")))
        .arg("--exr")
        .arg(&exr)
        .arg("--report")
        .arg(&report)
        .args(extra)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&output.stderr);
    assert!(
        exr.exists() && report.exists(),
        "{name}: no image or report; mpirun said:\n{log}"
    );
    let report = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    Some((Image::load(&exr).unwrap(), report))
}

fn bitwise_equal(a: &Image, b: &Image) -> bool {
    a.width == b.width
        && a.height == b.height
        && a.pixels
            .iter()
            .zip(&b.pixels)
            .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits))
}

#[test]
fn three_ranks_draw_the_single_process_image_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let Some((image, report)) = distributed(dir.path(), "three", &["--frames", "2"]) else {
        return;
    };
    assert!(bitwise_equal(
        &image,
        &single_process(dir.path(), "tracing=vertices")
    ));
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2);
    for frame in frames {
        let workers = frame["workers"].as_array().unwrap();
        assert_eq!(workers.len(), 2);
        for w in workers {
            assert!(
                w["packages"].as_u64().unwrap() > 0,
                "every worker works: {w}"
            );
        }
        let triangles: u64 = workers
            .iter()
            .map(|w| w["triangles"].as_u64().unwrap())
            .sum();
        assert_eq!(triangles, frame["active_triangles"].as_u64().unwrap());
    }
    assert!(report["lost_ranks"].as_array().unwrap().is_empty());
}

#[test]
fn a_reflector_chosen_per_pixel_is_traced_by_the_master_into_the_single_process_image() {
    let dir = tempfile::tempdir().unwrap();
    // At this size `tracing=auto` traces the cover per pixel: no package to hand out.
    let Some((image, report)) = distributed(dir.path(), "auto", &["-p", "tracing=auto"]) else {
        return;
    };
    assert!(bitwise_equal(
        &image,
        &single_process(dir.path(), "tracing=auto")
    ));
    let frame = &report["frames"].as_array().unwrap()[0];
    assert_eq!(frame["active_triangles"].as_u64(), Some(0), "{frame}");
}

#[test]
fn a_slowed_worker_is_given_less_work() {
    let dir = tempfile::tempdir().unwrap();
    let Some((_, report)) =
        distributed(dir.path(), "slow", &["--frames", "3", "--slow-rank", "2:4"])
    else {
        return;
    };
    // After the first frame the packages are sized from the measured speeds: rank 2, four
    // times slower, gets about a fifth of the triangles. Measured 2026-11-30 in two runs: its
    // triangles 0.17–0.26 of rank 1's, its measured speed 0.21–0.30 of rank 1's.
    for frame in &report["frames"].as_array().unwrap()[1..] {
        let workers = frame["workers"].as_array().unwrap();
        let share = |rank: u64| {
            workers.iter().find(|w| w["rank"] == rank).unwrap()["triangles"]
                .as_f64()
                .unwrap()
        };
        let (fast, slow) = (share(1), share(2));
        assert!(
            slow < 0.6 * fast,
            "frame {}: slow {slow} fast {fast}",
            frame["frame"]
        );
        let speeds: Vec<f64> = workers
            .iter()
            .map(|w| w["speed_used"].as_f64().unwrap())
            .collect();
        assert!(speeds[1] < 0.6 * speeds[0], "speeds {speeds:?}");
    }
}

#[test]
fn a_worker_killed_mid_frame_does_not_stop_the_frame() {
    let dir = tempfile::tempdir().unwrap();
    let Some((image, report)) = distributed(
        dir.path(),
        "killed",
        &[
            "--frames",
            "2",
            "--fail-rank",
            "2:2",
            "--worker-timeout-ms",
            "3000",
        ],
    ) else {
        return;
    };
    let lost: Vec<u64> = report["lost_ranks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_u64().unwrap())
        .collect();
    assert_eq!(lost, vec![2], "the report names the lost rank");
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2, "both frames complete");
    assert_eq!(frames[0]["lost_ranks"].as_array().unwrap().len(), 1);
    // The frame is whole: the same image as one process draws.
    assert!(bitwise_equal(
        &image,
        &single_process(dir.path(), "tracing=vertices")
    ));
}
