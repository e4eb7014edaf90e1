//! One search shared by several processes: each decides a share of every level, and every
//! process receives every decision.
//!
//! The processes run the same program on the same input (MPI's model: `mpirun -np N linkspace
//! ...`), so each builds the same `Prune` and walks the same tree. The level-by-level driver
//! deals each level's cells out in chunks, round robin over the processes; each decides its
//! chunks on its own threads, the decisions travel as bytes (`Wire`) to every process, and
//! every process routes all of them in level order. So every process holds the whole result,
//! the same cells in the same order as a single process reports, and whatever follows the
//! search (post-processing, the next search) runs alike everywhere; one process writes.
//!
//! The kernel knows only `Peers` (rank, size, one collective: gather bytes from everyone); the
//! binary provides it over MPI. Only searches run on the thread that installed the peers are
//! shared: a search started inside a parallel map runs wholly in each process, since the
//! processes could not agree on which of them meets which collective first.

use super::{Limit, Reason, Step};
use crate::kernel::interval::{BoxSweep, Interval, IntervalBox};
use smallvec::SmallVec;
use std::sync::{Mutex, OnceLock};
use std::thread::ThreadId;

/// The processes that share this one's searches.
///
/// Every method but `rank` and `size` is a collective: all processes call it, in the same order.
pub trait Peers: Send + Sync {
    /// This process's place, 0 for the one that writes.
    fn rank(&self) -> usize;
    /// How many processes share the searches (at least 1).
    fn size(&self) -> usize;
    /// Every process's bytes, in rank order.
    fn all_gather(&self, mine: &[u8]) -> Vec<Vec<u8>>;
}

/// The installed peers, the thread that installed them, and their rank and size (read once:
/// only that thread may talk to them).
struct Installed {
    peers: Box<dyn Peers>,
    thread: ThreadId,
    rank: usize,
    size: usize,
}

static PEERS: OnceLock<Installed> = OnceLock::new();

/// Shares the searches this thread runs from now on with `peers` (once per process; a second
/// call is refused and returns false).
pub fn share_searches(peers: Box<dyn Peers>) -> bool {
    let (rank, size) = (peers.rank(), peers.size());
    PEERS.set(Installed { peers, thread: std::thread::current().id(), rank, size }).is_ok()
}

/// The peers a search started now shares its work with: `None` in a process alone, and on a
/// thread other than the one that installed them.
pub(crate) fn peers() -> Option<&'static dyn Peers> {
    let installed = PEERS.get()?;
    (installed.size > 1 && installed.thread == std::thread::current().id()).then_some(installed.peers.as_ref())
}

/// This process's rank and the number of processes (0 and 1 in a process alone), from any
/// thread.
pub fn rank_and_size() -> (usize, usize) {
    PEERS.get().map_or((0, 1), |i| (i.rank, i.size))
}

/// `f` of every item, in item order, on every process: each of the processes sharing this
/// thread's searches computes every `size`-th item (its rank's), on up to `threads` threads,
/// and every process receives every result. A process alone maps them all on its threads.
///
/// The work after a search (re-examining isolated boxes, labelling components, reading boxes
/// out) is shared this way, so that it shrinks with the ranks as the search does. `f` must be
/// a function of the item and of what every process holds alike; a result that reads a clock
/// (a deadline) differs between processes only in what the gathered vector then says alike.
pub(crate) fn map_shared<T: Sync, R: Send + Wire>(items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    map_shared_with(peers(), items, threads, f)
}

fn map_shared_with<T: Sync, R: Send + Wire>(peers: Option<&dyn Peers>, items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let Some(peers) = peers else { return super::map_parallel(items, threads, f) };
    let (rank, size) = (peers.rank(), peers.size());
    // Dealt round robin: neighbouring items (boxes of one cluster) cost alike.
    let mine: Vec<&T> = items.iter().skip(rank).step_by(size).collect();
    // On threads of their own even when there is one: a search `f` starts there runs wholly
    // in this process (`peers` is the installing thread's), never a collective the other
    // processes, mapping other items, would not join.
    let done = std::thread::scope(|s| s.spawn(|| super::map_parallel(&mine, threads, |item| f(item))).join().expect("invariant: parallel jobs do not panic"));
    let mut out = Vec::new();
    done.put(&mut out);
    drop(done);
    let mut theirs: Vec<std::vec::IntoIter<R>> = peers.all_gather(&out).iter().map(|bytes| Vec::<R>::take(&mut bytes.as_slice()).into_iter()).collect();
    (0..items.len()).map(|i| theirs[i % size].next().expect("invariant: every rank maps its share")).collect()
}

