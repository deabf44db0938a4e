pub mod cave;
pub mod data;
pub mod device;
pub mod geometry;
