//! The tangential compliance `u = C q` restricted to the contact points.
//!
//! Units: tractions `q` in Pa, displacements `u` in m, compliance in m/Pa.
//!
//! `C` couples every pair of contact points through the Cerruti kernel `K(d)` of their grid
//! offset `d` (element coefficients of [`crate::halfspace::influence`]; for a periodic patch the
//! exact periodic kernel, the inverse FFT of the periodic spectra):
//! `u_i = Σ_j K(p_j − p_i) q_j`, with `K = [[K_xx, K_xy], [K_xy, K_yy]]`. Two exact
//! implementations:
//!
//! - [`DirectCompliance`] (`Operator::Dense`): direct summation over all pairs of contact points,
//!   `O(n²)` for `n` contact points, with the entries read from a table of `K` by grid offset
//!   instead of a stored `n × n` matrix. The matrix is block-Toeplitz: grouping the points in
//!   runs along `y` (consecutive grid points of one grid row), the block of a target run and a
//!   source run is a Toeplitz matrix whose entries are one contiguous segment of a table row.
//!   The table is `O(N)` for `N` grid points (single precision, relative rounding 6e-8; 13 MB
//!   at 1024²) and fits in the last-level cache, where the `n × n` matrix (97 MB at n = 4029)
//!   had to stream from memory at every product: 3× faster (BENCHMARKS.md, "Tangential
//!   contact"). Sums are accumulated in double precision with fused multiply-adds, in a fixed
//!   order, with AVX2 where the CPU has it (bit-identical to the portable code; tested).
//! - [`FftCompliance`] (`Operator::Fft`): scatter to the grid, FFT convolution with the three
//!   Cerruti spectra, gather, `O(N log N)`, in work arrays held by the operator (a product
//!   allocates nothing).
//!
//! Both give the same product to round-off (tested).

use super::Operator;
use crate::core::fft::{Boundary, FftPlan, PairWorkspace, SharedMut};
use crate::halfspace::influence::{
    cerruti_spectra, cerruti_uxx, cerruti_uxy, cerruti_uyy, CerrutiConstants, CerrutiSpectra,
};
use ndarray::Array2;
use rayon::prelude::*;
use std::sync::{Mutex, TryLockError};

/// `u = C q` on the contact points, `q` and `u` as `[x, y]` pairs in the point order (row-major
/// grid order).
pub(super) enum Compliance {
    Dense(Box<DirectCompliance>),
    Fft(Box<FftCompliance>),
}

impl Compliance {
    /// Build the compliance operator on the contact `points` of a grid of `shape`: `Dense` or
    /// `Fft` as asked, `Auto` the one with the lower [`estimated_costs`].
    pub(super) fn new(
        operator: Operator,
        boundary: Boundary,
        shape: (usize, usize),
        points: &[(usize, usize)],
        spacing: (f64, f64),
        k: CerrutiConstants,
    ) -> Self {
        let (dx, dy) = spacing;
        let fft = match operator {
            Operator::Dense => false,
            Operator::Fft => true,
            Operator::Auto => {
                let plan_points = match boundary {
                    Boundary::Periodic => shape.0 * shape.1,
                    Boundary::ZeroPadded => 4 * shape.0 * shape.1,
                };
                let (dense, fft) = estimated_costs(points.len(), plan_points);
                fft < dense
            }
        };
        if fft {
            let plan = FftPlan::new(shape.0, shape.1, boundary);
            let spectra = cerruti_spectra(&plan, dx, dy, k);
            Compliance::Fft(Box::new(FftCompliance::new(plan, spectra, points)))
        } else {
            Compliance::Dense(Box::new(DirectCompliance::new(
                boundary, shape, points, dx, dy, k,
            )))
        }
    }

    /// The operator built (`Dense` or `Fft`).
    pub(super) fn operator(&self) -> Operator {
        match self {
            Compliance::Dense(_) => Operator::Dense,
            Compliance::Fft(_) => Operator::Fft,
        }
    }

    pub(super) fn apply(&self, q: &[[f64; 2]], u: &mut [[f64; 2]]) {
        match self {
            Compliance::Dense(d) => d.apply(q, u),
            Compliance::Fft(f) => f.apply(q, u),
        }
    }
}

/// Consecutive contact points along `y` in one grid row (consecutive in the point order too).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    /// Grid row `i`.
    i: usize,
    /// Grid column `j` of the first point.
    j0: usize,
    /// Index of the first point.
    start: usize,
    /// Number of points.
    len: usize,
}

