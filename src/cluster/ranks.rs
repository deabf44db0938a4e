//! The ranks of an MPI job as a device inside a host sees them (the
//! device's `caveray.mpi`): a frame's collectives (the regions' exchange,
//! direct-send, the gather of the bands) are made by the render thread,
//! one frame at a time. Built without the `mpi` feature there is no way to
//! make one, and every call on one is the single rank's.

use std::sync::{Mutex, MutexGuard};

pub struct Ranks {
    #[cfg(feature = "mpi")]
    world: super::mpi::World,
}

/// One frame's collectives at a time in this process, whichever device
/// makes them: MPI_THREAD_SERIALIZED allows no more.
static TURN: Mutex<()> = Mutex::new(());

impl Ranks {
    /// The job this process was started in, on MPI_COMM_WORLD: the host's
    /// MPI where it initialised it, else initialised here.
    #[cfg(feature = "mpi")]
    pub fn world() -> Result<Self, String> {
        Ok(Self {
            world: super::mpi::World::share()?,
        })
    }

    pub fn rank(&self) -> usize {
        #[cfg(feature = "mpi")]
        return self.world.rank();
        #[cfg(not(feature = "mpi"))]
        0
    }

    pub fn size(&self) -> usize {
        #[cfg(feature = "mpi")]
        return self.world.size();
        #[cfg(not(feature = "mpi"))]
        1
    }

    /// Held while one frame makes its collectives, so that two render
    /// threads of this process never interleave theirs. (Every rank must
    /// render its data-parallel frames in the same order.)
    pub fn turn(&self) -> MutexGuard<'_, ()> {
        TURN.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Sends `to[j]` to rank j; returns what each rank sent this one.
    pub fn exchange(&self, to: &[Vec<u8>]) -> Result<Vec<Vec<u8>>, String> {
        #[cfg(feature = "mpi")]
        return self.world.exchange(to);
        #[cfg(not(feature = "mpi"))]
        Ok(to.to_vec())
    }

    /// Every rank's `bytes`, on every rank, in rank order.
    pub fn all_gather(&self, bytes: &[u8]) -> Result<Vec<Vec<u8>>, String> {
        #[cfg(feature = "mpi")]
        return self.world.all_gather(bytes);
        #[cfg(not(feature = "mpi"))]
        Ok(vec![bytes.to_vec()])
    }
}
