//! The two drivers: one thread in any `Store` order, or many threads level by level.
//!
//! Both take a cell, check the limits, let the `Prune` decide it, and route the decision:
//! discards to `Stats`, results and undecided cells to the `Sink`, children back to the pool.
//! A run stopped by a limit reports every pending cell as `Undecided::Pending`: nothing is
//! silently dropped.
//!
//! `run_by_level` walks the tree breadth first. The cells of a level are cut into chunks that
//! workers take from a shared counter; each worker owns its `Prune` for the whole run (its
//! scratch state is built once, not per chunk). The decisions are routed in level order on the
//! calling thread, and `Prune::process` depends on the cell alone, so the cells reported, and
//! their order, do not depend on the number of threads or on scheduling.

use super::limits::{process_cpu_seconds, Budget, Limit, Limits, Progress, Status};
use super::share::{self, Decision, Named, Peers, Wire};
use super::store::{Pool, Store};
use super::{Prune, Reason, Sink, Stats, Step, Undecided, INTERRUPTED};
use smallvec::SmallVec;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// Levels with fewer cells are decided on the calling thread alone.
const SERIAL_BELOW: usize = 8;

/// How often a driver reports progress.
const PROGRESS_EVERY: Duration = Duration::from_millis(200);

/// Runs `prune` from `start` on the calling thread, taking pending cells in `store` order.
///
/// Returns how the run ended and its counters.
///
/// # Examples
///
/// Bisect [0, 1] until pieces are shorter than 1/8, keeping those that hold 0.3:
///
/// ```
/// use linkspace::kernel::search::{run, Prune, Reason, Sink, Step, Store, Limits, Undecided, Status};
/// use std::ops::ControlFlow;
/// use std::sync::atomic::AtomicBool;
///
/// #[derive(Clone, Copy)]
/// struct Apart;
/// impl Reason for Apart {
///     fn name(self) -> &'static str {
///         "apart"
///     }
/// }
/// struct Bisect;
/// impl Prune for Bisect {
///     type Cell = (f64, f64);
///     type Found = (f64, f64);
///     type Reason = Apart;
///     fn process(&mut self, (a, b): (f64, f64)) -> Step<(f64, f64), (f64, f64), Apart> {
///         if !(a <= 0.3 && 0.3 <= b) {
///             Step::Discard(Apart)
///         } else if b - a < 0.125 {
///             Step::Found((a, b))
///         } else {
///             let m = 0.5 * (a + b);
///             Step::Split([(a, m), (m, b)].into_iter().collect())
///         }
///     }
/// }
/// struct Keep(Vec<(f64, f64)>);
/// impl Sink<(f64, f64), (f64, f64)> for Keep {
///     fn found(&mut self, f: (f64, f64)) -> ControlFlow<()> { self.0.push(f); ControlFlow::Continue(()) }
///     fn undecided(&mut self, _: (f64, f64), _: Undecided) -> ControlFlow<()> { ControlFlow::Continue(()) }
/// }
/// let mut keep = Keep(vec![]);
/// let (status, stats) = run(&mut Bisect, (0.0, 1.0), Store::DepthFirst, &Limits::default(), &AtomicBool::new(false), &mut keep);
/// assert_eq!(status, Status::Finished);
/// assert_eq!(keep.0, vec![(0.25, 0.3125)]);
/// assert_eq!(stats.discarded(Apart), 4);
/// ```
pub fn run<P: Prune>(prune: &mut P, start: P::Cell, store: Store, limits: &Limits, cancel: &AtomicBool, sink: &mut impl Sink<P::Cell, P::Found>) -> (Status, Stats) {
    let budget = Budget::start(*limits, cancel);
    let c0 = process_cpu_seconds();
    let mut stats = Stats::default();
    let mut discards = Discards::default();
    let mut pool = Pool::new(store);
    let mut pending_share = prune.share(&start);
    let mut pending_bytes = prune.bytes(&start);
    let key = prune.key(&start);
    pool.restore(start, key);
    let mut status = Status::Finished;
    let mut last_progress = Instant::now();
    let mut report_pending = true;

    while let Some(cell) = pool.pop() {
        if let Some(limit) = budget.exhausted(stats.processed, pending_bytes) {
            let key = prune.key(&cell);
            pool.restore(cell, key);
            status = Status::Stopped(limit);
            break;
        }
        pending_share -= prune.share(&cell);
        pending_bytes = pending_bytes.saturating_sub(prune.bytes(&cell));
        stats.processed += 1;
        stats.max_level = stats.max_level.max(prune.level(&cell));
        let step = prune.process_until(cell, &|| budget.interrupted().is_some());
        let cut_short = is_interrupted(&step);
        let flow = route(step, &mut stats, &mut discards, sink, |children| {
            for c in &children {
                pending_share += prune.share(c);
                pending_bytes += prune.bytes(c);
            }
            pool.push_children(children.into_iter().map(|c| {
                let k = prune.key(&c);
                (c, k)
            }));
        });
        if flow.is_break() {
            status = Status::Stopped(Limit::Sink);
            report_pending = false;
            break;
        }
        if cut_short {
            status = Status::Stopped(budget.interrupted().unwrap_or(Limit::Time));
            break;
        }
        // The clock is read every 64 cells only: a cell can cost less than reading it.
        if stats.processed % 64 == 0 && last_progress.elapsed() >= PROGRESS_EVERY {
            last_progress = Instant::now();
            sink.progress(&Progress { processed: stats.processed, pending: pool.len(), decided: (1.0 - pending_share).clamp(0.0, 1.0) });
        }
    }
    if report_pending {
        report_undecided(pool.drain(), &mut stats, sink);
    }
    discards.into_stats(&mut stats);
    stats.seconds = budget.elapsed().as_secs_f64();
    stats.cpu_seconds = process_cpu_seconds() - c0;
    (status, stats)
}

