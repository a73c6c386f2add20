//! FFT convolution of surface tractions with half-space influence coefficients.
//!
//! Two modes ([`Boundary`]):
//! - **Periodic**: the patch is one period of an infinite surface; the convolution is circular
//!   on the `nx × ny` grid (FFT size = grid size).
//! - **Zero-padded** (DC-FFT, Liu, Wang & Liu, Wear 243 (2000) 101–111): a finite contact on an
//!   infinite half-space; tractions are zero outside the grid, the grid is padded to
//!   `2nx × 2ny` and the kernel is laid out over the signed offsets `-(n-1)..=(n-1)`, which
//!   makes the circular convolution equal the linear one on the original grid.
//!
//! [`FftPlan`] holds the FFT plans (built once); [`KernelSpectrum`] holds a transformed kernel
//! (built once per influence function). Solvers apply them in their iterations without
//! re-planning. Real-to-complex transforms along y (contiguous axis) use `realfft`, complex
//! transforms along x use `rustfft`; rows are processed in parallel with rayon. Results are
//! bit-identical whatever the thread count (each row is transformed independently).
//!
//! Plans, spectra and workspaces are generic over the precision ([`FftReal`]): double for the
//! half-space operators, single where an approximation is all that is needed (the
//! preconditioner of the normal contact solver), at half the memory traffic and about half
//! the time of a transform pair.

use ndarray::{Array2, Axis};
use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::{Complex, Complex64};
use rustfft::num_traits::Float;
use rustfft::{Fft, FftNum, FftPlanner};
use std::sync::Arc;

/// Precision of a plan's transforms: `f64` or `f32`. Sums (energies, callers' reductions) are
/// accumulated in `f64` either way.
pub trait FftReal: FftNum + Float + Default + Into<f64> {}
impl FftReal for f32 {}
impl FftReal for f64 {}

/// `v` in precision `T` (exact for `T = f64`).
fn from_f64<T: FftReal>(v: f64) -> T {
    T::from_f64(v).expect("every f64 converts to f32 or f64")
}

/// Boundary treatment of the convolution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Boundary {
    /// Circular convolution: the grid is one period of the surface.
    Periodic,
    /// Linear convolution by zero padding to twice the size (DC-FFT).
    ZeroPadded,
}

/// FFT plans for one grid size and boundary mode.
///
/// Spectra are stored transposed, shape `(nfy/2 + 1, nfx)`: row `m` holds the x-transform of
/// the y-frequency `m`. Kernels and fields must be transformed with the same plan.
#[derive(Clone)]
pub struct FftPlan<T: FftReal = f64> {
    nx: usize,
    ny: usize,
    nfx: usize,
    nfy: usize,
    boundary: Boundary,
    r2c: Arc<dyn RealToComplex<T>>,
    c2r: Arc<dyn ComplexToReal<T>>,
    fwd: Arc<dyn Fft<T>>,
    inv: Arc<dyn Fft<T>>,
}

impl<T: FftReal> std::fmt::Debug for FftPlan<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FftPlan")
            .field("grid", &(self.nx, self.ny))
            .field("fft", &(self.nfx, self.nfy))
            .field("boundary", &self.boundary)
            .field("precision_bits", &(8 * std::mem::size_of::<T>()))
            .finish()
    }
}

/// The Fourier transform of an influence-coefficient kernel, ready to multiply field spectra.
#[derive(Debug, Clone)]
pub struct KernelSpectrum<T: FftReal = f64> {
    /// Transposed layout `(nfy/2 + 1, nfx)`, see [`FftPlan`].
    pub values: Array2<Complex<T>>,
}

impl<T: FftReal> FftPlan<T> {
    /// Plan transforms for an `nx × ny` grid.
    pub fn new(nx: usize, ny: usize, boundary: Boundary) -> Self {
        assert!(nx > 0 && ny > 0, "FftPlan: empty grid");
        let (nfx, nfy) = match boundary {
            Boundary::Periodic => (nx, ny),
            Boundary::ZeroPadded => (2 * nx, 2 * ny),
        };
        let mut rp = RealFftPlanner::<T>::new();
        let mut cp = FftPlanner::<T>::new();
        Self {
            nx,
            ny,
            nfx,
            nfy,
            boundary,
            r2c: rp.plan_fft_forward(nfy),
            c2r: rp.plan_fft_inverse(nfy),
            fwd: cp.plan_fft_forward(nfx),
            inv: cp.plan_fft_inverse(nfx),
        }
    }

