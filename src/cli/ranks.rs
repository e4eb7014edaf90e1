//! MPI ranks: the only user of the `mpi` crate (feature `mpi`).
//!
//! Under `mpirun -np N linkspace COMMAND ...` every rank runs the same command on the same
//! input; the searches that run on the main thread are shared (`search::share_searches`): each
//! rank decides a share of every level, and every rank holds the whole result. Rank 0 alone
//! prints and writes; the others send stdout and stderr to /dev/null.

use anyhow::{anyhow, Result};
use linkspace::app::{share_searches, Peers};
use mpi::datatype::PartitionMut;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::CommunicatorCollectives;
use mpi::Count;
use std::cell::RefCell;

thread_local! {
    /// The world communicator, on the thread that joined: MPI is initialised there, and the
    /// kernel shares only searches run on that thread.
    static WORLD: RefCell<Option<SimpleCommunicator>> = const { RefCell::new(None) };
}

/// Keeps MPI initialised while it lives (dropping it finalises MPI).
pub struct Ranks {
    _universe: mpi::environment::Universe,
}

/// Joins the run's ranks when `mpirun` (or Slurm's PMI) started this process, and shares the
/// searches of this thread with them; `None` in a process started alone.
pub fn join() -> Result<Option<Ranks>> {
    let launched = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"].iter().any(|v| std::env::var_os(v).is_some());
    if !launched {
        return Ok(None);
    }
    let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Funneled).ok_or_else(|| anyhow!("MPI was initialised twice"))?;
    let world = universe.world();
    let rank = usize::try_from(world.rank()).unwrap_or(0);
    WORLD.with(|w| *w.borrow_mut() = Some(world));
    share_searches(Box::new(World));
    if rank != 0 {
        silence();
    }
    Ok(Some(Ranks { _universe: universe }))
}

/// Whether this process writes: rank 0, or a process alone.
pub fn writes() -> bool {
    linkspace::app::rank_and_size().0 == 0
}

/// Every rank's bytes, in rank order (a collective, on the thread that joined).
pub fn all_gather(mine: &[u8]) -> Vec<Vec<u8>> {
    World.all_gather(mine)
}

/// Points stdout and stderr at /dev/null: rank 0 speaks for the run.
fn silence() {
    use std::os::fd::AsRawFd;
    if let Ok(null) = std::fs::OpenOptions::new().write(true).open("/dev/null") {
        // SAFETY: dup2 on a valid open descriptor and the process's own 1 and 2; nothing
        // else holds a borrowed view of those descriptors' state.
        unsafe {
            libc::dup2(null.as_raw_fd(), 1);
            libc::dup2(null.as_raw_fd(), 2);
        }
    }
}

/// The world communicator as the kernel's `Peers`; used only on the thread that joined (the
/// kernel's rule), where `WORLD` is set.
struct World;

fn with_world<T>(f: impl FnOnce(&SimpleCommunicator) -> T) -> T {
    WORLD.with(|w| f(w.borrow().as_ref().expect("invariant: the kernel calls its peers on the thread that joined")))
}

impl Peers for World {
    fn rank(&self) -> usize {
        with_world(|w| usize::try_from(w.rank()).unwrap_or(0))
    }

    fn size(&self) -> usize {
        with_world(|w| usize::try_from(w.size()).unwrap_or(1))
    }

    fn all_gather(&self, mine: &[u8]) -> Vec<Vec<u8>> {
        with_world(|w| {
            let size = usize::try_from(w.size()).unwrap_or(1);
            let count = Count::try_from(mine.len()).expect("invariant: a level's message is under 2 GiB");
            let mut counts = vec![0 as Count; size];
            w.all_gather_into(&count, &mut counts[..]);
            let displs: Vec<Count> = counts.iter().scan(0, |at, &c| Some(std::mem::replace(at, *at + c))).collect();
            let total = counts.iter().map(|&c| c as usize).sum();
            let mut all = vec![0u8; total];
            {
                let mut partition = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
                w.all_gather_varcount_into(mine, &mut partition);
            }
            counts.iter().zip(&displs).map(|(&c, &d)| all[d as usize..(d + c) as usize].to_vec()).collect()
        })
    }
}
