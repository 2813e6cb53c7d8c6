//! Vertex tracing over MPI (Ullmann et al. 2001, §4), behind the feature `mpi`: what
//! `mpirun -np N specula render SCENE --method vertex-tracing --distributed` runs on every rank
//! ([`run`]).
//!
//! Rank 0 is the master, the others workers; every rank loads the scene itself and computes
//! the frame's ID buffer itself (CPU primary rays: one visibility source on every rank, so all
//! agree on the active triangles). The master hands out task packages of active triangles on
//! demand, sized per worker by the balancer (`super::balance`) from its measured speed and
//! re-sized after each frame; workers answer with their pixels, which the master composites
//! over the rest of the scene. Every rank traces its ID buffer and the rest of the scene on the
//! CPU, so the image equals, bit for bit, a single-process run with `visibility=cpu` (a
//! package's pixels do not depend on how the frame was cut; see `super::refine`); a default
//! single-process run on a machine with a Vulkan adapter takes the GPU ID buffer and may differ.
//!
//! Faults: Debian's OpenMPI 4.1 has no ULFM, so a lost worker is found by a timeout: a package
//! not answered within [`Options::timeout`] makes its worker lost, its packages go to the
//! others, the frame completes and the report names the loss. After start-up only nonblocking
//! point-to-point messages are used (no collectives once a rank may be gone), errors are
//! returned instead of aborting, and when a rank was lost no rank calls MPI_Finalize (which
//! would wait for the dead rank): [`run`] returns without it and the process exits. Run with
//! `mpirun --enable-recovery` so that mpirun does not kill the job when a rank dies.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;
use mpi::point_to_point::{Destination, MatchedReceiveVec, Source};
use mpi::raw::AsRaw;
use mpi::topology::{Communicator, SimpleCommunicator};
use specula_scene::{Camera, Scene};
use specula_trace::Image;

use super::balance::{imbalance, Balancer, WorkerFrame};
use super::refine::{OriginalSamples, PackageCounters, Topology};
use super::wire::{self, Message};
use super::FrameSetup;
use super::Params;
use specula_core::live_scene::LiveScene;

pub use super::wire::WireError;

const TAG: i32 = 15;
/// How long a rank sleeps when no message is waiting (leaves the core to the ranks that work:
/// with more ranks than cores, a busy-polling master would halve a worker's speed).
const IDLE: Duration = Duration::from_micros(200);

/// What a distributed run is asked for; every rank must be given the same.
#[derive(Clone, Debug)]
pub struct Options {
    pub frames: u32,
    pub width: u32,
    pub height: u32,
    pub params: Params,
    /// Packages each worker asks for per frame at the frame's start (the grain).
    pub packages_per_worker: usize,
    /// A worker that leaves a package unanswered this long is lost.
    pub timeout: Duration,
    /// (rank, factor): that worker runs `factor` times slower (it sleeps), for tests of the
    /// balancer.
    pub slow: Option<(usize, f64)>,
    /// (rank, n): that worker dies on receiving its n-th package, for tests of fault handling.
    pub fail: Option<(usize, u32)>,
}

/// Why a rank's part of a distributed run failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("MPI could not be initialised (run under mpirun)")]
    Initialise,
    #[error("the master's outputs: {0}")]
    Deliver(Box<dyn std::error::Error + Send + Sync>),
    #[error("a malformed message from rank {rank}")]
    MalformedMessage {
        rank: usize,
        #[source]
        source: WireError,
    },
    #[error("rank {rank}: a package came before its frame")]
    PackageBeforeFrame { rank: usize },
    #[error("rank {rank}: package {start}..{end} is outside the frame's {triangles} triangles")]
    PackageOutsideFrame {
        rank: usize,
        start: u32,
        end: u32,
        triangles: usize,
    },
}

/// What a rank's part of a distributed run ends with.
pub enum Outcome {
    /// Rank 0: the last frame's image and the report of every frame.
    Master { image: Image, report: Report },
    /// A worker: its part is done (it was told to quit).
    Worker,
}

