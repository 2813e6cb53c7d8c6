//! `specula render SCENE --method vertex-tracing --distributed`: vertex tracing over MPI
//! (Ullmann et al. 2001, §4), run as `mpirun -np N specula render ...`.
//!
//! Rank 0 is the master, the others workers; every rank loads the scene itself and computes
//! the frame's ID buffer itself (CPU primary rays: one visibility source on every rank, so all
//! agree on the active triangles). The master hands out task packages of active triangles on
//! demand, sized per worker by the [`Balancer`] from its measured speed and re-sized after each
//! frame; workers answer with their pixels, which the master composites over the rest of the
//! scene. The image equals the single-process one bit for bit (a package's pixels do not depend
//! on how the frame was cut; see `vertex_tracing::refine`).
//!
//! Faults: Debian's OpenMPI 4.1 has no ULFM, so a lost worker is found by a timeout: a package
//! not answered within `--worker-timeout-ms` makes its worker lost, its packages go to the
//! others, the frame completes and the report names the loss. After start-up only nonblocking
//! point-to-point messages are used (no collectives once a rank may be gone), errors are
//! returned instead of aborting, and when a rank was lost the master writes its image and
//! report and exits without MPI_Finalize (which would wait for the dead rank). Run with
//! `mpirun --enable-recovery` so that mpirun does not kill the job when a rank dies.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use glam::Vec3;
use mpi::point_to_point::{Destination, MatchedReceiveVec, Source};
use mpi::raw::AsRaw;
use mpi::topology::Communicator;
use specula_methods::vertex_tracing::balance::{imbalance, Balancer, WorkerFrame};
use specula_methods::vertex_tracing::refine::{OriginalSamples, PackageCounters, RefineSettings};
use specula_methods::vertex_tracing::wire::Message;
use specula_methods::vertex_tracing::{FrameSetup, Topology};
use specula_methods::LiveScene;
use specula_scene::{Camera, Scene};
use specula_trace::Image;

const TAG: i32 = 15;
/// How long a rank sleeps when no message is waiting (leaves the core to the ranks that work:
/// with more ranks than cores, a busy-polling master would halve a worker's speed).
const IDLE: Duration = Duration::from_micros(200);

/// What the command line asks of a distributed run.
pub struct Options {
    pub frames: u32,
    pub width: u32,
    pub height: u32,
    pub settings: RefineSettings,
    pub max_depth: u32,
    pub packages_per_worker: usize,
    pub timeout: Duration,
    /// (rank, factor): that worker runs `factor` times slower (it sleeps), for tests of the
    /// balancer.
    pub slow: Option<(usize, f64)>,
    /// (rank, n): that worker dies on receiving its n-th package, for tests of fault handling.
    pub fail: Option<(usize, u32)>,
    pub output: PathBuf,
    pub exr: Option<PathBuf>,
    pub report: Option<PathBuf>,
}

/// One package as the master received it: who computed it, its triangles, the seconds the
/// worker reported and the pixels it returned (what the simulation is fed with).
#[derive(serde::Serialize)]
struct PackageRecord {
    rank: usize,
    start: usize,
    end: usize,
    seconds: f64,
    pixels: usize,
}

/// One frame of the master's report.
#[derive(serde::Serialize)]
struct FrameReport {
    frame: u32,
    seconds: f64,
    /// From the first package sent to the last result composited.
    refine_seconds: f64,
    visibility_seconds: f64,
    active_triangles: usize,
    packages: u32,
    workers: Vec<WorkerFrame>,
    /// 1 − mean/max of the live workers' busy seconds.
    imbalance: f64,
    lost_ranks: Vec<usize>,
    samples: u64,
    /// Bytes of result messages received.
    result_bytes: u64,
    package_records: Vec<PackageRecord>,
}

#[derive(serde::Serialize)]
struct Report {
    scene: String,
    ranks: usize,
    width: u32,
    height: u32,
    frames: Vec<FrameReport>,
    lost_ranks: Vec<usize>,
}

/// Runs this rank's part; returns after the master wrote its outputs (workers: after Quit).
pub fn run(scene: Scene, options: &Options) -> Result<()> {
    let universe = mpi::initialize().context("MPI could not be initialised (run under mpirun)")?;
    let world = universe.world();
    // Errors are returned (and a lost peer found by timeout), not fatal to the whole job.
    unsafe {
        mpi::ffi::MPI_Comm_set_errhandler(world.as_raw(), mpi::ffi::RSMPI_ERRORS_RETURN);
    }
    let live = LiveScene::new(scene);
    let topology = Arc::new(Topology::new(live.scene()));
    let finalize = if world.rank() == 0 {
        master(&world, &live, &topology, options)?
    } else {
        worker(&world, &live, &topology, options)?
    };
    if !finalize {
        // A rank was lost: MPI_Finalize would wait for it.
        std::process::exit(0);
    }
    Ok(())
}

fn send(world: &mpi::topology::SimpleCommunicator, rank: usize, message: &Message) {
    let bytes = message.encode();
    mpi::request::scope(|scope| {
        world
            .process_at_rank(rank as i32)
            .immediate_send_with_tag(scope, &bytes[..], TAG)
            .wait();
    });
}

