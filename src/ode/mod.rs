//! Adaptive high-order ODE integrator with dense output and event location.
//!
//! [`Dop853`] is the explicit Runge–Kutta pair of Dormand and Prince of order 8 with embedded
//! error estimators of orders 5 and 3 and a continuous extension of order 7, following
//! Hairer's `dop853.f` (Hairer, Nørsett, Wanner, *Solving ODEs I*, 2nd ed., Sect. II.5–II.6;
//! coefficients in [`coefficients`]). The exact engine uses it for the `tilted` force law
//! between junction events; see `docs/ode.md`.
//!
//! Usage pattern of the exact engine:
//! ```
//! use stickslip::ode::{Dop853, OdeSystem};
//! struct Decay;
//! impl OdeSystem for Decay {
//!     fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) {
//!         dydt[0] = -y[0];
//!     }
//! }
//! let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
//! let (mut t, mut y) = (0.0, [1.0]);
//! let next_event = 0.75;
//! while t < next_event {
//!     ode.step(&mut Decay, &mut t, &mut y, next_event).unwrap();
//!     // First time in the step where 0.5 - y0 goes from < 0 to >= 0, i.e. y0 falls to 0.5.
//!     if let Some(tc) = ode.locate(|_t, y| 0.5 - y[0]).unwrap() {
//!         assert!((tc - std::f64::consts::LN_2).abs() < 1e-10);
//!     }
//! }
//! assert_eq!(t, next_event); // the last step was cut short exactly at the event time
//! ode.reset(); // the right-hand side changes at the event
//! ```
//!
//! For stiff plates (tiny mass, large `K/eta`, large `kappa N`) [`Rosenbrock`] is the
//! linearly implicit, L-stable RODAS4 with analytic Jacobian ([`StiffSystem`]), dense output
//! and rigorous bounds of it (see `docs/rosenbrock.md`).
//!
//! Layout: `system` (the system, the counters and the errors every stepper shares),
//! [`coefficients`] (the Butcher table), `stepper` (step-size control, the public
//! [`Dop853`] type), `dense` (continuous extension), `root` (crossing detection and Brent's
//! bracketing root finder); `rosenbrock` (the [`Rosenbrock`] stepper, dense output, bounds),
//! `rodas4` (its coefficients and their algebraic tests), `lu` (small dense LU).

pub mod coefficients;
mod dense;
mod lu;
mod rodas4;
mod root;
mod rosenbrock;
mod stepper;
mod system;

pub use lu::MAX_DIM as ROSENBROCK_MAX_DIM;
pub use root::brent;
pub use rosenbrock::{Rosenbrock, RosenbrockConfig, RosenbrockN, StiffSystem};
pub use stepper::{Dop853, Dop853Config, MIN_RTOL};
pub use system::{OdeError, OdeStats, OdeSystem};