/// The runs of row-major sorted contact points.
fn runs_of(points: &[(usize, usize)]) -> Vec<Run> {
    let mut runs: Vec<Run> = Vec::new();
    for (k, &(i, j)) in points.iter().enumerate() {
        match runs.last_mut() {
            Some(r) if r.i == i && r.j0 + r.len == j && r.len < MAX_RUN => r.len += 1,
            _ => runs.push(Run {
                i,
                j0: j,
                start: k,
                len: 1,
            }),
        }
    }
    runs
}

/// Longest run (points): a target run's partial sums, `MAX_RUN / LANES` vectors per component,
/// stay in registers.
const MAX_RUN: usize = 4 * LANES;

/// Targets computed together in the direct summation (one SIMD register of `f64` with AVX2).
const LANES: usize = 4;

/// Direct summation of the restricted compliance with the kernel looked up by grid offset.
///
/// Table layout: row `a` holds the kernel for one row offset `di`, column `c` for one column
/// offset `dj` (offsets target − source; `K` is even, so the sign convention does not change
/// the values). For target run `T` and source run `S` the entry of target point `t` and source
/// point `s` is at `origin(T, S) + t − s`, `origin = row(T.i − S.i)·width + col(T.j0 − S.j0)`:
/// - periodic: `row = di mod nx`, `col = (dj mod ny) + m`, the columns extended periodically by
///   `m` on both sides (`width = ny + 2m`);
/// - zero-padded: `row = di + span_i`, `col = dj + span_j + m` (`width = 2 span_j + 1 + 2m`),
///   zero outside the offsets that occur;
///
/// with the margin `m` = longest run + [`LANES`], so that every block, including the lanes past
/// the end of a target run, is one contiguous segment of a row. For fixed `s`, `LANES`
/// consecutive targets read `LANES` consecutive entries: one vector load per component.
pub(super) struct DirectCompliance {
    /// Runs in point order.
    runs: Vec<Run>,
    boundary: Boundary,
    shape: (usize, usize),
    /// Zero-padded: `(span_i, span_j)` of the contact set.
    span: (usize, usize),
    margin: usize,
    width: usize,
    xx: Vec<f32>,
    xy: Vec<f32>,
    yy: Vec<f32>,
}

impl DirectCompliance {
    fn new(
        boundary: Boundary,
        shape: (usize, usize),
        points: &[(usize, usize)],
        dx: f64,
        dy: f64,
        k: CerrutiConstants,
    ) -> Self {
        let runs = runs_of(points);
        let (imin, imax) = points
            .iter()
            .fold((usize::MAX, 0), |(a, b), p| (a.min(p.0), b.max(p.0)));
        let (jmin, jmax) = points
            .iter()
            .fold((usize::MAX, 0), |(a, b), p| (a.min(p.1), b.max(p.1)));
        let span = (imax - imin, jmax - jmin);
        let kernel = KernelTable::new(boundary, shape, span, dx, dy, k);
        let margin = runs.iter().map(|r| r.len).max().unwrap_or(1) + LANES;
        let (rows, width) = match boundary {
            Boundary::Periodic => (shape.0, shape.1 + 2 * margin),
            Boundary::ZeroPadded => (2 * span.0 + 1, 2 * span.1 + 1 + 2 * margin),
        };
        let mut xx = vec![0.0f32; rows * width];
        let mut xy = vec![0.0f32; rows * width];
        let mut yy = vec![0.0f32; rows * width];
        xx.par_chunks_mut(width)
            .zip(xy.par_chunks_mut(width))
            .zip(yy.par_chunks_mut(width))
            .enumerate()
            .for_each(|(a, ((rxx, rxy), ryy))| {
                for c in 0..width {
                    let offset = match boundary {
                        Boundary::Periodic => Some((a as isize, c as isize - margin as isize)),
                        Boundary::ZeroPadded => {
                            let dj = c as isize - (margin + span.1) as isize;
                            (dj.unsigned_abs() <= span.1)
                                .then_some((a as isize - span.0 as isize, dj))
                        }
                    };
                    if let Some((di, dj)) = offset {
                        let (vxx, vxy, vyy) = kernel.get(di, dj);
                        (rxx[c], rxy[c], ryy[c]) = (vxx as f32, vxy as f32, vyy as f32);
                    }
                }
            });
        Self {
            runs,
            boundary,
            shape,
            span,
            margin,
            width,
            xx,
            xy,
            yy,
        }
    }

    /// Table index of the entry for target point 0 of run `t` and source point 0 of run `s`.
    fn block_origin(&self, t: &Run, s: &Run) -> usize {
        let (row, col) = match self.boundary {
            Boundary::Periodic => (
                wrap(t.i, s.i, self.shape.0),
                wrap(t.j0, s.j0, self.shape.1) + self.margin,
            ),
            Boundary::ZeroPadded => (
                t.i + self.span.0 - s.i,
                t.j0 + self.span.1 + self.margin - s.j0,
            ),
        };
        row * self.width + col
    }

