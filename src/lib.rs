pub mod cave;
pub mod geometry;
