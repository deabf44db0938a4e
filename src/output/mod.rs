//! Pictures for people: PNG files, contact sheets of all walls, heat maps.

mod contact_sheet;
mod heatmap;
mod plot;
mod png;

pub use contact_sheet::{contact_sheet, SheetLayout};
pub use heatmap::{dssim_heatmap, side_by_side};
pub use plot::{Chart, Series, XAxis};
pub use png::{frame_to_rgba, write_png, write_rgba_png, OutputError};