/// The connected components of `boxes` (as `interval::components`: the same labels), their
/// sweep shared like `map_shared`: slices of the sweep order on every process and thread.
pub(crate) fn components_shared(boxes: &[IntervalBox], threads: usize) -> (Vec<usize>, usize) {
    components_shared_with(peers(), boxes, threads)
}

fn components_shared_with(peers: Option<&dyn Peers>, boxes: &[IntervalBox], threads: usize) -> (Vec<usize>, usize) {
    let sweep = BoxSweep::new(boxes);
    let workers = threads.max(1) * peers.map_or(1, |p| p.size());
    // Below a few thousand boxes the sweep takes less than a gather.
    if workers == 1 || boxes.len() < 4096 {
        return sweep.components([sweep.slice(0, 1).0]);
    }
    // A few slices per worker even out the slices' costs (boxes crowd where a curve runs
    // along the sweep's axis).
    let parts: Vec<usize> = (0..4 * workers).collect();
    let pairs = map_shared_with(peers, &parts, threads, |&k| sweep.slice(k, parts.len()).0);
    sweep.components(pairs)
}

/// A value as bytes, for another process running the same program.
///
/// `take` reads back what `put` wrote; the bytes never leave the processes of one run, so a
/// malformed message is a broken invariant, not input.
pub trait Wire: Sized {
    /// Appends the value.
    fn put(&self, out: &mut Vec<u8>);
    /// Reads a value from the front of `input`, advancing it.
    fn take(input: &mut &[u8]) -> Self;
}

fn take_bytes<const N: usize>(input: &mut &[u8]) -> [u8; N] {
    let (head, rest) = input.split_first_chunk::<N>().expect("invariant: peers send what they read");
    *input = rest;
    *head
}

macro_rules! wire_number {
    ($($t:ty),*) => {$(
        impl Wire for $t {
            fn put(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            fn take(input: &mut &[u8]) -> Self {
                <$t>::from_le_bytes(take_bytes(input))
            }
        }
    )*};
}
wire_number!(u8, u32, u64, f64);

impl Wire for usize {
    fn put(&self, out: &mut Vec<u8>) {
        (*self as u64).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        usize::try_from(u64::take(input)).expect("invariant: peers share one word size")
    }
}

impl Wire for bool {
    fn put(&self, out: &mut Vec<u8>) {
        u8::from(*self).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        u8::take(input) != 0
    }
}

impl Wire for Interval {
    fn put(&self, out: &mut Vec<u8>) {
        // The empty interval has no bounds to send: NaN marks it.
        let (a, b) = if self.is_empty() { (f64::NAN, f64::NAN) } else { (self.inf(), self.sup()) };
        a.put(out);
        b.put(out);
    }
    fn take(input: &mut &[u8]) -> Self {
        let (a, b) = (f64::take(input), f64::take(input));
        if a.is_nan() {
            Interval::EMPTY
        } else {
            inari::interval!(a, b).expect("invariant: peers send valid bounds")
        }
    }
}

impl Wire for IntervalBox {
    fn put(&self, out: &mut Vec<u8>) {
        self.dims.put(out);
        self.level.put(out);
    }
    fn take(input: &mut &[u8]) -> Self {
        IntervalBox { dims: Wire::take(input), level: Wire::take(input) }
    }
}

/// Text as its length and its bytes (`String` and `&'static str`).
fn put_text(text: &str, out: &mut Vec<u8>) {
    text.len().put(out);
    out.extend_from_slice(text.as_bytes());
}

fn take_text<'a>(input: &mut &'a [u8]) -> &'a str {
    let n = usize::take(input);
    let (s, rest) = input.split_at(n);
    *input = rest;
    std::str::from_utf8(s).expect("invariant: peers send UTF-8")
}

