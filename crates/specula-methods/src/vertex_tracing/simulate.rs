//! A discrete-event simulation of distributed vertex tracing (§4, Figure 9), to extend what
//! can be measured on one machine (1–3 MPI ranks) to 1–32 workers, mixed 10 and 100 Mbit/s
//! links and workers of different speeds. It drives the same `Balancer` as the MPI master.
//!
//! Model: the frame's work is the measured cost of each active triangle (seconds on a worker
//! of speed 1, from a real run's packages: a package's time spread evenly over its triangles)
//! and the pixels each returns; a worker of speed s computes a package in Σ cost / s, plus a
//! fixed cost (measured) when the package does not continue the worker's previous one (its
//! border vertices are traced again), after it has computed the frame's ID buffer itself.
//! Messages take the link's latency plus their bytes (`super::wire`'s sizes) over the
//! bandwidth; results also cross the master's link, one at a time (it is shared). The master
//! answers a result at once with the worker's next package, as the MPI master does.
//!
//! What it leaves out: the master's own work (the rest of the scene, compositing), contention
//! between processes on one machine, and the border vertices a smaller package traces twice.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::balance::{imbalance, Assignment, Balancer};
use super::wire;

/// The measured frame: each active triangle's cost and pixels.
#[derive(Clone, Debug)]
pub struct Workload {
    /// Seconds on a worker of speed 1, per active triangle.
    pub seconds: Vec<f64>,
    /// Pixels the triangle returns.
    pub pixels: Vec<f64>,
    /// Seconds a worker of speed 1 spends on a package that does not continue its previous
    /// one, besides its triangles: the vertices on its borders, traced again.
    pub per_package_seconds: f64,
    /// Seconds a worker of speed 1 spends on the frame's ID buffer before any package.
    pub setup_seconds: f64,
}

impl Workload {
    /// From measured packages: (first triangle, end, seconds, pixels returned), covering
    /// `triangles` triangles; each package's time less `per_package_seconds` is spread evenly.
    pub fn from_packages(
        triangles: usize,
        packages: &[(usize, usize, f64, usize)],
        per_package_seconds: f64,
        setup_seconds: f64,
    ) -> Workload {
        let mut seconds = vec![0.0; triangles];
        let mut pixels = vec![0.0; triangles];
        for &(start, end, s, p) in packages {
            let n = (end - start).max(1) as f64;
            for t in start..end.min(triangles) {
                seconds[t] = (s - per_package_seconds).max(0.0) / n;
                pixels[t] = p as f64 / n;
            }
        }
        Workload {
            seconds,
            pixels,
            per_package_seconds,
            setup_seconds,
        }
    }

    pub fn total_seconds(&self) -> f64 {
        self.seconds.iter().sum()
    }
}

/// One worker: its speed (1 = the measured worker) and its link.
#[derive(Clone, Copy, Debug)]
pub struct WorkerSpec {
    pub speed: f64,
    pub bits_per_second: f64,
    pub latency_seconds: f64,
}

#[derive(Clone, Copy, Debug)]
pub struct Network {
    /// The master's link, shared by every result.
    pub master_bits_per_second: f64,
}

/// One simulated frame.
#[derive(Clone, Debug)]
pub struct SimulatedFrame {
    pub seconds: f64,
    /// Seconds each worker computed packages.
    pub busy: Vec<f64>,
    pub imbalance: f64,
    pub packages: usize,
}

#[derive(Debug, PartialEq)]
struct Event {
    time: f64,
    order: u64,
    worker: usize,
    kind: EventKind,
}

#[derive(Debug, PartialEq)]
enum EventKind {
    /// A package reached the worker.
    PackageArrives(Assignment),
    /// A result left the worker's link and waits for the master's: (bits, compute seconds).
    ResultSent(Assignment, f64, f64),
    /// A result reached the master.
    ResultArrives(Assignment, f64),
}

impl Eq for Event {}

impl Ord for Event {
    fn cmp(&self, other: &Self) -> Ordering {
        // Earliest first in a max-heap.
        other
            .time
            .total_cmp(&self.time)
            .then(other.order.cmp(&self.order))
    }
}