    /// Grid size `(nx, ny)` of the fields this plan transforms.
    pub fn grid_shape(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// FFT size `(nfx, nfy)` (equal to the grid, or twice it when zero-padded).
    pub fn fft_shape(&self) -> (usize, usize) {
        (self.nfx, self.nfy)
    }

    /// Boundary mode of this plan.
    pub fn boundary(&self) -> Boundary {
        self.boundary
    }

    /// Shape of a spectrum, `(nfy/2 + 1, nfx)`.
    pub fn spectrum_shape(&self) -> (usize, usize) {
        (self.nfy / 2 + 1, self.nfx)
    }

    /// Angular wavenumbers `(qx, qy)` (rad/m) of the spectrum layout for spacings `dx`, `dy`:
    /// `qx` has `nfx` entries (signed), `qy` has `nfy/2 + 1` (non-negative).
    pub fn wavenumbers(&self, dx: f64, dy: f64) -> (Vec<f64>, Vec<f64>) {
        let lx = self.nfx as f64 * dx;
        let ly = self.nfy as f64 * dy;
        let qx = (0..self.nfx)
            .map(|k| {
                let k = if k <= self.nfx / 2 {
                    k as f64
                } else {
                    k as f64 - self.nfx as f64
                };
                2.0 * std::f64::consts::PI * k / lx
            })
            .collect();
        let qy = (0..self.nfy / 2 + 1)
            .map(|m| 2.0 * std::f64::consts::PI * m as f64 / ly)
            .collect();
        (qx, qy)
    }

    /// Kernel spectrum given directly in Fourier space as a function of `(qx, qy)` (rad/m),
    /// e.g. the exact periodic half-space compliance `2/(E*|q|)`; evaluated in double precision
    /// and stored in the plan's.
    pub fn spectrum_from_wavenumbers<F>(&self, dx: f64, dy: f64, f: F) -> KernelSpectrum<T>
    where
        F: Fn(f64, f64) -> Complex64 + Sync,
    {
        let (qx, qy) = self.wavenumbers(dx, dy);
        let mut values = Array2::<Complex<T>>::zeros(self.spectrum_shape());
        values
            .axis_iter_mut(Axis(0))
            .into_par_iter()
            .enumerate()
            .for_each(|(m, mut row)| {
                for (k, v) in row.iter_mut().enumerate() {
                    let c = f(qx[k], qy[m]);
                    *v = Complex::new(from_f64(c.re), from_f64(c.im));
                }
            });
        KernelSpectrum { values }
    }
}

impl FftPlan<f64> {
    /// Forward transform of an `(nfx, nfy)` real array (already padded).
    fn forward_full(&self, mut buf: Array2<f64>) -> Array2<Complex64> {
        let nh = self.nfy / 2 + 1;
        let mut rows = Array2::<Complex64>::zeros((self.nfx, nh));
        buf.axis_iter_mut(Axis(0))
            .into_par_iter()
            .zip(rows.axis_iter_mut(Axis(0)).into_par_iter())
            .for_each_init(
                || self.r2c.make_scratch_vec(),
                |scratch, (mut inp, mut out)| {
                    let inp = inp.as_slice_mut().expect("contiguous row");
                    let out = out.as_slice_mut().expect("contiguous row");
                    self.r2c
                        .process_with_scratch(inp, out, scratch)
                        .expect("r2c sizes match the plan");
                },
            );
        let mut spec = rows.reversed_axes().as_standard_layout().into_owned();
        spec.axis_iter_mut(Axis(0)).into_par_iter().for_each_init(
            || vec![Complex64::default(); self.fwd.get_inplace_scratch_len()],
            |scratch, mut row| {
                self.fwd
                    .process_with_scratch(row.as_slice_mut().expect("contiguous row"), scratch);
            },
        );
        spec
    }

    /// Forward transform of a grid field (`nx × ny`); zero-padded when the plan is.
    pub fn forward(&self, field: &Array2<f64>) -> Array2<Complex64> {
        assert_eq!(
            field.dim(),
            (self.nx, self.ny),
            "FftPlan::forward: field shape does not match the plan"
        );
        let buf = if self.boundary == Boundary::Periodic {
            field.as_standard_layout().into_owned()
        } else {
            let mut b = Array2::<f64>::zeros((self.nfx, self.nfy));
            b.slice_mut(ndarray::s![..self.nx, ..self.ny]).assign(field);
            b
        };
        self.forward_full(buf)
    }

    /// Inverse transform of a spectrum, normalised, cropped to the grid (`nx × ny`).
    /// The spectrum is consumed (used as work space).
    pub fn inverse(&self, mut spec: Array2<Complex64>) -> Array2<f64> {
        assert_eq!(
            spec.dim(),
            self.spectrum_shape(),
            "FftPlan::inverse: bad shape"
        );
        spec.axis_iter_mut(Axis(0)).into_par_iter().for_each_init(
            || vec![Complex64::default(); self.inv.get_inplace_scratch_len()],
            |scratch, mut row| {
                self.inv
                    .process_with_scratch(row.as_slice_mut().expect("contiguous row"), scratch);
            },
        );
        let mut rows = spec.reversed_axes().as_standard_layout().into_owned();
        let scale = 1.0 / (self.nfx * self.nfy) as f64;
        let mut out = Array2::<f64>::zeros((self.nx, self.ny));
        let nfy = self.nfy;
        let ny = self.ny;
        rows.axis_iter_mut(Axis(0))
            .into_par_iter()
            .take(self.nx)
            .zip(out.axis_iter_mut(Axis(0)).into_par_iter())
            .for_each_init(
                || (self.c2r.make_scratch_vec(), vec![0.0; nfy]),
                |(scratch, full), (mut inp, mut o)| {
                    let inp = inp.as_slice_mut().expect("contiguous row");
                    // The imaginary parts of the DC (and Nyquist) terms of a real signal are
                    // round-off; realfft insists they are zero.
                    inp[0].im = 0.0;
                    if nfy.is_multiple_of(2) {
                        inp[nfy / 2].im = 0.0;
                    }
                    self.c2r
                        .process_with_scratch(inp, full, scratch)
                        .expect("c2r sizes match the plan");
                    for (dst, src) in o.iter_mut().zip(full[..ny].iter()) {
                        *dst = src * scale;
                    }
                },
            );
        out
    }