impl Wire for String {
    fn put(&self, out: &mut Vec<u8>) {
        put_text(self, out)
    }
    fn take(input: &mut &[u8]) -> Self {
        take_text(input).to_owned()
    }
}

impl<K: Wire + Ord, V: Wire> Wire for std::collections::BTreeMap<K, V> {
    fn put(&self, out: &mut Vec<u8>) {
        self.len().put(out);
        for (k, v) in self {
            k.put(out);
            v.put(out);
        }
    }
    fn take(input: &mut &[u8]) -> Self {
        let n = usize::take(input);
        (0..n).map(|_| (K::take(input), V::take(input))).collect()
    }
}

/// The limits in the order processes agree on them (`agree`), which is also their code.
const LIMITS: [Limit; 5] = [Limit::Cancelled, Limit::Time, Limit::Memory, Limit::Boxes, Limit::Sink];

impl Wire for Limit {
    fn put(&self, out: &mut Vec<u8>) {
        (LIMITS.iter().position(|l| l == self).expect("invariant: every limit is listed") as u8).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        LIMITS[usize::from(u8::take(input))]
    }
}

impl<T: Wire> Wire for Vec<T> {
    fn put(&self, out: &mut Vec<u8>) {
        self.len().put(out);
        for x in self {
            x.put(out);
        }
    }
    fn take(input: &mut &[u8]) -> Self {
        let n = usize::take(input);
        (0..n).map(|_| T::take(input)).collect()
    }
}

impl<T: Wire, const N: usize> Wire for [T; N] {
    fn put(&self, out: &mut Vec<u8>) {
        for x in self {
            x.put(out);
        }
    }
    fn take(input: &mut &[u8]) -> Self {
        std::array::from_fn(|_| T::take(input))
    }
}

impl<T: Wire> Wire for Option<T> {
    fn put(&self, out: &mut Vec<u8>) {
        self.is_some().put(out);
        if let Some(x) = self {
            x.put(out);
        }
    }
    fn take(input: &mut &[u8]) -> Self {
        bool::take(input).then(|| T::take(input))
    }
}

impl<A: Wire, B: Wire> Wire for (A, B) {
    fn put(&self, out: &mut Vec<u8>) {
        self.0.put(out);
        self.1.put(out);
    }
    fn take(input: &mut &[u8]) -> Self {
        (A::take(input), B::take(input))
    }
}

impl<A: Wire, B: Wire, C: Wire> Wire for (A, B, C) {
    fn put(&self, out: &mut Vec<u8>) {
        self.0.put(out);
        self.1.put(out);
        self.2.put(out);
    }
    fn take(input: &mut &[u8]) -> Self {
        (A::take(input), B::take(input), C::take(input))
    }
}

impl Wire for &'static str {
    fn put(&self, out: &mut Vec<u8>) {
        put_text(self, out)
    }
    fn take(input: &mut &[u8]) -> Self {
        intern(take_text(input))
    }
}

/// The one `&'static str` with this text: reasons travel as text and come back as the static
/// names the kernel counts by. They are a search's closed set of names, so the table stays
/// small.
fn intern(s: &str) -> &'static str {
    static NAMES: Mutex<Vec<&'static str>> = Mutex::new(Vec::new());
    let mut names = NAMES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(&n) = names.iter().find(|&&n| n == s) {
        return n;
    }
    let n: &'static str = Box::leak(s.to_owned().into_boxed_str());
    names.push(n);
    n
}

/// A discard reason that came from another process: its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Named(pub &'static str);

impl Reason for Named {
    fn name(self) -> &'static str {
        self.0
    }
}

/// A decision as the level driver keeps it: the cell's level, its children's bytes, the step.
pub(crate) type Decision<C, F, R> = (u32, usize, Step<C, F, R>);

pub(crate) fn put_decision<C: Wire, F: Wire, R: Reason>((level, bytes, step): &Decision<C, F, R>, out: &mut Vec<u8>) {
    level.put(out);
    bytes.put(out);
    match step {
        Step::Discard(r) => {
            0u8.put(out);
            r.name().put(out);
        }
        Step::Found(f) => {
            1u8.put(out);
            f.put(out);
        }
        Step::Undecided(c, why) => {
            2u8.put(out);
            c.put(out);
            why.put(out);
        }
        Step::Split(children) => {
            3u8.put(out);
            children.len().put(out);
            for c in children {
                c.put(out);
            }
        }
    }
}

