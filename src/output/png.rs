use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::render::Frame;

#[derive(Debug, Error)]
pub enum OutputError {
    #[error("cannot write {}: {source}", .path.display())]
    Write {
        path: PathBuf,
        source: image::ImageError,
    },
}

/// The frame as an 8-bit sRGB image, top row first.
pub fn frame_to_rgba(frame: &Frame) -> image::RgbaImage {
    image::RgbaImage::from_raw(frame.size.x, frame.size.y, frame.to_srgb8_top_down())
        .expect("a frame holds exactly width x height pixels")
}

/// Writes a frame as an sRGB PNG (frames are lower-left first; PNGs top-down).
pub fn write_png(frame: &Frame, path: &Path) -> Result<(), OutputError> {
    write_rgba_png(&frame_to_rgba(frame), path)
}

pub fn write_rgba_png(image: &image::RgbaImage, path: &Path) -> Result<(), OutputError> {
    image.save(path).map_err(|source| OutputError::Write {
        path: path.to_path_buf(),
        source,
    })
}
