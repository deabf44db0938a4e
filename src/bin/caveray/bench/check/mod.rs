//! `caveray bench check`: the ratios that make caveray what it is, measured
//! within one run at tiny sizes (CPU and lavapipe, a few minutes on two
//! cores), against a baseline committed beside the code
//! (`bench_results/baseline.json`). A figure fails when it is worse than
//! its baseline by more than its rule's margin, or crosses its rule's
//! limit; the check prints which, with both numbers, and exits non-zero.
//! Each figure is a ratio of two things measured in the same run (or a
//! size, or an image's likeness), so a machine's speed or load cancels out.
//! Writing the baseline is deliberate: `--write-baseline REASON`.

mod measure;

use std::collections::BTreeMap;
use std::path::PathBuf;

use clap::Args;
use serde::{Deserialize, Serialize};

use crate::report::{write_json, Machine};
use crate::Failure;

#[derive(Args)]
pub struct CheckArgs {
    /// The committed baseline to compare with.
    #[arg(long, default_value = "bench_results/baseline.json")]
    baseline: PathBuf,
    /// Where this run's figures (check.json) and the reports of the
    /// benchmarks it runs go.
    #[arg(long, default_value = "out/bench/check")]
    out: PathBuf,
    /// Write this run's figures as the new baseline, with the reason for
    /// the change (a deliberate commit: say why the figures moved).
    #[arg(long, value_name = "REASON")]
    write_baseline: Option<String>,
}

/// Which way a figure improves.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
enum Better {
    Higher,
    Lower,
}

/// What a figure is and what it must stay within.
struct Rule {
    /// The figure's name; a name ending in `.*` covers every figure that
    /// begins with what comes before (one per wall).
    name: &'static str,
    what: &'static str,
    better: Better,
    /// The most a figure may be worse than its baseline, as a factor
    /// (worse: value / baseline where lower is better, baseline / value
    /// where higher is). None: compared with its limit only (a figure near
    /// zero, or one whose noise is its whole size).
    margin: Option<f64>,
    /// The value it must not cross whatever the baseline: the least where
    /// higher is better, the most where lower is.
    limit: Option<f64>,
}

