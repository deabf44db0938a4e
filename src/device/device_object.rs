//! The device as an object: the parameters hosts set on it. Its commit is
//! the device's own (it switches callbacks and backends), so the table
//! serves checks and introspection only.

use super::table::{p, DefaultValue, SubtypeInfo, EXT_FRAME_PAIR};
use super::types::DataType as T;
use crate::render::Backend;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::DEVICE,
    subtype: "default",
    description: "caveray: off-axis volume ray casting for CAVEs and powerwalls",
    extensions: &[EXT_FRAME_PAIR],
    params: &[
        p("statusCallback", &[T::STATUS_CALLBACK], false, DefaultValue::None,
          "function receiving every error, warning and info message; takes effect on commit"),
        p("statusCallbackUserData", &[T::VOID_POINTER], false, DefaultValue::None,
          "passed back as the status callback's first argument"),
        p("backend", &[T::STRING], false, DefaultValue::None,
          "auto | gpu | cpu: the Vulkan ray caster, the CPU renderer, or a hardware GPU when one opens \
           and the CPU otherwise (default auto, or $CAVERAY_BACKEND)")
        .names(&Backend::NAMES),
        p("caveray.memoryBudget", &[T::UINT64], false, DefaultValue::None,
          "bytes of volume textures the GPU may hold (unset or 0: what its driver allows); the volumes \
           of a world past it are paged, each holding the bricks its views ask for within its share; \
           one too small for a single brick is refused before anything is allocated, and backend auto \
           renders it on the CPU"),
        p("caveray.streamWait", &[T::FLOAT32], false, DefaultValue::None,
          "milliseconds a frame waits for the bricks of paged volumes (unset: until all it selected \
           are resident); past it the frame renders coarser levels where bricks are missing, reports \
           renderProgress below 1, and later frames refine"),
        p("caveray.mpi", &[T::STRING], false, DefaultValue::None,
          "\"world\": every rank of the MPI job (MPI_COMM_WORLD, initialised here unless the host did) \
           renders its world's region (the world's caveray.region) of each frame and the frames are \
           composited, every rank getting the whole image (ANARI_CAVERAY_DEVICE_MPI; needs a build \
           with the mpi feature)"),
        p("pairStereoFrames", &[T::BOOL], false, DefaultValue::Bool(true),
          "render two frames that show the eyes of one wall in one re-projection pass when the first \
           renders, keeping the second's image for its render (ANARI_CAVERAY_FRAME_STEREO_PAIR)"),
    ],
    commit: None,
};
