//! The test kit of `stickslip`: one set of scenes, the lists of force laws and bond kinds,
//! and run helpers, shared by the root crate's tests (`tests/`), benches (`benches/`) and
//! examples (`examples/`). A dev-dependency only: the library ships without it.
//!
//! - [`scenes`]: the letter's Fig. 1 ([`FIG1`], read from `scenarios/fig1.toml`) and the
//!   scenes built from it ([`fig1_with`], [`fixed_fig1`], [`scaled`], ...);
//! - [`kinds`]: [`LAWS`] and [`BONDS`], the library's own lists, so that a loop over them
//!   tests a new law or bond kind as soon as the library has it;
//! - [`runs`]: runs that keep what a test reads ([`events_of`], [`samples_of`], [`steps`],
//!   [`verdict_of`]), through the
//!   library's [`stickslip::runner::Simulation`] handle, with no engine visitor;
//! - [`creep`]: the Bell theory of low-velocity creep that `examples/creep.rs` and
//!   `tests/suite/creep.rs` compare the exact engine with;
//! - [`concrete`]: the kit's one engine visitor, [`Concrete`]: work on the concrete engine, the
//!   reference of the handle's cost.

pub mod concrete;
pub mod creep;
pub mod kinds;
pub mod runs;
pub mod scenes;

pub use concrete::{Concrete, ConcreteRun};
pub use kinds::{BONDS, LAWS, law_bond_pairs};
pub use runs::{Trace, events_of, first_rupture, samples_of, steps, verdict_of};
pub use scenes::{
    FIG1, bond_named, fig1, fig1_with, fixed_fig1, law_named, scaled, scaled_linear, scaled_tilted, scaled_with, scene,
};
