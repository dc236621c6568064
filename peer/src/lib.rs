//! Nothing but a home for the peer bench (`benches/peer.rs`): see `peer/Cargo.toml`.
