//! No heap allocation per step, dense evaluation or event location (a global allocator
//! that counts the allocations of the current thread only, so that the test harness's own
//! threads do not interfere).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use stickslip::ode::{Dop853, Rosenbrock, StiffSystem};

struct Counting;

thread_local! {
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
}

fn bump() {
    let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
}

fn allocs() -> u64 {
    ALLOCS.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn no_allocation_per_step() {
    let mut f = |t: f64, y: &[f64], d: &mut [f64]| {
        d[0] = y[1];
        d[1] = -y[0] - 0.1 * y[1] + 0.5 + 0.02 * t;
        d[2] = (0.1 * y[0]).exp();
    };
    let mut ode = Dop853::new(3, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, [1.0, 0.0, 0.0]);
    ode.step(&mut f, &mut t, &mut y, 0.03).unwrap();
    let mut out = [0.0; 3];
    let before = allocs();
    let mut k = 2;
    let mut hits = 0;
    while t < 30.0 {
        let t_max = f64::from(k) * 0.03;
        ode.step(&mut f, &mut t, &mut y, t_max).unwrap();
        let (t_old, t_new) = ode.last_step().unwrap();
        ode.dense(0.5 * (t_old + t_new), &mut out).unwrap();
        hits += usize::from(ode.locate_component(2, 5.0).unwrap().is_some());
        hits += usize::from(ode.locate(|_, y| y[0] - 1.2).unwrap().is_some());
        if t == t_max {
            ode.reset();
            k += 1;
        }
    }
    let after = allocs();
    assert!(hits > 0);
    assert_eq!(after - before, 0, "allocations during stepping");
}

/// The Rosenbrock integrator does not allocate per step, dense evaluation or bound.
#[test]
fn rosenbrock_no_allocation_per_step() {
    struct Plate;
    impl StiffSystem for Plate {
        fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
            d[0] = y[1];
            d[1] = -1e4 * y[0] - 10.0 * y[1] - y[0].powi(3) + 0.5 + 0.02 * t;
            d[2] = y[0];
        }
        fn jacobian(&mut self, _t: f64, y: &[f64], j: &mut [f64], ft: &mut [f64]) {
            j.copy_from_slice(&[0.0, 1.0, 0.0, -1e4 - 3.0 * y[0] * y[0], -10.0, 0.0, 1.0, 0.0, 0.0]);
            ft.copy_from_slice(&[0.0, 0.02, 0.0]);
        }
    }
    let mut ode = Rosenbrock::new(3, 1e-8, 1e-10).unwrap();
    let (mut t, mut y) = (0.0, [1.0, 0.0, 0.0]);
    ode.step(&mut Plate, &mut t, &mut y, 0.03).unwrap();
    let mut out = [0.0; 3];
    let before = allocs();
    let mut k = 2;
    while t < 3.0 {
        let t_max = f64::from(k) * 0.03;
        ode.step(&mut Plate, &mut t, &mut y, t_max).unwrap();
        let (t_old, t_new) = ode.last_step().unwrap();
        ode.dense(0.5 * (t_old + t_new), &mut out).unwrap();
        let _ = ode.component_bounds(0).unwrap();
        if t == t_max {
            ode.reset();
            k += 1;
        }
    }
    assert_eq!(allocs() - before, 0, "allocations during stepping");
}