    /// Spectrum of a real-space kernel given as a function of the signed grid offset
    /// `(di, dj)` between the field point and the source element.
    ///
    /// Periodic plans sample offsets in `[-n/2, n/2)` (nearest image); for an exactly periodic
    /// kernel supply the spectrum directly with [`FftPlan::spectrum_from_wavenumbers`].
    /// Zero-padded plans sample `-(n-1)..=(n-1)` and put zero at the unused offset `±n`.
    pub fn kernel_spectrum<F>(&self, kernel: F) -> KernelSpectrum
    where
        F: Fn(isize, isize) -> f64 + Sync,
    {
        let (nfx, nfy) = (self.nfx, self.nfy);
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        let padded = self.boundary == Boundary::ZeroPadded;
        let offset = |k: usize, nf: usize, n: isize| -> Option<isize> {
            let k = k as isize;
            let nf = nf as isize;
            let d = if k < nf - k { k } else { k - nf };
            if padded && d.abs() >= n {
                None
            } else {
                Some(d)
            }
        };
        let mut buf = Array2::<f64>::zeros((nfx, nfy));
        buf.axis_iter_mut(Axis(0))
            .into_par_iter()
            .enumerate()
            .for_each(|(i, mut row)| {
                if let Some(di) = offset(i, nfx, nx) {
                    for (j, v) in row.iter_mut().enumerate() {
                        if let Some(dj) = offset(j, nfy, ny) {
                            *v = kernel(di, dj);
                        }
                    }
                }
            });
        KernelSpectrum {
            values: self.forward_full(buf),
        }
    }