pub(crate) fn take_decision<C: Wire, F: Wire>(input: &mut &[u8]) -> Decision<C, F, Named> {
    let level = u32::take(input);
    let bytes = usize::take(input);
    let step = match u8::take(input) {
        0 => Step::Discard(Named(Wire::take(input))),
        1 => Step::Found(F::take(input)),
        2 => Step::Undecided(C::take(input), Wire::take(input)),
        3 => {
            let n = usize::take(input);
            Step::Split((0..n).map(|_| C::take(input)).collect::<SmallVec<[C; 4]>>())
        }
        tag => unreachable!("invariant: peers send known steps (got {tag})"),
    };
    (level, bytes, step)
}

/// The limit the processes stop on together: the first they name, in `Limit` order, when any
/// of them names one (each reads its own clock and cancel flag).
pub(crate) fn agree(peers: &dyn Peers, mine: Option<Limit>) -> Option<Limit> {
    let code = mine.map_or(0u8, |l| 1 + LIMITS.iter().position(|&o| o == l).expect("invariant: every limit is listed") as u8);
    peers.all_gather(&[code]).iter().filter_map(|b| b.first().copied()).filter(|&c| c > 0).min().map(|c| LIMITS[usize::from(c - 1)])
}

/// The sum over the processes of each one's `values` (all of one length).
pub(crate) fn sum(peers: &dyn Peers, values: &[f64]) -> Vec<f64> {
    let mut mine = Vec::new();
    values.to_vec().put(&mut mine);
    let mut total = vec![0.0; values.len()];
    for bytes in peers.all_gather(&mine) {
        let theirs = Vec::<f64>::take(&mut bytes.as_slice());
        for (t, v) in total.iter_mut().zip(theirs) {
            *t += v;
        }
    }
    total
}

/// The sum over the processes sharing this thread's searches of each one's `values` (the
/// values themselves in a process alone): counters a search keeps beside the kernel's.
pub(crate) fn total(values: &[f64]) -> Vec<f64> {
    match peers() {
        Some(p) => sum(p, values),
        None => values.to_vec(),
    }
}