    fn apply(&self, q: &[[f64; 2]], u: &mut [[f64; 2]]) {
        let qx: Vec<f64> = q.iter().map(|v| v[0]).collect();
        let qy: Vec<f64> = q.iter().map(|v| v[1]).collect();
        // One output slice per target run, filled in parallel; every sum runs over the source
        // runs in order, so the result does not depend on the thread count.
        let mut outputs: Vec<&mut [[f64; 2]]> = Vec::with_capacity(self.runs.len());
        let mut rest = u;
        for r in &self.runs {
            let (head, tail) = rest.split_at_mut(r.len);
            outputs.push(head);
            rest = tail;
        }
        outputs
            .into_par_iter()
            .zip(self.runs.par_iter())
            .for_each(|(out, t)| self.target_run(t, &qx, &qy, out));
    }

    /// `u` on the points of target run `t`: the sum over every source run of its Toeplitz block,
    /// in `⌈T.len / LANES⌉` vectors of partial sums held over all source runs.
    fn target_run(&self, t: &Run, qx: &[f64], qy: &[f64], out: &mut [[f64; 2]]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return unsafe { self.target_run_avx2(t, qx, qy, out) };
        }
        self.target_run_portable(t, qx, qy, out)
    }

    /// [`Self::target_run`] without SIMD intrinsics.
    fn target_run_portable(&self, t: &Run, qx: &[f64], qy: &[f64], out: &mut [[f64; 2]]) {
        let (ax, ay) = match t.len.div_ceil(LANES) {
            1 => self.sums_portable::<1>(t, qx, qy),
            2 => self.sums_portable::<2>(t, qx, qy),
            3 => self.sums_portable::<3>(t, qx, qy),
            _ => self.sums_portable::<4>(t, qx, qy),
        };
        for (k, o) in out.iter_mut().enumerate() {
            *o = [ax[k], ay[k]];
        }
    }

    /// [`Self::block_origin`], checked: the block reads the table entries
    /// `origin + c·LANES + l − w` for chunks `c < nc`, lanes `l` and sources `w < S.len`, i.e.
    /// `origin + 1 − S.len .. origin + nc·LANES`; the lower end is non-negative by the margin,
    /// the upper end is asserted here.
    fn checked_origin(&self, t: &Run, s: &Run, nc: usize) -> usize {
        let origin = self.block_origin(t, s);
        assert!(
            origin + nc * LANES <= self.xx.len(),
            "table segment out of range"
        );
        origin
    }

    /// Portable summation; the same fused multiply-adds in the same order as the AVX2 build
    /// (`mul_add` is a hardware instruction on current CPUs, a correctly rounded software
    /// routine elsewhere).
    fn sums_portable<const NC: usize>(
        &self,
        t: &Run,
        qx: &[f64],
        qy: &[f64],
    ) -> ([f64; MAX_RUN], [f64; MAX_RUN]) {
        let mut ax = [0.0; MAX_RUN];
        let mut ay = [0.0; MAX_RUN];
        for s in &self.runs {
            let origin = self.checked_origin(t, s, NC);
            for w in 0..s.len {
                let (x, y) = (qx[s.start + w], qy[s.start + w]);
                let base = origin - w;
                for m in 0..NC * LANES {
                    let (kxx, kxy, kyy) = (
                        self.xx[base + m] as f64,
                        self.xy[base + m] as f64,
                        self.yy[base + m] as f64,
                    );
                    ax[m] = kxx.mul_add(x, kxy.mul_add(y, ax[m]));
                    ay[m] = kxy.mul_add(x, kyy.mul_add(y, ay[m]));
                }
            }
        }
        (ax, ay)
    }

    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn target_run_avx2(&self, t: &Run, qx: &[f64], qy: &[f64], out: &mut [[f64; 2]]) {
        // SAFETY (all four): AVX2 and FMA are available (this function's contract).
        let (ax, ay) = match t.len.div_ceil(LANES) {
            1 => unsafe { self.sums_avx2::<1>(t, qx, qy) },
            2 => unsafe { self.sums_avx2::<2>(t, qx, qy) },
            3 => unsafe { self.sums_avx2::<3>(t, qx, qy) },
            _ => unsafe { self.sums_avx2::<4>(t, qx, qy) },
        };
        for (k, o) in out.iter_mut().enumerate() {
            *o = [ax[k], ay[k]];
        }
    }

    /// [`Self::sums_portable`] with AVX2 intrinsics: `NC` vectors of `LANES` targets per
    /// component, one broadcast of each source traction, fused multiply-adds in the portable
    /// code's order (so the same rounding, bit for bit).
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    unsafe fn sums_avx2<const NC: usize>(
        &self,
        t: &Run,
        qx: &[f64],
        qy: &[f64],
    ) -> ([f64; MAX_RUN], [f64; MAX_RUN]) {
        use std::arch::x86_64::*;
        let mut ax = [_mm256_setzero_pd(); NC];
        let mut ay = [_mm256_setzero_pd(); NC];
        let (pxx, pxy, pyy) = (self.xx.as_ptr(), self.xy.as_ptr(), self.yy.as_ptr());
        for (r, s) in self.runs.iter().enumerate() {
            // Checks lo ≥ 0 (by construction of the margin) and the end of the segment.
            let origin = self.checked_origin(t, s, NC);
            // Prefetch the segment of the block four ahead (its table row is elsewhere): the
            // blocks are short, and the product waits on the table's cache misses otherwise.
            if let Some(s2) = self.runs.get(r + 4) {
                let o2 = self.checked_origin(t, s2, NC);
                let (lo2, hi2) = (o2 + 1 - s2.len, o2 + NC * LANES);
                let mut k = lo2;
                while k < hi2 {
                    // SAFETY: lo2..hi2 lies inside the table (checked_origin).
                    unsafe {
                        _mm_prefetch::<_MM_HINT_T0>(pxx.add(k) as *const i8);
                        _mm_prefetch::<_MM_HINT_T0>(pxy.add(k) as *const i8);
                        _mm_prefetch::<_MM_HINT_T0>(pyy.add(k) as *const i8);
                    }
                    k += 16;
                }
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(pxx.add(hi2 - 1) as *const i8);
                    _mm_prefetch::<_MM_HINT_T0>(pxy.add(hi2 - 1) as *const i8);
                    _mm_prefetch::<_MM_HINT_T0>(pyy.add(hi2 - 1) as *const i8);
                }
            }
            let (sx, sy) = (&qx[s.start..s.start + s.len], &qy[s.start..s.start + s.len]);
            for (w, (&x, &y)) in sx.iter().zip(sy).enumerate() {
                let (x, y) = (_mm256_set1_pd(x), _mm256_set1_pd(y));
                let base = origin - w;
                for c in 0..NC {
                    // SAFETY: base + c·LANES + LANES ≤ origin + NC·LANES ≤ table length
                    // (checked_origin); unaligned loads of 4 f32.
                    let (kxx, kxy, kyy) = unsafe {
                        let o = base + c * LANES;
                        (
                            _mm256_cvtps_pd(_mm_loadu_ps(pxx.add(o))),
                            _mm256_cvtps_pd(_mm_loadu_ps(pxy.add(o))),
                            _mm256_cvtps_pd(_mm_loadu_ps(pyy.add(o))),
                        )
                    };
                    ax[c] = _mm256_fmadd_pd(kxx, x, _mm256_fmadd_pd(kxy, y, ax[c]));
                    ay[c] = _mm256_fmadd_pd(kxy, x, _mm256_fmadd_pd(kyy, y, ay[c]));
                }
            }
        }
        let mut rx = [0.0; MAX_RUN];
        let mut ry = [0.0; MAX_RUN];
        for c in 0..NC {
            // SAFETY: c·LANES + LANES ≤ MAX_RUN.
            unsafe {
                _mm256_storeu_pd(rx.as_mut_ptr().add(c * LANES), ax[c]);
                _mm256_storeu_pd(ry.as_mut_ptr().add(c * LANES), ay[c]);
            }
        }
        (rx, ry)
    }
}

