pub mod capi;
pub mod cave;
pub mod data;
pub mod device;
pub mod geometry;
pub mod output;
pub mod render;
pub mod scene;