const RULES: &[Rule] = &[
    Rule {
        name: "stereo.pair_over_left",
        what: "Buchacher & Erdt's protocol (cthead, 128², 32 layers, 8 views): the re-projected pair (T_l+r) over one eye (T_l), median over the views; at 2 a pair costs two passes",
        better: Better::Lower,
        margin: Some(1.5),
        limit: Some(2.0),
    },
    Rule {
        name: "stereo.dssim_max",
        what: "the same: the re-projected right eye's largest DSSIM against its own pass",
        better: Better::Lower,
        margin: None,
        limit: Some(0.01),
    },
    Rule {
        name: "walk.front_pair_over_left",
        what: "the CAVE walk (Cologne rig, scale 0.05, the CT head lying as in benchmarks.md, 16 frames, each pass the fastest of 3): the front wall's re-projected pair over one eye, median over the frames",
        better: Better::Lower,
        margin: Some(1.5),
        limit: Some(2.0),
    },
    Rule {
        name: "walk.planned_v",
        what: "the same walk: V with the cost planner's path on every wall-frame, over all walls (the share of a second pass saved)",
        better: Better::Higher,
        margin: None,
        limit: Some(0.25),
    },
    Rule {
        name: "walk.planned_v.*",
        what: "the same, per wall that sees the volume: the planner never costs much more than two passes",
        better: Better::Higher,
        margin: None,
        limit: Some(-0.15),
    },
    Rule {
        name: "walk.dssim_max",
        what: "the same: the largest DSSIM of a re-projected wall-frame",
        better: Better::Lower,
        margin: None,
        limit: Some(0.02),
    },
    Rule {
        name: "cpu.packets_over_scalar",
        what: "the CPU renderer's packets (as wide as the CPU runs) against the scalar reference, both marching every step (cthead, 128², 4 views, each way three times, interleaved): the reference's fastest time over the packets', median over the views",
        better: Better::Higher,
        margin: Some(1.5),
        limit: Some(1.5),
    },
    Rule {
        name: "cpu.avx512_over_avx2",
        what: "the CPU renderer's packets sixteen samples wide (AVX-512) against eight (AVX2), skipping on (the same views, interleaved): the AVX2 time over the AVX-512 time; measured only on CPUs with AVX-512",
        better: Better::Higher,
        margin: Some(1.25),
        limit: Some(1.0),
    },
    Rule {
        name: "cpu.skipping_speedup",
        what: "empty-space skipping on the CPU (the same views, interleaved): time with skipping off over time with it on",
        better: Better::Higher,
        margin: Some(1.5),
        limit: Some(1.2),
    },
    Rule {
        name: "cpu.wide_over_binary",
        what: "the CPU's surface traversal: the nearest hits of the same rays on the CT head's isosurface (stride 4) in the binary BVH the GPU takes over the CPU's wide one (eight children a node, triangles in blocks of eight, the widest SIMD this CPU runs), fastest of four interleaved, median over 4 views, one thread",
        better: Better::Higher,
        margin: Some(1.5),
        limit: Some(1.2),
    },
    Rule {
        name: "cpu.surface_packets_speedup",
        what: "camera rays traced to their first surface eight together (blocks of 4 x 2 pixels going down the wide BVH as one) against one by one, on the CT head's isosurface (stride 4), fastest of four interleaved, median over 4 views, one thread; both must find hits at the same distances: the single rays' time over the packets'",
        better: Better::Higher,
        margin: Some(1.25),
        limit: Some(1.0),
    },
    Rule {
        name: "cpu.tets_over_grid",
        what: "an unstructured field on the CPU: a frame of the Marschner-Lobb signal on 33^3 vertices cut into 196,608 tetrahedra over a frame of the same grid (128², 4 views, interleaved, skipping on), median over the views; the tetrahedra are found by walking from cell to cell",
        better: Better::Lower,
        margin: Some(1.5),
        limit: None,
    },
    Rule {
        name: "gpu.tets_over_grid",
        what: "the same on the GPU (lavapipe): the tetrahedra's frame over the grid's",
        better: Better::Lower,
        margin: Some(1.5),
        limit: None,
    },
    Rule {
        name: "gpu.skipping_speedup",
        what: "the same on the GPU (lavapipe)",
        better: Better::Higher,
        margin: Some(1.5),
        limit: Some(1.2),
    },
    Rule {
        name: "gpu.lod_speedup",
        what: "level of detail on the GPU (filtered sampling, the same views, interleaved): full detail's time over level of detail 2's",
        better: Better::Higher,
        margin: Some(1.5),
        limit: Some(1.1),
    },
    Rule {
        name: "gpu.lod_ssim",
        what: "the same: level of detail 2's image against the exact path's full detail (SSIM, first view)",
        better: Better::Higher,
        margin: None,
        limit: Some(0.9),
    },
    Rule {
        name: "deadline.worst_age_over_render",
        what: "frames with an 8 ms deadline through the device (CPU, a camera moving for 120 refreshes of a 90 Hz display, ambient occlusion): the oldest image shown over the time of one whole render",
        better: Better::Lower,
        margin: Some(1.5),
        limit: Some(5.0),
    },
    Rule {
        name: "memory.cpu_bytes_per_voxel",
        what: "bytes the CPU renderer holds per voxel of a uint16 volume (cthead): the stored voxels and its f32 copy for the packets",
        better: Better::Lower,
        margin: Some(1.1),
        limit: None,
    },
    Rule {
        name: "memory.gpu_bytes_per_voxel",
        what: "bytes the GPU renderer holds per voxel of the same volume, host memory and textures together",
        better: Better::Lower,
        margin: Some(1.1),
        limit: None,
    },
    Rule {
        name: "memory.cpu_bytes_per_triangle",
        what: "bytes per triangle of an indexed mesh (the CT head's isosurface, stride 4) as the CPU traces it: the shape and its BVH",
        better: Better::Lower,
        margin: Some(1.1),
        limit: None,
    },
    Rule {
        name: "memory.gpu_bytes_per_triangle",
        what: "the same mesh's bytes per triangle in the GPU's surface buffers",
        better: Better::Lower,
        margin: Some(1.1),
        limit: None,
    },
    Rule {
        name: "gpu_cpu.ssim",
        what: "the GPU's image against the CPU reference's (cthead, 128², one view of the protocol)",
        better: Better::Higher,
        margin: None,
        limit: Some(0.999),
    },
];

