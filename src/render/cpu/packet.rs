//! Consecutive primary samples of one ray through one trilinear volume,
//! classified at once in vector lanes: the CPU's fast path, sixteen at a
//! time in AVX-512 lanes, or eight in AVX2 lanes. The arithmetic is the
//! reference's (sample.rs) but for two roundings: grid points come from
//! the ray's grid origin and direction (g = go + gd t, not M (o + d t)),
//! and the opacity correction's power from a log2/exp2 pair good to about
//! 1e-7. Both widths compute each sample alike, bit for bit; compositing
//! sums the lanes in another order. Where AVX2 and FMA are missing, or
//! the scene is not one trilinear volume, the march takes the scalar path.

use glam::{UVec3, Vec3, Vec4};

use crate::render::simd::Level;
use crate::scene::TABLE_SIZE;

/// Samples per packet at most (AVX-512's).
pub(super) const MAX_LANES: usize = 16;

/// Samples per packet at `level`.
pub(super) fn lanes(level: Level) -> usize {
    match level {
        Level::Avx512 => 16,
        _ => 8,
    }
}

/// A table split into channels, so that lanes gather one float each.
pub(super) struct Channels {
    r: [f32; TABLE_SIZE],
    g: [f32; TABLE_SIZE],
    b: [f32; TABLE_SIZE],
    a: [f32; TABLE_SIZE],
}

impl Channels {
    pub fn new(table: &[Vec4]) -> Box<Self> {
        let mut c = Box::new(Self {
            r: [0.0; TABLE_SIZE],
            g: [0.0; TABLE_SIZE],
            b: [0.0; TABLE_SIZE],
            a: [0.0; TABLE_SIZE],
        });
        for (i, e) in table.iter().take(TABLE_SIZE).enumerate() {
            (c.r[i], c.g[i], c.b[i], c.a[i]) = (e.x, e.y, e.z, e.w);
        }
        c
    }
}

/// The ray parameters of a packet's samples: sample m is at the middle
/// of full step k + m from t0, t0 + (k + m) step + step / 2, computed in
/// the lanes in the march's own order of operations.
#[derive(Clone, Copy, Debug)]
pub(super) struct Steps {
    pub t0: f32,
    pub k: u32,
    pub step: f32,
}

impl Steps {
    /// Sample m's t, as the lanes compute it.
    pub fn t(&self, m: usize) -> f32 {
        self.t0 + (self.k + m as u32) as f32 * self.step + 0.5 * self.step
    }
}

/// One volume as the packet path reads it.
pub(super) struct PacketGrid<'a> {
    /// AVX2 or AVX-512: the lanes' width.
    pub level: Level,
    pub values: &'a [f32],
    pub dims: [i32; 3],
    pub channels: &'a Channels,
    pub value_lo: f32,
    pub value_scale: f32,
}

/// A packet's samples' straight color and corrected opacity (0:
/// nothing), in its first `lanes` lanes.
#[derive(Clone, Copy)]
pub(super) struct Packet {
    /// Straight color, a channel at a time.
    pub rgb: [[f32; MAX_LANES]; 3],
    pub alpha: [f32; MAX_LANES],
    /// Some sample shows.
    pub any: bool,
    pub lanes: usize,
}

impl Packet {
    fn empty(lanes: usize) -> Self {
        Self {
            rgb: [[0.0; MAX_LANES]; 3],
            alpha: [0.0; MAX_LANES],
            any: false,
            lanes,
        }
    }
}

/// Whether the packet path's gathers reach every voxel of a grid of
/// `dims`: their indices are 32-bit and signed, so a grid of 2^31 voxels
/// or more takes the scalar path.
pub(super) fn addressable(dims: UVec3) -> bool {
    u64::from(dims.x) * u64::from(dims.y) * u64::from(dims.z) <= i32::MAX as u64
}

/// The lanes the packet path takes on this CPU: AVX-512's where it has
/// them, else AVX2's (with FMA), unless `CAVERAY_SIMD` names a narrower
/// level; none on the portable level.
pub(super) fn level() -> Option<Level> {
    Some(Level::chosen()).filter(|&l| l >= Level::Avx2)
}

impl Packet {
    pub fn color(&self, lane: usize) -> Vec3 {
        Vec3::new(self.rgb[0][lane], self.rgb[1][lane], self.rgb[2][lane])
    }