/// `a − b` modulo `n` for `a, b < n`.
fn wrap(a: usize, b: usize, n: usize) -> usize {
    if a >= b {
        a - b
    } else {
        a + n - b
    }
}

/// The FFT path of [`Compliance`].
///
/// A product allocates nothing: the row transforms and the transforms' scratch live in a
/// [`PairWorkspace`] made with the operator ([`FftPlan::convolve_pair`]). The grid-sized work
/// arrays of the earlier product (fields, spectra, outputs: 1–8 MiB each) were allocated and
/// freed at every product, and glibc hands blocks of that size back to the kernel, so every
/// product faulted them in again (BENCHMARKS.md, "Tangential contact").
///
/// The workspace is behind a mutex because the product takes `&self`. The solver calls it from
/// one thread at a time (its own parallelism is inside the product), so the lock is never
/// contended there; a second caller that finds it held gets a fresh workspace for its product
/// instead of waiting (same result, the allocation cost of the earlier code), so concurrent use
/// stays correct and never serialises. A per-thread workspace (`thread_local`) would have
/// been sized for one grid and kept for the thread's life; the workspace belongs to the
/// operator and goes with it.
pub(super) struct FftCompliance {
    plan: FftPlan,
    spectra: CerrutiSpectra,
    points: Vec<(usize, usize)>,
    /// The points of grid row `i` are `row_starts[i]..row_starts[i + 1]` (`nx + 1` entries).
    row_starts: Vec<usize>,
    workspace: Mutex<PairWorkspace>,
}