fn rule(name: &str) -> Option<&'static Rule> {
    RULES.iter().find(|r| match r.name.strip_suffix('*') {
        Some(prefix) => name.starts_with(prefix),
        None => r.name == name,
    })
}

/// The committed baseline.
#[derive(Serialize, Deserialize)]
struct Baseline {
    /// Why these figures are the baseline (what changed them).
    reason: String,
    machine: serde_json::Value,
    figures: BTreeMap<String, f64>,
}

/// One figure as this run judged it.
#[derive(Serialize)]
struct Judged {
    name: String,
    what: &'static str,
    value: f64,
    baseline: Option<f64>,
    better: Better,
    margin: Option<f64>,
    limit: Option<f64>,
    /// How many times worse than the baseline (below 1: better).
    worse_by: Option<f64>,
    /// Why it fails, if it does.
    failure: Option<String>,
}

/// What `caveray bench check` writes to `check.json`.
#[derive(Serialize)]
struct CheckReport {
    benchmark: &'static str,
    machine: Machine,
    seconds: f64,
    figures: Vec<Judged>,
    failures: usize,
}

pub fn run(args: CheckArgs) -> Result<(), Failure> {
    let started = std::time::Instant::now();
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", args.out.display())))?;
    // Read first: a missing or broken baseline should not wait minutes.
    let baseline = match &args.write_baseline {
        Some(_) => None,
        None => Some(read_baseline(&args.baseline)?),
    };
    let figures = measure::all(&args.out)?;
    for name in figures.keys() {
        if rule(name).is_none() {
            return Err(Failure::Runtime(format!(
                "internal: bench check measured '{name}', which no rule states"
            )));
        }
    }
    let judged: Vec<Judged> = figures
        .iter()
        .map(|(name, &value)| {
            let base = baseline.as_ref().and_then(|b| b.figures.get(name).copied());
            judge(name, value, base, baseline.is_some())
        })
        .collect();
    let failures = judged.iter().filter(|j| j.failure.is_some()).count();
    let report = CheckReport {
        benchmark: "check",
        machine: Machine::this(),
        seconds: started.elapsed().as_secs_f64(),
        figures: judged,
        failures,
    };
    let path = args.out.join("check.json");
    write_json(&report, &path)?;
    print_table(&report);
    println!("wrote {} ({:.0} s)", path.display(), report.seconds);
    if let Some(reason) = args.write_baseline {
        // A baseline that crosses a limit would pass what must fail.
        if failures > 0 {
            return Err(Failure::Runtime(format!(
                "bench check: not writing {}: {failures} figure(s) cross their limits",
                args.baseline.display()
            )));
        }
        let baseline = Baseline {
            reason,
            machine: serde_json::to_value(Machine::this())
                .map_err(|e| Failure::Runtime(e.to_string()))?,
            figures,
        };
        write_json(&baseline, &args.baseline)?;
        println!("wrote the baseline {}", args.baseline.display());
        return Ok(());
    }
    if failures > 0 {
        let which: Vec<String> = report
            .figures
            .iter()
            .filter_map(|j| j.failure.as_ref().map(|f| format!("{}: {f}", j.name)))
            .collect();
        return Err(Failure::Runtime(format!(
            "bench check: {failures} of {} figures fail against {}:\n  {}",
            report.figures.len(),
            args.baseline.display(),
            which.join("\n  ")
        )));
    }
    println!(
        "bench check: all {} figures within their margins and limits",
        report.figures.len()
    );
    Ok(())
}

fn read_baseline(path: &std::path::Path) -> Result<Baseline, Failure> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        Failure::Runtime(format!(
            "cannot read the baseline {}: {e} (write one with --write-baseline REASON)",
            path.display()
        ))
    })?;
    serde_json::from_str(&text)
        .map_err(|e| Failure::Runtime(format!("the baseline {}: {e}", path.display())))
}

