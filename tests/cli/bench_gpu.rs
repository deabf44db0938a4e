//! `scripts/bench-gpu`, the one command for a machine with a GPU, at its
//! token size (GPU_BENCH_QUICK=1) on lavapipe: every benchmark writes its
//! JSON with the adapter, timed without the shader cache, and the summary
//! holds every table; on a software adapter it says these are not GPU
//! timings; where the CPU has AVX-512, its volume packets run at both
//! widths.

use std::process::Command;

use serde_json::Value;

#[test]
fn the_gpu_benchmark_script_writes_every_report_with_its_adapter() {
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("bench_gpu");
    let _ = std::fs::remove_dir_all(&out);
    let result = Command::new("bash")
        .arg("scripts/bench-gpu")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("CAVERAY", env!("CARGO_BIN_EXE_caveray"))
        .env("GPU_BENCH_QUICK", "1")
        .env("GPU_BENCH_OUT", &out)
        .env_remove("MESA_SHADER_CACHE_DISABLE")
        .output()
        .expect("bash runs scripts/bench-gpu");
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    assert!(stderr.contains("the adapter is a software one"), "{stderr}");
    let summary = std::fs::read_to_string(out.join("summary.txt")).unwrap();
    for name in [
        "stereo",
        "raycast",
        "raycast lod 1",
        "raycast lod 2",
        "raycast lod 4",
        "cave-stereo",
        "autostereo",
        "surfaces",
        "surfaces bumpy",
    ] {
        assert!(
            summary.contains(&format!("== {name}: caveray bench")),
            "{name}:\n{summary}"
        );
    }
    for file in [
        "stereo",
        "raycast",
        "raycast_lod1",
        "raycast_lod2",
        "raycast_lod4",
        "cave_stereo",
        "autostereo",
        "surfaces",
        "surfaces_bumpy",
    ] {
        let path = out.join(format!("{file}.json"));
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let report: Value = serde_json::from_str(&text).unwrap();
        // Each report names its adapter wherever it ran on the GPU.
        let mut adapters = Vec::new();
        find(&report, &mut adapters);
        assert!(!adapters.is_empty(), "{file}: no adapter");
        for a in adapters {
            assert_eq!(a["device_type"], "Cpu", "{file}: {a}");
            assert_eq!(a["shader_cache"], "disabled", "{file}: {a}");
        }
    }
    // Where the CPU has AVX-512, its volume packets at each width, the
    // width each report says.
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    if cpuinfo.split_whitespace().any(|flag| flag == "avx512f") {
        for round in [1, 2] {
            for simd in ["avx2", "avx512"] {
                assert!(summary.contains(&format!("== cpu {simd} {round}: caveray bench raycast")));
                let path = out.join(format!("cpu_simd_{simd}_{round}.json"));
                let report: Value =
                    serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
                assert_eq!(report["cpu_packets"], simd, "{}", path.display());
            }
        }
    }
}

/// Every object with an `adapter` field in `v`.
fn find<'a>(v: &'a Value, found: &mut Vec<&'a Value>) {
    match v {
        Value::Object(m) => {
            if m.contains_key("adapter") && m.contains_key("shader_cache") {
                found.push(v);
            }
            m.values().for_each(|x| find(x, found));
        }
        Value::Array(a) => a.iter().for_each(|x| find(x, found)),
        _ => {}
    }
}