    /// `out = kernel ⊛ field` on the grid.
    pub fn convolve(&self, kernel: &KernelSpectrum, field: &Array2<f64>) -> Array2<f64> {
        let mut spec = self.forward(field);
        multiply_in_place(&mut spec, &kernel.values);
        self.inverse(spec)
    }
}

/// Reusable work arrays for allocation-free convolutions with one [`FftPlan`]
/// ([`FftPlan::convolve_into`]); iterative solvers create one and keep it for all iterations.
///
/// The rows are padded (`padded_row_length`): the x-transforms read and write them down
/// columns, and with the power-of-two strides of the transform sizes every element of a column
/// would fall into the same few cache sets.
#[derive(Debug, Clone)]
pub struct ConvolutionWorkspace<T: FftReal = f64> {
    /// Row transforms: `nfx` rows of `nfy/2 + 1` values, row stride `padded_row_length(nfy/2 + 1)`.
    rows: Vec<Complex<T>>,
}

/// Row stride (complex values of precision `T`) for rows of `n` values read down their columns:
/// the smallest `m ≥ n` whose rows start an odd number of 64-byte cache lines apart, so that a
/// column's elements spread over all cache sets instead of aliasing to a few (a stride of
/// `2^k + 16` bytes, as for `n = 2^j + 1` double-precision values, maps 32 consecutive rows to
/// one or two sets).
fn padded_row_length<T: FftReal>(n: usize) -> usize {
    let per_line = (64 / std::mem::size_of::<Complex<T>>()).max(1);
    per_line * (n.div_ceil(per_line) | 1)
}

/// y-frequencies transformed along x together: their columns of the row transforms are gathered
/// into one buffer (`COLUMNS` rows of `nfx` values, 128 KiB at `nfx = 1024` in double
/// precision: it stays in L2).
const COLUMNS: usize = 8;

impl<T: FftReal> FftPlan<T> {
    /// Work arrays for [`FftPlan::convolve_into`] and [`FftPlan::convolve_fused`].
    pub fn workspace(&self) -> ConvolutionWorkspace<T> {
        let nh = self.nfy / 2 + 1;
        ConvolutionWorkspace {
            rows: vec![Complex::default(); self.nfx * padded_row_length::<T>(nh)],
        }
    }
}

impl FftPlan<f64> {
    /// `out = kernel ⊛ field` on the grid, like [`FftPlan::convolve`] but without allocating
    /// (see [`FftPlan::convolve_fused`] for the steps). `field` and `out` have the grid shape
    /// `(nx, ny)`.
    pub fn convolve_into(
        &self,
        kernel: &KernelSpectrum,
        field: &Array2<f64>,
        out: &mut Array2<f64>,
        ws: &mut ConvolutionWorkspace,
    ) {
        let (nx, ny) = (self.nx, self.ny);
        assert_eq!(field.dim(), (nx, ny), "convolve_into: field shape");
        assert_eq!(out.dim(), (nx, ny), "convolve_into: output shape");
        let field = field.as_standard_layout();
        let field = field.as_slice().expect("standard layout");
        let out = SharedMut::new(out.as_slice_mut().expect("output in standard layout"));
        self.convolve_fused::<0, 0, ()>(
            kernel,
            ws,
            |i, buf| {
                buf.copy_from_slice(&field[i * ny..(i + 1) * ny]);
                []
            },
            |_| Some(()),
            |_, _, i, result| {
                // SAFETY: each output row is written by one call only, nothing reads it meanwhile.
                unsafe { out.row(i, ny) }.copy_from_slice(result);
                []
            },
        );
    }
}

impl<T: FftReal> FftPlan<T> {
    /// One convolution with the passes before and after it fused into the transforms, so that
    /// an iterative solver touches each grid row once while it is in cache:
    ///
    /// 1. for every grid row `i` (in parallel): `load(i, row)` writes row `i` of the field `f`
    ///    to be convolved into `row` (length `ny`) and may update the caller's own arrays for
    ///    that row; it returns `A` partial sums; the row is transformed at once (real-to-complex
    ///    along y);
    /// 2. `mid(&sums)` sees the sums of step 1 (added in row order, so they do not depend on the
    ///    thread count) and returns the context `M` of step 4, or `None` to stop here: the caller
    ///    found that the convolution is not needed after all (e.g. converged);
    /// 3. per block of `COLUMNS` y-frequencies (in parallel): their columns gathered into a
    ///    buffer that stays in cache, x-transform, kernel product, inverse x-transform, the `nx`
    ///    rows that are kept scattered back (no transposed copy of the spectrum is made); then
    ///    the inverse real transforms of those rows. Step 3 also sums the energy
    ///    `E = Σ_x f·(K⊛f) = (1/N_fft) Σ_q K̃(q)|f̂(q)|²` (Parseval; the kernel spectrum is taken
    ///    as real, as for every even kernel; summed in `f64`);
    /// 4. for every grid row `i`: `store(&context, E, i, result)` receives the scaled result row
    ///    and returns `B` partial sums (added in row order).
    ///
    /// With zero padding, the padded rows are never transformed (their spectrum is zero).
    /// Returns the sums of step 1, and `(E, sums of step 4)` unless `mid` stopped.
    pub fn convolve_fused<const A: usize, const B: usize, M: Sync>(
        &self,
        kernel: &KernelSpectrum<T>,
        ws: &mut ConvolutionWorkspace<T>,
        load: impl Fn(usize, &mut [T]) -> [f64; A] + Sync,
        mid: impl FnOnce(&[f64; A]) -> Option<M>,
        store: impl Fn(&M, f64, usize, &[T]) -> [f64; B] + Sync,
    ) -> ([f64; A], Option<(f64, [f64; B])>) {
        let (nx, ny, nfx, nfy) = (self.nx, self.ny, self.nfx, self.nfy);
        let nh = nfy / 2 + 1;
        assert_eq!(
            kernel.values.dim(),
            (nh, nfx),
            "convolve_fused: kernel shape"
        );
        // Row strides of the row transforms and of the column buffer.
        let (sh, sx) = (padded_row_length::<T>(nh), padded_row_length::<T>(nfx));
        assert_eq!(ws.rows.len(), nfx * sh, "convolve_fused: workspace shape");
        // 1. Load and real-transform the nx data rows (rows nx.. of `ws.rows` stay zero).
        let mut load_parts = vec![[0.0; A]; nx];
        ws.rows[..nx * sh]
            .par_chunks_mut(sh)
            .zip(load_parts.par_iter_mut())
            .enumerate()
            .for_each_init(
                || (vec![T::zero(); nfy], self.r2c.make_scratch_vec()),
                |(buf, scratch), (i, (row_out, part))| {
                    *part = load(i, &mut buf[..ny]);
                    buf[ny..].fill(T::zero());
                    self.r2c
                        .process_with_scratch(buf, &mut row_out[..nh], scratch)
                        .expect("r2c sizes match the plan");
                },
            );
        let load_sums = sum_in_order(&load_parts);
        let Some(context) = mid(&load_sums) else {
            return (load_sums, None);
        };
        // 2.–3. Per block of COLUMNS y-frequencies (in parallel): gather the block's columns of
        // the row transforms into a local buffer, x-transform each y-frequency, multiply by
        // the kernel (and sum the energy), inverse x-transform, scatter the kept rows back.
        // The half spectrum holds y-frequencies 0..=nfy/2; all but 0 and (even nfy) nfy/2 stand
        // for their mirror images too.
        let kern = kernel.values.as_slice().expect("standard layout");
        let mut energy_parts = vec![[0.0; 1]; nh];
        let rows = SharedMut::new(&mut ws.rows);
        energy_parts
            .par_chunks_mut(COLUMNS)
            .enumerate()
            .for_each_init(
                || {
                    let n = self
                        .fwd
                        .get_inplace_scratch_len()
                        .max(self.inv.get_inplace_scratch_len());
                    (
                        vec![Complex::<T>::default(); COLUMNS * sx],
                        vec![Complex::<T>::default(); n],
                    )
                },
                |(block, scratch), (b, energy)| {
                    let m0 = b * COLUMNS;
                    let mb = energy.len();
                    for k in 0..nfx {
                        // SAFETY: columns m0..m0 + mb are read and written by this call only.
                        let src = unsafe { rows.get(k * sh + m0, mb) };
                        for (dm, v) in src.iter().enumerate() {
                            block[dm * sx + k] = *v;
                        }
                    }
                    for (dm, e_part) in energy.iter_mut().enumerate() {
                        let m = m0 + dm;
                        let row = &mut block[dm * sx..dm * sx + nfx];
                        let krow = &kern[m * nfx..(m + 1) * nfx];
                        self.fwd.process_with_scratch(row, scratch);
                        let mut e = 0.0;
                        for (s, k) in row.iter_mut().zip(krow) {
                            e += (s.norm_sqr() * k.re).into();
                            *s = *s * *k;
                        }
                        let weight = if m == 0 || (nfy % 2 == 0 && m == nfy / 2) {
                            1.0
                        } else {
                            2.0
                        };
                        e_part[0] = weight * e;
                        self.inv.process_with_scratch(row, scratch);
                    }
                    // Only the nx rows of the grid are kept (zero-padded rows stay zero).
                    for k in 0..nx {
                        // SAFETY: as above.
                        let dst = unsafe { rows.get(k * sh + m0, mb) };
                        for (dm, v) in dst.iter_mut().enumerate() {
                            *v = block[dm * sx + k];
                        }
                    }
                },
            );
        let scale = 1.0 / (nfx * nfy) as f64;
        let energy = sum_in_order(&energy_parts)[0] * scale;
        let scale_t: T = from_f64(scale);
        // 4. Inverse real transforms of the nx rows that are kept, scale, store.
        let mut store_parts = vec![[0.0; B]; nx];
        let context = &context;
        ws.rows[..nx * sh]
            .par_chunks_mut(sh)
            .zip(store_parts.par_iter_mut())
            .enumerate()
            .for_each_init(
                || (vec![T::zero(); nfy], self.c2r.make_scratch_vec()),
                |(buf, scratch), (i, (row, part))| {
                    let row = &mut row[..nh];
                    // Imaginary parts of the DC (and Nyquist) terms of a real signal are
                    // round-off; realfft insists they are zero.
                    row[0].im = T::zero();
                    if nfy.is_multiple_of(2) {
                        row[nfy / 2].im = T::zero();
                    }
                    self.c2r
                        .process_with_scratch(row, buf, scratch)
                        .expect("c2r sizes match the plan");
                    for v in &mut buf[..ny] {
                        *v = *v * scale_t;
                    }
                    *part = store(context, energy, i, &buf[..ny]);
                },
            );
        (load_sums, Some((energy, sum_in_order(&store_parts))))
    }
}

/// Reusable work arrays for [`FftPlan::convolve_pair`]: the row transforms of both fields and
/// one set of transform scratch per parallel task, so that a product allocates nothing.
///
/// The work is split into a fixed number of tasks (twice the rayon threads when the workspace
/// is made), each with its own scratch, instead of rayon's `for_each_init` (which allocates
/// its state for every piece of work it splits off). Every row and every y-frequency is
/// transformed on its own, so the result does not depend on the split.
#[derive(Debug, Clone)]
pub struct PairWorkspace {
    /// Row transforms of `f_x` and `f_y`, laid out as [`ConvolutionWorkspace`]'s; rows `nx..`
    /// (zero padding) stay zero.
    rows: [Vec<Complex64>; 2],
    tasks: Vec<PairScratch>,
}

/// `f(i, row i of x, row i of y, task scratch)` for the `nx` data rows (stride `sh`) of the two
/// row-transform arrays of [`PairWorkspace`], in parallel: contiguous ranges of rows, one per
/// task, each with its own scratch.
fn for_each_row_pair(
    rows_x: &mut [Complex64],
    rows_y: &mut [Complex64],
    nx: usize,
    sh: usize,
    tasks: &mut [PairScratch],
    f: impl Fn(usize, &mut [Complex64], &mut [Complex64], &mut PairScratch) + Sync,
) {
    let per_task = nx.div_ceil(tasks.len()).max(1);
    rows_x[..nx * sh]
        .par_chunks_mut(per_task * sh)
        .zip(rows_y[..nx * sh].par_chunks_mut(per_task * sh))
        .zip(tasks.par_iter_mut())
        .enumerate()
        .for_each(|(b, ((chunk_x, chunk_y), task))| {
            for (di, (row_x, row_y)) in chunk_x
                .chunks_mut(sh)
                .zip(chunk_y.chunks_mut(sh))
                .enumerate()
            {
                f(b * per_task + di, row_x, row_y, task);
            }
        });
}

/// One task's scratch of [`FftPlan::convolve_pair`].
#[derive(Debug, Clone)]
struct PairScratch {
    /// A real row of each field (length `nfy`).
    real: [Vec<f64>; 2],
    r2c: Vec<Complex64>,
    c2r: Vec<Complex64>,
    /// x-transforms (forward and inverse).
    fft: Vec<Complex64>,
    /// `COLUMNS` y-frequencies of each field, row stride `padded_row_length(nfx)`.
    block: [Vec<Complex64>; 2],
}

impl FftPlan<f64> {
    /// Work arrays for [`FftPlan::convolve_pair`].
    pub fn pair_workspace(&self) -> PairWorkspace {
        let nh = self.nfy / 2 + 1;
        let (sh, sx) = (
            padded_row_length::<f64>(nh),
            padded_row_length::<f64>(self.nfx),
        );
        let fft = self
            .fwd
            .get_inplace_scratch_len()
            .max(self.inv.get_inplace_scratch_len());
        let task = PairScratch {
            real: [vec![0.0; self.nfy], vec![0.0; self.nfy]],
            r2c: self.r2c.make_scratch_vec(),
            c2r: self.c2r.make_scratch_vec(),
            fft: vec![Complex64::default(); fft],
            block: [
                vec![Complex64::default(); COLUMNS * sx],
                vec![Complex64::default(); COLUMNS * sx],
            ],
        };
        let rows = vec![Complex64::default(); self.nfx * sh];
        PairWorkspace {
            rows: [rows.clone(), rows],
            tasks: vec![task; 2 * rayon::current_num_threads().max(1)],
        }
    }