impl FftCompliance {
    fn new(plan: FftPlan, spectra: CerrutiSpectra, points: &[(usize, usize)]) -> Self {
        let nx = plan.grid_shape().0;
        let mut row_starts = vec![0; nx + 1];
        for &(i, _) in points {
            row_starts[i + 1] += 1;
        }
        for i in 0..nx {
            row_starts[i + 1] += row_starts[i];
        }
        assert!(
            points.windows(2).all(|w| w[0] < w[1]),
            "contact points in row-major order"
        );
        let workspace = Mutex::new(plan.pair_workspace());
        Self {
            plan,
            spectra,
            points: points.to_vec(),
            row_starts,
            workspace,
        }
    }

    fn apply(&self, q: &[[f64; 2]], u: &mut [[f64; 2]]) {
        assert_eq!(q.len(), self.points.len(), "one traction per contact point");
        assert_eq!(
            u.len(),
            self.points.len(),
            "one displacement per contact point"
        );
        let (points, rows) = (&self.points, &self.row_starts);
        let spectra = &self.spectra;
        let kernels = [&spectra.xx, &spectra.xy, &spectra.yy];
        let out = SharedMut::new(u);
        let run = |ws: &mut PairWorkspace| {
            self.plan.convolve_pair(
                kernels,
                ws,
                |i, fx, fy| {
                    for k in rows[i]..rows[i + 1] {
                        let j = points[k].1;
                        (fx[j], fy[j]) = (q[k][0], q[k][1]);
                    }
                },
                |i, ux, uy| {
                    let (start, end) = (rows[i], rows[i + 1]);
                    // SAFETY: the points of row i are written by this call only.
                    let u = unsafe { out.get(start, end - start) };
                    for (o, &(_, j)) in u.iter_mut().zip(&points[start..end]) {
                        *o = [ux[j], uy[j]];
                    }
                },
            )
        };
        match self.workspace.try_lock() {
            Ok(mut ws) => run(&mut ws),
            // A panic in an earlier product leaves nothing behind that matters: the data rows
            // are rewritten by every product, the padding rows are never written.
            Err(TryLockError::Poisoned(e)) => run(&mut e.into_inner()),
            Err(TryLockError::WouldBlock) => run(&mut self.plan.pair_workspace()),
        }
    }
}

/// Kernel `(K_xx, K_xy, K_yy)` by signed grid offset, tabulated once.
struct KernelTable {
    boundary: Boundary,
    xx: Array2<f64>,
    xy: Array2<f64>,
    yy: Array2<f64>,
}

impl KernelTable {
    /// Zero-padded: the element coefficients for offsets `0..=span` (the rest by symmetry:
    /// `K_xx`, `K_yy` even, `K_xy` odd in each offset). Periodic: the exact periodic kernel on the
    /// whole period, from the inverse FFT of the periodic spectra (the same operator as the FFT
    /// path).
    fn new(
        boundary: Boundary,
        shape: (usize, usize),
        span: (usize, usize),
        dx: f64,
        dy: f64,
        k: CerrutiConstants,
    ) -> Self {
        match boundary {
            Boundary::ZeroPadded => {
                let (a, b) = (0.5 * dx, 0.5 * dy);
                let dims = (span.0 + 1, span.1 + 1);
                let tab = |f: fn(f64, f64, f64, f64, CerrutiConstants) -> f64| {
                    let mut t = Array2::<f64>::zeros(dims);
                    t.indexed_iter_mut()
                        .par_bridge()
                        .for_each(|((i, j), v)| *v = f(i as f64 * dx, j as f64 * dy, a, b, k));
                    t
                };
                Self {
                    boundary,
                    xx: tab(cerruti_uxx),
                    xy: tab(cerruti_uxy),
                    yy: tab(cerruti_uyy),
                }
            }
            Boundary::Periodic => {
                let plan = FftPlan::new(shape.0, shape.1, Boundary::Periodic);
                let s = cerruti_spectra(&plan, dx, dy, k);
                Self {
                    boundary,
                    xx: plan.inverse(s.xx.values),
                    xy: plan.inverse(s.xy.values),
                    yy: plan.inverse(s.yy.values),
                }
            }
        }
    }