/// Runs breadth first from `start` on one thread per element of `workers` (one `Prune` each;
/// a single worker runs on the calling thread).
///
/// The cells reported, and their order, are those of a serial breadth-first walk whatever the
/// number of workers. The calling thread is the first worker; the others are started once for
/// the whole run (not per level: starting a thread costs as much as deciding a few 3R cells)
/// and are handed each level through a channel.
pub fn run_by_level<P>(workers: &mut [P], start: P::Cell, limits: &Limits, cancel: &AtomicBool, sink: &mut impl Sink<P::Cell, P::Found>) -> (Status, Stats)
where
    P: Prune + Send,
{
    let budget = Budget::start(*limits, cancel);
    with_crew(workers, &budget, |decide| walk_levels(start, &budget, sink, None, decide))
}

/// As `run_by_level`, with each level shared among the processes of `share::Peers` when this
/// thread has them (`share`): every process gets the cells and the order a single process
/// reports. Its cells and results travel between processes, hence `Wire`.
pub fn run_shared<P>(workers: &mut [P], start: P::Cell, limits: &Limits, cancel: &AtomicBool, sink: &mut impl Sink<P::Cell, P::Found>) -> (Status, Stats)
where
    P: Prune + Send,
    P::Cell: Wire,
    P::Found: Wire,
{
    run_shared_with(share::peers(), workers, start, limits, cancel, sink)
}

/// `run_shared` among `peers`.
pub(crate) fn run_shared_with<P>(peers: Option<&dyn Peers>, workers: &mut [P], start: P::Cell, limits: &Limits, cancel: &AtomicBool, sink: &mut impl Sink<P::Cell, P::Found>) -> (Status, Stats)
where
    P: Prune + Send,
    P::Cell: Wire,
    P::Found: Wire,
{
    let Some(peers) = peers else {
        return run_by_level(workers, start, limits, cancel, sink);
    };
    let budget = Budget::start(*limits, cancel);
    let (status, mut stats) = with_crew(workers, &budget, |decide| walk_levels(start, &budget, sink, Some(peers), |level| decide_shared(level, peers, decide)));
    stats.cpu_seconds = share::sum(peers, &[stats.cpu_seconds])[0];
    (status, stats)
}

