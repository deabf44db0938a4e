//! caveray: render, inspect and benchmark CAVE rigs.

use std::path::PathBuf;
use std::process::ExitCode;

use anari_library_caveray::cave::inspect::{inspect, Pinhole, Report, Selection, ViewReport};
use anari_library_caveray::cave::{Eye, Rig};
use clap::{Args, Parser, Subcommand, ValueEnum};
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
    /// Show every wall's and eye's camera under the three off-axis strategies.
    Inspect(InspectArgs),
}

#[derive(Args)]
struct InspectArgs {
    /// Rig file (TOML), e.g. cave_configs/cologne_5wall.toml.
    #[arg(long)]
    config: PathBuf,
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
    /// One wall by name, or all.
    #[arg(long, default_value = "all")]
    wall: String,
    #[arg(long, value_enum, default_value_t = EyeArg::Both)]
    eye: EyeArg,
    /// List N strategy-2 rays per view, spread over the wall.
    #[arg(long, default_value_t = 0)]
    rays: u32,
    /// Print one JSON document instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum EyeArg {
    Left,
    Right,
    Mono,
    /// Every eye the wall is rendered for.
    Both,
}

fn triple(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let values: Vec<f64> = parts
        .iter()
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected three numbers X,Y,Z, got '{s}'"))?;
    match values[..] {
        [x, y, z] if values.iter().all(|v| v.is_finite()) => Ok(DVec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers X,Y,Z, got '{s}'")),
    }
}

/// A failure the user caused (exit 2) or one the tool hit (exit 1).
enum Failure {
    Usage(String),
    Runtime(String),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version
            print!("{e}");
            return ExitCode::SUCCESS;
        }
        Err(e) => return fail(Failure::Usage(first_line(&e.to_string()))),
    };
    let result = match cli.command {
        Command::Inspect(args) => run_inspect(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => fail(f),
    }
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

fn run_inspect(args: InspectArgs) -> Result<(), Failure> {
    let rig = Rig::load(&args.config).map_err(|e| Failure::Usage(e.to_string()))?;
    let wall = (!args.wall.eq_ignore_ascii_case("all")).then_some(args.wall.as_str());
    if let Some(name) = wall {
        if rig.wall(name).is_none() {
            let names: Vec<&str> = rig.walls.iter().map(|w| w.name.as_str()).collect();
            return Err(Failure::Usage(format!(
                "rig '{}' has no wall '{name}' (walls: {}, or all)",
                rig.name,
                names.join(", ")
            )));
        }
    }
    if let Some(t) = args.time {
        if !t.is_finite() {
            return Err(Failure::Usage(format!(
                "--time must be a finite number, got {t}"
            )));
        }
    }
    let base = args.time.map_or(rig.viewer.head, |t| rig.head_at(t));
    let head = anari_library_caveray::cave::HeadPose {
        position: args.head.unwrap_or(base.position),
        orientation: args
            .head_ypr
            .map_or(base.orientation, |ypr| rig.viewer.frame.orientation(ypr)),
    };
    let eyes: &[Eye] = match args.eye {
        EyeArg::Left => &[Eye::Left],
        EyeArg::Right => &[Eye::Right],
        EyeArg::Mono => &[Eye::Mono],
        EyeArg::Both => &Eye::ALL,
    };
    let report = inspect(
        &rig,
        &head,
        &Selection {
            wall,
            eyes,
            rays: args.rays,
        },
    );
    if report.views.is_empty() {
        return Err(Failure::Usage(format!(
            "no wall of '{}' is rendered for that eye",
            rig.name
        )));
    }
    if args.json {
        let text =
            serde_json::to_string_pretty(&report).map_err(|e| Failure::Runtime(e.to_string()))?;
        println!("{text}");
    } else {
        print_report(&report);
    }
    Ok(())
}

fn print_report(r: &Report) {
    let u = r.units;
    println!("{} (units: {u})", r.rig);
    println!(
        "head at {}  orientation (x,y,z,w) {}",
        v3(&r.head.position),
        vn(&r.head.orientation, 4)
    );
    for v in &r.views {
        print_view(v, u);
    }
}

fn print_view(v: &ViewReport, u: &str) {
    println!();
    println!(
        "== {} / {} eye at {} {u}, {} x {} px",
        v.wall,
        v.eye,
        v3(&v.eye_position),
        v.resolution[0],
        v.resolution[1]
    );
    let Some(c) = &v.cameras else {
        println!(
            "   no camera: {}",
            v.error.as_deref().unwrap_or("unknown error")
        );
        return;
    };
    println!("   strategy 1, matrix camera (OpenGL view and projection, shown row by row)");
    print_matrix("view", &c.matrix.view);
    print_matrix("proj", &c.matrix.proj);
    println!("   strategy 2, pinhole + image region");
    print_pinhole("position", &c.pinhole.position, &c.pinhole);
    println!("   strategy 3, pinhole recovered from the matrices");
    print_pinhole(
        "recovered eye",
        &c.from_matrices.recovered_eye,
        &c.from_matrices.pinhole,
    );
    println!(
        "   largest disagreement of the 4 ray generators over {} pixels: {:.3e} {u}",
        c.pixels_compared, c.max_ray_disagreement
    );
    for ray in &c.rays {
        println!(
            "     pixel ({:>4}, {:>4})  origin {}  direction {}",
            ray.pixel[0],
            ray.pixel[1],
            v3(&ray.origin),
            vn(&ray.direction, 6)
        );
    }
}

fn print_pinhole(label: &str, position: &[f64; 3], p: &Pinhole) {
    println!(
        "     {label} {}  direction {}  up {}",
        v3(position),
        v3(&p.direction),
        v3(&p.up)
    );
    println!(
        "     fovy {:.4} deg  aspect {:.6}  imageRegion [{}]",
        p.fovy.to_degrees(),
        p.aspect,
        vn(&p.image_region, 6)
    );
}

fn print_matrix(name: &str, cols: &[f64; 16]) {
    for row in 0..4 {
        let label = if row == 0 { name } else { "" };
        let cells: Vec<String> = (0..4)
            .map(|col| format!("{:>13.6}", cols[col * 4 + row]))
            .collect();
        println!("     {label:<5}[{} ]", cells.join(""));
    }
}

fn v3(v: &[f64; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3})", v[0], v[1], v[2])
}

fn vn(v: &[f64], digits: usize) -> String {
    v.iter()
        .map(|x| format!("{x:.digits$}"))
        .collect::<Vec<_>>()
        .join(", ")
}
