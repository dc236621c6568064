//! Adaptive high-order ODE integrator with dense output and event location (being built).
