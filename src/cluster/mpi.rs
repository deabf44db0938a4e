//! The few MPI calls a CAVE cluster needs (init, rank and size, barrier,
//! gather, and the all-to-all of direct-send compositing), declared by hand against Open MPI's C ABI (Debian's
//! `libopenmpi-dev`): there its handles are the addresses of its
//! predefined objects (`MPI_COMM_WORLD` is `&ompi_mpi_comm_world`).
//! Errors abort the job, as MPI's default handler does.

use std::ffi::{c_char, c_int, c_void};
use std::ptr::addr_of_mut;

/// One of Open MPI's predefined objects, used only by address.
#[repr(C)]
struct Predefined {
    _private: [u8; 0],
}

#[link(name = "mpi")]
extern "C" {
    static mut ompi_mpi_comm_world: Predefined;
    static mut ompi_mpi_byte: Predefined;
    fn MPI_Initialized(flag: *mut c_int) -> c_int;
    fn MPI_Init(argc: *mut c_int, argv: *mut *mut *mut c_char) -> c_int;
    fn MPI_Init_thread(
        argc: *mut c_int,
        argv: *mut *mut *mut c_char,
        required: c_int,
        provided: *mut c_int,
    ) -> c_int;
    fn MPI_Finalized(flag: *mut c_int) -> c_int;
    fn MPI_Allgather(
        send: *const c_void,
        send_count: c_int,
        send_type: *mut c_void,
        recv: *mut c_void,
        recv_count: c_int,
        recv_type: *mut c_void,
        comm: *mut c_void,
    ) -> c_int;
    fn MPI_Allgatherv(
        send: *const c_void,
        send_count: c_int,
        send_type: *mut c_void,
        recv: *mut c_void,
        recv_counts: *const c_int,
        displacements: *const c_int,
        recv_type: *mut c_void,
        comm: *mut c_void,
    ) -> c_int;
    fn MPI_Finalize() -> c_int;
    fn MPI_Comm_rank(comm: *mut c_void, rank: *mut c_int) -> c_int;
    fn MPI_Comm_size(comm: *mut c_void, size: *mut c_int) -> c_int;
    fn MPI_Barrier(comm: *mut c_void) -> c_int;
    fn MPI_Gather(
        send: *const c_void,
        send_count: c_int,
        send_type: *mut c_void,
        recv: *mut c_void,
        recv_count: c_int,
        recv_type: *mut c_void,
        root: c_int,
        comm: *mut c_void,
    ) -> c_int;
    fn MPI_Gatherv(
        send: *const c_void,
        send_count: c_int,
        send_type: *mut c_void,
        recv: *mut c_void,
        recv_counts: *const c_int,
        displacements: *const c_int,
        recv_type: *mut c_void,
        root: c_int,
        comm: *mut c_void,
    ) -> c_int;
    fn MPI_Alltoall(
        send: *const c_void,
        send_count: c_int,
        send_type: *mut c_void,
        recv: *mut c_void,
        recv_count: c_int,
        recv_type: *mut c_void,
        comm: *mut c_void,
    ) -> c_int;
    fn MPI_Alltoallv(
        send: *const c_void,
        send_counts: *const c_int,
        send_displacements: *const c_int,
        send_type: *mut c_void,
        recv: *mut c_void,
        recv_counts: *const c_int,
        recv_displacements: *const c_int,
        recv_type: *mut c_void,
        comm: *mut c_void,
    ) -> c_int;
}

/// MPI_COMM_WORLD: the address of Open MPI's predefined communicator
/// (taking an extern static's address reads nothing).
fn world() -> *mut c_void {
    addr_of_mut!(ompi_mpi_comm_world).cast()
}

/// MPI_BYTE, likewise.
fn byte() -> *mut c_void {
    addr_of_mut!(ompi_mpi_byte).cast()
}

fn check(what: &str, code: c_int) -> Result<(), String> {
    if code == 0 {
        Ok(())
    } else {
        Err(format!("{what} failed (MPI error {code})"))
    }
}

/// MPI_THREAD_SERIALIZED: calls from any thread, one at a time.
const THREAD_SERIALIZED: c_int = 2;

/// This process's place in MPI_COMM_WORLD; MPI is finalised when it is
/// dropped, if this process's `join` started it.
pub struct World {
    rank: usize,
    size: usize,
    finalise: bool,
}