/// The master's report of a distributed run, written as JSON by `specula render --distributed
/// --report FILE`: per frame, each worker's packages, triangles, busy time and speed, the
/// imbalance, the lost ranks, and every package received.
#[derive(Debug, serde::Serialize)]
pub struct Report {
    scene: String,
    ranks: usize,
    width: u32,
    height: u32,
    frames: Vec<FrameReport>,
    lost_ranks: Vec<usize>,
}

impl Report {
    /// Ranks the run started with, master included.
    pub fn ranks(&self) -> usize {
        self.ranks
    }

    /// Frames rendered.
    pub fn frames(&self) -> usize {
        self.frames.len()
    }

    /// The workers lost during the run, by rank.
    pub fn lost_ranks(&self) -> &[usize] {
        &self.lost_ranks
    }
}

/// One frame of the master's report.
#[derive(Debug, serde::Serialize)]
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

/// One package as the master received it: who computed it, its triangles, the seconds the
/// worker reported and the pixels it returned (what the simulation is fed with).
#[derive(Debug, serde::Serialize)]
struct PackageRecord {
    rank: usize,
    start: usize,
    end: usize,
    seconds: f64,
    pixels: usize,
}

impl PackageRecord {
    fn new(rank: usize, triangles: Range<usize>, seconds: f64, pixels: usize) -> PackageRecord {
        PackageRecord {
            rank,
            start: triangles.start,
            end: triangles.end,
            seconds,
            pixels,
        }
    }
}

/// What the master does with the last frame's image and the report while MPI still runs (the
/// CLI writes its files): an error here ends the run with [`Error::Deliver`].
pub type Deliver<'a> =
    Box<dyn FnOnce(&Image, &Report) -> Result<(), Box<dyn std::error::Error + Send + Sync>> + 'a>;

/// Runs this rank's part of a distributed run of `scene` under `mpirun` (rank 0 the master,
/// the others workers); returns when the master has the last frame (workers: when told to
/// quit). The master prints a line per frame, and a warning per lost worker, to stderr, tells
/// the workers to quit, then hands the image and report to `deliver`.
///
/// MPI is initialised here and finalised before returning, after `deliver`, so the outputs are
/// written even where finalising would hang; unless a rank was lost: then MPI_Finalize, which
/// would wait for the dead rank, is never called, and the caller should exit soon after.
pub fn run(scene: Scene, options: &Options, deliver: Deliver<'_>) -> Result<Outcome, Error> {
    let universe = mpi::initialize().ok_or(Error::Initialise)?;
    let world = universe.world();
    // Errors are returned (and a lost peer found by timeout), not fatal to the whole job.
    unsafe {
        mpi::ffi::MPI_Comm_set_errhandler(world.as_raw(), mpi::ffi::RSMPI_ERRORS_RETURN);
    }
    let live = LiveScene::new(scene);
    let topology = Arc::new(Topology::new(live.scene()));
    let (outcome, finalize) = if world.rank() == 0 {
        let (image, report) = master(&world, &live, &topology, options)?;
        deliver(&image, &report).map_err(Error::Deliver)?;
        let finalize = report.lost_ranks.is_empty();
        (Outcome::Master { image, report }, finalize)
    } else {
        (Outcome::Worker, worker(&world, &live, &topology, options)?)
    };
    if !finalize {
        // A rank was lost: MPI_Finalize (the universe's drop) would wait for it.
        std::mem::forget(universe);
    }
    Ok(outcome)
}

fn send(world: &SimpleCommunicator, rank: usize, message: &Message) {
    let bytes = message.encode();
    mpi::request::scope(|scope| {
        world
            .process_at_rank(rank as i32)
            .immediate_send_with_tag(scope, &bytes[..], TAG)
            .wait();
    });
}

