//! Beyond one machine: a CAVE's views shared out over the processes of an
//! MPI job (one per node, each driving its GPU), kept in step by a barrier
//! that plays the swap lock's part, their images and timings gathered on
//! rank 0; or one volume cut into bricks over the processes (`split`),
//! each rendering its own region (`region`) of every view, the partial
//! images composited in visibility order (`composite`), by the tool or by
//! a device whose frames are a job's (`Ranks`). All but the talking is
//! plain arithmetic, built always; talking to MPI (`mpi`) only with the
//! `mpi` feature, so a build without it is unchanged.

mod assign;
mod composite;
#[cfg(feature = "mpi")]
pub mod mpi;
mod ranks;
mod region;
mod split;

pub use assign::assign;
pub use composite::{band, bands_of, composite, floats_of, Partial};
pub use ranks::Ranks;
pub use region::Region;
pub use split::{Brick, Split};

/// Processes in the job that started this one, as the launcher says
/// (Open MPI's `mpirun`, or a PMI launcher such as MPICH's hydra), where it says one; without
/// the `mpi` feature such a job cannot be joined, and each of its
/// processes would render every view.
pub fn launched_size() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.parse().ok())
}
