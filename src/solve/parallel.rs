//! The same branch and prune on all cores, with exactly the serial answer.
//!
//! The search tree is walked level by level. The boxes of a level are cut into fixed chunks of
//! `CHUNK` boxes, in order, and each chunk is shrunk on some worker with its own contractors.
//! Shrinking a box depends on nothing but the box (contractors keep no state from one box to
//! the next), and results are taken back in chunk order, so the tree, and with it the set of
//! solution boxes, does not depend on the number of threads or on scheduling. Only the order in
//! which boxes are reported differs from the depth-first serial driver.
//!
//! Breadth-first order also gives the convergence measurement of seed 000, section V: the
//! widest diagonal among the boxes of each level.

use super::driver::{process_cpu_seconds, BoxSink, BoxStatus, Limit, Progress, Shrunk, Solver, Stats, Status};
use crate::interval::IntervalBox;
use crate::lp::LpCounters;
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Boxes per unit of parallel work: fixed, so that chunks do not depend on the thread count.
const CHUNK: usize = 4;

impl Solver<'_> {
    /// Runs on `threads` worker threads (at least 1), breadth first. `level_diagonals`, when
    /// given, receives per tree level the widest primary diagonal among that level's boxes
    /// after shrinking (those not proven empty): the enclosure reached at each iteration.
    pub fn run_parallel(&self, threads: usize, cancel: &AtomicBool, sink: &mut dyn BoxSink, mut level_diagonals: Option<&mut Vec<f64>>) -> (Status, Stats) {
        let t0 = Instant::now();
        let c0 = process_cpu_seconds();
        let mut stats = Stats::default();
        let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build() {
            Ok(p) => p,
            // No threads to be had: the serial driver gives the same set of boxes.
            Err(_) => return self.run(cancel, sink),
        };
        let mut level = vec![self.initial()];
        let mut status = Status::Complete;
        let mut lp = LpCounters::default();
        while !level.is_empty() {
            if let Some(limit) = self.limit_before(&stats, level.len() as u64, t0, cancel) {
                status = Status::Incomplete(limit);
                break;
            }
            let shrunk: Vec<(Vec<(Shrunk, IntervalBox, Stats)>, LpCounters)> = pool.install(|| {
                level
                    .par_chunks(CHUNK)
                    .map(|chunk| {
                        let mut contractor = self.contractor();
                        let done = chunk
                            .iter()
                            .map(|b| {
                                let mut b = b.clone();
                                let mut s = Stats::default();
                                let r = self.shrink(&mut b, contractor.as_mut(), &mut s);
                                (r, b, s)
                            })
                            .collect();
                        (done, contractor.lp_counters())
                    })
                    .collect()
            });
            let mut next = Vec::new();
            if let Some(d) = level_diagonals.as_deref_mut() {
                let widest = shrunk.iter().flat_map(|(c, _)| c).filter(|(r, _, _)| !matches!(r, Shrunk::Empty)).map(|(_, b, _)| b.diagonal(self.primaries())).fold(0.0, f64::max);
                d.push(widest);
            }
            for (chunk, counters) in shrunk {
                lp.solved += counters.solved;
                lp.unverified += counters.unverified;
                for (outcome, b, s) in chunk {
                    stats.processed += 1;
                    stats.shrink_rounds += s.shrink_rounds;
                    stats.certified += s.certified;
                    stats.max_level = stats.max_level.max(b.level);
                    match outcome {
                        Shrunk::Empty => stats.empty += 1,
                        Shrunk::Solution | Shrunk::Unique => {
                            stats.solutions += 1;
                            let tag = if matches!(outcome, Shrunk::Unique) { BoxStatus::Unique } else { BoxStatus::Solution };
                            if sink.emit(tag, &b).is_break() && status == Status::Complete {
                                status = Status::Incomplete(Limit::Sink);
                            }
                        }
                        Shrunk::Stalled => {
                            let (lower, upper) = self.split(&b);
                            stats.bisected += 1;
                            next.push(lower);
                            next.push(upper);
                        }
                    }
                }
            }
            level = next;
            sink.progress(&Progress { processed: stats.processed, pending: level.len(), decided: f64::NAN });
            if status != Status::Complete {
                break;
            }
        }
        if status != Status::Complete {
            for b in &level {
                if sink.emit(BoxStatus::Undecided, b).is_break() {
                    break;
                }
            }
        }
        stats.lp = lp;
        stats.seconds = t0.elapsed().as_secs_f64();
        stats.cpu_seconds = process_cpu_seconds() - c0;
        (status, stats)
    }
}