    /// The kernel at the signed offset `(di, dj)`; even in `(di, dj) → (−di, −dj)`, so the sign
    /// convention of the offset (source − target or target − source) does not matter.
    fn get(&self, di: isize, dj: isize) -> (f64, f64, f64) {
        match self.boundary {
            Boundary::ZeroPadded => {
                let (ai, aj) = (di.unsigned_abs(), dj.unsigned_abs());
                let s = if (di < 0) != (dj < 0) && di != 0 && dj != 0 {
                    -1.0
                } else {
                    1.0
                };
                (self.xx[[ai, aj]], s * self.xy[[ai, aj]], self.yy[[ai, aj]])
            }
            Boundary::Periodic => {
                let (nx, ny) = self.xx.dim();
                let i = di.rem_euclid(nx as isize) as usize;
                let j = dj.rem_euclid(ny as isize) as usize;
                (self.xx[[i, j]], self.xy[[i, j]], self.yy[[i, j]])
            }
        }
    }
}

/// Estimated cost of one product with each operator `(dense, fft)`, in ns (2 threads).
///
/// Measured on the reference statistics' periodic patch (`cargo bench --bench tangential`,
/// 2 threads, idle machine, allocation-free FFT product; BENCHMARKS.md,
/// "Tangential contact"): the direct summation costs 0.12–0.25 ns per pair of contact points
/// (`n²` pairs; less per pair as `n` grows: 0.18 at n = 3391 on 512², 0.12 at 13 222 on
/// 1024²), the FFT product (two forward and two inverse real transforms, six spectral
/// products) 0.28–0.36 ns per `N log2 N` (`N` = FFT grid points: 6.8–7.5 ms at 1024²). With
/// 0.18 and 0.33 the choice is right in all four measured cases (dense at 1194 of 512² and
/// 4612 of 1024² contact points, FFT at 3391 and 13 222), where the former constants (0.35 and
/// 3.5, from the product that allocated its arrays) took the dense operator in the last two,
/// 1.3× and 2.8× slower. The crossover lies near n ≈ 2300 on 512² and n ≈ 6200 on 1024².
fn estimated_costs(n: usize, plan_points: usize) -> (f64, f64) {
    const DENSE_NS_PER_PAIR: f64 = 0.18;
    const FFT_NS_PER_POINT_LOG: f64 = 0.33;
    let dense = DENSE_NS_PER_PAIR * (n as f64).powi(2);
    let nf = plan_points as f64;
    let fft = FFT_NS_PER_POINT_LOG * nf * nf.log2().max(1.0);
    (dense, fft)
}

