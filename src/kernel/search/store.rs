//! The order in which pending cells are taken (ibex's `CellBuffer`).

use std::cmp::Ordering;
use std::collections::{BinaryHeap, VecDeque};

/// How the serial driver orders pending cells.
// The orders' usual names (ibex's buffers, textbooks), though each ends in `First`.
#[allow(clippy::enum_variant_names)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Store {
    /// A stack: the first child of a split is explored first (small memory, deterministic).
    #[default]
    DepthFirst,
    /// A queue: level by level, children in order (what `run_by_level` does on many threads).
    BreadthFirst,
    /// A heap on `Prune::key`: the smallest key first, ties in insertion order.
    BestFirst,
}

/// A cell with its best-first key and insertion number (for a deterministic tie-break).
pub(super) struct Keyed<C> {
    key: f64,
    seq: u64,
    cell: C,
}

impl<C> PartialEq for Keyed<C> {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl<C> Eq for Keyed<C> {}
impl<C> PartialOrd for Keyed<C> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl<C> Ord for Keyed<C> {
    /// Reversed, so that `BinaryHeap` (a max-heap) pops the smallest key, then the oldest cell.
    fn cmp(&self, other: &Self) -> Ordering {
        other.key.total_cmp(&self.key).then(other.seq.cmp(&self.seq))
    }
}

/// The pending cells of a serial run.
pub(super) enum Pool<C> {
    Stack(Vec<C>),
    Queue(VecDeque<C>),
    Heap(BinaryHeap<Keyed<C>>, u64),
}

impl<C> Pool<C> {
    pub(super) fn new(store: Store) -> Self {
        match store {
            Store::DepthFirst => Pool::Stack(Vec::new()),
            Store::BreadthFirst => Pool::Queue(VecDeque::new()),
            Store::BestFirst => Pool::Heap(BinaryHeap::new(), 0),
        }
    }

    pub(super) fn len(&self) -> usize {
        match self {
            Pool::Stack(v) => v.len(),
            Pool::Queue(q) => q.len(),
            Pool::Heap(h, _) => h.len(),
        }
    }

    pub(super) fn pop(&mut self) -> Option<C> {
        match self {
            Pool::Stack(v) => v.pop(),
            Pool::Queue(q) => q.pop_front(),
            Pool::Heap(h, _) => h.pop().map(|k| k.cell),
        }
    }

    /// Puts back a cell just popped, so that it is the next one taken.
    pub(super) fn restore(&mut self, cell: C, key: f64) {
        match self {
            Pool::Stack(v) => v.push(cell),
            Pool::Queue(q) => q.push_front(cell),
            Pool::Heap(..) => self.push_one(cell, key),
        }
    }

    /// Adds the children of a split so that they are explored in their given order.
    pub(super) fn push_children(&mut self, children: impl DoubleEndedIterator<Item = (C, f64)>) {
        match self {
            // Pushed last, popped first: the first child is explored first.
            Pool::Stack(v) => v.extend(children.rev().map(|(c, _)| c)),
            Pool::Queue(q) => q.extend(children.map(|(c, _)| c)),
            Pool::Heap(..) => children.for_each(|(c, k)| self.push_one(c, k)),
        }
    }

    fn push_one(&mut self, cell: C, key: f64) {
        if let Pool::Heap(h, seq) = self {
            *seq += 1;
            h.push(Keyed { key, seq: *seq, cell });
        }
    }

    /// Empties the pool in the order the cells would have been taken.
    pub(super) fn drain(&mut self) -> Vec<C> {
        let mut out = Vec::with_capacity(self.len());
        while let Some(c) = self.pop() {
            out.push(c);
        }
        out
    }
}