/// The next message waiting from anyone: (sender rank, message).
fn poll(world: &SimpleCommunicator) -> Result<Option<(usize, Message)>, Error> {
    let Some(probed) = world.any_process().immediate_matched_probe_with_tag(TAG) else {
        return Ok(None);
    };
    let from = probed.1.source_rank() as usize;
    let (bytes, _) = probed.matched_receive_vec::<u8>();
    let decoded =
        Message::decode(&bytes).map_err(|source| Error::MalformedMessage { rank: from, source })?;
    Ok(Some((from, decoded)))
}

/// Rank 0: every frame drawn with the workers; then each live worker is told to quit (and
/// whether to finalise). Returns the last frame's image and the report.
fn master(
    world: &SimpleCommunicator,
    live: &LiveScene,
    topology: &Arc<Topology>,
    options: &Options,
) -> Result<(Image, Report), Error> {
    let mut master = Master {
        world,
        live,
        topology,
        options,
        camera: live.scene().camera.clone(),
        balancer: Balancer::new(world.size() as usize - 1, options.packages_per_worker),
        sent_at: HashMap::new(),
    };
    let mut report = Report {
        scene: live.scene().name.clone(),
        ranks: world.size() as usize,
        width: options.width,
        height: options.height,
        frames: Vec::new(),
        lost_ranks: Vec::new(),
    };
    let mut image = Image::new(options.width, options.height);
    for frame in 0..options.frames {
        let (drawn, frame_report) = master.draw_frame(frame)?;
        image = drawn;
        report.lost_ranks.extend(&frame_report.lost_ranks);
        report.frames.push(frame_report);
    }
    let finalize = report.lost_ranks.is_empty();
    for w in master.balancer.live_workers() {
        send(world, w + 1, &Message::Quit { finalize });
    }
    Ok((image, report))
}

/// The master's state across frames. Workers are numbered from 0 (rank − 1), as the
/// balancer numbers them.
struct Master<'a> {
    world: &'a SimpleCommunicator,
    live: &'a LiveScene,
    topology: &'a Arc<Topology>,
    options: &'a Options,
    camera: Camera,
    balancer: Balancer,
    /// When each unanswered package was sent, by (worker, package id): for the timeout.
    sent_at: HashMap<(usize, u32), Instant>,
}

/// What the master gathered of one frame's packages.
struct Gathered {
    /// The rest of the scene with the packages' pixels composited over it.
    image: Image,
    packages: u32,
    samples: u64,
    result_bytes: u64,
    records: Vec<PackageRecord>,
    /// Ranks lost during the frame.
    lost_ranks: Vec<usize>,
}

impl Gathered {
    /// Composites a package's `pixels` and counts it.
    fn add(&mut self, record: PackageRecord, counters: &PackageCounters, pixels: &[(u32, Vec3)]) {
        composite(&mut self.image, pixels);
        self.packages += 1;
        self.samples += counters.vertex_rays + counters.filled_pixels;
        self.records.push(record);
    }
}