/// The next message waiting from anyone: (sender rank, message).
fn poll(world: &mpi::topology::SimpleCommunicator) -> Result<Option<(usize, Message)>> {
    let Some(probed) = world.any_process().immediate_matched_probe_with_tag(TAG) else {
        return Ok(None);
    };
    let from = probed.1.source_rank() as usize;
    let (bytes, _) = probed.matched_receive_vec::<u8>();
    let decoded =
        Message::decode(&bytes).with_context(|| format!("a malformed message from rank {from}"))?;
    Ok(Some((from, decoded)))
}

fn master(
    world: &mpi::topology::SimpleCommunicator,
    live: &LiveScene,
    topology: &Arc<Topology>,
    options: &Options,
) -> Result<bool> {
    let workers = world.size() as usize - 1;
    let mut balancer = Balancer::new(workers, options.packages_per_worker);
    let camera = live.scene().camera.clone();
    let (width, height) = (options.width, options.height);
    let mut report = Report {
        scene: live.scene().name.clone(),
        ranks: world.size() as usize,
        width,
        height,
        frames: Vec::new(),
        lost_ranks: Vec::new(),
    };
    let mut image = Image::new(width, height);
    for frame in 0..options.frames {
        let start = Instant::now();
        for w in balancer.live_workers() {
            let message = Message::Frame {
                frame,
                camera: camera.clone(),
                width,
                height,
            };
            send(world, w + 1, &message);
        }
        let setup = FrameSetup::traced(
            live,
            &camera,
            width,
            height,
            topology.clone(),
            options.settings,
            options.max_depth,
        );
        let visibility_seconds = start.elapsed().as_secs_f64();
        let count = setup.active.len();
        // The rest of the scene first, so that the refinement phase timed below is the
        // packages' alone (the workers compute their ID buffers meanwhile).
        let (rest, _) = setup.rest_of_scene(live, &camera, options.max_depth);
        image = rest;
        let refine_start = Instant::now();
        balancer.start_frame(count);
        let mut sent_at = HashMap::new();
        for w in balancer.live_workers() {
            hand_out(world, &mut balancer, &mut sent_at, w, frame, count);
        }
        let (mut packages, mut samples, mut result_bytes) = (0u32, 0u64, 0u64);
        let mut records = Vec::new();
        let mut lost_now = Vec::new();
        while !balancer.frame_done() {
            if balancer.live_workers().is_empty() {
                // No worker (one rank), or every worker lost: the master does the rest itself,
                // as one package.
                let remaining = balancer.take_queue();
                for range in remaining {
                    let mut package = setup.package(range.clone());
                    let inputs = setup.inputs(live, &camera, options.settings, options.max_depth);
                    package.run(&inputs, None);
                    let pixels = package.take_pixels(&inputs);
                    composite(&mut image, &pixels);
                    samples += package.counters.vertex_rays + package.counters.filled_pixels;
                    packages += 1;
                    records.push(PackageRecord {
                        rank: 0,
                        start: range.start,
                        end: range.end,
                        seconds: package.counters.seconds,
                        pixels: pixels.len(),
                    });
                }
                break;
            }
            match poll(world)? {
                Some((
                    from,
                    Message::Result {
                        frame: f,
                        id,
                        counters,
                        pixels,
                    },
                )) if f == frame && from >= 1 => {
                    let w = from - 1;
                    if let Some(done) = balancer.finished(w, id, counters.seconds) {
                        sent_at.remove(&(w, id));
                        records.push(PackageRecord {
                            rank: from,
                            start: done.triangles.start,
                            end: done.triangles.end,
                            seconds: counters.seconds,
                            pixels: pixels.len(),
                        });
                        composite(&mut image, &pixels);
                        packages += 1;
                        samples += counters.vertex_rays + counters.filled_pixels;
                        result_bytes +=
                            specula_methods::vertex_tracing::wire::result_bytes(pixels.len())
                                as u64;
                        hand_out(world, &mut balancer, &mut sent_at, w, frame, count);
                    }
                }
                Some(_) => {}
                None => std::thread::sleep(IDLE),
            }
            // A package unanswered past the timeout: its worker is lost.
            let late: Vec<usize> = sent_at
                .iter()
                .filter(|(_, at)| at.elapsed() > options.timeout)
                .map(|((w, _), _)| *w)
                .collect();
            for w in late {
                if balancer.is_lost(w) {
                    continue;
                }
                eprintln!(
                    "warning: rank {} did not answer within {} ms: lost; its packages go to the others",
                    w + 1,
                    options.timeout.as_millis()
                );
                balancer.lose(w);
                sent_at.retain(|(lost, _), _| *lost != w);
                lost_now.push(w + 1);
                report.lost_ranks.push(w + 1);
                // The idle live workers take the orphans.
                for other in balancer.live_workers() {
                    if balancer.outstanding(other).is_empty() {
                        hand_out(world, &mut balancer, &mut sent_at, other, frame, count);
                    }
                }
            }
        }
        let refine_seconds = refine_start.elapsed().as_secs_f64();
        let stats = balancer.end_frame();
        let busy: Vec<f64> = stats
            .iter()
            .filter(|s| !s.lost && s.packages > 0)
            .map(|s| s.busy_seconds)
            .collect();
        let seconds = start.elapsed().as_secs_f64();
        eprintln!(
            "frame {frame}: {seconds:.3} s, {count} triangles in {packages} packages over {} workers, imbalance {:.1} %",
            busy.len(),
            100.0 * imbalance(&busy)
        );
        report.frames.push(FrameReport {
            frame,
            seconds,
            refine_seconds,
            visibility_seconds,
            active_triangles: count,
            packages,
            imbalance: imbalance(&busy),
            workers: stats,
            lost_ranks: lost_now,
            samples,
            result_bytes,
            package_records: records,
        });
    }
    write_outputs(&image, options, &report)?;
    let finalize = report.lost_ranks.is_empty();
    for w in balancer.live_workers() {
        send(world, w + 1, &Message::Quit { finalize });
    }
    Ok(finalize)
}