impl PartialOrd for Event {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Simulates one frame with `balancer` (whose speeds carry over from earlier frames).
pub(crate) fn simulate_frame(
    workload: &Workload,
    workers: &[WorkerSpec],
    network: Network,
    balancer: &mut Balancer,
) -> SimulatedFrame {
    let count = workload.seconds.len();
    balancer.start_frame(count);
    let mut events = BinaryHeap::new();
    let mut order = 0u64;
    // When each worker is free to compute (after its ID buffer), and when the master's link is.
    let mut worker_free: Vec<f64> = workers
        .iter()
        .map(|w| workload.setup_seconds / w.speed)
        .collect();
    let mut master_link_free = 0.0f64;
    let mut busy = vec![0.0; workers.len()];
    let mut last_end: Vec<Option<usize>> = vec![None; workers.len()];
    let mut packages = 0;
    let send = |events: &mut BinaryHeap<Event>, order: &mut u64, at: f64, w: usize, a| {
        let spec = workers[w];
        let arrival =
            at + spec.latency_seconds + (wire::PACKAGE_BYTES * 8) as f64 / spec.bits_per_second;
        *order += 1;
        events.push(Event {
            time: arrival,
            order: *order,
            worker: w,
            kind: EventKind::PackageArrives(a),
        });
    };
    for w in 0..workers.len() {
        if let Some(a) = balancer.next_package(w, count) {
            send(&mut events, &mut order, 0.0, w, a);
        }
    }
    let mut end = 0.0f64;
    while let Some(event) = events.pop() {
        let w = event.worker;
        let spec = workers[w];
        match event.kind {
            EventKind::PackageArrives(a) => {
                let work: f64 = workload.seconds[a.triangles.clone()].iter().sum();
                let fixed = if last_end[w] == Some(a.triangles.start) {
                    0.0
                } else {
                    workload.per_package_seconds
                };
                last_end[w] = Some(a.triangles.end);
                let seconds = (work + fixed) / spec.speed;
                let start = worker_free[w].max(event.time);
                let done = start + seconds;
                worker_free[w] = done;
                busy[w] += seconds;
                let pixels: f64 = workload.pixels[a.triangles.clone()].iter().sum();
                let bits = (wire::result_bytes(pixels.round() as usize) * 8) as f64;
                order += 1;
                events.push(Event {
                    time: done + bits / spec.bits_per_second,
                    order,
                    worker: w,
                    kind: EventKind::ResultSent(a, bits, seconds),
                });
            }
            EventKind::ResultSent(a, bits, seconds) => {
                // Into the master over its shared link, one result at a time, in time order.
                let enters = event.time.max(master_link_free);
                master_link_free = enters + bits / network.master_bits_per_second;
                order += 1;
                events.push(Event {
                    time: master_link_free + spec.latency_seconds,
                    order,
                    worker: w,
                    kind: EventKind::ResultArrives(a, seconds),
                });
            }
            EventKind::ResultArrives(a, seconds) => {
                balancer.finished(w, a.id, seconds);
                packages += 1;
                end = end.max(event.time);
                if let Some(next) = balancer.next_package(w, count) {
                    send(&mut events, &mut order, event.time, w, next);
                }
            }
        }
    }
    balancer.end_frame();
    SimulatedFrame {
        seconds: end,
        imbalance: imbalance(&busy),
        busy,
        packages,
    }
}

/// The steady state of `workers`: frames simulated until the balancer has measured every
/// worker (the paper's sizes are set after each frame); the last of `frames` is returned.
pub fn steady_frame(
    workload: &Workload,
    workers: &[WorkerSpec],
    network: Network,
    packages_per_worker: usize,
    frames: usize,
) -> SimulatedFrame {
    let mut balancer = Balancer::new(workers.len(), packages_per_worker);
    let mut last = None;
    for _ in 0..frames.max(1) {
        last = Some(simulate_frame(workload, workers, network, &mut balancer));
    }
    last.expect("at least one frame")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform(triangles: usize, seconds: f64) -> Workload {
        Workload {
            seconds: vec![seconds / triangles as f64; triangles],
            pixels: vec![10.0; triangles],
            per_package_seconds: 0.0,
            setup_seconds: 0.0,
        }
    }

    fn fast(n: usize, speed: f64) -> Vec<WorkerSpec> {
        vec![
            WorkerSpec {
                speed,
                bits_per_second: 1e12,
                latency_seconds: 0.0,
            };
            n
        ]
    }

    const NETWORK: Network = Network {
        master_bits_per_second: 1e12,
    };

    #[test]
    fn one_worker_takes_the_whole_work_and_n_equal_workers_divide_it() {
        let work = uniform(1000, 8.0);
        let one = steady_frame(&work, &fast(1, 1.0), NETWORK, 4, 2);
        assert!((one.seconds - 8.0).abs() < 1e-4, "{}", one.seconds);
        let four = steady_frame(&work, &fast(4, 1.0), NETWORK, 4, 2);
        assert!(
            (four.seconds - 2.0).abs() < 0.05,
            "{} {:?}",
            four.seconds,
            four.busy
        );
        assert!(four.imbalance < 0.02);
    }

    #[test]
    fn a_slow_shared_link_bounds_the_frame() {
        // 1000 triangles × 10 pixels × 16 bytes ≈ 160 kB: 1.3 s over 1 Mbit/s.
        let work = uniform(1000, 0.01);
        let slow = Network {
            master_bits_per_second: 1e6,
        };
        let frame = steady_frame(&work, &fast(8, 1.0), slow, 4, 2);
        let bits = (1000 * 10 * 16) as f64 * 8.0;
        assert!(frame.seconds >= bits / 1e6, "{}", frame.seconds);
    }
}