impl Master<'_> {
    /// One frame: the workers told of it, the master's own ID buffer and rest of the scene,
    /// then the refinement phase (packages handed out until every one is answered). Returns
    /// the frame's image and its report.
    fn draw_frame(&mut self, frame: u32) -> Result<(Image, FrameReport), Error> {
        let start = Instant::now();
        self.announce_frame(frame);
        let setup = FrameSetup::traced(
            self.live,
            &self.camera,
            self.options.width,
            self.options.height,
            self.topology.clone(),
            self.options.params,
            self.options.params.max_depth,
            None,
        );
        let visibility_seconds = start.elapsed().as_secs_f64();
        let count = setup.active.len();
        // The rest of the scene first, so that the refinement phase timed below is the
        // packages' alone (the workers compute their ID buffers meanwhile).
        let (rest, _) = setup.rest_of_scene(self.live, &self.camera, self.options.params.max_depth);
        let refine_start = Instant::now();
        let gathered = self.refine_frame(&setup, rest, frame)?;
        let refine_seconds = refine_start.elapsed().as_secs_f64();
        let workers = self.balancer.end_frame();
        let busy: Vec<f64> = workers
            .iter()
            .filter(|s| !s.lost && s.packages > 0)
            .map(|s| s.busy_seconds)
            .collect();
        let seconds = start.elapsed().as_secs_f64();
        eprintln!(
            "frame {frame}: {seconds:.3} s, {count} triangles in {} packages over {} workers, imbalance {:.1} %",
            gathered.packages,
            busy.len(),
            100.0 * imbalance(&busy)
        );
        let report = FrameReport {
            frame,
            seconds,
            refine_seconds,
            visibility_seconds,
            active_triangles: count,
            packages: gathered.packages,
            imbalance: imbalance(&busy),
            workers,
            lost_ranks: gathered.lost_ranks,
            samples: gathered.samples,
            result_bytes: gathered.result_bytes,
            package_records: gathered.records,
        };
        Ok((gathered.image, report))
    }

    /// Tells every live worker to start `frame` (each computes its ID buffer).
    fn announce_frame(&self, frame: u32) {
        for w in self.balancer.live_workers() {
            let message = Message::Frame {
                frame,
                camera: self.camera.clone(),
                width: self.options.width,
                height: self.options.height,
            };
            send(self.world, w + 1, &message);
        }
    }

    /// The refinement phase of `frame`: packages handed out on demand and their results
    /// composited over `rest`, until every package is answered; a worker that misses the
    /// timeout is lost, and when no worker is left the master refines the rest itself.
    fn refine_frame(
        &mut self,
        setup: &FrameSetup,
        rest: Image,
        frame: u32,
    ) -> Result<Gathered, Error> {
        let count = setup.active.len();
        self.balancer.start_frame(count);
        self.sent_at.clear();
        for w in self.balancer.live_workers() {
            self.hand_out(w, frame, count);
        }
        let mut gathered = Gathered {
            image: rest,
            packages: 0,
            samples: 0,
            result_bytes: 0,
            records: Vec::new(),
            lost_ranks: Vec::new(),
        };
        while !self.balancer.frame_done() {
            if self.balancer.live_workers().is_empty() {
                // No worker (one rank), or every worker lost.
                self.refine_remaining_here(setup, &mut gathered);
                break;
            }
            match poll(self.world)? {
                Some((
                    from,
                    Message::Result {
                        frame: f,
                        id,
                        counters,
                        pixels,
                    },
                )) if f == frame && from >= 1 => {
                    if self.take_result(from, id, &counters, &pixels, &mut gathered) {
                        self.hand_out(from - 1, frame, count);
                    }
                }
                Some(_) => {}
                None => std::thread::sleep(IDLE),
            }
            self.lose_late_workers(frame, count, &mut gathered.lost_ranks);
        }
        Ok(gathered)
    }

    /// The packages no worker is left for, refined by the master itself, each range as one
    /// package.
    fn refine_remaining_here(&mut self, setup: &FrameSetup, gathered: &mut Gathered) {
        let (settings, max_depth) = (self.options.params, self.options.params.max_depth);
        for range in self.balancer.take_queue() {
            let mut package = setup.package(range.clone());
            let inputs = setup.inputs(self.live, &self.camera, settings, max_depth);
            package.run(&inputs, None);
            let pixels = package.take_pixels(&inputs, None);
            let record = PackageRecord::new(0, range, package.counters.seconds, pixels.len());
            gathered.add(record, &package.counters, &pixels);
        }
    }

    /// A result from rank `from` for package `id`: composited and counted. Returns false,
    /// taking nothing, when the package was no longer the worker's (a late answer from a worker
    /// declared lost, whose work was handed out again).
    fn take_result(
        &mut self,
        from: usize,
        id: u32,
        counters: &PackageCounters,
        pixels: &[(u32, Vec3)],
        gathered: &mut Gathered,
    ) -> bool {
        let w = from - 1;
        let Some(done) = self.balancer.finished(w, id, counters.seconds) else {
            return false;
        };
        self.sent_at.remove(&(w, id));
        let record = PackageRecord::new(from, done.triangles, counters.seconds, pixels.len());
        gathered.add(record, counters, pixels);
        gathered.result_bytes += wire::result_bytes(pixels.len()) as u64;
        true
    }

    /// Declares lost each worker with a package unanswered past the timeout (its packages go
    /// back to the queue, and the idle live workers take them); adds its rank to `lost_ranks`.
    fn lose_late_workers(&mut self, frame: u32, count: usize, lost_ranks: &mut Vec<usize>) {
        let late: Vec<usize> = self
            .sent_at
            .iter()
            .filter(|(_, at)| at.elapsed() > self.options.timeout)
            .map(|((w, _), _)| *w)
            .collect();
        for w in late {
            if self.balancer.is_lost(w) {
                continue;
            }
            eprintln!(
                "warning: rank {} did not answer within {} ms: lost; its packages go to the others",
                w + 1,
                self.options.timeout.as_millis()
            );
            self.balancer.lose(w);
            self.sent_at.retain(|(lost, _), _| *lost != w);
            lost_ranks.push(w + 1);
            // The idle live workers take the orphans.
            for other in self.balancer.live_workers() {
                if self.balancer.outstanding(other).is_empty() {
                    self.hand_out(other, frame, count);
                }
            }
        }
    }

    /// Sends `worker` its next package of `frame` (of `triangles` active triangles), if any
    /// is left, and notes when (for the timeout).
    fn hand_out(&mut self, worker: usize, frame: u32, triangles: usize) {
        let Some(p) = self.balancer.next_package(worker, triangles) else {
            return;
        };
        let message = Message::Package {
            frame,
            id: p.id,
            start: p.triangles.start as u32,
            end: p.triangles.end as u32,
        };
        send(self.world, worker + 1, &message);
        self.sent_at.insert((worker, p.id), Instant::now());
    }
}

