//! Geometries: one module per subtype. caveray draws surfaces of fields,
//! so its one geometry is the isosurface.

pub mod isosurface;

pub use isosurface::IsoGeometry;
