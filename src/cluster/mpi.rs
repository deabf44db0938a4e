//! The few MPI calls a CAVE cluster needs (init, rank and size, barrier,
//! gather, and the all-to-all of direct-send compositing), through the
//! bindings rsmpi's `mpi-sys` generates at build time for the MPI found
//! on the machine (its `mpicc`, or `MPICC`): Open MPI, MPICH and MPICH's
//! derivatives alike, whose handles differ (pointers in one, integers in
//! the other) and which its `RSMPI_*` constants hide. The calls are made
//! on raw handles rather than through rsmpi's safe layer because a device
//! inside a host must work on a duplicate of a world the host may have
//! initialised, and must never finalise the host's. Errors abort the
//! job, as MPI's default handler does; where a rank refuses a collective
//! (a size past MPI's int counts) every rank learns of it first, so that
//! none is left waiting.

use std::ffi::c_int;

use mpi::ffi::{
    MPI_Abort, MPI_Allgather, MPI_Allgatherv, MPI_Alltoall, MPI_Alltoallv, MPI_Barrier, MPI_Comm,
    MPI_Comm_dup, MPI_Comm_rank, MPI_Comm_size, MPI_Datatype, MPI_Finalize, MPI_Finalized,
    MPI_Gather, MPI_Gatherv, MPI_Init, MPI_Init_thread, MPI_Initialized, MPI_Query_thread,
};

/// MPI_COMM_WORLD.
fn world() -> MPI_Comm {
    // SAFETY: a constant mpi-sys's C shim sets once, read only.
    unsafe { mpi::ffi::RSMPI_COMM_WORLD }
}

/// A byte, as MPI counts them.
fn byte() -> MPI_Datatype {
    // SAFETY: likewise.
    unsafe { mpi::ffi::RSMPI_UINT8_T }
}

fn check(what: &str, code: c_int) -> Result<(), String> {
    if code == 0 {
        Ok(())
    } else {
        Err(format!("{what} failed (MPI error {code})"))
    }
}

/// MPI_THREAD_SERIALIZED: calls from any thread, one at a time.
const THREAD_SERIALIZED: c_int = mpi::ffi::MPI_THREAD_SERIALIZED as c_int;

/// This process's place in a communicator of the job: MPI_COMM_WORLD for
/// the tool, a duplicate of it for a device inside a host (so that its
/// collectives never meet the host's).
pub struct World {
    rank: usize,
    size: usize,
    comm: MPI_Comm,
}

// SAFETY: the communicator is a handle MPI lets any thread use; callers
// make one call at a time (cluster::Ranks' turn), as
// MPI_THREAD_SERIALIZED asks.
unsafe impl Send for World {}
unsafe impl Sync for World {}

impl World {
    /// Joins the MPI job as its program: once per process, ended by
    /// [`World::end`].
    pub fn join() -> Result<Self, String> {
        let mut started = 0;
        // SAFETY: MPI's own initialisation queries, with valid pointers;
        // null argc/argv are allowed since MPI-2.
        unsafe {
            check("MPI_Initialized", MPI_Initialized(&mut started))?;
            if started != 0 {
                return Err("MPI was initialised already".into());
            }
            check(
                "MPI_Init",
                MPI_Init(std::ptr::null_mut(), std::ptr::null_mut()),
            )?;
        }
        Self::place(world())
    }

    /// Joins the MPI job from a library inside a host, on a duplicate of
    /// MPI_COMM_WORLD: with the host's MPI where it initialised it (left
    /// to the host to finalise; it must allow calls from other threads,
    /// MPI_THREAD_SERIALIZED at least), else initialised here for calls
    /// from one thread at a time (a render thread), and finalised at exit
    /// (or when the library is unloaded).
    pub fn share() -> Result<Self, String> {
        let (mut started, mut ended) = (0, 0);
        // SAFETY: MPI's initialisation queries, with valid pointers.
        unsafe {
            check("MPI_Initialized", MPI_Initialized(&mut started))?;
            check("MPI_Finalized", MPI_Finalized(&mut ended))?;
        }
        if ended != 0 {
            return Err("MPI was finalised already in this process".into());
        }
        let low = |provided: c_int| {
            format!(
                "this process's MPI provides thread level {provided}, below MPI_THREAD_SERIALIZED ({THREAD_SERIALIZED}), \
                 which rendering threads need: initialise it with MPI_Init_thread"
            )
        };
        if started != 0 {
            let mut provided = 0;
            // SAFETY: a query with a valid pointer.
            check("MPI_Query_thread", unsafe {
                MPI_Query_thread(&mut provided)
            })?;
            if provided < THREAD_SERIALIZED {
                return Err(low(provided));
            }
        } else {
            let mut provided = 0;
            // SAFETY: null argc/argv are allowed since MPI-2.
            check("MPI_Init_thread", unsafe {
                MPI_Init_thread(
                    std::ptr::null_mut(),
                    std::ptr::null_mut(),
                    THREAD_SERIALIZED,
                    &mut provided,
                )
            })?;
            if provided < THREAD_SERIALIZED {
                return Err(low(provided));
            }
            extern "C" fn finalise_at_exit() {
                let mut ended = 0;
                // SAFETY: at exit, after every call of this process.
                unsafe {
                    if MPI_Finalized(&mut ended) == 0 && ended == 0 {
                        MPI_Finalize();
                    }
                }
            }
            // SAFETY: registering a plain function to run at exit.
            unsafe {
                libc::atexit(finalise_at_exit);
            }
        }
        let mut comm = std::mem::MaybeUninit::<MPI_Comm>::uninit();
        // SAFETY: a collective on the world communicator, every rank's
        // device joining alike; MPI writes the duplicate's handle.
        check("MPI_Comm_dup", unsafe {
            MPI_Comm_dup(world(), comm.as_mut_ptr())
        })?;
        // SAFETY: MPI_Comm_dup succeeded, so it wrote the handle.
        Self::place(unsafe { comm.assume_init() })
    }

