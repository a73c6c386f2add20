//! The FFT compliance operator allocates no grid-sized arrays in a tangential step: its work
//! arrays live with the operator. (Before, every product allocated and freed its grids and
//! spectra, and glibc returned them to the kernel, so library users paid a page fault per page
//! per product; BENCHMARKS.md, "Tangential contact".)
//!
//! Its own test binary: the counting allocator sees every thread of the process, so no other
//! test may run beside it.

use asperity::contact::tangential::{
    Control, Operator, TangentialOptions, TangentialProblem, TangentialSolver,
};
use asperity::core::fft::Boundary;
use asperity::core::material::Material;
use ndarray::Array2;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Counts the allocations of at least [`LARGE`] bytes while [`COUNTING`] is set.
struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static LARGE_ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
static LARGEST: AtomicUsize = AtomicUsize::new(0);
static LARGE: AtomicUsize = AtomicUsize::new(usize::MAX);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) && layout.size() >= LARGE.load(Ordering::Relaxed) {
            LARGE_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
            LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        }
        // SAFETY: forwarded unchanged.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) && new_size >= LARGE.load(Ordering::Relaxed) {
            LARGE_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
            LARGEST.fetch_max(new_size, Ordering::Relaxed);
        }
        // SAFETY: forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Steps of a displacement cycle with the FFT operator, periodic and zero-padded, on a contact
/// spot small against the grid: after the first step, no allocation as large as half a grid
/// field (the contact-point vectors of the solver are ten times smaller).
#[test]
fn fft_operator_steps_allocate_no_grid_arrays() {
    let n = 96;
    let dx = 1e-6;
    let radius = 12.0;
    let centre = 0.5 * (n as f64 - 1.0);
    let p = Array2::from_shape_fn((n, n), |(i, j)| {
        let r = (i as f64 - centre).hypot(j as f64 - centre) / radius;
        if r < 1.0 {
            1e8 * (1.0 - r * r).sqrt()
        } else {
            0.0
        }
    });
    let points = p.iter().filter(|v| **v > 0.0).count();
    let steel = Material::STEEL;
    let large = n * n * std::mem::size_of::<f64>() / 2;
    assert!(
        points * 2 * std::mem::size_of::<f64>() * 4 < large,
        "{points} points"
    );
    for boundary in [Boundary::Periodic, Boundary::ZeroPadded] {
        let mut s = TangentialSolver::new(
            &TangentialProblem {
                pressure: &p,
                dx,
                dy: dx,
                boundary,
                friction_coefficient: 0.5,
                body1: steel,
                body2: steel,
            },
            TangentialOptions {
                operator: Operator::Fft,
                ..TangentialOptions::default()
            },
        )
        .unwrap();
        let d = s.gross_slip_displacement([1.0, 0.0]).unwrap();
        s.step(Control::Displacement([0.2 * d, 0.0])).unwrap();
        LARGE.store(large, Ordering::SeqCst);
        LARGE_ALLOCATIONS.store(0, Ordering::SeqCst);
        LARGEST.store(0, Ordering::SeqCst);
        COUNTING.store(true, Ordering::SeqCst);
        let mut products = 0;
        for f in [0.4, 0.6, 0.3, -0.2] {
            products += s
                .step(Control::Displacement([f * d, 0.0]))
                .unwrap()
                .iterations;
        }
        COUNTING.store(false, Ordering::SeqCst);
        assert!(products >= 4, "{products} products");
        assert_eq!(
            LARGE_ALLOCATIONS.load(Ordering::SeqCst),
            0,
            "{boundary:?}: allocations of ≥ {large} bytes in {products} products (largest {} bytes)",
            LARGEST.load(Ordering::SeqCst)
        );
    }
}
