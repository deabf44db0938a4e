//! What is rendered: volumes, transfer functions, surfaces with their
//! materials and samplers, and the scene that places and pairs them. Below the renderers and the ANARI object model alike,
//! so the renderers, the data readers and the device all describe a
//! volume the same way and none of them depends on another's room.

mod amr;
mod composition;
mod field;
mod nanovdb;
mod placement;
mod sampler;
mod shapes;
mod storage;
mod tet_walk;
mod transfer_function;
mod unstructured;
mod volume;

pub use amr::{
    AmrBlock, AmrError, AmrInput, AmrLevel, AmrVolume, AMR_ABSENT, AMR_EMPTY, MAX_AMR_LEVELS,
};
pub use composition::{PlacedVolume, Scene, SceneError, MAX_VOLUMES};
pub use field::SpatialField;
pub use nanovdb::{
    half_to_f32, NanoVdbError, NanoVdbGrid, RootTile, VdbValues, LEAF_OFF_TABLE,
    LOWER_OFF_CHILD_MASK, LOWER_OFF_TABLE, NANOVDB_MAGIC, NANOVDB_MAGIC_FILE, NANOVDB_MAGIC_GRID,
    NANOVDB_MAJOR, UPPER_OFF_CHILD_MASK, UPPER_OFF_TABLE, VDB_TYPE_NAMES,
};
pub use placement::{transformed_box, ObjectIds};
pub use sampler::{Image, Sampler, SamplerError, SamplerKind, Wrap, DEFAULT_ATTRIBUTE, MAX_TEXELS};
pub use shapes::{
    AlphaMode, Attribute, ColorSource, Coverage, Kept, Made, OpacitySource, Pbr, PlacedShape,
    Primitives, Shape, ShapeError, ShapeInput, Source, SurfaceMaterial, Uniforms, ATTRIBUTE_NAMES,
    MAX_PRIMITIVES,
};
pub use storage::{Buf, Lent, Mapping, Reading};
pub use transfer_function::{TransferFunction, TransferFunctionError, TABLE_SIZE};
pub use unstructured::{
    check_counts, CellKind, MeshInput, MeshNode, MeshValues, NearCells, RayCells,
    UnstructuredError, UnstructuredVolume, CELL_TOLERANCE, MAX_MESH_CELLS, MAX_MESH_INDICES,
    MAX_MESH_VERTICES, MESH_STACK, NEWTON_STEPS, NEWTON_TOLERANCE, WALK_STEPS, WALK_WORDS,
};
pub use volume::{Filter, Scaling, StructuredVolume, VolumeError, Voxels, MAX_VOXELS};