    /// Front-to-back compositing of the lanes, each lit by `light`, behind
    /// `acc` (premultiplied): all of them, or up to and including the
    /// first after which the opacity reaches `stop`. Prefix products of
    /// the transmittances in the lanes (a shift per doubling), so no lane
    /// waits for the one before it. Only for a packet that
    /// [`PacketGrid::classify`] made.
    pub fn composite(&self, acc: Vec4, light: Vec3, stop: f32, depth_at: f32) -> Composited {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: `classify` made the packet at its grid's level, which
            // this CPU runs (PacketGrid's contract).
            unsafe {
                if self.lanes == 16 {
                    avx512::composite(self, acc, light, stop, depth_at)
                } else {
                    avx2::composite(self, acc, light, stop, depth_at)
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (acc, light, stop, depth_at);
            unreachable!("the packet path runs on x86_64 only")
        }
    }
}

/// What compositing a packet did.
pub(super) struct Composited {
    /// Premultiplied color and opacity behind the lanes used.
    pub acc: Vec4,
    /// Lanes composited: all, or fewer where the opacity reached `stop`.
    pub used: usize,
    /// The first lane after which the opacity reached `depth_at`.
    pub depth_lane: Option<usize>,
}

impl PacketGrid<'_> {
    /// Samples per packet.
    pub fn lanes(&self) -> usize {
        lanes(self.level)
    }

