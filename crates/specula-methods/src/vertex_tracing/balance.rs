//! Central dynamic load balancing (Ullmann et al. 2001, §4): the master hands out task
//! packages of reflector triangles on demand, each sized for the worker that asks from its
//! measured speed, and re-sizes them after every frame. No MPI here: the MPI master
//! (`specula render --distributed`) and the discrete-event simulation ([`super::simulate`])
//! drive the same [`Balancer`].
//!
//! Sizing: a worker of speed s (triangles per second, measured over its last frame) among
//! workers of total speed S gets packages of `remaining × s / S / packages_per_worker`
//! triangles at the frame's start, so that each worker asks about `packages_per_worker` times
//! per frame; as the queue runs down, packages shrink with what is left (factoring: never
//! more than half the worker's share of what remains, since the others still hold work), so
//! that the last packages end close together. A worker that does not answer within the
//! timeout is lost: its outstanding packages go back to the front of the queue for the others.

use std::collections::VecDeque;
use std::ops::Range;

/// A package: a range of the frame's active triangles.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assignment {
    pub id: u32,
    pub triangles: Range<usize>,
}

/// What a worker did in one frame.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct WorkerFrame {
    pub rank: usize,
    pub packages: u32,
    pub triangles: usize,
    /// Seconds the worker reported computing.
    pub busy_seconds: f64,
    /// Triangles per second used to size its packages this frame.
    pub speed_used: f64,
    pub lost: bool,
}

pub struct Balancer {
    /// Triangles per second per worker (index = worker slot), from the last frame.
    speeds: Vec<f64>,
    lost: Vec<bool>,
    pub packages_per_worker: usize,
    queue: VecDeque<Range<usize>>,
    outstanding: Vec<Vec<Assignment>>,
    next_id: u32,
    frame: Vec<WorkerFrame>,
}

impl Balancer {
    /// `workers` workers of equal assumed speed.
    pub fn new(workers: usize, packages_per_worker: usize) -> Balancer {
        Balancer {
            speeds: vec![1.0; workers],
            lost: vec![false; workers],
            packages_per_worker: packages_per_worker.max(1),
            queue: VecDeque::new(),
            outstanding: vec![Vec::new(); workers],
            next_id: 0,
            frame: Vec::new(),
        }
    }

    pub fn workers(&self) -> usize {
        self.speeds.len()
    }

    pub fn live_workers(&self) -> Vec<usize> {
        (0..self.workers()).filter(|&w| !self.lost[w]).collect()
    }

    #[cfg_attr(not(feature = "mpi"), allow(dead_code))] // the MPI master's alone
    pub fn is_lost(&self, worker: usize) -> bool {
        self.lost[worker]
    }

    /// Starts a frame of `triangles` active triangles.
    pub fn start_frame(&mut self, triangles: usize) {
        self.queue.clear();
        if triangles > 0 {
            self.queue.push_back(0..triangles);
        }
        for outstanding in &mut self.outstanding {
            outstanding.clear();
        }
        self.frame = (0..self.workers())
            .map(|w| WorkerFrame {
                rank: w + 1,
                speed_used: self.speeds[w],
                lost: self.lost[w],
                ..Default::default()
            })
            .collect();
    }

    fn remaining(&self) -> usize {
        self.queue.iter().map(|r| r.len()).sum()
    }

    /// The package size for `worker` now: its share of the frame split into
    /// `packages_per_worker` pieces, at most half its share of what is left.
    pub fn package_size(&self, worker: usize, frame_triangles: usize) -> usize {
        let live: f64 = self.live_workers().iter().map(|&w| self.speeds[w]).sum();
        let share = self.speeds[worker] / live.max(f64::MIN_POSITIVE);
        let planned = frame_triangles as f64 * share / self.packages_per_worker as f64;
        let guided = self.remaining() as f64 * share / 2.0;
        planned.min(guided).ceil().max(1.0) as usize
    }

    /// The next package for `worker` (None when the queue is empty).
    pub fn next_package(&mut self, worker: usize, frame_triangles: usize) -> Option<Assignment> {
        let size = self.package_size(worker, frame_triangles);
        let front = self.queue.pop_front()?;
        let end = (front.start + size).min(front.end);
        if end < front.end {
            self.queue.push_front(end..front.end);
        }
        let assignment = Assignment {
            id: self.next_id,
            triangles: front.start..end,
        };
        self.next_id += 1;
        self.outstanding[worker].push(assignment.clone());
        Some(assignment)
    }

    /// `worker` finished package `id` in `seconds`. Returns the package, or None if it was not
    /// outstanding (a late answer from a worker declared lost: its work was handed out again).
    pub fn finished(&mut self, worker: usize, id: u32, seconds: f64) -> Option<Assignment> {
        let at = self.outstanding[worker].iter().position(|a| a.id == id)?;
        let assignment = self.outstanding[worker].remove(at);
        let stats = &mut self.frame[worker];
        stats.packages += 1;
        stats.triangles += assignment.triangles.len();
        stats.busy_seconds += seconds;
        Some(assignment)
    }