impl World {
    /// Joins the MPI job: once per process.
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
        Self::place(true)
    }

    /// Joins the MPI job from a library inside a host: with the host's
    /// MPI where it initialised it (left to the host to finalise), else
    /// initialised here for calls from one thread at a time (a render
    /// thread), and finalised when the process exits, on its main thread.
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
        if started == 0 {
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
                return Err(format!(
                    "this MPI provides thread level {provided}, below MPI_THREAD_SERIALIZED, which rendering threads need"
                ));
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
        Self::place(false)
    }

    fn place(finalise: bool) -> Result<Self, String> {
        let (mut rank, mut size) = (0, 0);
        // SAFETY: the world communicator, valid after MPI_Init.
        unsafe {
            check("MPI_Comm_rank", MPI_Comm_rank(world(), &mut rank))?;
            check("MPI_Comm_size", MPI_Comm_size(world(), &mut size))?;
        }
        Ok(Self {
            rank: rank as usize,
            size: size as usize,
            finalise,
        })
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
        check("MPI_Barrier", unsafe { MPI_Barrier(world()) })
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
                world(),
            )
        })?;
        let lens: Vec<u64> = lens
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect();
        let total: u64 = lens.iter().sum();
        let fits = |n: u64| n <= c_int::MAX as u64;
        if !fits(bytes.len() as u64) || !fits(total) {
            return Err(format!(
                "gathering {total} bytes on rank 0 passes MPI's int counts"
            ));
        }
        let counts: Vec<c_int> = lens.iter().map(|&n| n as c_int).collect();
        let mut displacements = Vec::with_capacity(counts.len());
        let mut at = 0;
        for &n in &counts {
            displacements.push(at);
            at += n;
        }
        let mut all = vec![0u8; total as usize];
        // SAFETY: each rank sends its bytes; the root receives them at
        // the displacements, within `all`, which holds their sum.
        check("MPI_Gatherv", unsafe {
            MPI_Gatherv(
                bytes.as_ptr().cast(),
                bytes.len() as c_int,
                byte(),
                all.as_mut_ptr().cast(),
                counts.as_ptr(),
                displacements.as_ptr(),
                byte(),
                0,
                world(),
            )
        })?;
        Ok(counts
            .iter()
            .zip(&displacements)
            .map(|(&n, &at)| all[at as usize..(at + n) as usize].to_vec())
            .collect())
    }
}

impl World {
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
                world(),
            )
        })?;
        let got: Vec<u64> = got
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect();
        let counts =
            |lens: &mut dyn Iterator<Item = u64>| -> Result<(Vec<c_int>, Vec<c_int>), String> {
                let (mut counts, mut at) = (Vec::new(), Vec::new());
                let mut total: u64 = 0;
                for n in lens {
                    at.push(c_int::try_from(total).map_err(|_| "passes MPI's int counts")?);
                    counts.push(c_int::try_from(n).map_err(|_| "passes MPI's int counts")?);
                    total += n;
                }
                c_int::try_from(total).map_err(|_| "passes MPI's int counts")?;
                Ok((counts, at))
            };
        let too_big = |e: String| format!("an exchange of {e}");
        let (send_counts, send_at) =
            counts(&mut to.iter().map(|m| m.len() as u64)).map_err(too_big)?;
        let (recv_counts, recv_at) = counts(&mut got.iter().copied()).map_err(too_big)?;
        let send: Vec<u8> = to.concat();
        let mut recv = vec![0u8; got.iter().sum::<u64>() as usize];
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
                world(),
            )
        })?;
        Ok(recv_counts
            .iter()
            .zip(&recv_at)
            .map(|(&n, &at)| recv[at as usize..(at + n) as usize].to_vec())
            .collect())
    }
}

impl World {
    /// Every rank's `bytes`, on every rank in rank order.
    pub fn all_gather(&self, bytes: &[u8]) -> Result<Vec<Vec<u8>>, String> {
        let len = (bytes.len() as u64).to_le_bytes();
        let mut lens = vec![0u8; 8 * self.size];
        // SAFETY: 8 bytes from each rank into `lens`, 8 per rank.
        check("MPI_Allgather", unsafe {
            MPI_Allgather(
                len.as_ptr().cast(),
                8,
                byte(),
                lens.as_mut_ptr().cast(),
                8,
                byte(),
                world(),
            )
        })?;
        let mut counts = Vec::with_capacity(self.size);
        let mut at = Vec::with_capacity(self.size);
        let mut total: u64 = 0;
        for c in lens.chunks_exact(8) {
            let n = u64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
            let int = |v: u64| {
                c_int::try_from(v).map_err(|_| {
                    format!("gathering {v} bytes on every rank passes MPI's int counts")
                })
            };
            at.push(int(total)?);
            counts.push(int(n)?);
            total += n;
        }
        c_int::try_from(total).map_err(|_| {
            format!("gathering {total} bytes on every rank passes MPI's int counts")
        })?;
        let mut all = vec![0u8; total as usize];
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
                world(),
            )
        })?;
        Ok(counts
            .iter()
            .zip(&at)
            .map(|(&n, &at)| all[at as usize..(at + n) as usize].to_vec())
            .collect())
    }
}

impl Drop for World {
    fn drop(&mut self) {
        if self.finalise {
            // SAFETY: once, after every collective of this process.
            unsafe {
                MPI_Finalize();
            }
        }
    }
}
