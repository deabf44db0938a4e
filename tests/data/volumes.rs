//! Volumes and transfer functions: raw files, the manifest, procedural
//! volumes, presets and ParaView color maps, and their error messages.

use crate::common;

use std::path::{Path, PathBuf};

use anari_library_caveray::data::{
    load_paraview, load_raw, marschner_lobb, preset, shepp_logan, solid_box, DataError, Manifest,
    VoxelType, PRESETS,
};
use anari_library_caveray::scene::{
    StructuredVolume, TransferFunction, TransferFunctionError, VolumeError, Voxels,
};
use glam::{UVec3, Vec3, Vec4};

/// A fresh scratch directory per test.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caveray-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_u16(path: &Path, values: &[u16]) {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn raw_files_load_little_endian_and_normalised() {
    let dir = scratch("raw");
    let path = dir.join("v.raw");
    write_u16(&path, &[0, 65535, 256, 1, 2, 3, 4, 5]);
    let v = load_raw(
        &path,
        UVec3::new(2, 2, 2),
        VoxelType::U16,
        Vec3::new(1.0, 1.0, 2.0),
    )
    .unwrap();
    assert_eq!(
        v.voxels(),
        &Voxels::U16(vec![0, 65535, 256, 1, 2, 3, 4, 5].into())
    );
    assert_eq!(v.value(1), 1.0);
    assert_eq!(v.value_range(), (0.0, 1.0));
    assert_eq!(v.bounds(), (Vec3::ZERO, Vec3::new(1.0, 1.0, 2.0)));
    // The file's bytes, mapped rather than copied; a mapped file must not
    // shrink while it is in use, so the volume goes before it is rewritten.
    assert!(v.voxels().is_mapped());
    drop(v);
    std::fs::write(&path, 1.5f32.to_le_bytes()).unwrap();
    let f = load_raw(&path, UVec3::ONE, VoxelType::F32, Vec3::ONE).unwrap();
    assert_eq!(f.value(0), 1.5);
}

#[test]
fn a_raw_file_of_the_wrong_size_names_both_numbers() {
    let dir = scratch("rawsize");
    let path = dir.join("short.raw");
    write_u16(&path, &[1, 2, 3]);
    let err = load_raw(&path, UVec3::new(4, 4, 2), VoxelType::U16, Vec3::ONE).unwrap_err();
    let text = err.to_string();
    assert!(
        matches!(
            err,
            DataError::FileSize {
                expected: 64,
                actual: 6,
                ..
            }
        ),
        "{text}"
    );
    assert!(
        text.contains("has 6 bytes") && text.contains("4x4x2 uint16 needs 64 bytes"),
        "{text}"
    );
    let err = load_raw(
        &dir.join("absent.raw"),
        UVec3::ONE,
        VoxelType::U8,
        Vec3::ONE,
    )
    .unwrap_err();
    assert!(err.to_string().contains("absent.raw"), "{err}");
    assert_eq!(
        VoxelType::parse("int7").unwrap_err().to_string(),
        "unknown voxel type 'int7' (expected uint8, uint16 or float32)"
    );
}

#[test]
fn bad_volumes_are_rejected() {
    let err = StructuredVolume::new(
        UVec3::new(0, 4, 4),
        Voxels::U8(vec![].into()),
        Vec3::ZERO,
        Vec3::ONE,
    )
    .unwrap_err();
    assert_eq!(
        err,
        VolumeError::ZeroDims {
            dims: UVec3::new(0, 4, 4)
        }
    );
    assert!(err.to_string().contains("0x4x4"));
    let err = StructuredVolume::new(
        UVec3::splat(2),
        Voxels::U8(vec![0; 7].into()),
        Vec3::ZERO,
        Vec3::ONE,
    )
    .unwrap_err();
    assert!(err.to_string().contains("needs 8 voxels, got 7"), "{err}");
    let err = StructuredVolume::new(
        UVec3::ONE,
        Voxels::U8(vec![0].into()),
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 1.0),
    )
    .unwrap_err();
    assert!(matches!(err, VolumeError::BadSpacing { .. }));
    let err = StructuredVolume::new(
        UVec3::new(2, 1, 1),
        Voxels::F32(vec![0.0, f32::NAN].into()),
        Vec3::ZERO,
        Vec3::ONE,
    )
    .unwrap_err();
    assert_eq!(err, VolumeError::NonFiniteVoxel { index: 1 });
}

