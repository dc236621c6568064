//! Closed-form propagator of the linear-law plate between events (being built).
