//! Which vector unit the CPU renderer's lane-parallel kernels run on: the
//! widest this CPU has, found once at run time, or one named by
//! `CAVERAY_SIMD` (`portable`, `avx2`, `avx512`) to compare paths. Every
//! kernel is one body compiled for each level, with the same arithmetic
//! (no fused multiply-adds the portable build lacks), so all levels give
//! the same bits.

use std::sync::OnceLock;

/// A kernel's build: the crate's baseline target, or one with AVX2 and
/// FMA, or one with AVX-512 (F, VL, DQ, BW) besides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// The build's baseline instructions (SSE2 on x86-64).
    Portable,
    Avx2,
    Avx512,
}

impl Level {
    pub const ALL: [Level; 3] = [Level::Portable, Level::Avx2, Level::Avx512];

    /// Whether this CPU runs code built for `self`.
    pub fn runs(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            match self {
                Level::Portable => true,
                Level::Avx2 => has!("avx2") && has!("fma"),
                Level::Avx512 => {
                    Level::Avx2.runs()
                        && has!("avx512f")
                        && has!("avx512vl")
                        && has!("avx512dq")
                        && has!("avx512bw")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self == Level::Portable
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Level::Portable => "portable",
            Level::Avx2 => "avx2",
            Level::Avx512 => "avx512",
        }
    }

    /// The widest level this CPU runs, or the one `CAVERAY_SIMD` names if
    /// this CPU runs it (a name it does not run, or does not know, leaves
    /// the widest).
    pub fn chosen() -> Level {
        static CHOSEN: OnceLock<Level> = OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let widest = Level::ALL
                .into_iter()
                .rev()
                .find(|l| l.runs())
                .unwrap_or(Level::Portable);
            std::env::var("CAVERAY_SIMD")
                .ok()
                .and_then(|v| Level::ALL.into_iter().find(|l| l.name() == v.trim()))
                .filter(|l| l.runs())
                .unwrap_or(widest)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_portable_level_always_runs_and_the_chosen_one_runs_here() {
        assert!(Level::Portable.runs());
        assert!(Level::chosen().runs());
        if Level::Avx512.runs() {
            assert!(Level::Avx2.runs(), "AVX-512 without AVX2");
        }
    }
}