#[test]
fn a_volume_can_be_placed_and_scaled() {
    let v = shepp_logan(9).placed(Vec3::new(10.0, 0.0, 0.0), 4.0);
    let (lo, hi) = v.bounds();
    assert!((lo - Vec3::new(8.0, -2.0, -2.0)).length() < 1e-5, "{lo}");
    assert!((hi - Vec3::new(12.0, 2.0, 2.0)).length() < 1e-5, "{hi}");
}

#[test]
fn procedural_volumes_have_known_values() {
    let n = 33;
    let centre = |v: &StructuredVolume| v.value((16 * n * n + 16 * n + 16) as usize);
    let phantom = shepp_logan(n);
    assert_eq!(phantom.dims(), UVec3::splat(n));
    assert_eq!(phantom.bounds(), (Vec3::splat(-1.0), Vec3::splat(1.0)));
    // The centre is inside the skull (1.0) and the brain (-0.8) only.
    assert!(
        (centre(&phantom) - 0.2).abs() < 1e-6,
        "{}",
        centre(&phantom)
    );
    assert_eq!(phantom.value(0), 0.0, "corners are outside the head");
    let (lo, hi) = phantom.value_range();
    assert!(lo >= 0.0 && hi <= 1.0 && hi > 0.9);
    // Marschner-Lobb at the origin: (1 - 0 + 0.25 (1 + cos 12 pi)) / 2.5 = 0.6.
    assert!((centre(&marschner_lobb(n)) - 0.6).abs() < 1e-5);
    assert_eq!(solid_box(5).value_range(), (1.0, 1.0));
}

#[test]
fn transfer_functions_interpolate_and_alpha_scales_opacity() {
    let tf = TransferFunction::new(
        vec![Vec4::new(0.0, 0.0, 1.0, 1.0), Vec4::new(1.0, 0.0, 0.0, 0.5)],
        vec![0.0, 0.5, 1.0],
        (0.0, 10.0),
        2.0,
    )
    .unwrap();
    assert_eq!(tf.evaluate(0.0), Vec4::new(0.0, 0.0, 1.0, 0.0));
    // Color halfway, opacity halfway (0.5), alpha 0.75 -> 0.375.
    assert_eq!(tf.evaluate(0.5), Vec4::new(0.5, 0.0, 0.5, 0.375));
    assert_eq!(tf.evaluate(2.0), Vec4::new(1.0, 0.0, 0.0, 0.5));
    let table = tf.table();
    assert_eq!(table.len(), anari_library_caveray::scene::TABLE_SIZE);
    assert_eq!(table[0], tf.evaluate(0.0));
    assert_eq!(*table.last().unwrap(), tf.evaluate(1.0));
}

#[test]
fn bad_transfer_functions_are_rejected() {
    let c = vec![Vec4::ONE];
    assert_eq!(
        TransferFunction::new(vec![], vec![1.0], (0.0, 1.0), 1.0).unwrap_err(),
        TransferFunctionError::Empty
    );
    let err = TransferFunction::new(c.clone(), vec![0.5, f32::NAN], (0.0, 1.0), 1.0).unwrap_err();
    assert_eq!(
        err.to_string(),
        "opacity[1] is not a finite number in [0, 1]"
    );
    let err = TransferFunction::new(
        vec![Vec4::ONE, Vec4::splat(2.0)],
        vec![1.0],
        (0.0, 1.0),
        1.0,
    )
    .unwrap_err();
    assert_eq!(
        err,
        TransferFunctionError::OutOfRange {
            what: "color",
            index: 1
        }
    );
    let err = TransferFunction::new(c.clone(), vec![1.0], (1.0, 1.0), 1.0).unwrap_err();
    assert!(
        err.to_string().contains("value range [1, 1] is empty"),
        "{err}"
    );
    assert!(TransferFunction::new(c.clone(), vec![1.0], (0.0, f32::INFINITY), 1.0).is_err());
    assert_eq!(
        TransferFunction::new(c, vec![1.0], (0.0, 1.0), 0.0).unwrap_err(),
        TransferFunctionError::UnitDistance(0.0)
    );
}

