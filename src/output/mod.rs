//! Pictures for people: PNG files, contact sheets of all walls, heat maps.

mod contact_sheet;
mod png;

pub use contact_sheet::{contact_sheet, SheetLayout};
pub use png::{frame_to_rgba, write_png, write_rgba_png, OutputError};