/// `value` of figure `name` against its rule and its baseline `base`
/// (`compare`: whether there is a baseline to compare with at all).
fn judge(name: &str, value: f64, base: Option<f64>, compare: bool) -> Judged {
    let Some(r) = rule(name) else {
        unreachable!("run checks every figure has a rule")
    };
    // Only a figure with a margin is a ratio to its baseline: a share
    // near zero (a wall's V) has none worth dividing by.
    let worse_by = base.filter(|_| r.margin.is_some()).map(|b| match r.better {
        Better::Lower => value / b,
        Better::Higher => b / value,
    });
    let crossed = r.limit.filter(|&limit| {
        value.is_nan()
            || match r.better {
                Better::Lower => value > limit,
                Better::Higher => value < limit,
            }
    });
    let failure = if let Some(limit) = crossed {
        Some(format!(
            "{} crosses its limit {} ({} is better; baseline {})",
            number(value),
            number(limit),
            if r.better == Better::Higher {
                "higher"
            } else {
                "lower"
            },
            base.map_or("none".into(), number)
        ))
    } else if let (Some(margin), Some(b), Some(w)) = (r.margin, base, worse_by) {
        (w.is_nan() || w > margin).then(|| {
            format!(
                "{} is {w:.2}x worse than the baseline {} (margin {margin}x)",
                number(value),
                number(b)
            )
        })
    } else if compare && base.is_none() && r.margin.is_some() {
        Some(format!(
            "{} has no baseline: measure one with --write-baseline REASON",
            number(value)
        ))
    } else {
        None
    };
    Judged {
        name: name.to_string(),
        what: r.what,
        value,
        baseline: base,
        better: r.better,
        margin: r.margin,
        limit: r.limit,
        worse_by,
        failure,
    }
}

fn number(x: f64) -> String {
    anari_library_caveray::geometry::Rounded(x).to_string()
}

fn print_table(report: &CheckReport) {
    println!(
        "{:<34} {:>10} {:>10} {:>8} {:>7} {:>8}  verdict",
        "figure", "now", "baseline", "worse", "margin", "limit"
    );
    for j in &report.figures {
        let opt = |x: Option<f64>| x.map_or("-".into(), number);
        println!(
            "{:<34} {:>10} {:>10} {:>8} {:>7} {:>8}  {}",
            j.name,
            number(j.value),
            opt(j.baseline),
            j.worse_by.map_or("-".into(), |w| format!("{w:.2}x")),
            opt(j.margin),
            opt(j.limit),
            if j.failure.is_some() { "FAIL" } else { "ok" }
        );
    }
    for j in &report.figures {
        if let Some(f) = &j.failure {
            println!("FAIL {}: {f}", j.name);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rule_has_a_margin_or_a_limit_and_names_one_figure_family() {
        for r in RULES {
            assert!(r.margin.is_some() || r.limit.is_some(), "{}", r.name);
            assert!(r.margin.is_none_or(|m| m > 1.0), "{}", r.name);
            assert_eq!(
                rule(r.name.trim_end_matches('*')).map(|f| f.name),
                Some(r.name)
            );
        }
    }

    #[test]
    fn a_figure_fails_past_its_margin_or_its_limit_and_says_both_numbers() {
        // Lower is better, margin 1.5, limit 2.
        let ok = judge("stereo.pair_over_left", 1.4, Some(1.2), true);
        assert!(ok.failure.is_none());
        let slower = judge("stereo.pair_over_left", 1.9, Some(1.2), true);
        assert_eq!(
            slower.failure.as_deref(),
            Some("1.9 is 1.58x worse than the baseline 1.2 (margin 1.5x)")
        );
        let crossed = judge("stereo.pair_over_left", 4.2, Some(3.5), true);
        assert_eq!(
            crossed.failure.as_deref(),
            Some("4.2 crosses its limit 2 (lower is better; baseline 3.5)")
        );
        // Higher is better: a speed-up that halves fails its margin.
        let halved = judge("cpu.skipping_speedup", 1.3, Some(2.6), true);
        assert!(halved.failure.unwrap().contains("2.00x worse"));
        // Per-wall figures share one rule; NaN never passes.
        assert!(judge("walk.planned_v.left", -0.05, None, false)
            .failure
            .is_none());
        assert!(judge("walk.planned_v.left", f64::NAN, Some(0.1), true)
            .failure
            .is_some());
        // A figure with a margin but no baseline fails a comparison; one
        // with a limit alone needs none.
        assert!(judge("cpu.skipping_speedup", 2.0, None, true)
            .failure
            .unwrap()
            .contains("no baseline"));
        assert!(judge("gpu_cpu.ssim", 1.0, None, true).failure.is_none());
    }
}