/// Sends `worker` its next package of `frame`, if any is left, and notes when (for the
/// timeout).
fn hand_out(
    world: &mpi::topology::SimpleCommunicator,
    balancer: &mut Balancer,
    sent_at: &mut HashMap<(usize, u32), Instant>,
    worker: usize,
    frame: u32,
    triangles: usize,
) {
    let Some(p) = balancer.next_package(worker, triangles) else {
        return;
    };
    let message = Message::Package {
        frame,
        id: p.id,
        start: p.triangles.start as u32,
        end: p.triangles.end as u32,
    };
    send(world, worker + 1, &message);
    sent_at.insert((worker, p.id), Instant::now());
}

fn composite(image: &mut Image, pixels: &[(u32, Vec3)]) {
    for &(k, color) in pixels {
        if let Some(p) = image.pixels.get_mut(k as usize) {
            *p = color;
        }
    }
}

fn write_outputs(image: &Image, options: &Options, report: &Report) -> Result<()> {
    image.save_png(&options.output)?;
    if let Some(exr) = &options.exr {
        image.save_exr(exr)?;
    }
    if let Some(path) = &options.report {
        write_json(path, report)?;
    }
    eprintln!(
        "distributed vertex tracing: {} ranks, {} frame(s) -> {}{}",
        report.ranks,
        report.frames.len(),
        options.output.display(),
        if report.lost_ranks.is_empty() {
            String::new()
        } else {
            format!("; lost ranks {:?}", report.lost_ranks)
        }
    );
    Ok(())
}

fn write_json(path: &Path, report: &Report) -> Result<()> {
    let text = serde_json::to_string_pretty(report)?;
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

fn worker(
    world: &mpi::topology::SimpleCommunicator,
    live: &LiveScene,
    topology: &Arc<Topology>,
    options: &Options,
) -> Result<bool> {
    let rank = world.rank() as usize;
    let mut view: Option<(Camera, FrameSetup)> = None;
    // The original vertices this worker traced in the frame so far: its packages come from one
    // region of the mesh, one after another, so their borders are traced once.
    let mut traced = OriginalSamples::default();
    let mut received = 0u32;
    loop {
        let Some((from, message)) = poll(world)? else {
            std::thread::sleep(IDLE);
            continue;
        };
        if from != 0 {
            continue;
        }
        match message {
            Message::Frame {
                camera,
                width,
                height,
                ..
            } => {
                let setup = FrameSetup::traced(
                    live,
                    &camera,
                    width,
                    height,
                    topology.clone(),
                    options.settings,
                    options.max_depth,
                );
                view = Some((camera, setup));
                traced = OriginalSamples::default();
            }
            Message::Package {
                frame,
                id,
                start,
                end,
            } => {
                received += 1;
                if options.fail == Some((rank, received)) {
                    eprintln!("rank {rank}: dying on package {received}, as --fail-rank asks");
                    std::process::abort();
                }
                let Some((camera, setup)) = &view else {
                    bail!("rank {rank}: a package came before its frame");
                };
                if end as usize > setup.active.len() || start > end {
                    bail!(
                        "rank {rank}: package {start}..{end} is outside the frame's {} triangles",
                        setup.active.len()
                    );
                }
                let clock = Instant::now();
                let mut package = setup.package(start as usize..end as usize);
                let mut inputs = setup.inputs(live, camera, options.settings, options.max_depth);
                inputs.originals = Some(&traced);
                package.run(&inputs, None);
                let pixels = package.take_pixels(&inputs);
                traced.absorb(&package);
                if let Some((slow_rank, factor)) = options.slow {
                    if slow_rank == rank {
                        std::thread::sleep(clock.elapsed().mul_f64((factor - 1.0).max(0.0)));
                    }
                }
                let counters = PackageCounters {
                    seconds: clock.elapsed().as_secs_f64(),
                    ..package.counters
                };
                send(
                    world,
                    0,
                    &Message::Result {
                        frame,
                        id,
                        counters,
                        pixels,
                    },
                );
            }
            Message::Quit { finalize } => return Ok(finalize),
            Message::Result { .. } => {}
        }
    }
}