fn composite(image: &mut Image, pixels: &[(u32, Vec3)]) {
    for &(k, color) in pixels {
        if let Some(p) = image.pixels.get_mut(k as usize) {
            *p = color;
        }
    }
}

/// A worker rank: computes each frame's ID buffer and refines the packages the master sends,
/// until told to quit. Returns whether to finalise MPI.
fn worker(
    world: &SimpleCommunicator,
    live: &LiveScene,
    topology: &Arc<Topology>,
    options: &Options,
) -> Result<bool, Error> {
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
                let recycled = view.take().map(|(_, setup)| setup.surfaces);
                let setup = FrameSetup::traced(
                    live,
                    &camera,
                    width,
                    height,
                    topology.clone(),
                    options.params,
                    options.params.max_depth,
                    recycled,
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
                    return Err(Error::PackageBeforeFrame { rank });
                };
                let (counters, pixels) =
                    refine_package(live, camera, setup, &mut traced, options, rank, start..end)?;
                let result = Message::Result {
                    frame,
                    id,
                    counters,
                    pixels,
                };
                send(world, 0, &result);
            }
            Message::Quit { finalize } => return Ok(finalize),
            Message::Result { .. } => {}
        }
    }
}

/// A worker's package `triangles` of the frame `setup`, refined with the original vertices it
/// `traced` so far (and adding this package's): its counters, timed as the balancer measures
/// them (slowed as `--slow-rank` asks), and its pixels.
fn refine_package(
    live: &LiveScene,
    camera: &Camera,
    setup: &FrameSetup,
    traced: &mut OriginalSamples,
    options: &Options,
    rank: usize,
    triangles: Range<u32>,
) -> Result<(PackageCounters, Vec<(u32, Vec3)>), Error> {
    let Range { start, end } = triangles;
    if end as usize > setup.active.len() || start > end {
        return Err(Error::PackageOutsideFrame {
            rank,
            start,
            end,
            triangles: setup.active.len(),
        });
    }
    let clock = Instant::now();
    let mut package = setup.package(start as usize..end as usize);
    let mut inputs = setup.inputs(live, camera, options.params, options.params.max_depth);
    inputs.originals = Some(&*traced);
    package.run(&inputs, None);
    let pixels = package.take_pixels(&inputs, None);
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
    Ok((counters, pixels))
}