    /// Declares `worker` lost: its outstanding packages go back to the front of the queue.
    #[cfg_attr(not(feature = "mpi"), allow(dead_code))] // the MPI master's alone
    pub fn lose(&mut self, worker: usize) -> Vec<Assignment> {
        self.lost[worker] = true;
        self.frame[worker].lost = true;
        let orphans = std::mem::take(&mut self.outstanding[worker]);
        for orphan in orphans.iter().rev() {
            self.queue.push_front(orphan.triangles.clone());
        }
        orphans
    }

    #[cfg_attr(not(feature = "mpi"), allow(dead_code))] // the MPI master's alone
    pub fn outstanding(&self, worker: usize) -> &[Assignment] {
        &self.outstanding[worker]
    }

    /// Whether every triangle of the frame is handed out and answered.
    #[cfg_attr(not(feature = "mpi"), allow(dead_code))] // the MPI master's alone
    pub fn frame_done(&self) -> bool {
        self.queue.is_empty() && self.outstanding.iter().all(Vec::is_empty)
    }

    /// Empties the queue: the ranges no worker will get (the master does them itself).
    #[cfg_attr(not(feature = "mpi"), allow(dead_code))] // the MPI master's alone
    pub fn take_queue(&mut self) -> Vec<Range<usize>> {
        self.queue.drain(..).collect()
    }

    /// Ends the frame: each live worker's speed becomes what it measured (triangles per busy
    /// second), for the next frame's sizes (§4: "redistributes these accordingly, after each
    /// frame"). Returns the frame's statistics.
    pub fn end_frame(&mut self) -> Vec<WorkerFrame> {
        for (w, stats) in self.frame.iter().enumerate() {
            if !self.lost[w] && stats.busy_seconds > 0.0 && stats.triangles > 0 {
                self.speeds[w] = stats.triangles as f64 / stats.busy_seconds;
            }
        }
        std::mem::take(&mut self.frame)
    }
}

/// Load imbalance of a frame: 1 − mean/max of the live workers' busy times (0: all equally
/// busy; the share of the slowest worker's time the others spent idle, on average).
pub fn imbalance(busy_seconds: &[f64]) -> f64 {
    let max = busy_seconds.iter().copied().fold(0.0, f64::max);
    if max <= 0.0 {
        return 0.0;
    }
    let mean = busy_seconds.iter().sum::<f64>() / busy_seconds.len() as f64;
    1.0 - mean / max
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_triangle_once_even_when_a_worker_is_lost() {
        let mut b = Balancer::new(3, 4);
        b.start_frame(1000);
        let mut done = vec![0u32; 1000];
        let a = b.next_package(0, 1000).unwrap();
        let lost_package = b.next_package(1, 1000).unwrap();
        let c = b.next_package(2, 1000).unwrap();
        for (w, p) in [(0, a), (2, c)] {
            b.finished(w, p.id, 1.0).unwrap();
            p.triangles.for_each(|t| done[t] += 1);
        }
        let orphans = b.lose(1);
        assert_eq!(orphans, vec![lost_package.clone()]);
        assert!(b.finished(1, lost_package.id, 1.0).is_none());
        while !b.frame_done() {
            for w in [0, 2] {
                if let Some(p) = b.next_package(w, 1000) {
                    b.finished(w, p.id, 0.1).unwrap();
                    p.triangles.for_each(|t| done[t] += 1);
                }
            }
        }
        assert!(done.iter().all(|&d| d == 1));
    }

    #[test]
    fn a_slower_worker_gets_smaller_packages_after_a_frame() {
        let mut b = Balancer::new(2, 4);
        b.start_frame(800);
        // Worker 0 does 100 triangles a second, worker 1 a third of that.
        while !b.frame_done() {
            for (w, speed) in [(0, 100.0), (1, 100.0 / 3.0)] {
                if let Some(p) = b.next_package(w, 800) {
                    let seconds = p.triangles.len() as f64 / speed;
                    b.finished(w, p.id, seconds).unwrap();
                }
            }
        }
        b.end_frame();
        b.start_frame(800);
        let (fast, slow) = (b.package_size(0, 800), b.package_size(1, 800));
        // Shares 3/4 and 1/4 of 800, in four packages each (rounded up).
        assert!((150..=151).contains(&fast), "{fast}");
        assert!((50..=51).contains(&slow), "{slow}");
    }

    #[test]
    fn imbalance_is_zero_for_equal_loads() {
        assert_eq!(imbalance(&[2.0, 2.0]), 0.0);
        assert!((imbalance(&[1.0, 3.0]) - (1.0 - 2.0 / 3.0)).abs() < 1e-12);
    }
}