    /// Classifies [`Self::lanes`] samples at `steps` of a ray whose grid
    /// point is `go + gd * t`, each a full step of `exponent` unit
    /// distances. The grid's level must be one this CPU runs, at least
    /// AVX2 (as [`level`] gives).
    pub fn classify(&self, go: Vec3, gd: Vec3, steps: Steps, exponent: f32) -> Packet {
        let d = self.dims;
        // The gathers below read values[base + stride] for in-grid cells
        // only; this holds the slice to the grid's size.
        let voxels = d[0] as usize * d[1] as usize * d[2] as usize;
        assert!(self.values.len() >= voxels && voxels <= i32::MAX as usize);
        assert!(self.level >= Level::Avx2 && self.level.runs());
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: the CPU runs the grid's level (asserted above); every
            // gather index is clamped into the grid, whose size the assert
            // above holds to the slice.
            unsafe {
                if self.level == Level::Avx512 {
                    avx512::classify(self, go, gd, steps, exponent)
                } else {
                    avx2::classify(self, go, gd, steps, exponent)
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (go, gd, steps, exponent);
            unreachable!("the packet path runs on x86_64 only")
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use glam::Vec3;

    use glam::Vec4;

    use super::{Composited, Packet, PacketGrid, Steps, MAX_LANES};
    use crate::scene::TABLE_SIZE;

    /// Samples per packet here.
    const LANES: usize = 8;

    /// The samples' t (Steps::t, lane by lane).
    #[target_feature(enable = "avx2,fma")]
    fn ts(s: Steps) -> __m256 {
        let m = _mm256_add_epi32(
            _mm256_set1_epi32(s.k as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        );
        let along = _mm256_mul_ps(_mm256_cvtepi32_ps(m), _mm256_set1_ps(s.step));
        _mm256_add_ps(
            _mm256_add_ps(_mm256_set1_ps(s.t0), along),
            _mm256_set1_ps(0.5 * s.step),
        )
    }

    #[target_feature(enable = "avx2,fma")]
    fn mix(a: __m256, b: __m256, f: __m256) -> __m256 {
        // a (1 - f) + b f, as the reference's mix.
        _mm256_fmadd_ps(
            b,
            f,
            _mm256_mul_ps(a, _mm256_sub_ps(_mm256_set1_ps(1.0), f)),
        )
    }

    /// log2 of x in (0, 1]: exponent plus log2 of the mantissa, taken in
    /// [sqrt(1/2), sqrt(2)) by the series of atanh.
    #[target_feature(enable = "avx2,fma")]
    fn log2(x: __m256) -> __m256 {
        let bits = _mm256_castps_si256(x);
        let mut e = _mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127));
        let mut m = _mm256_castsi256_ps(_mm256_or_si256(
            _mm256_and_si256(bits, _mm256_set1_epi32(0x007f_ffff)),
            _mm256_set1_epi32(0x3f80_0000),
        ));
        let big = _mm256_cmp_ps(m, _mm256_set1_ps(std::f32::consts::SQRT_2), _CMP_GT_OQ);
        m = _mm256_blendv_ps(m, _mm256_mul_ps(m, _mm256_set1_ps(0.5)), big);
        e = _mm256_sub_epi32(e, _mm256_castps_si256(big)); // true is -1
        let one = _mm256_set1_ps(1.0);
        let r = _mm256_div_ps(_mm256_sub_ps(m, one), _mm256_add_ps(m, one));
        let r2 = _mm256_mul_ps(r, r);
        // 2 atanh(r) = ln(m): r (2 + 2r^2/3 + 2r^4/5 + ...), |r| < 0.172.
        let mut p = _mm256_set1_ps(2.0 / 11.0);
        for c in [2.0 / 9.0, 2.0 / 7.0, 2.0 / 5.0, 2.0 / 3.0, 2.0] {
            p = _mm256_fmadd_ps(p, r2, _mm256_set1_ps(c));
        }
        let ln = _mm256_mul_ps(p, r);
        _mm256_fmadd_ps(
            ln,
            _mm256_set1_ps(std::f32::consts::LOG2_E),
            _mm256_cvtepi32_ps(e),
        )
    }

    /// 2^y for y <= 0 (below -125 it is taken as 2^-125, as good as 0
    /// here): 2^round(y) by the exponent bits times 2^f, |f| <= 1/2, by
    /// its series.
    #[target_feature(enable = "avx2,fma")]
    fn exp2(y: __m256) -> __m256 {
        let y = _mm256_max_ps(y, _mm256_set1_ps(-125.0));
        let n = _mm256_round_ps(y, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
        let x = _mm256_mul_ps(_mm256_sub_ps(y, n), _mm256_set1_ps(std::f32::consts::LN_2));
        let mut p = _mm256_set1_ps(1.0 / 720.0);
        for c in [1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
            p = _mm256_fmadd_ps(p, x, _mm256_set1_ps(c));
        }
        let scale = _mm256_slli_epi32(
            _mm256_add_epi32(_mm256_cvtps_epi32(n), _mm256_set1_epi32(127)),
            23,
        );
        _mm256_mul_ps(p, _mm256_castsi256_ps(scale))
    }

    /// (values[i], values[i + 1]) for the eight indices i, as two vectors:
    /// four 64-bit gathers' worth of loads instead of sixteen 32-bit ones.
    ///
    /// # Safety
    /// Every i and i + 1 must index `values`.
    #[target_feature(enable = "avx2,fma")]
    unsafe fn pairs(values: &[f32], i: __m256i) -> (__m256, __m256) {
        let p = values.as_ptr().cast::<f64>();
        let lo = unsafe { _mm256_i32gather_pd::<4>(p, _mm256_castsi256_si128(i)) };
        let hi = unsafe { _mm256_i32gather_pd::<4>(p, _mm256_extracti128_si256::<1>(i)) };
        let (lo, hi) = (_mm256_castpd_ps(lo), _mm256_castpd_ps(hi));
        // [a0 b0 a1 b1 | a2 b2 a3 b3], [a4 b4 a5 b5 | a6 b6 a7 b7]
        let a = _mm256_shuffle_ps::<0b10_00_10_00>(lo, hi);
        let b = _mm256_shuffle_ps::<0b11_01_11_01>(lo, hi);
        // [a0 a1 a4 a5 | a2 a3 a6 a7] -> a0..a7
        let order = |v: __m256| {
            _mm256_castpd_ps(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(v)))
        };
        (order(a), order(b))
    }

    /// Lane j takes lane j - `shift` (the first `shift` lanes take 1).
    #[target_feature(enable = "avx2,fma")]
    fn shifted<const SHIFT: i32>(v: __m256) -> __m256 {
        let index = _mm256_setr_epi32(
            0,
            (1 - SHIFT).max(0),
            (2 - SHIFT).max(0),
            (3 - SHIFT).max(0),
            (4 - SHIFT).max(0),
            (5 - SHIFT).max(0),
            (6 - SHIFT).max(0),
            (7 - SHIFT).max(0),
        );
        let moved = _mm256_permutevar8x32_ps(v, index);
        let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let first = _mm256_cmpgt_epi32(_mm256_set1_epi32(SHIFT), lanes);
        _mm256_blendv_ps(moved, _mm256_set1_ps(1.0), _mm256_castsi256_ps(first))
    }

    #[target_feature(enable = "avx2,fma")]
    fn sum(v: __m256) -> f32 {
        let half = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let pair = _mm_add_ps(half, _mm_movehl_ps(half, half));
        _mm_cvtss_f32(_mm_add_ss(pair, _mm_movehdup_ps(pair)))
    }

    #[target_feature(enable = "avx2,fma")]
    pub(super) fn composite(
        packet: &Packet,
        acc: Vec4,
        light: glam::Vec3,
        stop: f32,
        depth_at: f32,
    ) -> Composited {
        let one = _mm256_set1_ps(1.0);
        let load = |v: &[f32; MAX_LANES]| unsafe { _mm256_loadu_ps(v.as_ptr()) };
        let a = load(&packet.alpha);
        // Inclusive prefix product of the lanes' transmittances.
        let mut kept = _mm256_sub_ps(one, a);
        kept = _mm256_mul_ps(kept, shifted::<1>(kept));
        kept = _mm256_mul_ps(kept, shifted::<2>(kept));
        kept = _mm256_mul_ps(kept, shifted::<4>(kept));
        let before = _mm256_set1_ps(1.0 - acc.w);
        // Opacity after each lane, and each lane's share of what is seen.
        let opacity = _mm256_sub_ps(one, _mm256_mul_ps(before, kept));
        let weight = _mm256_mul_ps(_mm256_mul_ps(before, shifted::<1>(kept)), a);
        let reached = |x: f32| {
            let m = _mm256_cmp_ps(opacity, _mm256_set1_ps(x), _CMP_GE_OQ);
            _mm256_movemask_ps(m) as u32
        };
        let stops = reached(stop);
        let used = if stops == 0 {
            LANES
        } else {
            stops.trailing_zeros() as usize + 1
        };
        let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let used_mask = _mm256_cmpgt_epi32(_mm256_set1_epi32(used as i32), lanes);
        let weight = _mm256_and_ps(weight, _mm256_castsi256_ps(used_mask));
        let mut opacities = [0.0f32; LANES];
        unsafe { _mm256_storeu_ps(opacities.as_mut_ptr(), opacity) };
        // As the scalar path, depth is taken at a sample that shows (which
        // matters for a threshold of 0).
        let shows = _mm256_movemask_ps(_mm256_cmp_ps(a, _mm256_setzero_ps(), _CMP_GT_OQ)) as u32;
        let depth = reached(depth_at) & shows & ((1u32 << used) - 1);
        let channel = |c: usize| sum(_mm256_mul_ps(weight, load(&packet.rgb[c])));
        Composited {
            acc: Vec4::new(
                acc.x + channel(0) * light.x,
                acc.y + channel(1) * light.y,
                acc.z + channel(2) * light.z,
                opacities[used - 1],
            ),
            used,
            depth_lane: (depth != 0).then(|| depth.trailing_zeros() as usize),
        }
    }

    #[target_feature(enable = "avx2,fma")]
    pub(super) fn classify(
        grid: &PacketGrid,
        go: Vec3,
        gd: Vec3,
        steps: Steps,
        exponent: f32,
    ) -> Packet {
        let zero = _mm256_setzero_ps();
        let one = _mm256_set1_ps(1.0);
        let t = ts(steps);
        let d = grid.dims;
        let mut cell = [_mm256_setzero_si256(); 3];
        let mut frac = [zero; 3];
        let mut stride = [_mm256_setzero_si256(); 3];
        let step = [1, d[0], d[0] * d[1]];
        for k in 0..3 {
            let hi = d[k] - 1;
            let g = _mm256_fmadd_ps(_mm256_set1_ps(gd[k]), t, _mm256_set1_ps(go[k]));
            // max first: a NaN lane becomes 0, as a clamp must not pass it.
            let g = _mm256_min_ps(_mm256_max_ps(g, zero), _mm256_set1_ps(hi as f32));
            let i0 = _mm256_min_epi32(_mm256_cvttps_epi32(g), _mm256_set1_epi32((hi - 1).max(0)));
            frac[k] = _mm256_sub_ps(g, _mm256_cvtepi32_ps(i0));
            // i1 = i0 + 1 within the grid, else i0 (an axis one vertex thick).
            let inside = _mm256_cmpgt_epi32(_mm256_set1_epi32(hi), i0);
            stride[k] = _mm256_and_si256(inside, _mm256_set1_epi32(step[k]));
            cell[k] = i0;
        }
        let base = _mm256_add_epi32(
            cell[0],
            _mm256_mullo_epi32(
                _mm256_set1_epi32(d[0]),
                _mm256_add_epi32(
                    cell[1],
                    _mm256_mullo_epi32(_mm256_set1_epi32(d[1]), cell[2]),
                ),
            ),
        );
        let [_, sy, sz] = stride;
        // Each x-neighbour pair is one 64-bit load: i0 + 1 <= hi along x
        // (dims.x >= 2 on this path).
        let pair = |offset: __m256i| unsafe { pairs(grid.values, _mm256_add_epi32(base, offset)) };
        let (v000, v100) = pair(_mm256_setzero_si256());
        let (v010, v110) = pair(sy);
        let (v001, v101) = pair(sz);
        let (v011, v111) = pair(_mm256_add_epi32(sy, sz));
        let x00 = mix(v000, v100, frac[0]);
        let x10 = mix(v010, v110, frac[0]);
        let x01 = mix(v001, v101, frac[0]);
        let x11 = mix(v011, v111, frac[0]);
        let v = mix(mix(x00, x10, frac[1]), mix(x01, x11, frac[1]), frac[2]);

        // Post-classification, as Grid::classify; a NaN value shows nothing.
        let number = _mm256_cmp_ps(v, v, _CMP_ORD_Q);
        let last = (TABLE_SIZE - 1) as f32;
        let u = _mm256_sub_ps(v, _mm256_set1_ps(grid.value_lo));
        let u = _mm256_mul_ps(u, _mm256_set1_ps(grid.value_scale));
        let u = _mm256_mul_ps(
            _mm256_min_ps(_mm256_max_ps(u, zero), one),
            _mm256_set1_ps(last),
        );
        let i = _mm256_min_epi32(
            _mm256_cvttps_epi32(u),
            _mm256_set1_epi32(TABLE_SIZE as i32 - 2),
        );
        let f = _mm256_sub_ps(u, _mm256_cvtepi32_ps(i));
        let lerp = |channel: &[f32; TABLE_SIZE]| unsafe {
            // i + 1 <= TABLE_SIZE - 1: the pair is in the table.
            let (a, b) = pairs(channel, i);
            mix(a, b, f)
        };
        let a = _mm256_and_ps(lerp(&grid.channels.a), number);
        let mut out = Packet::empty(LANES);
        let shows = _mm256_cmp_ps(a, zero, _CMP_GT_OQ);
        if _mm256_movemask_ps(shows) == 0 {
            return out;
        }
        out.any = true;
        let (r, g, b) = (
            lerp(&grid.channels.r),
            lerp(&grid.channels.g),
            lerp(&grid.channels.b),
        );
        // 1 - (1 - a)^exponent; 1 where a >= 1; 0 where a <= 0.
        let kept = exp2(_mm256_mul_ps(
            _mm256_set1_ps(exponent),
            log2(_mm256_max_ps(
                _mm256_sub_ps(one, a),
                _mm256_set1_ps(f32::MIN_POSITIVE),
            )),
        ));
        let corrected = _mm256_sub_ps(one, kept);
        let opaque = _mm256_cmp_ps(a, one, _CMP_GE_OQ);
        let corrected = _mm256_and_ps(_mm256_blendv_ps(corrected, one, opaque), shows);
        unsafe {
            _mm256_storeu_ps(out.rgb[0].as_mut_ptr(), r);
            _mm256_storeu_ps(out.rgb[1].as_mut_ptr(), g);
            _mm256_storeu_ps(out.rgb[2].as_mut_ptr(), b);
            _mm256_storeu_ps(out.alpha.as_mut_ptr(), corrected);
        }
        out
    }
}

/// The same kernels sixteen lanes wide. Each sample takes the AVX2
/// path's operations in the same order, so classifying gives the same
/// bits; only compositing's sums run in another order.
#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use glam::{Vec3, Vec4};

    use super::{Composited, Packet, PacketGrid, Steps, MAX_LANES};
    use crate::scene::TABLE_SIZE;

    /// Samples per packet here.
    const LANES: usize = 16;

    /// As avx2::ts.
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    fn ts(s: Steps) -> __m512 {
        let m = _mm512_add_epi32(_mm512_set1_epi32(s.k as i32), lane_numbers());
        let along = _mm512_mul_ps(_mm512_cvtepi32_ps(m), _mm512_set1_ps(s.step));
        _mm512_add_ps(
            _mm512_add_ps(_mm512_set1_ps(s.t0), along),
            _mm512_set1_ps(0.5 * s.step),
        )
    }

    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    fn mix(a: __m512, b: __m512, f: __m512) -> __m512 {
        _mm512_fmadd_ps(
            b,
            f,
            _mm512_mul_ps(a, _mm512_sub_ps(_mm512_set1_ps(1.0), f)),
        )
    }

    /// As avx2::log2.
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    fn log2(x: __m512) -> __m512 {
        let bits = _mm512_castps_si512(x);
        let e = _mm512_sub_epi32(_mm512_srli_epi32::<23>(bits), _mm512_set1_epi32(127));
        let m = _mm512_castsi512_ps(_mm512_or_si512(
            _mm512_and_si512(bits, _mm512_set1_epi32(0x007f_ffff)),
            _mm512_set1_epi32(0x3f80_0000),
        ));
        let big = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(m, _mm512_set1_ps(std::f32::consts::SQRT_2));
        let m = _mm512_mask_mul_ps(m, big, m, _mm512_set1_ps(0.5));
        let e = _mm512_mask_add_epi32(e, big, e, _mm512_set1_epi32(1));
        let one = _mm512_set1_ps(1.0);
        let r = _mm512_div_ps(_mm512_sub_ps(m, one), _mm512_add_ps(m, one));
        let r2 = _mm512_mul_ps(r, r);
        let mut p = _mm512_set1_ps(2.0 / 11.0);
        for c in [2.0 / 9.0, 2.0 / 7.0, 2.0 / 5.0, 2.0 / 3.0, 2.0] {
            p = _mm512_fmadd_ps(p, r2, _mm512_set1_ps(c));
        }
        let ln = _mm512_mul_ps(p, r);
        _mm512_fmadd_ps(
            ln,
            _mm512_set1_ps(std::f32::consts::LOG2_E),
            _mm512_cvtepi32_ps(e),
        )
    }

    /// As avx2::exp2.
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    fn exp2(y: __m512) -> __m512 {
        let y = _mm512_max_ps(y, _mm512_set1_ps(-125.0));
        let n = _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(y);
        let x = _mm512_mul_ps(_mm512_sub_ps(y, n), _mm512_set1_ps(std::f32::consts::LN_2));
        let mut p = _mm512_set1_ps(1.0 / 720.0);
        for c in [1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
            p = _mm512_fmadd_ps(p, x, _mm512_set1_ps(c));
        }
        let scale = _mm512_slli_epi32::<23>(_mm512_add_epi32(
            _mm512_cvtps_epi32(n),
            _mm512_set1_epi32(127),
        ));
        _mm512_mul_ps(p, _mm512_castsi512_ps(scale))
    }

    /// (values[i], values[i + 1]) for the sixteen indices i: two gathers
    /// of eight 64-bit pairs, split by two permutes.
    ///
    /// # Safety
    /// Every i and i + 1 must index `values`.
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    unsafe fn pairs(values: &[f32], i: __m512i) -> (__m512, __m512) {
        let p = values.as_ptr().cast::<f64>();
        let lo = unsafe { _mm512_i32gather_pd::<4>(_mm512_castsi512_si256(i), p) };
        let hi = unsafe { _mm512_i32gather_pd::<4>(_mm512_extracti64x4_epi64::<1>(i), p) };
        let (lo, hi) = (_mm512_castpd_ps(lo), _mm512_castpd_ps(hi));
        // lo: a0 b0 .. a7 b7, hi: a8 b8 .. a15 b15.
        let even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
        let odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
        (
            _mm512_permutex2var_ps(lo, even, hi),
            _mm512_permutex2var_ps(lo, odd, hi),
        )
    }

    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    fn lane_numbers() -> __m512i {
        _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
    }

    /// Lane j takes lane j - `shift` (the first `shift` lanes take 1).
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    fn shifted<const SHIFT: i32>(v: __m512) -> __m512 {
        let lanes = lane_numbers();
        let index = _mm512_max_epi32(
            _mm512_sub_epi32(lanes, _mm512_set1_epi32(SHIFT)),
            _mm512_setzero_si512(),
        );
        let moved = _mm512_permutexvar_ps(index, v);
        let first = _mm512_cmpgt_epi32_mask(_mm512_set1_epi32(SHIFT), lanes);
        _mm512_mask_mov_ps(moved, first, _mm512_set1_ps(1.0))
    }

    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    pub(super) fn composite(
        packet: &Packet,
        acc: Vec4,
        light: Vec3,
        stop: f32,
        depth_at: f32,
    ) -> Composited {
        let one = _mm512_set1_ps(1.0);
        let load = |v: &[f32; MAX_LANES]| unsafe { _mm512_loadu_ps(v.as_ptr()) };
        let a = load(&packet.alpha);
        // Inclusive prefix product of the lanes' transmittances.
        let mut kept = _mm512_sub_ps(one, a);
        kept = _mm512_mul_ps(kept, shifted::<1>(kept));
        kept = _mm512_mul_ps(kept, shifted::<2>(kept));
        kept = _mm512_mul_ps(kept, shifted::<4>(kept));
        kept = _mm512_mul_ps(kept, shifted::<8>(kept));
        let before = _mm512_set1_ps(1.0 - acc.w);
        let opacity = _mm512_sub_ps(one, _mm512_mul_ps(before, kept));
        let weight = _mm512_mul_ps(_mm512_mul_ps(before, shifted::<1>(kept)), a);
        let reached =
            |x: f32| u32::from(_mm512_cmp_ps_mask::<_CMP_GE_OQ>(opacity, _mm512_set1_ps(x)));
        let stops = reached(stop);
        let used = if stops == 0 {
            LANES
        } else {
            stops.trailing_zeros() as usize + 1
        };
        let used_mask = ((1u32 << used) - 1) as u16;
        let weight = _mm512_maskz_mov_ps(used_mask, weight);
        let mut opacities = [0.0f32; LANES];
        unsafe { _mm512_storeu_ps(opacities.as_mut_ptr(), opacity) };
        // As the scalar path, depth is taken at a sample that shows.
        let shows = u32::from(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, _mm512_setzero_ps()));
        let depth = reached(depth_at) & shows & u32::from(used_mask);
        let channel = |c: usize| _mm512_reduce_add_ps(_mm512_mul_ps(weight, load(&packet.rgb[c])));
        Composited {
            acc: Vec4::new(
                acc.x + channel(0) * light.x,
                acc.y + channel(1) * light.y,
                acc.z + channel(2) * light.z,
                opacities[used - 1],
            ),
            used,
            depth_lane: (depth != 0).then(|| depth.trailing_zeros() as usize),
        }
    }

    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    pub(super) fn classify(
        grid: &PacketGrid,
        go: Vec3,
        gd: Vec3,
        steps: Steps,
        exponent: f32,
    ) -> Packet {
        let zero = _mm512_setzero_ps();
        let one = _mm512_set1_ps(1.0);
        let t = ts(steps);
        let d = grid.dims;
        let mut cell = [_mm512_setzero_si512(); 3];
        let mut frac = [zero; 3];
        let mut stride = [_mm512_setzero_si512(); 3];
        let step = [1, d[0], d[0] * d[1]];
        for k in 0..3 {
            let hi = d[k] - 1;
            let g = _mm512_fmadd_ps(_mm512_set1_ps(gd[k]), t, _mm512_set1_ps(go[k]));
            // max first: a NaN lane becomes 0, as a clamp must not pass it.
            let g = _mm512_min_ps(_mm512_max_ps(g, zero), _mm512_set1_ps(hi as f32));
            let i0 = _mm512_min_epi32(_mm512_cvttps_epi32(g), _mm512_set1_epi32((hi - 1).max(0)));
            frac[k] = _mm512_sub_ps(g, _mm512_cvtepi32_ps(i0));
            let inside = _mm512_cmpgt_epi32_mask(_mm512_set1_epi32(hi), i0);
            stride[k] = _mm512_maskz_mov_epi32(inside, _mm512_set1_epi32(step[k]));
            cell[k] = i0;
        }
        let base = _mm512_add_epi32(
            cell[0],
            _mm512_mullo_epi32(
                _mm512_set1_epi32(d[0]),
                _mm512_add_epi32(
                    cell[1],
                    _mm512_mullo_epi32(_mm512_set1_epi32(d[1]), cell[2]),
                ),
            ),
        );
        let [_, sy, sz] = stride;
        let pair = |offset: __m512i| unsafe { pairs(grid.values, _mm512_add_epi32(base, offset)) };
        let (v000, v100) = pair(_mm512_setzero_si512());
        let (v010, v110) = pair(sy);
        let (v001, v101) = pair(sz);
        let (v011, v111) = pair(_mm512_add_epi32(sy, sz));
        let x00 = mix(v000, v100, frac[0]);
        let x10 = mix(v010, v110, frac[0]);
        let x01 = mix(v001, v101, frac[0]);
        let x11 = mix(v011, v111, frac[0]);
        let v = mix(mix(x00, x10, frac[1]), mix(x01, x11, frac[1]), frac[2]);

        let number = _mm512_cmp_ps_mask::<_CMP_ORD_Q>(v, v);
        let last = (TABLE_SIZE - 1) as f32;
        let u = _mm512_sub_ps(v, _mm512_set1_ps(grid.value_lo));
        let u = _mm512_mul_ps(u, _mm512_set1_ps(grid.value_scale));
        let u = _mm512_mul_ps(
            _mm512_min_ps(_mm512_max_ps(u, zero), one),
            _mm512_set1_ps(last),
        );
        let i = _mm512_min_epi32(
            _mm512_cvttps_epi32(u),
            _mm512_set1_epi32(TABLE_SIZE as i32 - 2),
        );
        let f = _mm512_sub_ps(u, _mm512_cvtepi32_ps(i));
        let lerp = |channel: &[f32; TABLE_SIZE]| unsafe {
            let (a, b) = pairs(channel, i);
            mix(a, b, f)
        };
        let a = _mm512_maskz_mov_ps(number, lerp(&grid.channels.a));
        let mut out = Packet::empty(LANES);
        let shows = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, zero);
        if shows == 0 {
            return out;
        }
        out.any = true;
        let (r, g, b) = (
            lerp(&grid.channels.r),
            lerp(&grid.channels.g),
            lerp(&grid.channels.b),
        );
        let kept = exp2(_mm512_mul_ps(
            _mm512_set1_ps(exponent),
            log2(_mm512_max_ps(
                _mm512_sub_ps(one, a),
                _mm512_set1_ps(f32::MIN_POSITIVE),
            )),
        ));
        let corrected = _mm512_sub_ps(one, kept);
        let opaque = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(a, one);
        let corrected = _mm512_maskz_mov_ps(shows, _mm512_mask_mov_ps(corrected, opaque, one));
        unsafe {
            _mm512_storeu_ps(out.rgb[0].as_mut_ptr(), r);
            _mm512_storeu_ps(out.rgb[1].as_mut_ptr(), g);
            _mm512_storeu_ps(out.rgb[2].as_mut_ptr(), b);
            _mm512_storeu_ps(out.alpha.as_mut_ptr(), corrected);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The packet levels this CPU runs.
    fn levels() -> Vec<Level> {
        // The CI machines and this one have AVX2; a CPU without it runs
        // the scalar path, which the reference tests cover.
        assert!(
            Level::Avx2.runs() || !cfg!(target_arch = "x86_64"),
            "this x86_64 CPU has no AVX2/FMA: the packet path is untested here"
        );
        [Level::Avx2, Level::Avx512]
            .into_iter()
            .filter(|l| l.runs())
            .collect()
    }

    /// A deterministic sequence in [0, 1).
    fn numbers(seed: u32) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        }
    }

    #[test]
    fn the_power_is_the_reference_power_to_single_precision() {
        // One voxel value everywhere: each lane's opacity is the table's.
        let values = vec![0.5f32; 8];
        let mut table = vec![Vec4::new(0.2, 0.4, 0.6, 0.0); TABLE_SIZE];
        for level in levels() {
            for a in [1e-6f32, 1e-3, 0.05, 0.3, 0.7, 0.999, 0.999_999, 1.0] {
                for exponent in [0.01f32, 0.5, 1.0, 3.7, 40.0] {
                    for e in table.iter_mut() {
                        e.w = a;
                    }
                    let c = Channels::new(&table);
                    let grid = PacketGrid {
                        level,
                        values: &values,
                        dims: [2, 2, 2],
                        channels: &c,
                        value_lo: 0.0,
                        value_scale: 1.0,
                    };
                    let at = Steps {
                        t0: 0.3,
                        k: 0,
                        step: 0.0,
                    };
                    let p = grid.classify(Vec3::ZERO, Vec3::ONE, at, exponent);
                    assert_eq!(p.lanes, lanes(level));
                    let want = if a >= 1.0 {
                        1.0
                    } else {
                        1.0 - (1.0 - a).powf(exponent)
                    };
                    for l in 0..p.lanes {
                        let err = (p.alpha[l] - want).abs();
                        assert!(
                            err <= 1e-6 + 1e-5 * want,
                            "{level:?} lane {l}: a {a} exponent {exponent}: {} vs {want}",
                            p.alpha[l]
                        );
                        assert!((p.color(l) - Vec3::new(0.2, 0.4, 0.6)).length() < 1e-6);
                    }
                }
            }
        }
    }

    #[test]
    fn every_width_classifies_each_sample_alike() {
        if !Level::Avx512.runs() {
            eprintln!("this CPU has no AVX-512: only AVX2 packets are tested here");
            return;
        }
        let mut next = numbers(11);
        let dims = [9, 7, 5];
        let values: Vec<f32> = (0..9 * 7 * 5).map(|_| next()).collect();
        let table: Vec<Vec4> = (0..TABLE_SIZE)
            .map(|_| Vec4::new(next(), next(), next(), 0.6 * next()))
            .collect();
        let c = Channels::new(&table);
        let grid = |level| PacketGrid {
            level,
            values: &values,
            dims,
            channels: &c,
            value_lo: 0.1,
            value_scale: 1.2,
        };
        let (eight, sixteen) = (grid(Level::Avx2), grid(Level::Avx512));
        for _ in 0..500 {
            // Rays that cross the grid and leave it (clamped samples).
            let go = Vec3::new(next() * 8.0, next() * 6.0, next() * 4.0);
            let gd = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
            let mut at = |k| Steps {
                t0: 10.0 * next() - 5.0,
                k,
                step: 0.7,
            };
            let steps = at(3);
            let wide = sixteen.classify(go, gd, steps, 0.8);
            for half in 0..2u32 {
                let narrow = eight.classify(
                    go,
                    gd,
                    Steps {
                        k: 3 + 8 * half,
                        ..steps
                    },
                    0.8,
                );
                for l in 0..8 {
                    let w = 8 * half as usize + l;
                    assert_eq!(
                        wide.alpha[w].to_bits(),
                        narrow.alpha[l].to_bits(),
                        "lane {w}"
                    );
                    if wide.alpha[w] > 0.0 {
                        assert_eq!(wide.color(w), narrow.color(l), "lane {w}");
                    }
                }
            }
        }
    }

    #[test]
    fn grids_of_two_to_the_31_voxels_are_left_to_the_scalar_path() {
        assert!(addressable(UVec3::new(2048, 2048, 511)));
        assert!(addressable(UVec3::new(1290, 1290, 1290)));
        assert!(!addressable(UVec3::new(2048, 2048, 512)));
        assert!(!addressable(UVec3::new(65536, 65536, 1)));
        assert!(!addressable(UVec3::splat(u32::MAX)));
    }

    #[test]
    fn lanes_composite_as_one_after_the_other() {
        let mut next = numbers(7);
        for case in 0..1000 {
            let Some(&level) = levels().get(case % 2).or(levels().first()) else {
                return;
            };
            let lanes = lanes(level);
            let mut packet = Packet::empty(lanes);
            for l in 0..lanes {
                // Zeros, small and large opacities, in any order.
                packet.alpha[l] = match case % 3 {
                    0 if l < 3 => 0.0,
                    1 => 0.9 * next(),
                    _ => 0.2 * next(),
                };
                for c in 0..3 {
                    packet.rgb[c][l] = next();
                }
            }
            let start = Vec4::new(0.1, 0.2, 0.1, 0.5 * next());
            let light = Vec3::new(1.0, 0.8, 0.6);
            let (stop, depth_at) = (0.9, if case % 2 == 0 { 0.0 } else { 0.6 });
            let got = packet.composite(start, light, stop, depth_at);
            // The scalar path: sample by sample, stopping after the lane
            // that reaches `stop`.
            let (mut acc, mut used, mut depth) = (start, lanes, None);
            for l in 0..lanes {
                let a = packet.alpha[l];
                if a > 0.0 {
                    let w = (1.0 - acc.w) * a;
                    acc = (acc.truncate() + packet.color(l) * light * w).extend(acc.w + w);
                    if depth.is_none() && acc.w >= depth_at {
                        depth = Some(l);
                    }
                    if acc.w >= stop {
                        used = l + 1;
                        break;
                    }
                }
            }
            assert_eq!(got.used, used, "case {case} ({level:?})");
            assert_eq!(got.depth_lane, depth, "case {case}");
            assert!(
                (got.acc - acc).abs().max_element() < 1e-5,
                "case {case}: {} vs {acc}",
                got.acc
            );
        }
    }
}
