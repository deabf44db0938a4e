//! NanoVDB grids written at test time by the NanoVDB library itself
//! (tests/writers/nanovdb_grids.cpp over Debian's libnanovdb-dev): a fog
//! sphere as Float, Fp16, Fp8 and Fp4 values (and finer, as Float) and a level-set torus, each
//! as its in-memory blob, as the library's value at every voxel of its
//! index box, and all of them in one .nvdb file.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use std::sync::Arc;

use anari_library_caveray::scene::{
    Filter, NanoVdbGrid, ObjectIds, PlacedVolume, Scene, SpatialField, StructuredVolume,
    TransferFunction, Voxels,
};
use glam::{Mat4, UVec3, Vec3};
use serde_json::Value;

pub struct Written {
    pub dir: PathBuf,
    /// Per grid: type, lo and hi (index box), world_lo, voxel, active,
    /// bytes, background.
    pub grids: Value,
}

impl Written {
    pub fn blob(&self, name: &str) -> Vec<u8> {
        std::fs::read(self.dir.join(format!("{name}.blob"))).unwrap()
    }

    pub fn file(&self) -> PathBuf {
        self.dir.join("grids.nvdb")
    }

    /// Grid `name` sampled with `filter`.
    pub fn grid(&self, name: &str, filter: Filter) -> NanoVdbGrid {
        NanoVdbGrid::new(&self.blob(name), filter).unwrap()
    }

    /// The grid's index box as a structured grid of the library's values,
    /// placed where the grid's map puts it.
    pub fn dense(&self, name: &str) -> StructuredVolume {
        let g = &self.grids[name];
        let v3 = |k: &str| -> [f64; 3] { std::array::from_fn(|i| g[k][i].as_f64().unwrap()) };
        let (lo, hi) = (v3("lo"), v3("hi"));
        let dims = UVec3::from_array(std::array::from_fn(|i| (hi[i] - lo[i]) as u32 + 1));
        let bytes = std::fs::read(self.dir.join(format!("{name}.f32"))).unwrap();
        let values: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let world_lo = Vec3::from_array(v3("world_lo").map(|x| x as f32));
        let voxel = g["voxel"].as_f64().unwrap() as f32;
        StructuredVolume::new(
            dims,
            Voxels::F32(values.into()),
            world_lo,
            Vec3::splat(voxel),
        )
        .unwrap()
    }
}

/// The grids, written once per test binary; None where the NanoVDB
/// headers are missing (CI fails then).
pub fn grids() -> Option<&'static Written> {
    static WRITTEN: OnceLock<Option<Written>> = OnceLock::new();
    WRITTEN.get_or_init(write).as_ref()
}

fn write() -> Option<Written> {
    if !Path::new("/usr/include/nanovdb/NanoVDB.h").exists() {
        super::missing("the NanoVDB headers (Debian's libnanovdb-dev, installed by scripts/deps)");
        return None;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let source = root.join("tests/writers/nanovdb_grids.cpp");
    // One writer for every test binary: built again only when its source
    // is newer.
    let tools = Path::new(env!("CARGO_TARGET_TMPDIR")).join("writers");
    std::fs::create_dir_all(&tools).unwrap();
    let exe = tools.join("nanovdb_grids");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if modified(&exe) < modified(&source) {
        let partial = tools.join(format!("nanovdb_grids.{}", std::process::id()));
        let built = Command::new("c++")
            .args(["-std=c++17", "-O1", "-Wall", "-Wextra", "-Werror"])
            .arg(&source)
            .arg("-o")
            .arg(&partial)
            .output()
            .expect("a C++ compiler");
        assert!(
            built.status.success(),
            "compiling the NanoVDB writer: {}",
            String::from_utf8_lossy(&built.stderr)
        );
        std::fs::rename(&partial, &exe).unwrap();
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "nanovdb_grids_{}",
        std::env::current_exe()
            .unwrap()
            .file_stem()
            .unwrap()
            .to_string_lossy()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let run = Command::new(&exe).arg(&dir).output().unwrap();
    assert!(
        run.status.success(),
        "the NanoVDB writer: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    Some(Written {
        dir,
        grids: serde_json::from_slice(&run.stdout).unwrap(),
    })
}

/// `volume` under `tf`, scaled by 0.15: the grids' ten-odd units fit the
/// tests' views of a unit volume.
pub fn scene(volume: impl Into<SpatialField>, tf: TransferFunction) -> Scene {
    Scene::placed(vec![PlacedVolume {
        volume: Arc::new(volume.into()),
        transfer_function: Arc::new(tf),
        transform: Mat4::from_scale(Vec3::splat(0.15)),
        ids: ObjectIds::NONE,
    }])
    .unwrap()
}