    /// `[u_x, u_y] = K ⊛ [f_x, f_y]` with the symmetric 2 × 2 kernel
    /// `K = [[K_xx, K_xy], [K_xy, K_yy]]` (`kernels = [K_xx, K_xy, K_yy]`; the tangential
    /// half-space compliance), without allocating:
    ///
    /// 1. for every grid row `i` (in parallel): `load(i, f_x row, f_y row)` writes row `i` of the
    ///    two fields (length `ny`, zero on entry); the rows are transformed at once
    ///    (real-to-complex along y);
    /// 2. per block of `COLUMNS` y-frequencies: x-transforms,
    ///    `û_x = K̂_xx f̂_x + K̂_xy f̂_y`, `û_y = K̂_yy f̂_y + K̂_xy f̂_x`, inverse x-transforms, the
    ///    `nx` rows that are kept scattered back;
    /// 3. for every grid row `i`: inverse real transforms, scaled, passed to
    ///    `store(i, u_x row, u_y row)`.
    ///
    /// The same transforms and products in the same order as [`FftPlan::forward`], the
    /// spectral products and [`FftPlan::inverse`], so the result is the same bit for bit.
    pub fn convolve_pair(
        &self,
        kernels: [&KernelSpectrum; 3],
        ws: &mut PairWorkspace,
        load: impl Fn(usize, &mut [f64], &mut [f64]) + Sync,
        store: impl Fn(usize, &[f64], &[f64]) + Sync,
    ) {
        let (nx, ny, nfx, nfy) = (self.nx, self.ny, self.nfx, self.nfy);
        let nh = nfy / 2 + 1;
        for k in kernels {
            assert_eq!(k.values.dim(), (nh, nfx), "convolve_pair: kernel shape");
        }
        let (sh, sx) = (padded_row_length::<f64>(nh), padded_row_length::<f64>(nfx));
        let PairWorkspace {
            rows: [rows_x, rows_y],
            tasks,
        } = ws;
        assert_eq!(rows_x.len(), nfx * sh, "convolve_pair: workspace shape");
        assert_eq!(rows_y.len(), nfx * sh, "convolve_pair: workspace shape");
        // 1. Load and real-transform the nx data rows.
        for_each_row_pair(rows_x, rows_y, nx, sh, tasks, |i, out_x, out_y, task| {
            let [fx, fy] = &mut task.real;
            fx.fill(0.0);
            fy.fill(0.0);
            load(i, &mut fx[..ny], &mut fy[..ny]);
            for (f, out) in [(&mut *fx, out_x), (&mut *fy, out_y)] {
                self.r2c
                    .process_with_scratch(f, &mut out[..nh], &mut task.r2c)
                    .expect("r2c sizes match the plan");
            }
        });
        // 2. Per block of COLUMNS y-frequencies: gather the columns, x-transform, kernel
        // product, inverse x-transform, scatter the kept rows back.
        let [kxx, kxy, kyy] = kernels.map(|k| k.values.as_slice().expect("standard layout"));
        let blocks = nh.div_ceil(COLUMNS);
        let per_task_blocks = blocks.div_ceil(tasks.len()).max(1);
        let (shared_x, shared_y) = (SharedMut::new(rows_x), SharedMut::new(rows_y));
        tasks.par_iter_mut().enumerate().for_each(|(t, task)| {
            let [bx, by] = &mut task.block;
            let first = (t * per_task_blocks).min(blocks);
            let last = ((t + 1) * per_task_blocks).min(blocks);
            for b in first..last {
                let m0 = b * COLUMNS;
                let mb = COLUMNS.min(nh - m0);
                for (rows, block) in [(&shared_x, &mut *bx), (&shared_y, &mut *by)] {
                    for k in 0..nfx {
                        // SAFETY: columns m0..m0 + mb are read and written by this task only.
                        let src = unsafe { rows.get(k * sh + m0, mb) };
                        for (dm, v) in src.iter().enumerate() {
                            block[dm * sx + k] = *v;
                        }
                    }
                }
                for dm in 0..mb {
                    let m = m0 + dm;
                    let x = &mut bx[dm * sx..dm * sx + nfx];
                    let y = &mut by[dm * sx..dm * sx + nfx];
                    self.fwd.process_with_scratch(x, &mut task.fft);
                    self.fwd.process_with_scratch(y, &mut task.fft);
                    let (kxx, kxy, kyy) = (
                        &kxx[m * nfx..(m + 1) * nfx],
                        &kxy[m * nfx..(m + 1) * nfx],
                        &kyy[m * nfx..(m + 1) * nfx],
                    );
                    for k in 0..nfx {
                        let (a, c) = (x[k], y[k]);
                        x[k] = a * kxx[k] + c * kxy[k];
                        y[k] = c * kyy[k] + a * kxy[k];
                    }
                    self.inv.process_with_scratch(x, &mut task.fft);
                    self.inv.process_with_scratch(y, &mut task.fft);
                }
                // Only the nx rows of the grid are kept (zero-padded rows stay zero).
                for (rows, block) in [(&shared_x, &*bx), (&shared_y, &*by)] {
                    for k in 0..nx {
                        // SAFETY: as above.
                        let dst = unsafe { rows.get(k * sh + m0, mb) };
                        for (dm, v) in dst.iter_mut().enumerate() {
                            *v = block[dm * sx + k];
                        }
                    }
                }
            }
        });
        // 3. Inverse real transforms of the nx rows that are kept, scale, store.
        let scale = 1.0 / (nfx * nfy) as f64;
        for_each_row_pair(rows_x, rows_y, nx, sh, tasks, |i, in_x, in_y, task| {
            let [ux, uy] = &mut task.real;
            for (row, u) in [(in_x, &mut *ux), (in_y, &mut *uy)] {
                let row = &mut row[..nh];
                // Imaginary parts of the DC (and Nyquist) terms of a real signal are
                // round-off; realfft insists they are zero.
                row[0].im = 0.0;
                if nfy.is_multiple_of(2) {
                    row[nfy / 2].im = 0.0;
                }
                self.c2r
                    .process_with_scratch(row, u, &mut task.c2r)
                    .expect("c2r sizes match the plan");
                for v in &mut u[..ny] {
                    *v *= scale;
                }
            }
            store(i, &ux[..ny], &uy[..ny]);
        });
    }
}

/// Raw pointer to a buffer whose disjoint parts are written by parallel calls: rows of a field
/// (the solvers' work arrays, [`FftPlan::convolve_into`]'s output), columns of the row
/// transforms ([`FftPlan::convolve_fused`]'s column blocks).
#[derive(Clone, Copy)]
pub(crate) struct SharedMut<T>(*mut T);
unsafe impl<T: Send> Send for SharedMut<T> {}
unsafe impl<T: Send> Sync for SharedMut<T> {}
impl<T> SharedMut<T> {
    pub(crate) fn new(buf: &mut [T]) -> Self {
        Self(buf.as_mut_ptr())
    }