#[test]
fn every_preset_is_valid_and_unknown_ones_list_the_choices() {
    for name in PRESETS {
        let tf = preset(name).unwrap();
        assert_eq!(tf.value_range(), (0.0, 1.0));
        assert_eq!(
            tf.evaluate(0.0).w,
            0.0,
            "{name}: empty space stays transparent"
        );
        if name == "level-set" {
            // A signed distance: its surface is the middle of the range,
            // its outside the top, as empty as deep inside.
            assert!(tf.evaluate(0.5).w >= 0.5, "{name}: the surface shows");
            assert_eq!(tf.evaluate(1.0).w, 0.0, "{name}: the outside is clear");
        } else {
            assert!(
                tf.evaluate(1.0).w >= 0.25,
                "{name}: the densest values are visible"
            );
        }
        let most = tf.table().iter().map(|c| c.w).fold(0.0, f32::max);
        assert!(most >= 0.5, "{name}: something is clearly opaque");
    }
    let err = preset("rainbow").unwrap_err().to_string();
    assert!(
        err.contains("unknown transfer function preset 'rainbow'") && err.contains("ct-skin-bone"),
        "{err}"
    );
}

#[test]
fn paraview_color_maps_load() {
    let dir = scratch("paraview");
    let path = dir.join("map.json");
    std::fs::write(
        &path,
        r#"[{"Name": "no colors"}, {"Name": "test", "ColorSpace": "RGB",
            "RGBPoints": [100, 0, 0, 1,  300, 1, 0, 0],
            "Points": [100, 0, 0.5, 0,  200, 0.8, 0.5, 0,  300, 0.2, 0.5, 0]}]"#,
    )
    .unwrap();
    let tf = load_paraview(&path).unwrap();
    assert_eq!(tf.value_range(), (100.0, 300.0));
    // Opacity peaks at 200 even though no color point is there.
    let mid = tf.evaluate(0.5);
    assert!(
        (mid.w - 0.8).abs() < 0.01 && (mid.x - 0.5).abs() < 0.01,
        "{mid}"
    );
    assert!((tf.evaluate(1.0).w - 0.2).abs() < 1e-6);

    std::fs::write(&path, r#"{"RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]}"#).unwrap();
    let ramp = load_paraview(&path).unwrap();
    assert!(
        (ramp.evaluate(0.25).w - 0.25).abs() < 0.01,
        "opacity ramps without Points"
    );

    for (text, needle) in [
        ("{]", "not a ParaView color map"),
        (r#"{"Name": "x"}"#, "no entry has RGBPoints"),
        (r#"{"RGBPoints": [0, 1, 1]}"#, "groups of 4"),
        (
            r#"{"RGBPoints": [0, 1, 1, 1, 0, 1, 1, 1]}"#,
            "no value range",
        ),
        (r#"{"RGBPoints": [0, 1, "a", 1]}"#, "finite numbers"),
        (
            r#"{"RGBPoints": [0, 1, 1, 1, 1, 2, 2, 2]}"#,
            "is not a finite number in [0, 1]",
        ),
    ] {
        std::fs::write(&path, text).unwrap();
        let err = load_paraview(&path).unwrap_err().to_string();
        assert!(
            err.contains(needle) && err.contains("map.json"),
            "{text}: {err}"
        );
    }
}

fn write_manifest(dir: &Path, sha: &str) -> PathBuf {
    write_u16(
        &dir.join("tiny.raw"),
        &[0, 100, 200, 300, 400, 500, 600, 700],
    );
    let manifest = dir.join("volumes.toml");
    std::fs::write(
        &manifest,
        format!(
            "[[volume]]\nname = \"tiny\"\nfile = \"tiny.raw\"\ndims = [2, 2, 2]\ndtype = \"uint16\"\nspacing = [1, 1, 3]\nsha256 = \"{sha}\"\n"
        ),
    )
    .unwrap();
    manifest
}

#[test]
fn manifest_volumes_are_checked_before_use() {
    let dir = scratch("manifest");
    // sha256 of the 16 bytes written by write_manifest.
    let bytes: Vec<u8> = [0u16, 100, 200, 300, 400, 500, 600, 700]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let good = sha256_hex(&bytes);
    let manifest = Manifest::load(&write_manifest(&dir, &good)).unwrap();
    let v = manifest.load_volume("TINY").unwrap();
    assert_eq!(v.spacing(), Vec3::new(1.0, 1.0, 3.0));
    let err = manifest.load_volume("engine").unwrap_err().to_string();
    assert!(
        err.contains("no volume named 'engine'") && err.contains("known: tiny"),
        "{err}"
    );

    let bad = Manifest::load(&write_manifest(&dir, &"0".repeat(64))).unwrap();
    let err = bad.load_volume("tiny").unwrap_err();
    assert!(matches!(err, DataError::Checksum { .. }), "{err}");
    assert!(err.to_string().contains(&good), "{err}");

    std::fs::write(dir.join("volumes.toml"), "[[volume]]\nname = 1\n").unwrap();
    let err = Manifest::load(&dir.join("volumes.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("volumes.toml") && err.contains("invalid type"),
        "{err}"
    );
    let err = Manifest::locate(Some(&dir.join("none.toml")), &[])
        .unwrap_err()
        .to_string();
    assert!(err.contains("none.toml"), "{err}");
}

#[test]
fn manifest_errors_name_the_line_and_column() {
    let m = Path::new("data/volumes.toml");
    let entry = "[[volume]]\nname = \"tiny\"\nfile = \"tiny.raw\"\ndims = [2, 2, 2]\n\
                 dtype = \"uint16\"\nspacing = [1, 1, 3]\n";
    assert!(Manifest::parse(entry, m).is_ok());
    for (from, to, message) in [
        // Syntax: placed at the cause, not where the parser gave up.
        (
            "dims = [2, 2, 2]",
            "dims = [2, 2, 2",
            "data/volumes.toml:4:8: unclosed '[': the array opened here is not closed before line 5 (expected `]`)",
        ),
        (
            "name = \"tiny\"",
            "name = \"tiny",
            "data/volumes.toml:2:8: unclosed string: the \" here is not closed on its line",
        ),
        // Schema: where the wrong value is.
        (
            "dims = [2, 2, 2]",
            "dims = [2, 2]",
            "data/volumes.toml:4:8: invalid length 2, expected an array of length 3",
        ),
    ] {
        let text = entry.replacen(from, to, 1);
        let err = Manifest::parse(&text, m).unwrap_err();
        assert!(matches!(err, DataError::Manifest { .. }), "{err}");
        assert_eq!(err.to_string(), message, "{text}");
    }
}

/// SHA-256 through the system's sha256sum, as an independent check.
fn sha256_hex(bytes: &[u8]) -> String {
    use std::io::Write;
    let mut child = std::process::Command::new("sha256sum")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("sha256sum is part of coreutils");
    child.stdin.take().unwrap().write_all(bytes).unwrap();
    let out = child.wait_with_output().unwrap();
    String::from_utf8(out.stdout)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .to_string()
}

#[test]
fn the_shared_real_volumes_load() {
    let path = common::shared_manifest();
    if !path.is_file() {
        common::missing(&format!("{} is absent", path.display()));
        return;
    }
    let manifest = Manifest::load(&path).unwrap();
    for entry in manifest.entries().iter().filter(|e| e.small) {
        let v = manifest
            .load_volume(&entry.name)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(v.dims(), UVec3::from_array(entry.dims), "{}", entry.name);
        let (lo, hi) = v.value_range();
        assert!(hi > lo, "{}: constant volume", entry.name);
    }
}

#[test]
fn sizes_that_overflow_or_exceed_the_budget_are_refused_before_reading() {
    let dir = scratch("rawhuge");
    let empty = dir.join("empty.raw");
    std::fs::write(&empty, []).unwrap();
    // 2^64 bytes would wrap to 0 as a byte count: refused by its voxel count.
    for dims in [
        UVec3::splat(u32::MAX),
        UVec3::new(1 << 16, 1 << 16, 1 << 16),
    ] {
        let err = load_raw(&empty, dims, VoxelType::F32, Vec3::ONE).unwrap_err();
        assert!(matches!(err, DataError::TooManyVoxels { .. }), "{err}");
        assert!(
            err.to_string().contains("4294967296 voxels at most"),
            "{err}"
        );
    }
    // A 3 GB (sparse) file for an 8^3 volume: refused by its size, unread.
    let big = dir.join("big.raw");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(3 << 30)
        .unwrap();
    let err = load_raw(&big, UVec3::splat(8), VoxelType::U8, Vec3::ONE).unwrap_err();
    assert!(
        err.to_string()
            .ends_with("has 3221225472 bytes, but 8x8x8 uint8 needs 512 bytes"),
        "{err}"
    );
    for special in ["/dev/zero", "/tmp"] {
        let err = load_raw(
            Path::new(special),
            UVec3::splat(8),
            VoxelType::U8,
            Vec3::ONE,
        )
        .unwrap_err();
        assert!(err.to_string().contains("not a regular file"), "{err}");
    }
    let err = load_paraview(Path::new("/dev/zero")).unwrap_err();
    assert!(err.to_string().contains("not a regular file"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_manifest_entry_says_which_way_up_its_data_is() {
    use anari_library_caveray::geometry::VolumeAxis;
    let entry = |extra: &str| {
        format!(
            "[[volume]]\nname = \"a\"\nfile = \"a.raw\"\ndims = [2, 2, 2]\n\
             dtype = \"uint8\"\nspacing = [1, 1, 1]\n{extra}\n"
        )
    };
    let path = Path::new("volumes.toml");
    let stated = Manifest::parse(&entry("up = \"-z\"\nfront = \"+y\""), path).unwrap();
    let o = stated.find("a").unwrap().orientation();
    assert_eq!(
        (o.up, o.front),
        (Some(VolumeAxis::NegZ), Some(VolumeAxis::PosY))
    );
    // The Stanford CT head's hash names it; an entry that states an axis
    // is taken at its word.
    let cthead = "sha256 = \"8a378356d37fc55a977032375b1bd34298c0b137167dd0f05e025d66e0ae5d94\"";
    let known = Manifest::parse(&entry(cthead), path).unwrap();
    let o = known.find("a").unwrap().orientation();
    assert_eq!(
        (o.up, o.front),
        (Some(VolumeAxis::NegZ), Some(VolumeAxis::NegY))
    );
    let own = Manifest::parse(&entry(&format!("{cthead}\nup = \"+x\"")), path).unwrap();
    let o = own.find("a").unwrap().orientation();
    assert_eq!((o.up, o.front), (Some(VolumeAxis::PosX), None));
    let plain = Manifest::parse(&entry(""), path).unwrap();
    assert_eq!(plain.find("a").unwrap().orientation().up, None);

    let err = Manifest::parse(&entry("up = \"sideways\""), path).unwrap_err();
    assert!(err.to_string().contains("'sideways'"), "{err}");
}
