//! `caveray bench`: speed measurements that write JSON and print a summary.

use clap::Subcommand;

use crate::Failure;

#[derive(Subcommand)]
pub enum BenchCommand {}

pub fn run(command: BenchCommand) -> Result<(), Failure> {
    match command {}
}