/// The level decider one thread per worker gives: the calling thread is the first worker; the
/// others are started once for the whole run (not per level: starting a thread costs as much
/// as deciding a few 3R cells) and are handed each level through a channel.
fn with_crew<P, T>(workers: &mut [P], budget: &Budget<'_>, body: impl FnOnce(&mut dyn FnMut(Vec<P::Cell>) -> LevelOutcome<P::Cell, P::Found, P::Reason>) -> T) -> T
where
    P: Prune + Send,
{
    assert!(!workers.is_empty(), "invariant: run_by_level needs at least one worker");
    let (first, rest) = workers.split_first_mut().expect("invariant: at least one worker");
    if rest.is_empty() {
        return body(&mut |level| decide_alone(first, level, budget));
    }
    std::thread::scope(|s| {
        let (done_tx, done_rx) = mpsc::channel();
        let mut job_txs = Vec::with_capacity(rest.len());
        for p in rest.iter_mut() {
            let (job_tx, job_rx) = mpsc::channel::<Arc<LevelJob<P::Cell>>>();
            job_txs.push(job_tx);
            let done_tx = done_tx.clone();
            s.spawn(move || {
                while let Some(job) = recv_spinning(&job_rx) {
                    if done_tx.send(take_chunks(p, &job, budget)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(done_tx);
        let out = {
            let mut decide = |level: Vec<P::Cell>| {
                // A level of a few cells costs less than waking the crew for it: the first
                // worker decides it alone, with the same answers.
                if level.len() < SERIAL_BELOW {
                    return decide_alone(first, level, budget);
                }
                let job = Arc::new(LevelJob::new(level, job_txs.len() + 1));
                for tx in &job_txs {
                    tx.send(job.clone()).expect("invariant: the crew lives as long as the run");
                }
                let mut done = vec![take_chunks(first, &job, budget)];
                done.extend((0..job_txs.len()).map(|_| recv_spinning(&done_rx).expect("invariant: Prune::process does not panic")));
                collect(job, done)
            };
            body(&mut decide)
        };
        // Dropping the senders ends the crew's loops; the scope joins them.
        drop(job_txs);
        out
    })
}

/// One process's decisions of a level, and the cells it did not take.
type Share<C, F> = (std::vec::IntoIter<Decision<C, F, Named>>, Vec<C>);

/// Decides this process's share of a level and returns every process's decisions: chunk `j`
/// of the level goes to process `j mod size`; the decisions come back in level order (a
/// level no process was interrupted in), or process by process (an interrupted level, which
/// depends on the clock anyway).
fn decide_shared<C: Wire, F: Wire, R: Reason>(level: Vec<C>, peers: &dyn Peers, decide: &mut dyn FnMut(Vec<C>) -> LevelOutcome<C, F, R>) -> LevelOutcome<C, F, Named> {
    let (rank, size) = (peers.rank(), peers.size());
    // Chunks small enough to balance the load, large enough that messages stay few.
    let chunk = (level.len() / (size * 8)).clamp(1, 256);
    let lengths: Vec<usize> = (0..level.len().div_ceil(chunk)).map(|j| chunk.min(level.len() - j * chunk)).collect();
    let mine: Vec<C> = level.into_iter().enumerate().filter(|(i, _)| (i / chunk) % size == rank).map(|(_, c)| c).collect();
    let (steps, unprocessed) = decide(mine);
    let mut bytes = Vec::new();
    steps.len().put(&mut bytes);
    for d in &steps {
        share::put_decision(d, &mut bytes);
    }
    drop(steps);
    unprocessed.put(&mut bytes);
    let mut theirs: Vec<Share<C, F>> = peers
        .all_gather(&bytes)
        .iter()
        .map(|b| {
            let mut input = b.as_slice();
            let n = usize::take(&mut input);
            let steps: Vec<_> = (0..n).map(|_| share::take_decision::<C, F>(&mut input)).collect();
            (steps.into_iter(), Vec::<C>::take(&mut input))
        })
        .collect();
    let interrupted = theirs.iter().any(|(_, u)| !u.is_empty());
    let mut out = Vec::with_capacity(lengths.iter().sum());
    let mut unprocessed = Vec::new();
    if interrupted {
        for (steps, u) in theirs {
            out.extend(steps);
            unprocessed.extend(u);
        }
    } else {
        for (j, &n) in lengths.iter().enumerate() {
            out.extend(theirs[j % size].0.by_ref().take(n));
        }
    }
    (out, unprocessed)
}

/// How long a thread waiting for the next level (or for the crew's decisions) spins before it
/// sleeps. Levels follow each other within microseconds, and waking a sleeping thread costs
/// tens of microseconds (more on a virtual machine, whose idle core is halted): paid twice per
/// level, that cost 3R node searches (levels of a few hundred cells, a few microseconds each)
/// most of their speed-up (robot e: 1.3x on 2 threads before, 1.75x with the spin).
const SPIN: Duration = Duration::from_micros(100);

/// The next message of `rx`, spinning for `SPIN` before blocking; `None` once every sender is
/// gone.
fn recv_spinning<T>(rx: &mpsc::Receiver<T>) -> Option<T> {
    let start = Instant::now();
    loop {
        for _ in 0..64 {
            match rx.try_recv() {
                Ok(x) => return Some(x),
                Err(mpsc::TryRecvError::Disconnected) => return None,
                Err(mpsc::TryRecvError::Empty) => std::hint::spin_loop(),
            }
        }
        if start.elapsed() > SPIN {
            return rx.recv().ok();
        }
    }
}

/// The decisions of a level, in level order: each with its cell's level and the bytes of the
/// children it made (for the memory limit).
type Decided<C, F, R> = Vec<Decision<C, F, R>>;

/// The step a `Prune` returns.
type PruneStep<P> = Step<<P as Prune>::Cell, <P as Prune>::Found, <P as Prune>::Reason>;

/// A level's decisions, and the cells cancel or time kept from being taken.
type LevelOutcome<C, F, R> = (Decided<C, F, R>, Vec<C>);

/// The breadth-first walk: takes each level's decisions from `decide_level` (which also returns
/// the cells cancel or time kept it from taking) and routes them in level order.
///
/// With `peers`, the processes agree on every clock-dependent stop (each reads its own clock
/// and cancel flag), so they walk the same tree.
fn walk_levels<C, F, R: Reason>(start: C, budget: &Budget<'_>, sink: &mut impl Sink<C, F>, peers: Option<&dyn Peers>, mut decide_level: impl FnMut(Vec<C>) -> LevelOutcome<C, F, R>) -> (Status, Stats) {
    let agree = |limit: Option<Limit>| match peers {
        Some(p) => share::agree(p, limit),
        None => limit,
    };
    let c0 = process_cpu_seconds();
    let mut stats = Stats::default();
    let mut discards = Discards::default();
    let mut level = vec![start];
    let mut status = Status::Finished;
    let mut report_pending = true;
    let mut pending = Vec::new();

    while !level.is_empty() {
        if let Some(limit) = agree(budget.exhausted(stats.processed, 0)) {
            status = Status::Stopped(limit);
            pending = level;
            break;
        }
        // Process as much of the level as the cell budget allows: the same prefix for any
        // thread count.
        let take = level.len().min(usize::try_from(budget.cells_left(stats.processed)).unwrap_or(usize::MAX));
        let rest = level.split_off(take);
        let (steps, unprocessed) = decide_level(level);
        let mut next = Vec::new();
        let mut next_bytes = 0usize;
        let cut_short = steps.iter().any(|(_, _, s)| is_interrupted(s));
        for (level_of, bytes, step) in steps {
            stats.processed += 1;
            stats.max_level = stats.max_level.max(level_of);
            let flow = route(step, &mut stats, &mut discards, sink, |children| {
                next_bytes += bytes;
                next.extend(children);
            });
            if flow.is_break() {
                status = Status::Stopped(Limit::Sink);
                report_pending = false;
                break;
            }
        }
        if !report_pending {
            break;
        }
        let stopped = if !unprocessed.is_empty() || cut_short {
            agree(budget.interrupted()).or(Some(Limit::Time))
        } else if !rest.is_empty() {
            Some(Limit::Boxes)
        } else if next_bytes > budget.max_memory() {
            Some(Limit::Memory)
        } else {
            None
        };
        sink.progress(&Progress { processed: stats.processed, pending: next.len() + rest.len() + unprocessed.len(), decided: f64::NAN });
        if let Some(limit) = stopped {
            status = Status::Stopped(limit);
            pending = unprocessed;
            pending.extend(rest);
            pending.extend(next);
            break;
        }
        level = next;
    }
    if report_pending {
        report_undecided(pending, &mut stats, sink);
    }
    discards.into_stats(&mut stats);
    stats.seconds = budget.elapsed().as_secs_f64();
    stats.cpu_seconds = process_cpu_seconds() - c0;
    (status, stats)
}

/// Whether a `Prune` left the cell undecided because the deadline or cancel came.
fn is_interrupted<C, F, R>(step: &Step<C, F, R>) -> bool {
    matches!(step, Step::Undecided(_, why) if *why == INTERRUPTED)
}

/// Decides one cell: its level, the bytes of its children, the step.
fn decide<P: Prune>(p: &mut P, c: P::Cell, budget: &Budget<'_>) -> (u32, usize, PruneStep<P>) {
    let l = p.level(&c);
    let step = p.process_until(c, &|| budget.interrupted().is_some());
    let bytes = match &step {
        Step::Split(children) => children.iter().map(|c| p.bytes(c)).sum(),
        _ => 0,
    };
    (l, bytes, step)
}

/// Decides a level on one worker, stopping when cancel or time interrupts it.
fn decide_alone<P: Prune>(p: &mut P, level: Vec<P::Cell>, budget: &Budget<'_>) -> LevelOutcome<P::Cell, P::Found, P::Reason> {
    let mut out = Vec::with_capacity(level.len());
    let mut cells = level.into_iter();
    for c in cells.by_ref() {
        out.push(decide(p, c, budget));
        if budget.interrupted().is_some() {
            break;
        }
    }
    (out, cells.collect())
}

/// One level cut into chunks that workers take from a shared counter.
struct LevelJob<C> {
    chunks: Vec<Mutex<Option<Vec<C>>>>,
    next: AtomicUsize,
    stop: AtomicBool,
}

impl<C> LevelJob<C> {
    fn new(level: Vec<C>, workers: usize) -> Self {
        // Chunks small enough to balance the load, large enough that taking one costs little.
        let chunk = (level.len() / (workers * 8)).clamp(1, 64);
        let mut chunks = Vec::with_capacity(level.len().div_ceil(chunk));
        let mut cells = level.into_iter().peekable();
        while cells.peek().is_some() {
            chunks.push(Mutex::new(Some(cells.by_ref().take(chunk).collect())));
        }
        LevelJob { chunks, next: AtomicUsize::new(0), stop: AtomicBool::new(false) }
    }
}

/// A worker's share of a level: the chunks it took, by index.
type Taken<C, F, R> = Vec<(usize, Decided<C, F, R>)>;

fn take_chunks<P: Prune>(p: &mut P, job: &LevelJob<P::Cell>, budget: &Budget<'_>) -> Taken<P::Cell, P::Found, P::Reason> {
    let mut mine = Vec::new();
    while !job.stop.load(Ordering::Relaxed) {
        let i = job.next.fetch_add(1, Ordering::Relaxed);
        let Some(slot) = job.chunks.get(i) else { break };
        let cells = slot.lock().expect("invariant: no worker panics holding a chunk").take().expect("invariant: each chunk is taken once");
        mine.push((i, cells.into_iter().map(|c| decide(p, c, budget)).collect()));
        if budget.interrupted().is_some() {
            job.stop.store(true, Ordering::Relaxed);
        }
    }
    mine
}

/// The decisions in chunk order; the chunks no worker took (cancel or time) stay pending. Only
/// an interrupted run, which depends on the clock anyway, has such gaps.
fn collect<C, F, R>(job: Arc<LevelJob<C>>, done: Vec<Taken<C, F, R>>) -> LevelOutcome<C, F, R> {
    let mut by_chunk: Vec<Option<Decided<C, F, R>>> = (0..job.chunks.len()).map(|_| None).collect();
    for (i, steps) in done.into_iter().flatten() {
        by_chunk[i] = Some(steps);
    }
    let mut out = Vec::new();
    let mut unprocessed = Vec::new();
    for (slot, steps) in job.chunks.iter().zip(by_chunk) {
        match steps {
            Some(steps) => out.extend(steps),
            None => unprocessed.extend(slot.lock().expect("invariant: no worker panics holding a chunk").take().into_iter().flatten()),
        }
    }
    (out, unprocessed)
}

fn report_undecided<C, F>(pending: impl IntoIterator<Item = C>, stats: &mut Stats, sink: &mut impl Sink<C, F>) {
    for c in pending {
        stats.undecided += 1;
        if sink.undecided(c, Undecided::Pending).is_break() {
            break;
        }
    }
}

/// Counts a decision and passes it on: results and undecided cells to the sink, children to
/// `split`. `Break` when the sink asks to stop.
fn route<C, F, R: Reason>(step: Step<C, F, R>, stats: &mut Stats, discards: &mut Discards, sink: &mut impl Sink<C, F>, split: impl FnOnce(SmallVec<[C; 4]>)) -> ControlFlow<()> {
    match step {
        Step::Discard(reason) => {
            discards.count(reason.name());
            ControlFlow::Continue(())
        }
        Step::Found(f) => {
            stats.found += 1;
            sink.found(f)
        }
        Step::Undecided(c, reason) => {
            stats.undecided += 1;
            sink.undecided(c, Undecided::Precision(reason))
        }
        Step::Split(children) => {
            stats.split += 1;
            split(children);
            ControlFlow::Continue(())
        }
    }
}

/// Per-reason discard counts of a run, kept in a short list while it runs: a search has a
/// handful of reasons, and a scan of a few string compares costs less per cell than a
/// `BTreeMap` entry (the 3R searches decide a cell in a few microseconds).
#[derive(Default)]
struct Discards(Vec<(&'static str, u64)>);

impl Discards {
    #[inline]
    fn count(&mut self, reason: &'static str) {
        match self.0.iter_mut().find(|(r, _)| *r == reason) {
            Some((_, n)) => *n += 1,
            None => self.0.push((reason, 1)),
        }
    }

    fn into_stats(self, stats: &mut Stats) {
        for (r, n) in self.0 {
            *stats.discarded.entry(r).or_default() += n;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::search::Store;

    /// Roots of sin(20 x) in [0, 3] (x = kπ/20), bracketed by bisection: a cell is an interval
    /// and its depth; it is discarded when sin keeps one sign on it (monotone pieces, checked at
    /// the ends plus a derivative bound), found when short.
    #[derive(Clone)]
    struct Roots;
    type Cell = (f64, f64, u32);
    #[derive(Clone, Copy)]
    struct OneSign;
    impl Reason for OneSign {
        fn name(self) -> &'static str {
            "one sign"
        }
    }
    impl Prune for Roots {
        type Cell = Cell;
        type Found = (f64, f64);
        type Reason = OneSign;
        fn process(&mut self, (a, b, l): Cell) -> Step<Cell, (f64, f64), OneSign> {
            let (fa, fb) = ((20.0 * a).sin(), (20.0 * b).sin());
            // |f'| ≤ 20, so f cannot reach 0 on [a, b] when min(|fa|, |fb|) > 20 (b − a).
            if fa * fb > 0.0 && fa.abs().min(fb.abs()) > 20.0 * (b - a) {
                return Step::Discard(OneSign);
            }
            if b - a < 1e-3 {
                return Step::Found((a, b));
            }
            let m = 0.5 * (a + b);
            Step::Split([(a, m, l + 1), (m, b, l + 1)].into_iter().collect())
        }
        fn level(&self, c: &Cell) -> u32 {
            c.2
        }
        fn share(&self, c: &Cell) -> f64 {
            (c.1 - c.0) / 3.0
        }
        fn key(&self, c: &Cell) -> f64 {
            -c.0
        }
    }

    #[derive(Default)]
    struct Keep {
        found: Vec<(f64, f64)>,
        pending: Vec<Cell>,
    }
    impl Sink<Cell, (f64, f64)> for Keep {
        fn found(&mut self, f: (f64, f64)) -> ControlFlow<()> {
            self.found.push(f);
            ControlFlow::Continue(())
        }
        fn undecided(&mut self, c: Cell, why: Undecided) -> ControlFlow<()> {
            assert_eq!(why, Undecided::Pending);
            self.pending.push(c);
            ControlFlow::Continue(())
        }
    }

    fn roots_in(found: &[(f64, f64)]) -> usize {
        (0..=19).filter(|k| found.iter().any(|&(a, b)| a <= *k as f64 * std::f64::consts::PI / 20.0 && *k as f64 * std::f64::consts::PI / 20.0 <= b)).count()
    }

    #[test]
    fn every_store_finds_every_root() {
        for store in [Store::DepthFirst, Store::BreadthFirst, Store::BestFirst] {
            let mut keep = Keep::default();
            let (status, stats) = run(&mut Roots, (0.0, 3.0, 0), store, &Limits::default(), &AtomicBool::new(false), &mut keep);
            assert_eq!(status, Status::Finished);
            // kπ/20 ≤ 3 for k = 0..=19.
            assert_eq!(roots_in(&keep.found), 20, "{store:?}");
            assert_eq!(stats.found as usize, keep.found.len());
            assert_eq!(stats.processed, stats.found + stats.split + stats.discarded_total());
        }
    }

    #[test]
    fn best_first_takes_the_smallest_key_first() {
        // key = −a: the rightmost cell first, so the first root found is the largest.
        let mut keep = Keep::default();
        run(&mut Roots, (0.0, 3.0, 0), Store::BestFirst, &Limits::default(), &AtomicBool::new(false), &mut keep);
        assert!(keep.found[0].0 > 2.8, "{:?}", keep.found[0]);
    }

    #[test]
    fn levels_on_many_workers_report_what_one_worker_reports_in_the_same_order() {
        let serial = {
            let mut keep = Keep::default();
            run(&mut Roots, (0.0, 3.0, 0), Store::BreadthFirst, &Limits::default(), &AtomicBool::new(false), &mut keep);
            keep.found
        };
        for workers in [1, 2, 3] {
            let mut keep = Keep::default();
            let mut prunes = vec![Roots; workers];
            let (status, _) = run_by_level(&mut prunes, (0.0, 3.0, 0), &Limits::default(), &AtomicBool::new(false), &mut keep);
            assert_eq!(status, Status::Finished);
            assert_eq!(keep.found, serial, "{workers} workers");
        }
    }

    /// `run(peer)` on one thread per peer of a group of `size` processes played by threads.
    fn on_each_process<T: Send>(size: usize, run: impl Fn(&crate::kernel::search::share::tests::ThreadPeers) -> T + Sync) -> Vec<T> {
        let group = crate::kernel::search::share::tests::ThreadPeers::group(size);
        std::thread::scope(|s| {
            let handles: Vec<_> = group.iter().map(|p| s.spawn(|| run(p))).collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        })
    }

    #[test]
    fn processes_sharing_a_search_each_report_what_one_process_reports() {
        let serial = {
            let mut keep = Keep::default();
            run_by_level(&mut [Roots], (0.0, 3.0, 0), &Limits::default(), &AtomicBool::new(false), &mut keep);
            keep.found
        };
        for size in [2, 3] {
            let results = on_each_process(size, |p| {
                let mut keep = Keep::default();
                let (status, stats) = run_shared_with(Some(p), &mut [Roots, Roots], (0.0, 3.0, 0), &Limits::default(), &AtomicBool::new(false), &mut keep);
                (status, stats.processed, keep.found)
            });
            let processed = results[0].1;
            for (status, p, found) in results {
                assert_eq!((status, p), (Status::Finished, processed));
                assert_eq!(found, serial, "{size} processes");
            }
        }
        // A cell limit stops every process at the same cell, with the same pending cells.
        let limits = Limits { max_cells: 40, ..Limits::default() };
        let results = on_each_process(2, |p| {
            let mut keep = Keep::default();
            let (status, stats) = run_shared_with(Some(p), &mut [Roots], (0.0, 3.0, 0), &limits, &AtomicBool::new(false), &mut keep);
            (status, stats.processed, keep.found, keep.pending)
        });
        assert_eq!(results[0], results[1]);
        assert_eq!((results[0].0, results[0].1), (Status::Stopped(Limit::Boxes), 40));
    }

    #[test]
    fn a_limit_reports_pending_cells_that_still_hold_every_root() {
        let limits = Limits { max_cells: 40, ..Limits::default() };
        for workers in [0, 1, 2] {
            let mut keep = Keep::default();
            let (status, stats) = if workers == 0 {
                run(&mut Roots, (0.0, 3.0, 0), Store::DepthFirst, &limits, &AtomicBool::new(false), &mut keep)
            } else {
                run_by_level(&mut vec![Roots; workers], (0.0, 3.0, 0), &limits, &AtomicBool::new(false), &mut keep)
            };
            assert_eq!(status, Status::Stopped(Limit::Boxes));
            assert_eq!(stats.processed, 40);
            let mut all = keep.found.clone();
            all.extend(keep.pending.iter().map(|&(a, b, _)| (a, b)));
            assert_eq!(roots_in(&all), 20, "{workers} workers");
        }
    }

    #[test]
    fn memory_and_cancel_stop_a_run_with_everything_pending_reported() {
        let tiny = Limits { max_memory: 3 * std::mem::size_of::<Cell>(), ..Limits::default() };
        let mut keep = Keep::default();
        let (status, _) = run(&mut Roots, (0.0, 3.0, 0), Store::BreadthFirst, &tiny, &AtomicBool::new(false), &mut keep);
        assert_eq!(status, Status::Stopped(Limit::Memory));
        assert!(!keep.pending.is_empty());
        let mut keep = Keep::default();
        let (status, stats) = run_by_level(&mut [Roots, Roots], (0.0, 3.0, 0), &Limits::default(), &AtomicBool::new(true), &mut keep);
        assert_eq!((status, stats.processed, keep.pending.len()), (Status::Stopped(Limit::Cancelled), 0, 1));
    }
}