/// Largest eigenvalue of the (symmetric positive semi-definite: a periodic patch in contact at
/// every point has the uniform traction as a null vector) restricted compliance by power
/// iteration (m/Pa). The start vector mixes both components so that no mode is missed by
/// symmetry.
pub(super) fn largest_eigenvalue(c: &Compliance, n: usize) -> f64 {
    let mut v: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let s = ((k as f64 + 1.0) * 0.618_033_988_75).fract();
            [1.0 + s, 0.5 - s]
        })
        .collect();
    let norm = |v: &[[f64; 2]]| {
        v.iter()
            .map(|a| a[0] * a[0] + a[1] * a[1])
            .sum::<f64>()
            .sqrt()
    };
    let mut u = vec![[0.0; 2]; n];
    let mut est = 0.0;
    for _ in 0..60 {
        let nv = norm(&v);
        v.iter_mut().for_each(|a| *a = [a[0] / nv, a[1] / nv]);
        c.apply(&v, &mut u);
        let rq: f64 = v
            .iter()
            .zip(&u)
            .map(|(a, b)| a[0] * b[0] + a[1] * b[1])
            .sum();
        let converged = (rq - est).abs() <= 1e-4 * rq;
        est = rq;
        std::mem::swap(&mut v, &mut u);
        if converged {
            break;
        }
    }
    est
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product by direct double summation over the kernel table, and its largest
    /// component (the scale of the comparison tolerances).
    fn direct_sum(
        table: &KernelTable,
        pts: &[(usize, usize)],
        q: &[[f64; 2]],
    ) -> (Vec<[f64; 2]>, f64) {
        let expected: Vec<[f64; 2]> = pts
            .iter()
            .map(|&(i, j)| {
                let mut e = [0.0; 2];
                for (b, &(i2, j2)) in pts.iter().enumerate() {
                    let (kxx, kxy, kyy) =
                        table.get(i2 as isize - i as isize, j2 as isize - j as isize);
                    e[0] += kxx * q[b][0] + kxy * q[b][1];
                    e[1] += kxy * q[b][0] + kyy * q[b][1];
                }
                e
            })
            .collect();
        let scale = expected
            .iter()
            .map(|e| e[0].abs().max(e[1].abs()))
            .fold(0.0, f64::max);
        (expected, scale)
    }

    #[test]
    fn runs_group_consecutive_points_of_a_row() {
        let pts = [(0, 1), (0, 2), (0, 3), (0, 5), (1, 0), (1, 1), (3, 7)];
        let r = runs_of(&pts);
        let got: Vec<(usize, usize, usize, usize)> =
            r.iter().map(|r| (r.i, r.j0, r.start, r.len)).collect();
        assert_eq!(
            got,
            vec![(0, 1, 0, 3), (0, 5, 3, 1), (1, 0, 4, 2), (3, 7, 6, 1)]
        );
    }

    /// The AVX2 kernel and the portable one perform the same fused multiply-adds in the same
    /// order: bit-identical products (results do not depend on the CPU).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn simd_and_portable_summation_agree_bit_for_bit() {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma"))
        {
            eprintln!("skipped: no AVX2/FMA on this CPU");
            return;
        }
        let shape = (40, 37);
        let pts: Vec<(usize, usize)> = (0..shape.0)
            .flat_map(|i| (0..shape.1).map(move |j| (i, j)))
            .filter(|&(i, j)| (j + 3 * i) % 37 < 3 + i % 23 || (i + j) % 17 == 0)
            .collect();
        let k = CerrutiConstants::two_bodies(80e9, 0.3, 80e9, 0.3);
        let c = DirectCompliance::new(Boundary::Periodic, shape, &pts, 1e-6, 1e-6, k);
        for nc in 1..=MAX_RUN / LANES {
            assert!(
                c.runs.iter().any(|r| r.len.div_ceil(LANES) == nc),
                "no run of {nc} chunks"
            );
        }
        let qx: Vec<f64> = (0..pts.len()).map(|m| (m as f64 * 0.7).sin()).collect();
        let qy: Vec<f64> = (0..pts.len()).map(|m| (m as f64 * 1.3).cos()).collect();
        for t in &c.runs {
            let mut simd = vec![[0.0; 2]; t.len];
            // SAFETY: AVX2 and FMA checked above.
            unsafe { c.target_run_avx2(t, &qx, &qy, &mut simd) };
            let mut portable = vec![[0.0; 2]; t.len];
            c.target_run_portable(t, &qx, &qy, &mut portable);
            for (k, (v, w)) in simd.iter().zip(&portable).enumerate() {
                assert_eq!(v[0].to_bits(), w[0].to_bits(), "run {t:?} point {k}");
                assert_eq!(v[1].to_bits(), w[1].to_bits(), "run {t:?} point {k}");
            }
        }
    }

    /// The product as it was computed before the workspace (whole-grid transforms, allocated
    /// at every call): the allocation-free one must give the same bits.
    fn allocating_product(f: &FftCompliance, q: &[[f64; 2]]) -> Vec<[f64; 2]> {
        use crate::core::fft::multiply_in_place;
        let (plan, spectra) = (&f.plan, &f.spectra);
        let mut fx = Array2::<f64>::zeros(plan.grid_shape());
        let mut fy = Array2::<f64>::zeros(plan.grid_shape());
        for (k, &(i, j)) in f.points.iter().enumerate() {
            fx[[i, j]] = q[k][0];
            fy[[i, j]] = q[k][1];
        }
        let sx = plan.forward(&fx);
        let sy = plan.forward(&fy);
        let mut ux = sx.clone();
        multiply_in_place(&mut ux, &spectra.xx.values);
        let mut t = sy.clone();
        multiply_in_place(&mut t, &spectra.xy.values);
        ux += &t;
        let mut uy = sy;
        multiply_in_place(&mut uy, &spectra.yy.values);
        let mut t = sx;
        multiply_in_place(&mut t, &spectra.xy.values);
        uy += &t;
        let (ux, uy) = (plan.inverse(ux), plan.inverse(uy));
        f.points
            .iter()
            .map(|&(i, j)| [ux[[i, j]], uy[[i, j]]])
            .collect()
    }

    /// The FFT product against the direct double sum `u_i = Σ_j K(p_j − p_i) q_j` with the
    /// kernel in double precision (element coefficients, or the exact periodic kernel), to
    /// 1e-12 of the largest displacement; bit for bit against the earlier allocating product;
    /// the same bits when the workspace is reused, used from pools of other sizes, or held
    /// elsewhere (a fresh one is made). Odd and even sizes, rows without contact points.
    #[test]
    fn fft_product_equals_direct_sum_and_the_allocating_product() {
        let k = CerrutiConstants::two_bodies(80e9, 0.3, 50e9, 0.25);
        let (dx, dy) = (1e-6, 1.3e-6);
        for (shape, boundary) in [
            ((9, 7), Boundary::Periodic),
            ((12, 10), Boundary::Periodic),
            ((9, 7), Boundary::ZeroPadded),
            ((20, 17), Boundary::ZeroPadded),
        ] {
            let pts: Vec<(usize, usize)> = (0..shape.0)
                .flat_map(|i| (0..shape.1).map(move |j| (i, j)))
                .filter(|&(i, j)| i != 3 && ((i * 5 + j * 3) % 4 != 0 || j == 6))
                .collect();
            let plan = FftPlan::new(shape.0, shape.1, boundary);
            let spectra = cerruti_spectra(&plan, dx, dy, k);
            let f = FftCompliance::new(plan, spectra, &pts);
            let table = KernelTable::new(boundary, shape, (shape.0 - 1, shape.1 - 1), dx, dy, k);
            for round in 0..2 {
                let q: Vec<[f64; 2]> = (0..pts.len())
                    .map(|m| {
                        let m = (m + 7 * round) as f64;
                        [(m * 0.7).sin() * 1e6, (m * 1.3).cos() * 1e6]
                    })
                    .collect();
                let mut u = vec![[0.0; 2]; pts.len()];
                f.apply(&q, &mut u);
                let (expected, scale) = direct_sum(&table, &pts, &q);
                assert!(scale > 0.0);
                for (a, (got, e)) in u.iter().zip(&expected).enumerate() {
                    for c in 0..2 {
                        assert!(
                            (got[c] - e[c]).abs() <= 1e-12 * scale,
                            "{boundary:?} {shape:?} point {a} comp {c}: {} vs {}",
                            got[c],
                            e[c]
                        );
                    }
                }
                let bits = |u: &[[f64; 2]]| -> Vec<u64> {
                    u.iter()
                        .flat_map(|v| [v[0].to_bits(), v[1].to_bits()])
                        .collect()
                };
                let want = bits(&allocating_product(&f, &q));
                assert_eq!(bits(&u), want, "{boundary:?} {shape:?}: allocating product");
                for threads in [1, 3] {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    let mut v = vec![[0.0; 2]; pts.len()];
                    pool.install(|| f.apply(&q, &mut v));
                    assert_eq!(bits(&v), want, "{boundary:?} {shape:?}: {threads} threads");
                }
                let held = f.workspace.lock().unwrap();
                let mut v = vec![[0.0; 2]; pts.len()];
                f.apply(&q, &mut v);
                drop(held);
                assert_eq!(bits(&v), want, "{boundary:?} {shape:?}: fresh workspace");
            }
        }
    }

    /// The direct summation against the matrix written out entry by entry from the kernel
    /// table, on a point set with runs of several lengths, wrapping offsets (periodic) and
    /// both signs of offsets.
    #[test]
    fn direct_summation_equals_the_explicit_matrix() {
        let shape = (9, 7);
        let pts: Vec<(usize, usize)> = (0..shape.0)
            .flat_map(|i| (0..shape.1).map(move |j| (i, j)))
            .filter(|&(i, j)| (i * 5 + j * 3) % 4 != 0 || j == 6)
            .collect();
        let k = CerrutiConstants::two_bodies(80e9, 0.3, 50e9, 0.25);
        let (dx, dy) = (1e-6, 1.3e-6);
        for boundary in [Boundary::Periodic, Boundary::ZeroPadded] {
            let c = DirectCompliance::new(boundary, shape, &pts, dx, dy, k);
            let table = KernelTable::new(boundary, shape, (8, 6), dx, dy, k);
            let q: Vec<[f64; 2]> = (0..pts.len())
                .map(|m| [(m as f64 * 0.7).sin(), (m as f64 * 1.3).cos()])
                .collect();
            let mut u = vec![[0.0; 2]; pts.len()];
            c.apply(&q, &mut u);
            let (expected, scale) = direct_sum(&table, &pts, &q);
            assert!(scale > 0.0);
            for (a, (got, e)) in u.iter().zip(&expected).enumerate() {
                for c in 0..2 {
                    // The table is stored in single precision (relative rounding 6e-8).
                    assert!(
                        (got[c] - e[c]).abs() <= 1e-6 * scale,
                        "{boundary:?} point {a} comp {c}: {} vs {}",
                        got[c],
                        e[c]
                    );
                }
            }
        }
    }
}