    fn place(comm: MPI_Comm) -> Result<Self, String> {
        let (mut rank, mut size) = (0, 0);
        // SAFETY: a communicator valid after MPI_Init.
        unsafe {
            check("MPI_Comm_rank", MPI_Comm_rank(comm, &mut rank))?;
            check("MPI_Comm_size", MPI_Comm_size(comm, &mut size))?;
        }
        Ok(Self {
            rank: rank as usize,
            size: size as usize,
            comm,
        })
    }

    /// Ends the program's part in the job: MPI is finalised where the
    /// program succeeded; where it failed, the whole job is aborted, as a
    /// rank that stopped between collectives leaves the others waiting.
    pub fn end(&self, succeeded: bool) {
        // SAFETY: once, after every call of this process.
        unsafe {
            if succeeded {
                MPI_Finalize();
            } else {
                MPI_Abort(self.comm, 1);
            }
        }
    }

    /// Whether every rank says `ok`: so that a refusal on one rank is every
    /// rank's.
    fn agree(&self, ok: bool) -> Result<bool, String> {
        Ok(self
            .all_gather_alike(&[u8::from(ok)])?
            .iter()
            .all(|&b| b == 1))
    }

    /// Every rank's `mine`, as long on every rank, one after another.
    fn all_gather_alike(&self, mine: &[u8]) -> Result<Vec<u8>, String> {
        let n = c_int::try_from(mine.len()).map_err(|_| "a piece past MPI's int counts")?;
        let mut all = vec![0u8; mine.len() * self.size];
        // SAFETY: `mine.len()` bytes from each rank into `all`, which holds
        // that many per rank.
        check("MPI_Allgather", unsafe {
            MPI_Allgather(
                mine.as_ptr().cast(),
                n,
                byte(),
                all.as_mut_ptr().cast(),
                n,
                byte(),
                self.comm,
            )
        })?;
        Ok(all)
    }

    pub fn rank(&self) -> usize {
        self.rank
    }

    pub fn size(&self) -> usize {
        self.size
    }

    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    /// Waits until every rank is here.
    pub fn barrier(&self) -> Result<(), String> {
        // SAFETY: a collective on the world communicator.
        check("MPI_Barrier", unsafe { MPI_Barrier(self.comm) })
    }

    /// Every rank's `bytes`, on rank 0 in rank order (empty elsewhere).
    /// Refused where the total would pass what MPI's int counts hold.
    pub fn gather(&self, bytes: &[u8]) -> Result<Vec<Vec<u8>>, String> {
        let len = (bytes.len() as u64).to_le_bytes();
        let mut lens = vec![0u8; if self.is_root() { 8 * self.size } else { 0 }];
        // SAFETY: 8 bytes from each rank into `lens` (8 per rank on the
        // root, which alone reads the receive buffer).
        check("MPI_Gather", unsafe {
            MPI_Gather(
                len.as_ptr().cast(),
                8,
                byte(),
                lens.as_mut_ptr().cast(),
                8,
                byte(),
                0,
                self.comm,
            )
        })?;
        let laid = layout(&lengths(&lens), "gathering on rank 0").and_then(|l| {
            c_int::try_from(bytes.len())
                .map(|_| l)
                .map_err(|_| format!("gathering {} bytes passes MPI's int counts", bytes.len()))
        });
        if !self.agree(laid.is_ok())? {
            return Err(laid.err().unwrap_or_else(|| {
                "another rank's share passes MPI's int counts: nothing is gathered".into()
            }));
        }
        let (counts, at) = laid?;
        let mut all = vec![0u8; total(&counts)];
        // SAFETY: each rank sends its bytes; the root receives them at
        // the displacements, within `all`, which holds their sum.
        check("MPI_Gatherv", unsafe {
            MPI_Gatherv(
                bytes.as_ptr().cast(),
                bytes.len() as c_int,
                byte(),
                all.as_mut_ptr().cast(),
                counts.as_ptr(),
                at.as_ptr(),
                byte(),
                0,
                self.comm,
            )
        })?;
        Ok(pieces(&all, &counts, &at))
    }