/// Per index, the largest of the processes' `values` (of any lengths).
pub(crate) fn widest(peers: &dyn Peers, values: &[f64]) -> Vec<f64> {
    let mut mine = Vec::new();
    values.to_vec().put(&mut mine);
    let mut out: Vec<f64> = Vec::new();
    for bytes in peers.all_gather(&mine) {
        let theirs = Vec::<f64>::take(&mut bytes.as_slice());
        if out.len() < theirs.len() {
            out.resize(theirs.len(), 0.0);
        }
        for (o, v) in out.iter_mut().zip(theirs) {
            *o = o.max(v);
        }
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::sync::{Arc, Barrier};

    /// `n` processes played by threads: a gather is a barrier around a shared table.
    pub(crate) struct ThreadPeers {
        pub rank: usize,
        table: Arc<(Mutex<Vec<Vec<u8>>>, Barrier)>,
    }

    impl ThreadPeers {
        pub(crate) fn group(n: usize) -> Vec<ThreadPeers> {
            let table = Arc::new((Mutex::new(vec![Vec::new(); n]), Barrier::new(n)));
            (0..n).map(|rank| ThreadPeers { rank, table: table.clone() }).collect()
        }
    }

    impl Peers for ThreadPeers {
        fn rank(&self) -> usize {
            self.rank
        }
        fn size(&self) -> usize {
            self.table.0.lock().unwrap().len()
        }
        fn all_gather(&self, mine: &[u8]) -> Vec<Vec<u8>> {
            let (slots, barrier) = &*self.table;
            slots.lock().unwrap()[self.rank] = mine.to_vec();
            barrier.wait();
            let all = slots.lock().unwrap().clone();
            barrier.wait();
            all
        }
    }

    #[test]
    fn values_come_back_as_they_were_sent() {
        let b = IntervalBox { dims: vec![inari::interval!(-1.0, 0.5).unwrap(), Interval::EMPTY, inari::interval!(3.0, 3.0).unwrap()], level: 7 };
        let step: Step<IntervalBox, (u8, IntervalBox), Named> = Step::Split([b.clone(), b.clone()].into_iter().collect());
        let mut out = Vec::new();
        put_decision(&(3, 99, step), &mut out);
        put_decision(&(4, 0, Step::<IntervalBox, (u8, IntervalBox), Named>::Undecided(b.clone(), "precision")), &mut out);
        put_decision(&(5, 0, Step::<IntervalBox, (u8, IntervalBox), Named>::Discard(Named("empty"))), &mut out);
        let mut input = out.as_slice();
        let (l, bytes, s) = take_decision::<IntervalBox, (u8, IntervalBox)>(&mut input);
        assert_eq!((l, bytes), (3, 99));
        let Step::Split(children) = s else { panic!("a split") };
        assert_eq!(children.len(), 2);
        assert_eq!(children[0].level, 7);
        assert!(children[0].dims[1].is_empty());
        assert_eq!(children[0].dims[0], b.dims[0]);
        let (_, _, s) = take_decision::<IntervalBox, (u8, IntervalBox)>(&mut input);
        assert!(matches!(s, Step::Undecided(_, "precision")));
        let (_, _, s) = take_decision::<IntervalBox, (u8, IntervalBox)>(&mut input);
        assert!(matches!(s, Step::Discard(Named("empty"))));
        assert!(input.is_empty());
    }

    #[test]
    fn shared_maps_and_components_are_the_one_process_ones() {
        // Boxes along a broken circle: four arcs, a few lone boxes, and boxes crowding where
        // the arcs run along the sweep's axis.
        let mut boxes = Vec::new();
        for k in 0..6000 {
            let t = k as f64 * std::f64::consts::TAU / 6000.0;
            if k % 1500 < 1490 {
                let (c, s) = (t.cos(), t.sin());
                boxes.push(IntervalBox { dims: vec![inari::interval!(c - 1e-3, c + 1e-3).unwrap(), inari::interval!(s - 1e-3, s + 1e-3).unwrap()], level: 0 });
            }
        }
        for k in 0..7 {
            let x = 3.0 + k as f64;
            boxes.push(IntervalBox { dims: vec![inari::interval!(x, x + 0.1).unwrap(), inari::interval!(0.0, 0.1).unwrap()], level: 0 });
        }
        let alone = crate::kernel::interval::components(&boxes);
        assert_eq!(alone.1, 4 + 7);
        for (ranks, threads) in [(1, 1), (1, 2), (2, 1), (3, 2)] {
            let group = ThreadPeers::group(ranks);
            let got: Vec<_> = std::thread::scope(|s| {
                let handles: Vec<_> = group
                    .iter()
                    .map(|p| {
                        let boxes = &boxes;
                        s.spawn(move || {
                            let peers: Option<&dyn Peers> = if ranks > 1 { Some(p) } else { None };
                            let squares = map_shared_with(peers, &(0..1001usize).collect::<Vec<_>>(), threads, |&i| (i * i, p.rank));
                            (squares, components_shared_with(peers, boxes, threads))
                        })
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().unwrap()).collect()
            });
            for (squares, components) in got {
                assert_eq!(squares.iter().map(|&(v, _)| v).collect::<Vec<_>>(), (0..1001usize).map(|i| i * i).collect::<Vec<_>>());
                // Each item was mapped by the rank it was dealt to: the work was shared.
                assert!(squares.iter().enumerate().all(|(i, &(_, by))| by == i % ranks), "{ranks} ranks");
                assert!(components == alone, "{ranks} ranks of {threads} threads label the components as one process");
            }
        }
    }

    #[test]
    fn processes_agree_on_the_first_limit_any_of_them_names() {
        let group = ThreadPeers::group(3);
        let mine = [None, Some(Limit::Boxes), Some(Limit::Time)];
        let agreed: Vec<_> = std::thread::scope(|s| {
            let handles: Vec<_> = group.iter().zip(mine).map(|(p, m)| s.spawn(move || (agree(p, m), agree(p, None), sum(p, &[p.rank as f64, 1.0])))).collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for a in agreed {
            assert_eq!(a, (Some(Limit::Time), None, vec![3.0, 3.0]));
        }
    }
}
