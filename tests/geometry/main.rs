//! Off-axis geometry and its invariants on the shipped rigs, the rig and
//! display formats, and contact sheet layouts.

#[path = "../common/mod.rs"]
mod common;

mod contact_sheets;
mod displays;
mod invariants;
mod rigs;