    /// A standard-layout array's buffer.
    pub(crate) fn of(a: &mut Array2<T>) -> Self {
        Self::new(
            a.as_slice_mut()
                .expect("work arrays are in standard layout"),
        )
    }

    /// The `len` values from `start`. Safety: they lie in the buffer, and no other call
    /// touches them meanwhile.
    #[allow(clippy::mut_from_ref)]
    pub(crate) unsafe fn get(&self, start: usize, len: usize) -> &mut [T] {
        std::slice::from_raw_parts_mut(self.0.add(start), len)
    }

    /// Row `i` of length `ny`. Safety: as for [`SharedMut::get`].
    #[allow(clippy::mut_from_ref)]
    pub(crate) unsafe fn row(&self, i: usize, ny: usize) -> &mut [T] {
        self.get(i * ny, ny)
    }
}

/// Sum of per-row partial sums in row order (the result does not depend on the thread count).
fn sum_in_order<const K: usize>(parts: &[[f64; K]]) -> [f64; K] {
    let mut total = [0.0; K];
    for p in parts {
        for k in 0..K {
            total[k] += p[k];
        }
    }
    total
}

/// `spec *= kernel` element-wise (parallel).
pub fn multiply_in_place(spec: &mut Array2<Complex64>, kernel: &Array2<Complex64>) {
    assert_eq!(
        spec.dim(),
        kernel.dim(),
        "spectrum and kernel shapes differ"
    );
    spec.as_slice_mut()
        .expect("standard layout")
        .par_iter_mut()
        .zip(kernel.as_slice().expect("standard layout").par_iter())
        .for_each(|(s, k)| *s *= k);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct O(N²) convolution, for checking the FFT paths.
    fn direct(field: &Array2<f64>, k: impl Fn(isize, isize) -> f64, periodic: bool) -> Array2<f64> {
        let (nx, ny) = field.dim();
        let mut out = Array2::zeros((nx, ny));
        for i in 0..nx {
            for j in 0..ny {
                let mut s = 0.0;
                for a in 0..nx {
                    for b in 0..ny {
                        let (mut di, mut dj) = (i as isize - a as isize, j as isize - b as isize);
                        if periodic {
                            let (n, m) = (nx as isize, ny as isize);
                            di = di.rem_euclid(n);
                            dj = dj.rem_euclid(m);
                            if di >= n - di {
                                di -= n;
                            }
                            if dj >= m - dj {
                                dj -= m;
                            }
                        }
                        s += k(di, dj) * field[[a, b]];
                    }
                }
                out[[i, j]] = s;
            }
        }
        out
    }

    fn test_field(nx: usize, ny: usize) -> Array2<f64> {
        Array2::from_shape_fn((nx, ny), |(i, j)| {
            ((i * 7 + j * 3) % 11) as f64 - 4.0 + 0.1 * i as f64
        })
    }

    fn kernel(di: isize, dj: isize) -> f64 {
        1.0 / (1.0 + (di as f64 + 0.3).powi(2) + 2.0 * (dj as f64).powi(2))
    }

    #[test]
    fn zero_padded_equals_direct_linear_convolution() {
        for (nx, ny) in [(6, 5), (7, 8)] {
            let f = test_field(nx, ny);
            let plan = FftPlan::new(nx, ny, Boundary::ZeroPadded);
            let ks = plan.kernel_spectrum(kernel);
            let got = plan.convolve(&ks, &f);
            let want = direct(&f, kernel, false);
            for (g, w) in got.iter().zip(want.iter()) {
                assert!((g - w).abs() < 1e-12 * (1.0 + w.abs()), "{g} vs {w}");
            }
        }
    }

    #[test]
    fn periodic_equals_direct_circular_convolution() {
        for (nx, ny) in [(6, 5), (8, 8)] {
            let f = test_field(nx, ny);
            let plan = FftPlan::new(nx, ny, Boundary::Periodic);
            let ks = plan.kernel_spectrum(kernel);
            let got = plan.convolve(&ks, &f);
            let want = direct(&f, kernel, true);
            for (g, w) in got.iter().zip(want.iter()) {
                assert!((g - w).abs() < 1e-12 * (1.0 + w.abs()), "{g} vs {w}");
            }
        }
    }

    #[test]
    fn wavenumber_kernel_differentiates_a_cosine() {
        // Multiplying by -qx² is the second x-derivative: cos(2πx/L)·(-(2π/L)²).
        let (nx, ny, dx, dy) = (16, 8, 0.5, 0.25);
        let plan = FftPlan::new(nx, ny, Boundary::Periodic);
        let lx = nx as f64 * dx;
        let k = 2.0 * std::f64::consts::PI / lx;
        let f = Array2::from_shape_fn((nx, ny), |(i, _)| (k * i as f64 * dx).cos());
        let ks = plan.spectrum_from_wavenumbers(dx, dy, |qx, _| Complex64::new(-qx * qx, 0.0));
        let got = plan.convolve(&ks, &f);
        for ((i, _), g) in got.indexed_iter() {
            let want = -k * k * (k * i as f64 * dx).cos();
            assert!((g - want).abs() < 1e-12, "{g} vs {want}");
        }
    }

    #[test]
    fn convolve_into_matches_convolve_and_reuses_workspace() {
        for (nx, ny, boundary) in [
            (6, 5, Boundary::ZeroPadded),
            (7, 8, Boundary::ZeroPadded),
            (70, 45, Boundary::ZeroPadded),
            (6, 5, Boundary::Periodic),
            (64, 66, Boundary::Periodic),
        ] {
            let plan = FftPlan::new(nx, ny, boundary);
            let ks = plan.kernel_spectrum(kernel);
            let mut ws = plan.workspace();
            let mut out = Array2::zeros((nx, ny));
            for round in 0..2 {
                let f = test_field(nx, ny).mapv(|v| v + round as f64);
                plan.convolve_into(&ks, &f, &mut out, &mut ws);
                let want = plan.convolve(&ks, &f);
                for (g, w) in out.iter().zip(want.iter()) {
                    assert!((g - w).abs() < 1e-11 * (1.0 + w.abs()), "{g} vs {w}");
                }
            }
        }
    }

    /// A single-precision plan (the preconditioner's) against the double-precision convolution.
    #[test]
    fn single_precision_plan_matches_double() {
        // Odd, even and padded sizes; nh = 21, 4, 34: full and partial column blocks.
        for (nx, ny, boundary) in [
            (40, 40, Boundary::Periodic),
            (9, 7, Boundary::Periodic),
            (33, 34, Boundary::ZeroPadded),
        ] {
            let spectrum =
                |qx: f64, qy: f64| Complex64::new(1.0 / (1.0 + qx * qx + 0.5 * qy * qy), 0.0);
            let (dx, dy) = (0.3, 0.2);
            let f = test_field(nx, ny);
            let run_f64 = {
                let plan = FftPlan::<f64>::new(nx, ny, boundary);
                let ks = plan.spectrum_from_wavenumbers(dx, dy, spectrum);
                let mut out = Array2::zeros((nx, ny));
                plan.convolve_into(&ks, &f, &mut out, &mut plan.workspace());
                out
            };
            let plan = FftPlan::<f32>::new(nx, ny, boundary);
            let ks = plan.spectrum_from_wavenumbers(dx, dy, spectrum);
            let out = std::sync::Mutex::new(Array2::<f64>::zeros((nx, ny)));
            plan.convolve_fused::<0, 0, ()>(
                &ks,
                &mut plan.workspace(),
                |i, buf| {
                    for (b, v) in buf.iter_mut().zip(f.row(i)) {
                        *b = *v as f32;
                    }
                    []
                },
                |_| Some(()),
                |_, _, i, row| {
                    let mut out = out.lock().unwrap();
                    for (o, v) in out.row_mut(i).iter_mut().zip(row) {
                        *o = f64::from(*v);
                    }
                    []
                },
            );
            let out = out.into_inner().unwrap();
            let scale = run_f64.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in out.iter().zip(run_f64.iter()) {
                assert!((a - b).abs() < 1e-5 * scale, "{a} vs {b} ({nx}×{ny})");
            }
        }
    }

    /// The fused convolution: load sums, the energy Σ f·(K⊛f) from the spectrum (Parseval),
    /// the store sees the result rows, and `mid` can stop before the transforms.
    #[test]
    fn convolve_fused_energy_sums_and_stop() {
        for (nx, ny, boundary) in [
            (7, 8, Boundary::ZeroPadded),
            (6, 5, Boundary::ZeroPadded),
            (8, 6, Boundary::Periodic),
            (9, 7, Boundary::Periodic),
        ] {
            let plan = FftPlan::new(nx, ny, boundary);
            // An even kernel (real spectrum), as for every half-space kernel.
            let ks = plan.kernel_spectrum(|di, dj| {
                1.0 / (1.0 + (di as f64).powi(2) + 2.0 * (dj as f64).powi(2))
            });
            let f = test_field(nx, ny);
            let want = plan.convolve(&ks, &f);
            let want_energy: f64 = f.iter().zip(want.iter()).map(|(a, b)| a * b).sum();
            let mut ws = plan.workspace();
            let got = std::sync::Mutex::new(Array2::<f64>::zeros((nx, ny)));
            let (load, rest) = plan.convolve_fused::<1, 1, f64>(
                &ks,
                &mut ws,
                |i, buf| {
                    buf.copy_from_slice(f.row(i).as_slice().unwrap());
                    [buf.iter().sum()]
                },
                |s| Some(2.0 * s[0]),
                |twice_sum, _, i, row| {
                    got.lock()
                        .unwrap()
                        .row_mut(i)
                        .assign(&ndarray::ArrayView1::from(row));
                    [row.iter().sum::<f64>() + *twice_sum * 0.0]
                },
            );
            assert!((load[0] - f.sum()).abs() < 1e-12);
            let (energy, store) = rest.unwrap();
            assert!(
                (energy - want_energy).abs() < 1e-10 * want_energy.abs(),
                "{energy} {want_energy}"
            );
            assert!((store[0] - want.sum()).abs() < 1e-10 * (1.0 + want.sum().abs()));
            let got = got.into_inner().unwrap();
            for (g, w) in got.iter().zip(want.iter()) {
                assert!((g - w).abs() < 1e-11 * (1.0 + w.abs()));
            }
            let (_, stopped) = plan.convolve_fused::<0, 0, ()>(
                &ks,
                &mut ws,
                |_, buf| {
                    buf.fill(1.0);
                    []
                },
                |_| None,
                |_, _, _, _| unreachable!("stopped before the transforms"),
            );
            assert!(stopped.is_none());
        }
    }
}
