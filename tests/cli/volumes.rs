//! `--volume` from anywhere: manifests found or not, names known or not,
//! and files in formats caveray recognises but does not read.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh folder two levels down, so that `../shared` beside it (where
/// the tool looks for the project's data) does not exist.
fn scratch(test: &str) -> PathBuf {
    let top = std::env::temp_dir().join(format!("caveray-volumes-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&top);
    let dir = top.join("elsewhere").join("work");
    std::fs::create_dir_all(&dir).unwrap();
    assert!(!dir.join("../shared").exists());
    dir
}

fn remove(dir: &Path) {
    std::fs::remove_dir_all(dir.parent().unwrap().parent().unwrap()).unwrap();
}

/// `caveray render` of the Cologne rig at 32x32, run in `dir` with
/// `CAVERAY_DATA` as given (unset if `None`).
fn render_in(dir: &Path, data: Option<&Path>, extra: &[&str]) -> Output {
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("cave_configs/cologne_5wall.toml");
    render_with(dir, data, &config, extra)
}

/// `render_in` of the rig `config`.
fn render_with(dir: &Path, data: Option<&Path>, config: &Path, extra: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_caveray"));
    command
        .args(["render", "--config", config.to_str().unwrap()])
        .args([
            "--out",
            dir.join("out").to_str().unwrap(),
            "--scale",
            "0.02",
        ])
        .args(extra)
        .current_dir(dir)
        .env_remove("CAVERAY_DATA");
    if let Some(data) = data {
        command.env("CAVERAY_DATA", data);
    }
    command.output().expect("caveray runs")
}

/// Runs and expects a one-line usage error (exit 2); returns its text.
fn usage_error(dir: &Path, data: Option<&Path>, extra: &[&str]) -> String {
    let result = render_in(dir, data, extra);
    let err = String::from_utf8(result.stderr).unwrap();
    assert_eq!(result.status.code(), Some(2), "{extra:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{extra:?}: {err}");
    assert!(err.starts_with("caveray: "), "{extra:?}: {err}");
    err.trim_end().to_string()
}

/// A manifest of one 8^3 uint8 volume, `tiny`, with only the fields a
/// manifest needs, and a second entry naming a file that is not there.
fn own_manifest(dir: &Path, sha256: Option<&str>) -> PathBuf {
    let ramp: Vec<u8> = (0..512).map(|i| (i % 256) as u8).collect();
    std::fs::write(dir.join("tiny_8x8x8_uint8.raw"), ramp).unwrap();
    let sha = sha256.map_or(String::new(), |s| format!("sha256 = \"{s}\"\n"));
    let text = format!(
        "[[volume]]\nname = \"tiny\"\nfile = \"tiny_8x8x8_uint8.raw\"\ndims = [8, 8, 8]\n\
         dtype = \"uint8\"\nspacing = [1, 1, 2]\n{sha}\n\
         [[volume]]\nname = \"absent\"\nfile = \"absent.raw\"\ndims = [2, 2, 2]\n\
         dtype = \"uint16\"\nspacing = [1, 1, 1]\n"
    );
    let manifest = dir.join("volumes.toml");
    std::fs::write(&manifest, text).unwrap();
    manifest
}

#[test]
fn without_a_manifest_the_error_says_how_to_name_one() {
    let dir = scratch("no-manifest");
    let err = usage_error(&dir, None, &["--volume", "cthead"]);
    assert_eq!(
        err,
        "caveray: no volume manifest found to look 'cthead' up in \
         (tried ../shared/data/volumes/volumes.toml): pass --manifest FILE or set \
         CAVERAY_DATA=DIR, the folder holding volumes.toml \
         (docs/data.md says where the data sets come from)"
    );
    // A CAVERAY_DATA without a manifest is named among the places tried.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let err = usage_error(&dir, Some(&empty), &["--volume", "cthead"]);
    let tried = format!(
        "(tried {}, ../shared/data/volumes/volumes.toml)",
        empty.join("volumes.toml").display()
    );
    assert!(err.contains(&tried), "{err}");
    // A path that is not there is not looked up as a name.
    let err = usage_error(&dir, None, &["--volume", "scans/head.raw"]);
    assert_eq!(err, "caveray: scans/head.raw: no such file");
    remove(&dir);
}

#[test]
fn an_unknown_name_lists_the_known_ones() {
    let dir = scratch("unknown");
    let manifest = own_manifest(&dir, None);
    let m = manifest.to_str().unwrap();
    let err = usage_error(&dir, None, &["--manifest", m, "--volume", "cthaed"]);
    assert_eq!(
        err,
        format!(
            "caveray: no volume named 'cthaed' in {m} (known: tiny, absent), nor is there \
             such a file; --volume also takes phantom[:N], shells[:N], marschner-lobb[:N], \
             box[:N] or a raw file"
        )
    );
    remove(&dir);
}

#[test]
fn a_manifest_of_ones_own_is_found_by_flag_or_by_caveray_data() {
    let dir = scratch("own");
    let manifest = own_manifest(&dir, None);
    let ok = |result: Output| {
        let err = String::from_utf8_lossy(&result.stderr).into_owned();
        assert!(result.status.success(), "{err}");
        assert!(dir.join("out/front_left.png").is_file());
        std::fs::remove_dir_all(dir.join("out")).unwrap();
    };
    let m = manifest.to_str().unwrap();
    ok(render_in(
        &dir,
        None,
        &["--manifest", m, "--volume", "tiny"],
    ));
    // Names are matched without regard to case.
    ok(render_in(&dir, Some(&dir), &["--volume", "TINY"]));
    // A listed file that is missing is the tool's failure (exit 1), named.
    let result = render_in(&dir, Some(&dir), &["--volume", "absent"]);
    let err = String::from_utf8(result.stderr).unwrap();
    assert_eq!(result.status.code(), Some(1), "{err}");
    assert!(err.contains("absent.raw: No such file"), "{err}");
    // A checksum that does not match is refused before the volume is used.
    own_manifest(&dir, Some(&"0".repeat(64)));
    let result = render_in(&dir, Some(&dir), &["--volume", "tiny"]);
    let err = String::from_utf8(result.stderr).unwrap();
    assert_eq!(result.status.code(), Some(1), "{err}");
    assert!(err.contains("checksum mismatch: sha256 is "), "{err}");
    remove(&dir);
}

/// A NIfTI-1 single file of `dims` uint8 voxels, each its index modulo
/// 251, placed by an sform that turns it 90 degrees about z and moves it.
fn nifti(dims: [i16; 3]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[..4].copy_from_slice(&348i32.to_le_bytes());
    for (i, d) in [3, dims[0], dims[1], dims[2], 1, 1, 1, 1]
        .iter()
        .enumerate()
    {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&2i16.to_le_bytes());
    h[72..74].copy_from_slice(&8i16.to_le_bytes());
    for i in 0..4 {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&1f32.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[123] = 2; // mm
    h[254..256].copy_from_slice(&1i16.to_le_bytes()); // sform_code
    let rows = [
        [0f32, -2.0, 0.0, 5.0],
        [2.0, 0.0, 0.0, -7.0],
        [0.0, 0.0, 2.0, 1.0],
    ];
    for (r, row) in rows.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            let at = 280 + 16 * r + 4 * c;
            h[at..at + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    let n = dims.iter().map(|&d| d as usize).product::<usize>();
    h.extend((0..n).map(|i| (i % 251) as u8));
    h
}

/// `caveray inspect --volume path --json`'s document.
fn inspect_json(path: &Path) -> serde_json::Value {
    let inspect = Command::new(env!("CARGO_BIN_EXE_caveray"))
        .args(["inspect", "--volume", path.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(inspect.status.success(), "{inspect:?}");
    serde_json::from_slice(&inspect.stdout).unwrap()
}

#[test]
fn a_nrrd_file_renders_in_the_cave_and_inspects_with_no_other_flag() {
    let dir = scratch("nrrd");
    let mut bytes = b"NRRD0004\n# written by hand\ntype: uint8\ndimension: 3\nsizes: 12 10 8\n\
        space: left-posterior-superior\nspace directions: (2,0,0) (0,2,0) (0,0,3)\n\
        space origin: (10,20,-5)\nencoding: raw\n\n"
        .to_vec();
    bytes.extend((0..960).map(|i| (i % 251) as u8));
    // Named as raw: the content tells.
    for name in ["ct.nrrd", "ct.raw"] {
        let path = dir.join(name);
        std::fs::write(&path, &bytes).unwrap();
        let p = path.to_str().unwrap();
        let result = render_in(&dir, None, &["--volume", p]);
        assert!(
            result.status.success(),
            "{p}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
    }
    let path = dir.join("ct.nrrd");
    let doc = inspect_json(&path);
    assert_eq!(doc["dims"], serde_json::json!([12, 10, 8]));
    assert_eq!(doc["ras"], true);
    // LPS turned into RAS+: x and y flip, with the origin.
    assert_eq!(
        doc["index_to_world"],
        serde_json::json!([
            [-2.0, 0.0, 0.0, -10.0],
            [0.0, -2.0, 0.0, -20.0],
            [0.0, 0.0, 3.0, -5.0]
        ])
    );
    let broken = dir.join("broken.nrrd");
    std::fs::write(
        &broken,
        b"NRRD0004\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n12345678",
    )
    .unwrap();
    let b = broken.to_str().unwrap();
    let err = usage_error(&dir, None, &["--volume", b]);
    assert_eq!(err, format!("caveray: {b}: type: missing"));
    remove(&dir);
}

#[test]
fn a_nifti_file_renders_in_the_cave_and_inspects_with_no_other_flag() {
    use std::io::Write;
    let dir = scratch("nifti");
    let plain = dir.join("scan.nii");
    std::fs::write(&plain, nifti([12, 10, 8])).unwrap();
    // The same gzipped, and named as raw: the content tells.
    let gz = dir.join("scan.nii.gz");
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    encoder.write_all(&nifti([12, 10, 8])).unwrap();
    std::fs::write(&gz, encoder.finish().unwrap()).unwrap();
    let dat = dir.join("scan.dat");
    std::fs::write(&dat, nifti([12, 10, 8])).unwrap();
    for path in [&plain, &gz, &dat] {
        let p = path.to_str().unwrap();
        let result = render_in(&dir, None, &["--volume", p]);
        assert!(
            result.status.success(),
            "{p}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("out/timings.json")).unwrap())
                .unwrap();
        assert!(
            report["views"].as_array().is_some_and(|v| !v.is_empty()),
            "{p}: {report}"
        );
    }
    let doc = inspect_json(&gz);
    assert_eq!(doc["dims"], serde_json::json!([12, 10, 8]));
    assert_eq!(doc["dtype"], "uint8");
    assert_eq!(doc["units"], "mm");
    assert_eq!(doc["placed_by"], "sform");
    assert_eq!(
        doc["index_to_world"],
        serde_json::json!([
            [0.0, -2.0, 0.0, 5.0],
            [2.0, 0.0, 0.0, -7.0],
            [0.0, 0.0, 2.0, 1.0]
        ])
    );
    assert_eq!(doc["value_range"], serde_json::json!([0.0, 250.0]));
    // Its header gives its size: --dims is refused; a broken one is named
    // by file and field.
    let p = plain.to_str().unwrap();
    let err = usage_error(&dir, None, &["--volume", p, "--dims", "8,8,8"]);
    assert!(
        err.contains("is a NIfTI file, whose header gives its size"),
        "{err}"
    );
    let mut cut = nifti([12, 10, 8]);
    cut.truncate(400);
    let broken = dir.join("broken.nii");
    std::fs::write(&broken, cut).unwrap();
    let b = broken.to_str().unwrap();
    let err = usage_error(&dir, None, &["--volume", b]);
    assert_eq!(
        err,
        format!("caveray: {b}: voxels: 12x10x8 uint8 needs 960 bytes from vox_offset 352; the file holds 48")
    );
    remove(&dir);
}

fn dicom() -> Vec<u8> {
    let mut bytes = vec![0u8; 128 + 4 + 512];
    bytes[128..132].copy_from_slice(b"DICM");
    bytes
}

#[test]
fn broken_files_with_headers_are_refused_by_their_readers() {
    let dir = scratch("formats");
    let vti = "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\">\n";
    // Named as raw where the content tells; by name where it does not.
    let files: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "ct.mha",
            b"ObjectType = Image\nNDims = 3\n".to_vec(),
            "MetaImage",
        ),
        (
            "ct.raw",
            b"ObjectType = Image\nNDims = 3\n".to_vec(),
            "MetaImage",
        ),
        (
            "ct.mhd",
            b"NDims = 3\nDimSize = 8 8 8\n".to_vec(),
            "MetaImage",
        ),
        (
            "ct.vtk",
            b"# vtk DataFile Version 3.0\n".to_vec(),
            "legacy VTK",
        ),
        ("ct.vti", vti.as_bytes().to_vec(), "VTK XML"),
        ("IM0001", dicom(), "DICOM"),
    ];
    for (name, bytes, format) in files {
        let path = dir.join(name);
        std::fs::write(&path, &bytes).unwrap();
        let p = path.to_str().unwrap();
        // Its reader names the file (or the slice) and the field at fault.
        let err = usage_error(&dir, None, &["--volume", p]);
        assert!(err.starts_with(&format!("caveray: {p}: ")), "{err}");
        // --dims does not make such a file raw.
        let err = usage_error(&dir, None, &["--volume", p, "--dims", "8,8,8"]);
        let start = format!("caveray: {p} is a {format} file, whose header gives its size");
        assert!(err.starts_with(&start), "{err}\nlacks {start}");
    }
    // A folder of slices, which are often named without an extension.
    let series = dir.join("series");
    std::fs::create_dir_all(&series).unwrap();
    std::fs::write(series.join("IM0001"), dicom()).unwrap();
    let s = series.to_str().unwrap();
    let err = usage_error(&dir, None, &["--volume", s]);
    assert!(
        err.starts_with(&format!(
            "caveray: {s}: files: no DICOM image slices in the folder (the first file: {s}/IM0001: "
        )),
        "{err}"
    );
    // Compressed data: decompress it first.
    let gz = dir.join("ct.raw.gz");
    std::fs::write(&gz, [0x1f, 0x8b, 8, 0, 0, 0, 0, 0]).unwrap();
    let g = gz.to_str().unwrap();
    assert_eq!(
        usage_error(&dir, None, &["--volume", g]),
        format!(
            "caveray: {g} is gzip-compressed; caveray reads raw volumes uncompressed: \
             decompress it (gunzip -k {g}) and load the file it holds"
        )
    );
    // A folder without slices is neither a volume nor a name.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let err = usage_error(&dir, None, &["--volume", empty.to_str().unwrap()]);
    assert!(err.contains("is a folder without DICOM slices"), "{err}");
    // Raw files are still raw: their size is asked for.
    let raw = dir.join("ct.raw");
    std::fs::write(&raw, [0u8; 512]).unwrap();
    let err = usage_error(&dir, None, &["--volume", raw.to_str().unwrap()]);
    assert!(
        err.contains("is a raw file: give its size with --dims"),
        "{err}"
    );
    remove(&dir);
}

/// The longest side of the volume's box in the world, as `render`
/// reports where it landed.
fn shown_size(dir: &Path, config: Option<&Path>, extra: &[&str]) -> f64 {
    let result = match config {
        Some(config) => render_with(dir, None, config, extra),
        None => render_in(dir, None, extra),
    };
    assert!(
        result.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&result.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/timings.json")).unwrap())
            .unwrap();
    let corner = |i: usize| -> Vec<f64> {
        (0..3)
            .map(|k| report["volume"]["world_box"][i][k].as_f64().unwrap())
            .collect()
    };
    let (lo, hi) = (corner(0), corner(1));
    (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max)
}

#[test]
fn a_volume_is_shown_at_its_own_size_where_the_rig_or_the_command_line_says() {
    let dir = scratch("life_size");
    let scan = dir.join("scan.nii");
    // 12 x 10 x 8 voxels of 2 mm: 22 mm along its longest side.
    std::fs::write(&scan, nifti([12, 10, 8])).unwrap();
    let s = scan.to_str().unwrap();
    let close = |got: f64, want: f64, what: &str| {
        assert!(
            (got - want).abs() < 1e-3 * want,
            "{what}: {got}, not {want}"
        );
    };
    close(
        shown_size(&dir, None, &["--volume", s]),
        1300.0,
        "the rig's size",
    );
    close(
        shown_size(&dir, None, &["--volume", s, "--volume-units", "mm"]),
        22.0,
        "life size in the mm rig",
    );
    // The file states millimetres: a unit for data that do not is not its.
    close(
        shown_size(&dir, None, &["--volume", s, "--volume-units", "m"]),
        22.0,
        "the file's own unit",
    );
    // The rig says so in its [scene]; the command line's size still wins.
    let rig_text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("cave_configs/cologne_5wall.toml"),
    )
    .unwrap();
    let life = dir.join("life.toml");
    std::fs::write(&life, rig_text.replace("size = 1300", "units = \"mm\"")).unwrap();
    close(
        shown_size(&dir, Some(&life), &["--volume", s]),
        22.0,
        "scene.units",
    );
    close(
        shown_size(&dir, Some(&life), &["--volume", s, "--volume-size", "500"]),
        500.0,
        "--volume-size over scene.units",
    );
    // A manifest volume's spacing states no unit: metres, as told.
    let manifest = own_manifest(&dir, None);
    let m = manifest.to_str().unwrap();
    close(
        shown_size(
            &dir,
            None,
            &["--manifest", m, "--volume", "tiny", "--volume-units", "m"],
        ),
        14_000.0,
        "8 voxels spaced 2 along z, in metres, in a mm rig",
    );
    let both = dir.join("both.toml");
    std::fs::write(
        &both,
        rig_text.replace("size = 1300", "size = 1300\nunits = \"mm\""),
    )
    .unwrap();
    let result = render_with(&dir, None, &both, &["--volume", s]);
    let err = String::from_utf8(result.stderr).unwrap();
    assert_eq!(result.status.code(), Some(2), "{err}");
    assert!(
        err.contains("scene.units") && err.contains("give one of them"),
        "{err}"
    );
    remove(&dir);
}

#[test]
fn a_gpu_memory_budget_pages_what_is_past_it_and_refuses_what_holds_no_brick() {
    let dir = scratch("gpu_budget");
    // The phantom's 128^3 float32 voxels take 8 MiB as a texture; paged,
    // a brick of 64^3 takes 1 MiB.
    let result = render_in(
        &dir,
        None,
        &["--backend", "gpu", "--gpu-memory-budget", "1K"],
    );
    let err = String::from_utf8(result.stderr).unwrap();
    assert_eq!(result.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot allocate 1048576 bytes for one 64x64x64 brick of a 128x128x128 volume, past its share of the GPU memory budget of 1024 bytes"),
        "{err}"
    );
    assert!(!dir.join("out/timings.json").exists());
    let err = usage_error(&dir, None, &["--gpu-memory-budget", "6T"]);
    assert!(
        err.contains("expected bytes, or a number with K, M or G, got '6T'"),
        "{err}"
    );
    let err = usage_error(&dir, None, &["--gpu-memory-budget", "0"]);
    assert!(
        err.contains("expected a positive number of bytes (e.g. 6G), got '0'"),
        "{err}"
    );
    // A budget the scene fits in renders, and so does one it is paged
    // within.
    for budget in ["8M", "4M"] {
        let result = render_in(
            &dir,
            None,
            &["--backend", "gpu", "--gpu-memory-budget", budget],
        );
        assert!(
            result.status.success(),
            "{budget}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        let out = String::from_utf8_lossy(&result.stdout);
        let paged = out.contains("the volume is paged on the GPU");
        assert_eq!(paged, budget == "4M", "{budget}: {out}");
        if paged {
            assert!(out.contains("within a budget of 4.0 MiB"), "{out}");
        }
    }
    remove(&dir);
}

/// `tets:N` renders every wall as an unstructured volume, and `--array`
/// is refused for what is not a mesh file (tests/data/vtk_mesh.rs inspects
/// the files meshio writes).
#[test]
fn tetrahedra_render_on_every_wall_and_array_needs_a_mesh_file() {
    let dir = scratch("tets");
    let out = render_in(&dir, None, &["--volume", "tets:8", "--backend", "cpu"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let walls = std::fs::read_dir(dir.join("out"))
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with("_left.png"))
        .count();
    assert!(walls >= 5, "{walls} left-eye images");
    let out = render_in(&dir, None, &["--volume", "tets:8", "--array", "f"]);
    assert!(!out.status.success());
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains("--array names an array of a VTK unstructured grid or a variable of a FLASH file; 'tets:8' is neither"),
        "{said}"
    );
    remove(&dir);
}
