//! `caveray inspect`: the cameras of every wall and eye, or what a volume
//! file's header says, as text or JSON.

use std::path::{Path, PathBuf};

use anari_library_caveray::cave::inspect::{inspect, Pinhole, Report, Selection, ViewReport};
use anari_library_caveray::cave::{Eye, Rig};
use anari_library_caveray::data::{load_volume_file, VolumeFormat};
use clap::{Args, ValueEnum};

use crate::{Failure, HeadArgs};

#[derive(Args)]
pub struct InspectArgs {
    /// Rig file (TOML), e.g. cave_configs/cologne_5wall.toml.
    #[arg(long, required_unless_present = "volume")]
    config: Option<PathBuf>,
    /// A volume file with a header (NIfTI, NRRD, MetaImage, VTK image data,
    /// or a DICOM series' folder): prints its size, type, spacing, index-to-world map and value range
    /// instead of a rig's views.
    #[arg(long, conflicts_with = "config")]
    volume: Option<PathBuf>,
    #[command(flatten)]
    head: HeadArgs,
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

pub fn run(args: InspectArgs) -> Result<(), Failure> {
    let config = match (&args.volume, &args.config) {
        (Some(volume), _) => return inspect_volume(volume, args.json),
        (None, Some(config)) => config,
        (None, None) => {
            return Err(Failure::Usage(
                "give a rig (--config) or a volume file (--volume)".into(),
            ))
        }
    };
    let rig = Rig::load(config).map_err(|e| Failure::Usage(e.to_string()))?;
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
    let head = args.head.pose(&rig)?;
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

/// What a volume file's header says, and its values' range.
fn inspect_volume(path: &Path, json: bool) -> Result<(), Failure> {
    if crate::scene::is_mesh_file(path) {
        return inspect_mesh(path, json);
    }
    if crate::scene::is_hdf5_file(path) {
        return inspect_flash(path, json);
    }
    if crate::scene::is_nvdb_file(path) {
        return inspect_nvdb(path, json);
    }
    if !VolumeFormat::of(path).is_some_and(|f| f.readable()) {
        return Err(Failure::Usage(format!(
            "{}: caveray inspect reads volume files with a header: NIfTI (.nii, .nii.gz, \
             .hdr/.img), NRRD (.nrrd, .nhdr), MetaImage (.mha, .mhd), VTK image data (.vti, \
             .vtk) and DICOM (a series' folder or one of its files)",
            path.display()
        )));
    }
    let file = load_volume_file(path).map_err(|e| Failure::Usage(e.to_string()))?;
    let (lo, hi) = file.volume.value_range();
    let rows: Vec<[f64; 4]> = (0..3).map(|r| file.affine.row(r).to_array()).collect();
    let dims = file.volume.dims();
    if json {
        let mut doc = serde_json::json!({
            "file": path.display().to_string(),
            "format": file.format.name(),
            "dims": dims.to_array(),
            "dtype": file.dtype,
            "units": file.units,
            "ras": file.anatomical,
            "index_to_world": rows,
            "value_range": [lo, hi],
        });
        for (key, value) in &file.details {
            doc[*key] = value.clone();
        }
        println!("{doc:#}");
        return Ok(());
    }
    println!("{}: {}", path.display(), file.format.name());
    println!("  dims          {} x {} x {}", dims.x, dims.y, dims.z);
    println!("  type          {}", file.dtype);
    for (key, value) in &file.details {
        let shown = match value {
            serde_json::Value::String(s) => s.clone(),
            other => other.to_string(),
        };
        println!("  {:<13} {shown}", key.replace('_', " "));
    }
    let space = if file.anatomical {
        "RAS+"
    } else {
        "the file's axes"
    };
    println!("  index to world ({space}, {}):", file.units);
    print_map(&rows, (lo, hi));
    Ok(())
}

/// What a VTK unstructured grid holds: its cells by kind, its box, its
/// arrays and the sampled one's range.
fn inspect_mesh(path: &Path, json: bool) -> Result<(), Failure> {
    let file = anari_library_caveray::data::load_vtk_mesh(path, None)
        .map_err(|e| Failure::Usage(e.to_string()))?;
    let mesh = &file.mesh;
    let (lo, hi) = mesh.bounds();
    let (vlo, vhi) = mesh.value_range();
    let cells: Vec<(&str, u64)> = mesh
        .cell_counts()
        .iter()
        .map(|(k, n)| (k.name(), *n))
        .collect();
    let arrays: Vec<String> = file
        .arrays
        .iter()
        .map(|(name, at_cells)| format!("{name} ({})", if *at_cells { "cells" } else { "points" }))
        .collect();
    if json {
        let by_kind: serde_json::Map<String, serde_json::Value> = cells
            .iter()
            .map(|(k, n)| (k.to_string(), serde_json::Value::from(*n)))
            .collect();
        let doc = serde_json::json!({
            "file": path.display().to_string(),
            "format": format!("VTK unstructured grid ({})", file.flavour),
            "cells": by_kind,
            "skipped_cells": file.skipped,
            "points": mesh.vertex_count(),
            "bounds": [lo.to_array(), hi.to_array()],
            "arrays": arrays,
            "array": file.array,
            "value_range": [vlo, vhi],
        });
        println!("{doc:#}");
        return Ok(());
    }
    println!(
        "{}: VTK unstructured grid ({})",
        path.display(),
        file.flavour
    );
    for (kind, n) in &cells {
        println!("  {kind:<13} {n}");
    }
    if file.skipped > 0 {
        println!("  left out      {} cells of lower dimension", file.skipped);
    }
    println!("  points        {}", mesh.vertex_count());
    println!("  bounds        {lo} to {hi}");
    println!("  arrays        {}", arrays.join(", "));
    println!("  value range   {vlo} to {vhi} ({})", file.array);
    Ok(())
}

/// What a NanoVDB file holds: its grids, and of the first its type,
/// class, active voxels, boxes and values.
fn inspect_nvdb(path: &Path, json: bool) -> Result<(), Failure> {
    let file = anari_library_caveray::data::load_nvdb(path, None)
        .map_err(|e| Failure::Usage(e.to_string()))?;
    let g = &file.grid;
    let (ilo, ihi) = g.active_box();
    let (wlo, whi) = g.bounds();
    let (vlo, vhi) = g.value_range();
    let [upper, lower, leaves] = g.node_counts();
    if json {
        let grids: Vec<serde_json::Value> = file
            .entries
            .iter()
            .map(|e| {
                serde_json::json!({
                    "name": e.name,
                    "type": e.grid_type,
                    "active_voxels": e.active_voxels,
                })
            })
            .collect();
        let doc = serde_json::json!({
            "file": path.display().to_string(),
            "format": "NanoVDB",
            "grids": grids,
            "grid": file.name,
            "type": g.values().name(),
            "class": g.class_name(),
            "active_voxels": g.active_voxels(),
            "active_box": [ilo.to_array(), ihi.to_array()],
            "bounds": [wlo.to_array(), whi.to_array()],
            "voxel_size": g.voxel_size().to_array(),
            "background": g.background(),
            "value_range": [vlo, vhi],
            "nodes": {"upper": upper, "lower": lower, "leaves": leaves},
            "bytes": g.bytes(),
        });
        println!("{doc:#}");
        return Ok(());
    }
    println!("{}: NanoVDB", path.display());
    for e in &file.entries {
        println!(
            "  grid          '{}': {}, {} active voxels",
            e.name, e.grid_type, e.active_voxels
        );
    }
    println!("  first grid    '{}'", file.name);
    println!(
        "  values        {} ({}), background {}",
        g.values().name(),
        g.class_name(),
        g.background()
    );
    println!("  active voxels {}", g.active_voxels());
    println!("  active box    voxels {ilo} to {ihi}");
    println!("  bounds        {wlo} to {whi}");
    println!("  voxel size    {}", g.voxel_size());
    println!("  nodes         {upper} upper, {lower} lower, {leaves} leaves");
    println!("  value range   {vlo} to {vhi}");
    println!("  held          {} bytes", g.bytes());
    Ok(())
}

/// What a FLASH file holds: its variables, levels, blocks and box.
#[cfg(feature = "hdf5")]
fn inspect_flash(path: &Path, json: bool) -> Result<(), Failure> {
    let file = anari_library_caveray::data::load_flash(path, None)
        .map_err(|e| Failure::Usage(e.to_string()))?;
    let amr = &file.amr;
    let (lo, hi) = amr.bounds();
    let (vlo, vhi) = amr.value_range();
    let levels: Vec<serde_json::Value> = amr
        .levels()
        .iter()
        .enumerate()
        .map(|(l, level)| {
            serde_json::json!({
                "level": l,
                "cell_width": level.width,
                "cells": level.cells,
                "bounds": [level.lo.to_array(), level.hi.to_array()],
            })
        })
        .collect();
    if json {
        let doc = serde_json::json!({
            "file": path.display().to_string(),
            "format": "FLASH (HDF5)",
            "variables": file.variables,
            "variable": file.variable,
            "blocks": amr.block_count(),
            "leaf_blocks": file.leaves,
            "block_cells": file.block_cells,
            "levels": levels,
            "bounds": [lo.to_array(), hi.to_array()],
            "finest_cell": amr.finest_cell().to_array(),
            "value_range": [vlo, vhi],
            "bytes": amr.bytes(),
        });
        println!("{doc:#}");
        return Ok(());
    }
    println!("{}: FLASH (HDF5)", path.display());
    println!("  variables     {}", file.variables.join(", "));
    let [x, y, z] = file.block_cells;
    let leaves = file
        .leaves
        .map_or(String::new(), |n| format!(", {n} of them leaves"));
    println!(
        "  blocks        {} of {x}x{y}x{z} cells{leaves}",
        amr.block_count()
    );
    for (l, level) in amr.levels().iter().enumerate() {
        if level.cells == 0 {
            continue;
        }
        println!(
            "  level {l:<7} cells {} wide: {} cells within {} to {}",
            level.width, level.cells, level.lo, level.hi
        );
    }
    println!("  bounds        {lo} to {hi}");
    println!("  finest cell   {}", amr.finest_cell());
    println!("  value range   {vlo} to {vhi} ({})", file.variable);
    println!("  held          {} bytes", amr.bytes());
    Ok(())
}

#[cfg(not(feature = "hdf5"))]
fn inspect_flash(path: &Path, _: bool) -> Result<(), Failure> {
    crate::scene::load_flash_file(&path.display().to_string(), None).map(|_| ())
}

/// A voxel-to-world map's rows and a value range.
fn print_map(rows: &[[f64; 4]], (lo, hi): (f32, f32)) {
    for r in rows {
        println!(
            "    [{:>10.4} {:>10.4} {:>10.4} {:>10.4}]",
            r[0], r[1], r[2], r[3]
        );
    }
    println!("  value range   {lo} to {hi}");
}
