//! caveray: render, inspect and benchmark CAVE rigs.

mod bench;
mod cluster;
mod data_parallel;
mod inspect;
mod options;
mod progress;
mod render;
mod render_display;
mod replay;
mod report;
mod scene;
mod view;

use std::process::ExitCode;

use anari_library_caveray::cave::{HeadPose, Rig};
use clap::parser::ValueSource;
use clap::{ArgMatches, Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use glam::DVec3;

#[derive(Parser)]
#[command(
    name = "caveray",
    version,
    about = "Off-axis volume rendering for CAVEs and powerwalls"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render every wall and eye of a rig to PNGs, contact sheets and
    /// timings; or a multi-view display's interleaved image and its views.
    Render(render::RenderArgs),
    /// Show every wall's and eye's camera under the four camera models
    /// (the three off-axis strategies and the native off-axis camera).
    Inspect(inspect::InspectArgs),
    /// Measure rendering speed (writes JSON, prints a summary).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Asynchronous rendering with image warping on a head path: DSSIM of
    /// every displayed frame against the ideal one, per warp mode (writes
    /// JSON, SVG traces and strips of frames).
    Replay(replay::ReplayArgs),
    /// Walk through a rig on the desktop: every wall rendered live for a
    /// simulated head, through deadline frames and warps, with controls.
    View(view::ViewArgs),
}

/// The tracked head, as the rig states it unless overridden.
#[derive(Args)]
pub struct HeadArgs {
    /// Head position X,Y,Z in the rig's units (default: the rig's).
    #[arg(long, value_parser = triple, allow_hyphen_values = true)]
    head: Option<DVec3>,
    /// Head yaw,pitch,roll in degrees relative to the rig's rest frame.
    #[arg(long, value_parser = triple, allow_hyphen_values = true)]
    head_ypr: Option<DVec3>,
    /// Take the head pose this many seconds along the rig's head path
    /// (--head and --head-ypr override its parts).
    #[arg(long)]
    time: Option<f64>,
}

impl HeadArgs {
    /// The time along the rig's head path asked for, if any.
    pub fn time(&self) -> Option<f64> {
        self.time
    }

    pub fn pose(&self, rig: &Rig) -> Result<HeadPose, Failure> {
        if let Some(t) = self.time {
            if !t.is_finite() {
                return Err(Failure::Usage(format!(
                    "--time must be a finite number, got {t}"
                )));
            }
        }
        if let Some(t) = self.time {
            let path = &rig.viewer.path;
            let (Some(first), Some(last)) = (path.first(), path.last()) else {
                return Err(Failure::Usage(format!(
                    "--time needs a head path, and rig \"{}\" has none",
                    rig.name
                )));
            };
            if !(first.time..=last.time).contains(&t) {
                return Err(Failure::Usage(format!(
                    "--time {t} is outside the rig's head path ({} to {} s)",
                    first.time, last.time
                )));
            }
        }
        let base = self.time.map_or(rig.viewer.head, |t| rig.head_at(t));
        Ok(HeadPose {
            position: self.head.unwrap_or(base.position),
            orientation: self
                .head_ypr
                .map_or(base.orientation, |ypr| rig.viewer.frame.orientation(ypr)),
        })
    }
}

pub fn triple(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let values: Vec<f64> = parts
        .iter()
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected three numbers X,Y,Z, got '{s}'"))?;
    match values[..] {
        // Finite in single precision too: the rays are.
        [x, y, z] if values.iter().all(|v| (*v as f32).is_finite()) => Ok(DVec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers X,Y,Z, got '{s}'")),
    }
}

/// The options given on the command line (not defaulted), by long name.
pub struct Given(Vec<String>);

impl Given {
    fn of(matches: &ArgMatches) -> Self {
        Self(
            matches
                .ids()
                .filter(|id| matches.value_source(id.as_str()) == Some(ValueSource::CommandLine))
                .map(|id| format!("--{}", id.as_str().replace('_', "-")))
                .collect(),
        )
    }

    /// A usage error naming those of `names` (long names, `--` included)
    /// that were given, with `verb` for one or several of them, then
    /// `rest`; none given, nothing.
    pub fn refuse(&self, names: &[&str], verb: [&str; 2], rest: &str) -> Result<(), Failure> {
        let given: Vec<&str> = names
            .iter()
            .copied()
            .filter(|n| self.0.iter().any(|g| g == n))
            .collect();
        let (list, verb) = match given[..] {
            [] => return Ok(()),
            [one] => (one.to_string(), verb[0]),
            [ref init @ .., last] => (format!("{} and {last}", init.join(", ")), verb[1]),
        };
        Err(Failure::Usage(format!("{list} {verb} {rest}")))
    }
}

/// A failure the user caused (exit 2) or one the tool hit (exit 1).
pub enum Failure {
    Usage(String),
    Runtime(String),
}

fn main() -> ExitCode {
    let parsed = Cli::command()
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m).map(|cli| (cli, m)));
    let (cli, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(e) if !e.use_stderr() => {
            // --help and --version
            print!("{e}");
            return ExitCode::SUCCESS;
        }
        Err(e) => return fail(Failure::Usage(first_line(&e.to_string()))),
    };
    let given = |name: &str| {
        matches
            .subcommand_matches(name)
            .map_or(Given(Vec::new()), Given::of)
    };
    let result = match cli.command {
        Command::Render(args) => render::run(args, &given("render")),
        Command::Inspect(args) => inspect::run(args),
        Command::Bench(command) => bench::run(command),
        Command::Replay(args) => replay::run(args),
        Command::View(args) => view::run(args, &given("view")),
    };
    let succeeded = result.is_ok();
    let code = match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => fail(f),
    };
    // After the message: a failed rank aborts the job it is in.
    cluster::end(succeeded);
    code
}

/// Clap's message without the usage block, folded onto one line.
fn first_line(message: &str) -> String {
    let body = message.split("\n\n").next().unwrap_or(message);
    let folded = body.split_whitespace().collect::<Vec<_>>().join(" ");
    let folded = folded.trim_start_matches("error: ");
    if folded.is_empty() {
        "invalid arguments (see caveray --help)".to_string()
    } else {
        folded.to_string()
    }
}

fn fail(failure: Failure) -> ExitCode {
    let (message, code) = match failure {
        Failure::Usage(m) => (m, 2),
        Failure::Runtime(m) => (m, 1),
    };
    eprintln!("caveray: {message}");
    ExitCode::from(code)
}
