//! NanoVDB files as the NanoVDB library writes them (`io::writeGrids`,
//! and raw grid buffers), made at test time: every grid is listed by
//! name and type, `--grid` picks one and names them all when it is not
//! one, `caveray inspect` prints the grid's type, voxels and boxes,
//! `render` draws every wall, and compressed or cut files are refused by
//! name.

use crate::common;

use anari_library_caveray::data::{load_nvdb, parse_nvdb};

fn caveray(args: &[&str]) -> std::process::Output {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_caveray"));
    cmd.args(args).env("CAVERAY_BACKEND", "cpu");
    cmd.output().unwrap()
}

#[test]
fn a_file_holds_its_grids_by_name_as_they_lie_in_memory() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let file = load_nvdb(&written.file(), None).unwrap();
    let names: Vec<(&str, &str)> = file
        .entries
        .iter()
        .map(|e| (e.name.as_str(), e.grid_type.as_str()))
        .collect();
    assert_eq!(
        names,
        [
            ("fog", "Float"),
            ("fog16", "Fp16"),
            ("fog8", "Fp8"),
            ("fog4", "Fp4"),
            ("torus", "Float"),
            ("fog_fine", "Float")
        ]
    );
    assert_eq!(file.name, "fog");
    for name in ["fog16", "torus"] {
        let from_file = load_nvdb(&written.file(), Some(name)).unwrap();
        assert_eq!(from_file.name, name);
        assert_eq!(from_file.grid.words(), {
            let blob = written.blob(name);
            blob.chunks_exact(4)
                .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                .collect::<Vec<_>>()
        });
        assert_eq!(
            from_file.grid.active_voxels(),
            written.grids[name]["active"].as_u64().unwrap()
        );
    }
    // A grid's buffer alone, as NanoVDB 32.6 and later write raw files.
    let raw = parse_nvdb(&written.blob("torus"), "torus.nvdb", None).unwrap();
    assert_eq!((raw.name.as_str(), raw.entries.len()), ("torus", 1));

    let e = load_nvdb(&written.file(), Some("smoke"))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("no grid named 'smoke'") && e.contains("'fog8' (Fp8)"),
        "{e}"
    );
    let mut bytes = std::fs::read(written.file()).unwrap();
    bytes[14] = 2;
    let e = parse_nvdb(&bytes, "grids.nvdb", None)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("compressed with BLOSC"), "{e}");
    bytes[14] = 0;
    bytes.truncate(bytes.len() - 1000);
    let e = parse_nvdb(&bytes, "grids.nvdb", None)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("grid 5 ('fog_fine'") && e.contains("runs past the end of the file"),
        "{e}"
    );
}

#[test]
fn the_tool_inspects_and_renders_a_grid_of_a_file() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let path = written.file();
    let path = path.to_str().unwrap();
    let inspect = caveray(&["inspect", "--volume", path]);
    let said = String::from_utf8_lossy(&inspect.stdout);
    assert!(inspect.status.success(), "{said}");
    let lo = &written.grids["fog"]["lo"];
    let box_line = format!("voxels [{}, {}, {}]", lo[0], lo[1], lo[2]);
    for line in [
        "NanoVDB",
        "'fog16': Fp16, 7224 active voxels",
        "Float (FogVolume)",
        "active voxels 7224",
        box_line.as_str(),
        "value range   0 to 1",
    ] {
        assert!(said.contains(line), "{line} not in {said}");
    }

    let out = written.dir.join("out");
    let render = caveray(&[
        "render",
        "--config",
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/cave_configs/cologne_5wall.toml"
        ),
        "--volume",
        path,
        "--grid",
        "torus",
        "--scale",
        "0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        render.status.success(),
        "{}",
        String::from_utf8_lossy(&render.stderr)
    );
    let pngs = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "png"))
        .count();
    assert!(pngs >= 10, "{pngs} images");

    let config = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cave_configs/cologne_5wall.toml"
    );
    let out = out.to_str().unwrap();
    let render_with = |volume: &str, grid: &str| {
        caveray(&[
            "render", "--config", config, "--volume", volume, "--grid", grid, "--out", out,
        ])
    };
    let wrong = render_with(path, "smoke");
    let said = String::from_utf8_lossy(&wrong.stderr);
    assert!(!wrong.status.success());
    assert!(
        said.contains("no grid named 'smoke'") && said.contains("'torus' (Float)"),
        "{said}"
    );
    let not_vdb = render_with("phantom", "fog");
    let said = String::from_utf8_lossy(&not_vdb.stderr);
    assert!(
        said.contains("--grid names a grid of a NanoVDB file"),
        "{said}"
    );
}
