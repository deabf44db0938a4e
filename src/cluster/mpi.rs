//! The few MPI calls a CAVE cluster needs (init, rank and size, barrier,
//! gather), declared by hand against Open MPI's C ABI (Debian's
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

/// This process's place in MPI_COMM_WORLD; MPI is finalised when it is
/// dropped.
pub struct World {
    rank: usize,
    size: usize,
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
        let (mut rank, mut size) = (0, 0);
        // SAFETY: the world communicator, valid after MPI_Init.
        unsafe {
            check("MPI_Comm_rank", MPI_Comm_rank(world(), &mut rank))?;
            check("MPI_Comm_size", MPI_Comm_size(world(), &mut size))?;
        }
        Ok(Self {
            rank: rank as usize,
            size: size as usize,
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

impl Drop for World {
    fn drop(&mut self) {
        // SAFETY: once, after every collective of this process.
        unsafe {
            MPI_Finalize();
        }
    }
}