    /// Every rank sends `to[j]` to rank j and gets back, in rank order,
    /// what each rank sent it (direct-send). Refused where a rank would
    /// send or receive more than MPI's int counts hold.
    pub fn exchange(&self, to: &[Vec<u8>]) -> Result<Vec<Vec<u8>>, String> {
        if to.len() != self.size {
            return Err(format!(
                "an exchange needs a message for each of {} ranks, got {}",
                self.size,
                to.len()
            ));
        }
        let lens: Vec<u8> = to
            .iter()
            .flat_map(|m| (m.len() as u64).to_le_bytes())
            .collect();
        let mut got = vec![0u8; 8 * self.size];
        // SAFETY: 8 bytes to and from each rank, within both buffers.
        check("MPI_Alltoall", unsafe {
            MPI_Alltoall(
                lens.as_ptr().cast(),
                8,
                byte(),
                got.as_mut_ptr().cast(),
                8,
                byte(),
                self.comm,
            )
        })?;
        let laid = layout(&lengths(&lens), "an exchange")
            .and_then(|send| layout(&lengths(&got), "an exchange").map(|recv| (send, recv)));
        if !self.agree(laid.is_ok())? {
            return Err(laid.err().unwrap_or_else(|| {
                "another rank's exchange passes MPI's int counts: nothing is sent".into()
            }));
        }
        let ((send_counts, send_at), (recv_counts, recv_at)) = laid?;
        let send: Vec<u8> = to.concat();
        let mut recv = vec![0u8; total(&recv_counts)];
        // SAFETY: the counts and displacements lie within `send` and
        // `recv`, which hold their sums; every rank's counts agree with the
        // lengths exchanged above.
        check("MPI_Alltoallv", unsafe {
            MPI_Alltoallv(
                send.as_ptr().cast(),
                send_counts.as_ptr(),
                send_at.as_ptr(),
                byte(),
                recv.as_mut_ptr().cast(),
                recv_counts.as_ptr(),
                recv_at.as_ptr(),
                byte(),
                self.comm,
            )
        })?;
        Ok(pieces(&recv, &recv_counts, &recv_at))
    }

    /// Every rank's `bytes`, on every rank in rank order.
    pub fn all_gather(&self, bytes: &[u8]) -> Result<Vec<Vec<u8>>, String> {
        let lens = self.all_gather_alike(&(bytes.len() as u64).to_le_bytes())?;
        let (counts, at) = layout(&lengths(&lens), "gathering on every rank")?;
        let mut all = vec![0u8; total(&counts)];
        // SAFETY: each rank's bytes land at its displacement within `all`,
        // which holds their sum; every rank agrees on the counts above.
        check("MPI_Allgatherv", unsafe {
            MPI_Allgatherv(
                bytes.as_ptr().cast(),
                bytes.len() as c_int,
                byte(),
                all.as_mut_ptr().cast(),
                counts.as_ptr(),
                at.as_ptr(),
                byte(),
                self.comm,
            )
        })?;
        Ok(pieces(&all, &counts, &at))
    }
}

/// The byte counts, 8 little-endian bytes each, that ranks told each other.
fn lengths(bytes: &[u8]) -> Vec<u64> {
    bytes
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect()
}

/// MPI's counts and displacements for pieces `lens` long, one after
/// another; refused where their total passes its int counts.
fn layout(lens: &[u64], what: &str) -> Result<(Vec<c_int>, Vec<c_int>), String> {
    let sum: u64 = lens.iter().sum();
    if sum > c_int::MAX as u64 {
        return Err(format!("{what} of {sum} bytes passes MPI's int counts"));
    }
    let counts: Vec<c_int> = lens.iter().map(|&n| n as c_int).collect();
    let mut at = Vec::with_capacity(counts.len());
    let mut next = 0;
    for &n in &counts {
        at.push(next);
        next += n;
    }
    Ok((counts, at))
}

fn total(counts: &[c_int]) -> usize {
    counts.iter().map(|&n| n as usize).sum()
}

/// The pieces at `at`, `counts` long, of what arrived.
fn pieces(all: &[u8], counts: &[c_int], at: &[c_int]) -> Vec<Vec<u8>> {
    counts
        .iter()
        .zip(at)
        .map(|(&n, &at)| all[at as usize..(at + n) as usize].to_vec())
        .collect()
}
